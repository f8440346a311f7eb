"""Analyses written once, fed an optimal gait (issue 19, item 6): the open loop of an
:class:`~gaitopt.optimize.OptimalGait` (its input profile on a clock since the section) is a
model like any other, so multiple shooting, continuation and step-to-step control take it.

The gait: the README's level compass optimum (slope 0, 0.3 m in 0.8 s, least ∫τ² dt,
6.668848534 N²·m²·s, multipliers −1.34078, 0.42715, −0.00283).  Sources of the expected values:
the optimum itself, computed by a different transcription (Radau collocation, its multipliers
by AD through the collocation and checked there against finite differences of the simulator),
against multiple shooting of the open loop here; the collocation's own offset Jacobian
(:func:`gaitopt.optimize.stabilisation.offset_jacobian`) against the shooting's; the
independent simulator driven by the optimum's NumPy profile (:class:`InputProfile`, not the
CasADi one the model uses) at a parameter the optimum never saw.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.continuation import PseudoArclength
from gaitopt.control import closed_loop, lqr
from gaitopt.errors import GaitoptInputError
from gaitopt.open_loop import open_loop_cycle
from gaitopt.optimize import InputProfile, OptimalGait, optimize_gait
from gaitopt.optimize.stabilisation import offset_jacobian
from gaitopt.orbit.feedforward import CLOCK, HOLD_MARGIN, feedforward_model

LEVEL = {"period": 0.8, "step_length": 0.3}
OPTIMIZE_ARGV = ["optimize", "compass_gait", "--set", "slope=0", "--fix", "step_length=0.3",
                 "--fix", "period=0.8", "--json"]  # fmt: skip


@pytest.fixture(scope="module")
def level():
    gait = optimize_gait(gaitopt.model("compass_gait", slope=0.0), **LEVEL)
    assert gait.success, gait.message
    return gait


@pytest.fixture(scope="module")
def cycle(level):
    found = open_loop_cycle(level)
    assert found.success, found.message
    return found


def test_the_clock_reads_the_optimum_profile(level):
    model = feedforward_model(level)
    profile = level.profiles[0]
    assert model.state_names[-1] == CLOCK
    assert model.section.coordinates == level.model.section.coordinates
    assert model.params == level.model.params and model.inputs == level.model.inputs
    # The same pieces, sides of the breaks, clamping and Horner arithmetic as InputProfile's:
    # equal to rounding (1e-12 N·m, the torque being O(5) N·m) at 1601 times, the breaks among them.
    times = np.union1d(np.linspace(0.0, 0.8, 1601), profile.breaks)
    ours = np.array([model.profile(t) for t in times]).ravel()
    theirs = np.array([profile(t) for t in times]).ravel()
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)
    # Held after the end (beyond HOLD_MARGIN): the last value, as the optimum's feedforward.
    assert model.profile(0.8 + 1e3 * HOLD_MARGIN)[0] == pytest.approx(profile(0.9)[0], abs=1e-12)
    # The parameters stay declared and changeable; the profile does not change with them.
    steeper = model.replace(slope=0.01)
    assert steeper.slope == 0.01 and type(steeper) is type(model)


def test_shooting_the_open_loop_reproduces_the_optimum(level, cycle):
    # Multiple shooting of the open loop against the collocation that found the optimum:
    # the period is free in the shooting (fixed, 0.8 s, in the optimisation) and comes out
    # 0.8 to 1e-9 (measured 2e-12; the collocation's discretisation error 9e-11); the fixed
    # point to 1e-9 (measured 1.3e-11).
    assert cycle.verified
    assert cycle.period == pytest.approx(0.8, abs=1e-9)
    for name, value in level.fixed_point.items():
        assert cycle.fixed_point[name] == pytest.approx(value, abs=1e-9), name
    assert cycle.fixed_point[CLOCK] == 0.0
    # The multipliers by the implicit function theorem on the shooting equations against the
    # collocation's AD multipliers: 1e-7 (measured 8e-9; the collocation's are accurate to
    # about 2e-7 against the transverse linearisation's re-integrated clock multipliers).
    np.testing.assert_allclose(
        np.sort_complex(cycle.multipliers), np.sort_complex(level.multipliers), rtol=0, atol=1e-7
    )
    assert not cycle.stable  # −1.34: the open loop is unstable, as the optimum says


def test_continuation_in_slope_holds_the_profile(level, cycle):
    # Every point certified (dense checks, discretisation error 1e-10, verified by simulation).
    branch = gaitopt.continuation(
        level, "slope", to=0.001, cascade=False, options=PseudoArclength(step=0.05)
    )
    assert branch.success, branch.message
    assert branch.params[-1] == pytest.approx(0.001, abs=1e-12)
    assert len(branch.cycles) >= 3
    assert all(c.success and c.verified for c in branch.cycles)
    assert all(type(c.model) is type(cycle.model) for c in branch.cycles)  # one profile
    assert branch.cycles[0].period == pytest.approx(cycle.period, abs=1e-9)
    # Downhill the same torque profile gives a longer step (0.8003 s at 0.001 rad).
    assert np.all(np.diff([c.period for c in branch.cycles]) > 0)
    # The last point is the optimum's open loop at slope 0.001: the independent simulator,
    # the base model driven by the optimum's NumPy profile as a feedforward, returns to its
    # fixed point (1e-8: the referee's simulation at rtol 1e-12, measured ~1e-10).
    last = branch.cycles[-1]
    base = level.model.replace(slope=0.001)
    x0 = base.state_vector({k: last.fixed_point[k] for k in base.state_names})
    sim = gaitopt.simulate(base, x0, steps=1, feedforward=level.feedforward, rtol=1e-12,
                           atol=1e-13)  # fmt: skip
    assert sim.success, sim.message
    assert np.max(np.abs(sim.section_states[-1] - x0)) < 1e-8
    assert sim.section_times[-1] == pytest.approx(last.period, abs=1e-8)


def test_step_to_step_control_of_the_optimum(level, cycle):
    controller = lqr(level, Q=1.0, R=1e-3)
    lin = controller.linearisation
    # The return map in state and in a per-step offset on the profile, by AD through the
    # shooting, against AD through the collocation (an independent transcription): 1e-6
    # (measured 1e-8 for A, 4e-9 for B; B = 0.021947, −0.060628, 0.0042672).
    col, w = level.transcription
    A_col, B_col = offset_jacobian(col, w, level.model.p)
    np.testing.assert_allclose(lin.A, A_col, rtol=0, atol=1e-6 * (1 + np.max(np.abs(A_col))))
    np.testing.assert_allclose(lin.B, B_col, rtol=0, atol=1e-6 * (1 + np.max(np.abs(B_col))))
    closed = np.abs(controller.closed_loop_multipliers)
    assert np.all(closed < 1) and np.max(closed) < 0.5  # 0.239 measured
    # Simulated from 1e-3 off in every section coordinate: the controlled walker converges
    # (0.239 per step: 1e-3 · 0.239⁸ ≈ 1e-8; allow a transient factor of 100), the uncontrolled
    # one walks away (|λ| = 1.34).
    s0 = controller.target + np.array([1e-3, -1e-3, 1e-3])
    start = dict(zip(cycle.model.section.coordinates, s0, strict=True))
    run = closed_loop(controller, controller.model, start, steps=8)
    assert run.survived == 8 and run.errors[-1] < 1e-6
    free = closed_loop(None, controller.model, start, steps=8, target=controller.target)
    assert free.errors[-1] > 1e-2


def test_a_failed_or_multistep_optimum_is_bad_input(level):
    failed = OptimalGait(False, "IPOPT did not converge", level.model, "effort")
    for call in (
        lambda: gaitopt.continuation(failed, "slope", to=0.01),
        lambda: lqr(failed),
        lambda: gaitopt.bifurcation_curve(failed, "PD", "slope", "mass_hip", to=12.0),
    ):
        with pytest.raises(GaitoptInputError, match="gait: the optimal gait given failed") as e:
            call()
        assert "\n" not in str(e.value)
    two = OptimalGait(True, "", level.model, "effort", profiles=level.profiles * 2,
                      fixed_point=level.fixed_point)  # fmt: skip
    with pytest.raises(GaitoptInputError, match="steps=1"):
        open_loop_cycle(two)


def test_profile_json_round_trip(level):
    profile = level.profiles[0]
    again = InputProfile.from_dict(json.loads(json.dumps(profile.as_dict())))
    assert np.array_equal(again.breaks, profile.breaks)
    assert np.array_equal(again.coefficients, profile.coefficients)
    with pytest.raises(ValueError, match="increasing breaks"):
        InputProfile.from_dict({"breaks": [0.0, 0.1], "coefficients": [[[1.0]], [[2.0]]]})


@pytest.fixture(scope="module")
def optimal_file(tmp_path_factory):
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(OPTIMIZE_ARGV) == 0
    path = tmp_path_factory.mktemp("optimal") / "optimal.json"
    path.write_text(out.getvalue())
    return path


def test_cli_control_and_continue_take_an_optimum(optimal_file, capsys):
    argv = ["control", "compass_gait", "--optimal", str(optimal_file), "--kind", "lqr",
            "--q", "1", "--r", "0.001", "--json"]  # fmt: skip
    assert main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["success"] and report["model"] == "compass_gait_feedforward"
    # The README's step-to-step gain for this optimum (gaitopt.optimize.stabilise, by AD
    # through the collocation): −196.607, −54.188, 4.374 N·m per (rad, rad/s, rad/s), to 1e-3.
    np.testing.assert_allclose(report["gain"][0], [-196.607, -54.188, 4.374], atol=1e-3)
    assert max(np.hypot(*z) for z in report["closed_loop_multipliers"]) < 1
    argv = ["continue", "compass_gait", "--optimal", str(optimal_file), "--param", "slope",
            "--to", "0.0005", "--step", "0.05", "--json"]  # fmt: skip
    assert main(argv) == 0
    branch = json.loads(capsys.readouterr().out)
    assert branch["model"] == "compass_gait_feedforward"
    assert branch["points"][-1]["param"] == pytest.approx(0.0005, abs=1e-12)


def test_cli_optimal_bad_input(optimal_file, tmp_path, capsys):
    failed = json.loads(optimal_file.read_text())
    failed["success"] = False
    bad = tmp_path / "failed.json"
    bad.write_text(json.dumps(failed))
    cases = [
        (["control", "compass_gait", "--optimal", str(bad), "--kind", "lqr"], "failed"),
        (["control", "compass_gait", "--optimal", str(optimal_file), "--kind", "lqr", "--set",
          "slope=0.01"], "--set does not apply"),
        (["continue", "slip", "--optimal", str(optimal_file), "--param", "slope", "--to",
          "0.01"], "not slip"),
        (["continue", "compass_gait", "--optimal", str(tmp_path / "none.json"), "--param",
          "slope", "--to", "0.01"], "cannot read"),
        (["continue", "compass_gait", "--optimal", str(optimal_file), "--param", "slope", "--to",
          "0.01", "--follow", "PD", "--param2", "mass_hip", "--to2", "12", "--guess",
          "stance=0.1"], "--guess does not apply"),
        (["control", "compass_gait", "--optimal", str(optimal_file), "--kind", "deadbeat",
          "--target", "stance=-0.15"], "--target does not apply"),
    ]  # fmt: skip
    for argv, words in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert words in err and "--optimal" in err and len(err.splitlines()) == 1, err


@pytest.mark.slow  # a study's fast mode (15-30 s here), as the other studies' in `make test-slow`
def test_open_loop_study_fast_mode(tmp_path):
    # problems/optimal_open_loop.py (the README's numbers come from its full run) in its fast
    # mode: the same comparisons as above, read from the JSON it writes.  Tolerances as above:
    # two transcriptions of one orbit (period, fixed point 1e-9; multipliers 1e-7; the return
    # map's Jacobians 1e-6), the continuation checked by the simulator with the NumPy profile.
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "problems" / "optimal_open_loop.py"
    spec = importlib.util.spec_from_file_location("study_optimal_open_loop", path)
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    assert study.main(["--out", str(tmp_path), "--fast"]) == 0
    folder = tmp_path / "optimal_open_loop"
    summary = json.loads((folder / "summary.json").read_text())
    shooting, control = summary["shooting"], summary["control"]
    assert shooting["success"]
    assert shooting["period_gap"] <= 1e-9 and shooting["fixed_point_gap"] <= 1e-9
    assert shooting["multiplier_gap"] <= 1e-7
    # 1e-6 relative to the largest entry of A (14.1) and of B (0.06), as above (measured 3.9e-7
    # and 2e-9 absolute).
    assert control["A_gap_to_collocation"] <= 1.5e-5 and control["B_gap_to_collocation"] <= 1e-6
    assert max(np.hypot(*z) for z in control["closed_loop_multipliers"]) < 1
    assert control["controlled_errors"][-1] < 1e-6 < control["uncontrolled_errors"][-1]
    cont = summary["continuation"]
    assert cont["success"] and cont["all_verified"] and cont["points"] >= 3
    assert cont["feedforward_return_error_at_end"] < 1e-8
    assert (folder / "branch.csv").exists() and (folder / "branch.png").exists()
