"""Gait libraries and Dask multi-starts (issue 11, item 6) on the level-ground compass gait.

Sources of the expected values: the library against cold starts (the same problem solved from
the model's default start, no warm start) to 1e-8 relative; the optimum at 0.3 m in 0.8 s
against issue 11's 6.668848535 N²·m²·s; the step length at which a torque bound becomes active,
located by the library's bisection, against the *unbounded* optima on either side (their peak
torque at the collocation points is below the bound just before it and above just after); the
Dask multi-start against the serial one (same computations in other processes: same minima).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.errors import GaitoptInputError
from gaitopt.optimize import gait_library, optimize_gait

PERIOD = 0.8  # s


@pytest.fixture(scope="module")
def level():
    return gaitopt.model("compass_gait", slope=0.0)


@pytest.fixture(scope="module")
def library(level):
    return gait_library(level, "step_length", [0.2, 0.25, 0.3], period=PERIOD, cold=2)


def test_library_agrees_with_cold_starts(library):
    assert library.success, library.message
    assert [pt.warm for pt in library.points] == [False, True, True]
    assert [c.value for c in library.cold_checks] == [0.2, 0.3]
    for check in library.cold_checks:
        # Same optimum from a cold start: cost to 1e-8 relative (measured ≤ 5e-14).
        assert check.agree, check.message
        assert check.relative_difference <= 1e-8
    # Issue 11's optimum at 0.3 m in 0.8 s (to its 10 digits).
    assert library.costs[-1] == pytest.approx(6.668848535, rel=1e-9)
    # Longer steps in the same time cost more effort.
    assert np.all(np.diff(library.costs) > 0)
    assert library.events == []  # no active-set change, no fold on [0.2, 0.3] m


def test_reduced_hessian_is_positive_definite(library):
    # Second-order sufficient condition at each strict local minimum: λmin > 0.
    for pt in library.points:
        lo, hi = pt.hessian
        assert 0 < lo <= hi, pt.hessian


def _node_peak(gait):
    col, w = gait.transcription
    return float(np.max(np.abs(col.blocks.get(w, "U0"))))


def test_active_set_change_where_the_torque_bound_becomes_active(level):
    # |τ| ≤ 1.4 N·m: inactive at 0.22 m (unbounded peak 1.13 N·m), active at 0.24 m (1.54).
    # At 0.24 m the optimum is solved with the arcs of the bound (the torque at -1.4 on one
    # arc inside the step, free on either side), which are part of its active set; the
    # library keeps its target 1e-6.
    bound = 1.4
    lib = gait_library(
        level,
        "step_length",
        [0.22, 0.24],
        period=PERIOD,
        bounds={"hip_torque": bound},
        cold=0,
        locate=0.05,
        tol=1e-6,
    )
    assert lib.success, lib.message
    assert len(lib.events) == 1
    event = lib.events[0]
    assert event.kind == "active set"
    assert set(event.after) - set(event.before) == {
        f"|hip_torque| <= {bound:g}",
        "arcs of the input bounds [free lo free]",
    }
    lo, hi = event.bracket
    assert 0.22 < lo < hi < 0.24 and hi - lo <= 0.05 * 0.02 + 1e-12
    # Independent: the unbounded optimum's peak torque crosses the bound inside the bracket,
    # give or take 2 mm (the peak rises ~21 N·m per m: 0.04 N·m either side).
    below = optimize_gait(level, period=PERIOD, step_length=lo - 2e-3, verify=False)
    above = optimize_gait(level, period=PERIOD, step_length=hi + 2e-3, verify=False)
    assert _node_peak(below) < bound < _node_peak(above)


def test_dask_multistart_finds_the_serial_minima(level):
    serial = optimize_gait(level, period=PERIOD, step_length=0.3, starts=2, verify=False)
    on_dask = optimize_gait(
        level, period=PERIOD, step_length=0.3, starts=2, verify=False, scheduler="local"
    )
    assert serial.success and on_dask.success, (serial.message, on_dask.message)
    assert len(on_dask.minima) == len(serial.minima) >= 1
    for a, b in zip(serial.minima, on_dask.minima, strict=True):
        # The same IPOPT runs in worker processes: identical to rounding (1e-12 relative).
        assert b.cost == pytest.approx(a.cost, rel=1e-12)
        assert b.starts == a.starts
    assert on_dask.cost == pytest.approx(serial.cost, rel=1e-12)


def test_library_rejects_bad_input(level):
    with pytest.raises(GaitoptInputError, match="`vary`"):
        gait_library(level, "step_length", [0.2, 0.3], step_length=0.3)
    with pytest.raises(GaitoptInputError, match="`vary`"):
        gait_library(level, "stride", [0.2, 0.3])
    with pytest.raises(GaitoptInputError, match="`values`"):
        gait_library(level, "step_length", [0.2, 0.3, 0.25])
    with pytest.raises(GaitoptInputError, match="`cold`"):
        gait_library(level, "step_length", [0.2, 0.3], cold=[0.25])


def test_cli_library(capsys, tmp_path):
    argv = ["optimize", "compass_gait", "--set", "slope=0", "--fix", "period=0.8",
            "--library", "step_length=0.25:0.3:2", "--cold", "0", "--json",
            "--out", str(tmp_path)]  # fmt: skip
    assert main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["success"] and report["vary"] == "step_length"
    assert [pt["value"] for pt in report["points"]] == [0.25, 0.3]
    assert report["points"][1]["cost"] == pytest.approx(6.668848535, rel=1e-9)
    assert (tmp_path / "library.json").exists() and (tmp_path / "library.csv").exists()
    bad = ["optimize", "compass_gait", "--library", "step_length=0.2:0.3"]
    assert main(bad) == 2


def test_problem_data_round_trips_every_option():
    # A Dask worker rebuilds the problem from plain data: every option must survive, the
    # kneed walker's clearance and knee margins included (exact equality of the statement).
    from gaitopt.optimize.library.workers import problem_data, problem_from
    from gaitopt.optimize.problem import as_problem

    problem = as_problem(
        gaitopt.model("kneed_walker"), cost="effort", clearance=0.01, guard_margin=0.05
    )
    rebuilt = problem_from(problem_data(problem))
    assert rebuilt.describe() == problem.describe()
    assert (rebuilt.clearance, rebuilt.guard_margin) == (0.01, 0.05)
