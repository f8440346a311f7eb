"""State bounds and declared path constraints (joint limits) of optimal gaits (issue 24, item 4).

Reference problem: the compass gait on level ground, step 0.3 m in 0.8 s, least effort; its
optimum 6.668848534 N²·m²·s is pinned by tests/test_optimize.py (the same statement, certified
to a discretisation error below 1e-8).  On it the swing rate peaks at 2.650 rad/s at heel strike
(measured here, the unbounded optimum) and the stance angle must reach ±asin(0.15) = ±0.1506
rad at the section and at heel strike (the step length), so:

* ``swing_dot <= 2`` is active (it cuts the peak), raises the cost, and holds on the dense
  samples of the final polynomials (the certificate's rule c ≥ −1e-9 (1 + max|c|));
* ``-5 <= swing_dot <= 5`` is inactive: the optimum is unchanged to 1e-9 relative;
* ``-0.1 <= stance <= 0.1`` excludes the gait: an honest failure naming the bound.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.errors import GaitoptInputError
from gaitopt.optimize import optimize_gait
from gaitopt.optimize.collocation import LIMIT_TOL

EFFORT = 6.668848534  # tests/test_optimize.py: compass gait, step 0.3 m in 0.8 s, level ground
ROOT = Path(__file__).resolve().parent.parent


def _compass(**kwargs):
    return optimize_gait(
        gaitopt.model("compass_gait", slope=0), period=0.8, step_length=0.3, **kwargs
    )


def _dense_rate(gait) -> np.ndarray:
    arc = gait.orbit[0]
    return arc.x[arc.states.index("swing_dot")]


@pytest.fixture(scope="module")
def free_gait():
    return _compass()


def test_unbounded_reference(free_gait):
    assert free_gait.success, free_gait.message
    assert free_gait.cost == pytest.approx(EFFORT, rel=1e-9)
    # The peak swing rate the active bound below must cut (measured: 2.650 rad/s).
    assert np.max(_dense_rate(free_gait)) > 2.5


def test_active_state_bound_changes_the_optimum_and_holds_densely(free_gait):
    gait = _compass(state_bounds={"swing_dot": (-10.0, 2.0)})
    assert gait.success and gait.verified, gait.message
    # Active: the cost rises (measured 8.9117 against 6.6688) and the JSON names it.
    assert gait.cost > free_gait.cost * 1.1
    label = "swing_dot <= 2 (single support)"
    assert label in gait.active_constraints
    assert gait.active_spans[label]  # when: a time span within the period
    assert all(0 <= a <= b <= 0.8 + 1e-12 for a, b in gait.active_spans[label])
    # Holds on the dense samples of the polynomials (the certificate's rule).
    rates = _dense_rate(gait)
    assert np.max(rates) <= 2.0 + LIMIT_TOL * (1 + np.max(np.abs(rates - 2.0)))
    # And the independent simulation confirms it (1e-6 relative cost, the certificate's).
    assert gait.verification["cost_simulated"] == pytest.approx(gait.cost, rel=1e-6)


def test_inactive_state_bound_leaves_the_optimum(free_gait):
    gait = _compass(state_bounds={"swing_dot": (-5.0, 5.0)})
    assert gait.success, gait.message
    assert gait.cost == pytest.approx(free_gait.cost, rel=1e-9)
    assert gait.cost == pytest.approx(EFFORT, rel=1e-9)
    assert not [a for a in gait.active_constraints if "swing_dot" in a]


def test_bound_excluding_the_gait_fails_honestly():
    gait = _compass(state_bounds={"stance": (-0.1, 0.1)})
    assert not gait.success
    assert "-0.1 <= stance <= 0.1" in gait.message  # names the bound at its limit


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"state_bounds": {"knee": (0, 1)}}, "unknown state 'knee'"),
        ({"state_bounds": {"swing": (1.0, 1.0)}}, "low < high"),
        ({"state_bounds": {"swing": (2.0, 1.0)}}, "low < high"),
        ({"state_bounds": {"swing": (-math.inf, math.inf)}}, "bounds nothing"),
        ({"state_bounds": {"swing": "wide"}}, "pair (low, high)"),
        ({"bounds": {"swing": 1.0}}, "a state of compass_gait, not an input"),
        ({"path_constraints": ("knee_flexion",)}, "declares none"),
    ],
)
def test_bad_input_is_one_line(kwargs, words):
    with pytest.raises(GaitoptInputError) as info:
        _compass(**kwargs)
    message = str(info.value)
    assert words in message and "\n" not in message


def test_unknown_limit_names_the_declared_ones():
    with pytest.raises(GaitoptInputError, match="five_link_biped's limits: knee_flexion"):
        optimize_gait(gaitopt.model("five_link_biped"), period=0.7, step_length=0.5,
                      path_constraints=("knee",))  # fmt: skip


def test_declared_knee_limits():
    # OptimTraj pathConstraint.m (867eeb3): c = (q1 − q2, q5 − q4) ≤ 0, i.e. the flexions
    # stance_thigh − stance_shank ≥ 0 and swing_thigh − swing_shank ≥ 0 (exact arithmetic).
    model = gaitopt.model("five_link_biped")
    stance, swing = model.phases[0].limits["knee_flexion"]
    x = np.arange(1.0, 11.0) / 10
    u, p = np.zeros(4), model.p
    assert float(stance.function(x, u, p)) == pytest.approx(x[1] - x[0], abs=1e-15)
    assert float(swing.function(x, u, p)) == pytest.approx(x[3] - x[4], abs=1e-15)
    # The kneed walker: only before its knee locks, q3 − q2 ≥ 0 (0 at both ends of the phase).
    kneed = gaitopt.model("kneed_walker")
    (flexion,) = kneed.phases[0].limits["knee_flexion"]
    assert flexion.at_start and flexion.at_end
    assert float(flexion.function(x[:6], np.zeros(len(kneed.inputs)), kneed.p)) == pytest.approx(
        0.1, abs=1e-15
    )
    assert not kneed.phases[1].limits


def _cli(capsys, *args):
    """``gaitopt optimize`` of the reference problem with ``args``: (status, stdout, stderr)."""
    argv = ["optimize", "compass_gait", "--set", "slope=0", "--fix", "step_length=0.3",
            "--fix", "period=0.8", *args]  # fmt: skip
    status = main(argv)
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--bound", "knee=0:1"], "no input or state 'knee'"),
        (["--bound", "swing=1:1"], "LOW must be below its HIGH"),
        (["--bound", "swing=2:1"], "LOW must be below its HIGH"),
        (["--bound", "swing=-1"], "MAX must be > 0"),
        (["--constrain", "knee_flexion"], "no limit 'knee_flexion'"),
    ],
)
def test_cli_bad_input_is_one_line(args, words, capsys):
    status, out, err = _cli(capsys, *args)
    assert status == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and words in lines[0] and args[1] in lines[0]


def test_cli_state_bound_is_active_in_the_json(capsys):
    status, out, err = _cli(capsys, "--bound", "swing_dot=:2", "--json")
    assert status == 0, err
    report = json.loads(out)
    assert "swing_dot <= 2 (single support)" in report["active_constraints"]
    assert report["problem"]["state_bounds"]["swing_dot"][1] == 2.0
    assert report["cost"] > EFFORT * 1.1
    assert report["active_spans"]["swing_dot <= 2 (single support)"]


def test_cli_excluding_bound_reports_failure(capsys):
    status, out, _ = _cli(capsys, "--bound", "stance=-0.1:0.1", "--json")
    assert status == 1
    report = json.loads(out)
    assert report["success"] is False and "-0.1 <= stance <= 0.1" in report["message"]


@pytest.mark.slow  # ≥ 25 s: run by `make test-slow` (CI runs both)
def test_five_link_knee_study_fast(tmp_path):
    # problems/optimal_five_link_knee.py --fast: the knee-limited 0.5 m / 0.7 s step of OptimTraj
    # (MAIN.m c8d1d91, pathConstraint.m 867eeb3), one start, refinement target 1e-8.  The stance
    # knee straightens at one touch point near heel strike; made a free mesh point
    # (gaitopt.optimize.state_arcs, ċ = 0 there) the optimum is certified.  The limit binds:
    # the free-knee optimum from start 0 (469.50197507 N²·m²·s, certified to 4.6e-11;
    # results/optimal_five_link_knee/table.csv lists it among the three free minima, the best
    # 456.19077299) hyperextends the stance knee by 0.016 rad, so the limited cost from the same
    # start is higher.
    run = subprocess.run(
        [sys.executable, str(ROOT / "problems" / "optimal_five_link_knee.py"), "--fast",
         "--out", str(tmp_path)],
        capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    summary = json.loads((tmp_path / "optimal_five_link_knee" / "summary.json").read_text())
    (row,) = summary["rows"]
    assert row["case"] == "knee limit", run.stderr
    assert row["success"] and row["verified"], row["message"]
    assert row["discretisation_error"] <= 1e-8
    # Above the free-knee optimum of the same start; and within 1e-6 of the uncertified value
    # of a uniform 48-interval mesh without the touch junction (469.6501187, the README's
    # before this change: an independent transcription, known to about 1e-4 because of its dip).
    assert row["cost"] > 469.50197507
    assert row["cost"] == pytest.approx(469.6501187, rel=1e-6)
    # The knee limit on 64 samples per mesh interval of the final polynomials, the touch point
    # among them, by the certificate's rule c >= -1e-9 (1 + max|c|) (measured -8.2e-12 rad),
    # and in the independent simulation of the step with its torques (DOP853, rtol 1e-12; the
    # same rule, measured +2.2e-9 rad).  It binds (below 1e-6), and the swing knee stays flexed.
    tolerance = row["dense_tolerance_rad"]
    assert -tolerance <= row["min_stance_knee_flexion_rad"] < 1e-6
    assert -tolerance <= row["min_stance_knee_flexion_simulated_rad"] < 1e-6
    assert row["min_swing_knee_flexion_rad"] > 1e-3
    assert "stance knee flexion >= 0 at 0.652" in row["touch_points"]
    assert "touch points of stance knee flexion >= 0 (single support)" in row["active_constraints"]
    (span,) = summary["active_spans"]["knee limit"]["stance knee flexion >= 0 (single support)"]
    assert 0.65 < span[0] <= span[1] < 0.66
    assert (tmp_path / "optimal_five_link_knee" / "table.csv").exists()


def test_kneed_walker_knee_limit_is_its_guard_side():
    # The kneed walker's knee flexion q3 − q2 ≥ 0 before the knee locks is the knee strike's
    # guard side, which the transcription keeps anyway: selecting it adds no rows (the same NLP,
    # so the same optimum to rounding, 1e-12 relative) and the dense check of the limit passes.
    # Problem: the README's kneed-walker row (default slope, 0.47 m in 0.5643 s, least effort
    # 2.191941449e-4 N²·m²·s, discretisation error 6.2e-9).
    model = gaitopt.model("kneed_walker")
    plain = optimize_gait(model, period=0.5643, step_length=0.47)
    limited = optimize_gait(model, period=0.5643, step_length=0.47,
                            path_constraints="knee_flexion")  # fmt: skip
    assert plain.success and limited.success, limited.message
    assert limited.cost == pytest.approx(plain.cost, rel=1e-12)
    assert limited.cost == pytest.approx(2.191941449e-4, rel=1e-8)
    col, _ = limited.transcription
    assert col.guard_limits == [(0, "swing knee flexion")] and not col.limit_groups
    arc = limited.orbit[0]  # three-link swing: the knee stays flexed on the dense samples
    flexion = arc.x[2] - arc.x[1]
    assert np.min(flexion) >= -LIMIT_TOL * (1 + np.max(np.abs(flexion)))
