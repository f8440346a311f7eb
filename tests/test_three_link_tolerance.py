"""The three-link walker's step time under a loose integrator (problems/three_link_tolerance.py).

Sources: gaitopt's gait 2.1677530383 s, μ₁ 0.6713863 (tests/test_three_link_walker.py, checked
there against a NumPy referee at rtol 1e-12); the study's table in
results/three_link_tolerance/tolerance.json (written by the study at this commit).  The claim
under test: at SciPy's default tolerance (rtol 1e-3, atol 1e-6) iterating the simulated return
map converges to a fixed point of its own (drift ≤ 1e-10) whose step time is not the ODE's (off
by more than 1e-2 s), while at rtol 1e-12 it is the ODE's (1e-8 s).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

import gaitopt

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "problems"))
import three_link_tolerance as study  # noqa: E402


@pytest.fixture(scope="module")
def setting():
    model = gaitopt.model("three_link_walker")
    cycle = gaitopt.find_limit_cycle(model)
    assert cycle.success, cycle.message
    names = list(model.state_names)
    return cycle, study._ScipyStep(model), [names.index(c) for c in cycle.section_coordinates]


def test_a_default_tolerance_simulation_has_a_self_consistent_fixed_point_that_is_not_the_gait(
    setting,
):
    cycle, step, coordinates = setting
    r = study.discretised_fixed_point(step, cycle.x, "RK45", 1e-3, 1e-6, coordinates)
    # Self-consistent: the iteration has converged (contraction ≤ 0.73 over 80 steps: ~1e-11).
    assert r["fixed_point_drift"] < 1e-10
    # ... and its step time is not the ODE's: off by more than 1e-2 s (0.037 s when written).
    assert abs(r["step_time_s"] - cycle.period) > 1e-2
    # The committed table holds the same numbers (SciPy's RK45 is deterministic; 1e-8 s / 1e-6
    # for the finite-difference multiplier, whose step is 1e-7).
    table = json.loads((ROOT / "results/three_link_tolerance/tolerance.json").read_text())
    row = next(
        row
        for row in table["rows"]
        if row["method"] == "RK45" and row["rtol"] == pytest.approx(1e-3)
    )
    assert r["step_time_s"] == pytest.approx(row["step_time_s"], abs=1e-8)
    mu = r["multipliers"][0]
    assert np.hypot(*mu) == pytest.approx(row["mu1"], abs=1e-6)


def test_the_committed_table_converges_to_the_gait_as_the_tolerance_tightens(setting):
    cycle, _, _ = setting
    table = json.loads((ROOT / "results/three_link_tolerance/tolerance.json").read_text())
    assert table["gaitopt"]["step_time_s"] == pytest.approx(cycle.period, abs=1e-10)
    for method in study.METHODS:
        rows = [row for row in table["rows"] if row["method"] == method]
        tight = min(rows, key=lambda row: row["rtol"])
        loose = max(rows, key=lambda row: row["rtol"])
        # rtol 1e-12: the ODE's step time to 1e-8 s and μ₁ to 1e-5 (finite differences, 1e-7).
        assert tight["step_time_s"] == pytest.approx(cycle.period, abs=1e-8)
        assert tight["mu1"] == pytest.approx(abs(cycle.multipliers[0]), abs=1e-5)
        # The defaults: another "gait", off by more than 1e-3 s (6.6e-3 to 3.7e-2 s when written).
        assert abs(loose["step_time_minus_gaitopt_s"]) > 1e-3
    # ... and the three methods' "gaits" at the defaults are far apart (0.068 s when written; the
    # issue's 2.2583406929 s is 0.091 s from the ODE's).
    loose = [row["step_time_s"] for row in table["rows"] if row["rtol"] == pytest.approx(1e-3)]
    assert len(loose) == len(study.METHODS)
    assert max(loose) - min(loose) > 5e-2
