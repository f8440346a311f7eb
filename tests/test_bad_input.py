"""Every bad input of issue 9, section 3, as a regression test: a clean answer, never a traceback,
a hang, a wrong category or a self-contradicting message.

CLI cases run :func:`gaitopt.cli.main` in-process (``capsys``); exit status 0 found, 1 not found,
2 bad input with exactly one line on stderr.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import json
import tempfile

import numpy as np
import pytest
from helpers import run_cli

import gaitopt
from gaitopt import cli
from gaitopt.errors import MAX_ORBIT_STEPS, MAX_SIMULATION_STEPS


def bad_input(capsys, *argv: str) -> str:
    """Run ``argv``; it must exit 2 with one line on stderr; return that line."""
    status, _, err = run_cli(capsys, *argv)
    lines = err.splitlines()
    assert status == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith("gaitopt: error: ")
    return lines[0]


# -- tracebacks ----------------------------------------------------------------------------------
@pytest.mark.parametrize("out", ["/dev/null/x", "FILE", ""])
def test_continue_out_is_checked_before_the_computation(capsys, tmp_path, out):
    if out == "FILE":
        out = str(tmp_path / "a_file")
        (tmp_path / "a_file").write_text("keep me")
    line = bad_input(capsys, "continue", "compass_gait", "--param", "slope", "--to", "0.06",
                     "--out", out)  # fmt: skip
    assert f"--out {out}" in line
    if out.endswith("a_file"):
        assert "existing file" in line and (tmp_path / "a_file").read_text() == "keep me"
    elif out:
        assert "/dev/null is a file" in line


def test_continue_out_that_fails_after_the_computation_falls_back(capsys, tmp_path, monkeypatch):
    """The computed branch is never lost: when --out cannot be written after all (the check
    before the run is bypassed here), the files go to a fallback folder that stderr names."""
    monkeypatch.setattr(cli, "_check_out", lambda args: None)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    status, out, err = run_cli(capsys, "continue", "vanderpol", "--param", "mu", "--to", "1.1",
                           "--no-cascade", "--json", "--out", "/dev/null/x")  # fmt: skip
    assert status == 2
    assert json.loads(out)["success"] is True  # the result is printed as usual
    lines = err.splitlines()
    assert len(lines) == 1 and "--out /dev/null/x" in lines[0], err
    folder = lines[0].rsplit("written to ", 1)[1].removesuffix(" instead")
    assert folder.startswith(str(tmp_path))
    branch = json.loads((tmp_path / folder.rsplit("/", 1)[1] / "branch.json").read_text())
    assert branch["param"] == "mu"


@pytest.mark.parametrize("setting", ["kappa_xdot=10", "desired_position=100"])
def test_planar_juggler_settings_that_moved_the_default_start_off_the_paddle(capsys, setting):
    """The default start was infeasible there (the impact above the ball's energy height) and
    its StateError escaped the CLI; now the vertical bounce (x̄, 0, E_d) is found."""
    status, out, err = run_cli(capsys, "solve", "planar_juggler", "--set", setting, "--json")
    report = json.loads(out)
    assert status == 0, report["message"]
    model = gaitopt.model("planar_juggler", **{setting.split("=")[0]: float(setting.split("=")[1])})
    # Source: closed-form fixed point (x̄, 0, E_d) and multipliers of the linearised map (module
    # docstring of gaitopt.models.planar_juggler); tolerance 1e-8, the shooting accuracy.
    assert report["fixed_point"]["x_dot_pre"] == pytest.approx(0.0, abs=1e-8)
    assert report["fixed_point"]["energy_pre"] == pytest.approx(model.desired_energy, abs=1e-8)
    assert report["fixed_point"]["x"] == pytest.approx(model.desired_position, abs=1e-8)
    got = np.sort_complex([complex(*z) for z in report["multipliers"]])
    expected = np.sort_complex(model.multipliers_closed_form().astype(complex))
    np.testing.assert_allclose(got, expected, rtol=1e-8)


def test_a_library_input_error_from_anywhere_is_exit_2(capsys, monkeypatch):
    """Input errors raised deep inside the library reach the CLI's handler, not the user."""

    def deep(*args, **kwargs):
        raise gaitopt.StateError("planar_juggler: a state needs 6 finite values")

    monkeypatch.setattr(cli.solve, "find_limit_cycle", deep)
    line = bad_input(capsys, "solve", "compass_gait")
    assert "a state needs 6 finite values" in line


# -- hangs: a limit, stated, at once --------------------------------------------------------------
def test_solve_steps_above_the_limit(capsys):
    line = bad_input(capsys, "solve", "compass_gait", "--steps", "1000")
    assert "--steps" in line and "'1000'" in line and f"limit {MAX_ORBIT_STEPS}" in line


def test_continue_max_period_above_the_limit(capsys):
    line = bad_input(capsys, "continue", "compass_gait", "--param", "slope", "--to", "0.06",
                     "--max-period", "100000")  # fmt: skip
    assert "--max-period" in line and f"limit {MAX_ORBIT_STEPS}" in line


def test_simulate_steps_above_the_limit(capsys):
    line = bad_input(capsys, "simulate", "compass_gait", "--steps", "10000000")
    assert "--steps" in line and f"limit {MAX_SIMULATION_STEPS}" in line
    with pytest.raises(gaitopt.GaitoptInputError, match=f"above the limit {MAX_SIMULATION_STEPS}"):
        gaitopt.simulate(gaitopt.model("compass_gait"), steps=10_000_000)


@pytest.mark.parametrize("value", ["1e308", "-1e308", "1e200"])
def test_guess_whose_equations_of_motion_overflow(capsys, value):
    """stance_dot = 1e308 made the integrator shrink its step for ever; now: bad input."""
    line = bad_input(capsys, "solve", "compass_gait", "--guess", f"stance_dot={value}")
    assert f"--guess stance_dot={value}" in line and "overflow" in line
    with pytest.raises(gaitopt.GuessError, match="overflow"):
        gaitopt.find_limit_cycle(gaitopt.model("compass_gait"), {"stance_dot": float(value)})
    with pytest.raises(gaitopt.StateError, match="overflow"):
        gaitopt.simulate(gaitopt.model("compass_gait"), {"stance_dot": float(value)})


# -- wrong category: bad input, not a solver failure -----------------------------------------------
@pytest.mark.parametrize(
    "argv",
    [
        ["control", "slip", "--kind", "deadbeat", "--from", "z=10"],
        ["control", "slip", "--kind", "lqr", "--target", "z=5"],
        ["simulate", "slip", "--x0", "z=10"],
        ["simulate", "slip", "--controller", "deadbeat", "--target", "z=5"],
    ],
    ids=" ".join,
)
def test_slip_apex_above_the_energy_height(capsys, argv):
    line = bad_input(capsys, *argv)
    top = gaitopt.model("slip").highest_apex()  # E/(m g), closed form
    assert f"{argv[-2]} {argv[-1]}" in line
    assert "energy height" in line and f"{top:.6g}" in line


# -- nonsense: numbers that do not exist are null; messages tell the true reason ------------------
@pytest.mark.parametrize(
    ("name", "params"),
    [("compass_gait", {"mass_hip": 20}), ("vanderpol", {"mu": 5}), ("vanderpol", {"mu": 10})],
)
def test_failed_direct_search_reports_no_period(name, params):
    """Periods −9.19, −1e149, −inf were printed for failed searches: a failure has no period."""
    cycle = gaitopt.find_limit_cycle(gaitopt.model(name, **params), follow=False)
    report = json.loads(json.dumps(cycle.as_dict(), allow_nan=False))
    if not report["success"]:
        assert report["period"] is None
        assert report["multipliers"] == [] and report["stable"] is None
        assert all(d is None or d > 0 for d in report["durations"])


def test_as_dict_period_only_for_a_gait_with_positive_finite_durations():
    model = gaitopt.model("compass_gait")
    for durations in ([-9.19], [0.3, -1e149], [float("-inf")], [float("nan")], [], [4.65e-8]):
        failed = gaitopt.LimitCycle(False, "x", model, period=float(np.sum(durations or [0])),
                                    durations=np.array(durations))  # fmt: skip
        report = failed.as_dict()
        assert report["period"] is None  # a rejected candidate orbit has no period
        json.dumps(report, allow_nan=False)  # strict JSON
    found = gaitopt.LimitCycle(True, "x", model, period=0.7, durations=np.array([0.7]))
    assert found.as_dict()["period"] == 0.7


def test_no_orbit_message_never_quotes_a_residual_within_tolerance():
    """ "no periodic orbit found" next to "residual 2.25e-12 (tolerance 1e-10)": a point within
    the tolerance is accepted; an orbit that solves the equations but is not isolated says so."""
    model = gaitopt.model("raibert_hopper")
    object.__setattr__(model, "k_attitude", 0.0)  # bypass check(): the pitch becomes neutral
    cycle = gaitopt.find_limit_cycle(model, follow=False)
    assert not cycle.success
    assert cycle.residual <= 1e-10
    assert "no periodic orbit found" not in cycle.message
    assert "singular" in cycle.message and "family" in cycle.message


def test_raibert_hopper_without_attitude_stiffness_is_bad_input(capsys):
    """k_attitude = 0: every body pitch is a gait (a family, multiplier 1): no isolated gait."""
    line = bad_input(capsys, "solve", "raibert_hopper", "--set", "k_attitude=0")
    assert "--set k_attitude=0" in line and "restoring torque" in line
    with pytest.raises(gaitopt.ParameterError, match="k_attitude"):
        gaitopt.model("raibert_hopper", k_attitude=0)


def test_vertical_hopper_tiny_gain_is_never_a_success_above_its_own_tolerance():
    """gain 4e-6: multiplier 1 − K = 0.999996 (closed form, module docstring) amplifies every
    error; the discretisation error stayed at 7e-8 > tol 1e-10 and yet success was claimed."""
    tol = 1e-10
    cycle = gaitopt.find_limit_cycle(gaitopt.model("vertical_hopper", gain=4e-6), follow=False)
    assert not (cycle.success and not cycle.discretisation_error <= tol)
    if not cycle.success:
        assert "discretisation error" in cycle.message and "above the tolerance" in cycle.message


@pytest.mark.parametrize(("spokes", "effect"), [(3, "backwards"), (4, "stops the wheel")])
def test_rimless_wheel_with_few_spokes_quotes_no_negative_rolling_speed(spokes, effect):
    """spokes = 3 quoted ω* = −0.95 rad/s: with α = π/spokes ≥ π/4, cot 2α ≤ 0 (Tedrake's closed
    form) and an impact keeps cos 2α ≤ 0 of the rate: no forward rolling at any slope."""
    note = gaitopt.model("rimless_wheel", spokes=spokes).existence_note()
    assert "no forward rolling fixed point" in note and effect in note
    assert "ω* = -" not in note and "ω* = −" not in note


def test_compass_gait_on_level_ground_is_not_a_standing_gait():
    """slope 0: the direct search converged to standing still and reported a timing mismatch."""
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait", slope=0.0), follow=False)
    assert not cycle.success
    assert "standing still" in cycle.message and "timing" not in cycle.message
    assert cycle.as_dict()["period"] is None


# -- Python API ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", [42, None, 1.5, ["compass_gait"]])
def test_model_name_that_is_not_a_string(name):
    with pytest.raises(gaitopt.UnknownModelError, match="must be a model name"):
        gaitopt.model(name)


def test_find_limit_cycle_and_simulate_accept_a_model_name():
    # Source: Drake's CompassGait / Goswami et al. 1996 default gait, period 0.7344606213 s
    # (README); tolerance 1e-9 s.
    gait = gaitopt.find_limit_cycle("compass_gait")
    assert gait.success and gait.period == pytest.approx(0.7344606213, abs=1e-9)
    sim = gaitopt.simulate("compass_gait", gait.x, steps=1)
    # The simulation from the fixed point returns to it (independent integrator; tol 1e-7).
    np.testing.assert_allclose(sim.section_states[-1], gait.x, atol=1e-7)
    with pytest.raises(gaitopt.UnknownModelError, match="`model` must be a model"):
        gaitopt.find_limit_cycle(42)
    with pytest.raises(gaitopt.UnknownModelError, match="'walkr'"):
        gaitopt.simulate("walkr")


@pytest.mark.parametrize("tol", [-1, 0, float("nan"), float("inf"), "1e-10", True])
def test_tolerance_must_be_positive_and_finite(tol):
    with pytest.raises(gaitopt.GaitoptInputError, match="`tol`"):
        gaitopt.find_limit_cycle(gaitopt.model("compass_gait"), tol=tol)


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        ({"rtol": -1}, "`rtol`"),
        ({"atol": 0}, "`atol`"),
        ({"max_phase_time": float("inf")}, "`max_phase_time`"),
        ({"steps": 2.5}, "`steps` must be an integer"),
        ({"steps": -1}, "`steps` must be at least 0"),
        ({"phase": 5}, "`phase`"),
    ],
)
def test_simulate_options(kwargs, pattern):
    with pytest.raises(gaitopt.GaitoptInputError, match=pattern):
        gaitopt.simulate(gaitopt.model("compass_gait"), **kwargs)


def test_assigning_a_parameter_says_how_to_change_it():
    walker = gaitopt.model("compass_gait")
    with pytest.raises(dataclasses.FrozenInstanceError) as info:
        walker.slope = 0.1  # type: ignore[misc]
    assert isinstance(info.value, gaitopt.FrozenModelError)
    assert "walker" not in str(info.value)  # it names the call, not our variable
    assert "replace(slope=0.1)" in str(info.value)
    assert "gaitopt.model('compass_gait', slope=0.1)" in str(info.value)
    assert walker.slope == 0.0525 and walker.replace(slope=0.1).slope == 0.1


def test_version(capsys):
    status, out, _ = run_cli(capsys, "--version")
    assert status == 0
    assert out.strip() == f"gaitopt {gaitopt.__version__}"
    assert gaitopt.__version__ == importlib.metadata.version("gaitopt")


# -- make gaits: tracked results do not change from run to run -----------------------------------
def test_make_gaits_cycle_json_holds_no_run_to_run_timing(tmp_path, capsys):
    """cycle.json stored solve_time, so every `make gaits` rewrote the tracked files."""
    from gaitopt import gaits

    assert gaits.main(["--out", str(tmp_path), "--models", "vanderpol"]) == 0
    capsys.readouterr()
    written = json.loads((tmp_path / "vanderpol" / "cycle.json").read_text())
    assert "solve_time" not in written and written["success"] is True
    # Everything else is deterministic: a second solve gives the same object (stored, as
    # make gaits stores it, to its certified digits).
    again = gaitopt.find_limit_cycle(gaitopt.model("vanderpol")).as_dict(timing=False)
    stored = gaits.certified_record(again)
    assert json.loads(json.dumps(gaitopt.files.jsonable(stored))) == written


# -- found by the CLI fuzz test (tests/test_cli_fuzz.py) -----------------------------------------
@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        # argparse stored [] for `--opt=--` (TypeError, AttributeError in the subcommand)
        (["simulate", "vanderpol", "--terrain=--"], "--terrain --: expected SEED:AMPLITUDE"),
        (["simulate", "vanderpol", "--controller=--"], "invalid choice: '--'"),
        (["solve", "vanderpol", "--set=--"], "--set --: expected NAME=VALUE"),
        # Dask's ValueError for an address without a port
        (["solve", "vanderpol", "--starts", "2", "--scheduler", ""], "argument --scheduler"),
        (["solve", "vanderpol", "--starts", "2", "--scheduler", "nowhere"], "'nowhere'"),
        # NumPy's ValueError for a negative seed of the multi-start sample
        (["solve", "vanderpol", "--starts", "2", "--seed", "-1"], "argument --seed"),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, list) else "",
)
def test_fuzz_findings(capsys, argv, expected):
    assert expected in bad_input(capsys, *argv)


def test_linkage_samples_above_the_limit(capsys):
    """`linkage jansen --samples 10000000` ran silently for ~25 minutes (issue 25): the count
    has a stated limit, checked before any work, in the CLI and in the Python API."""
    from gaitopt.linkage import JansenLinkage
    from gaitopt.linkage.jansen import MAX_SAMPLES

    line = bad_input(capsys, "linkage", "jansen", "--samples", "10000000")
    assert "--samples" in line and f"limit {MAX_SAMPLES}" in line
    with pytest.raises(gaitopt.GaitoptInputError, match=f"above the limit {MAX_SAMPLES}"):
        JansenLinkage().numbers(10_000_000)
