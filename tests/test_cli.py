"""The ``gaitopt`` command line (docs/design.md, "Public contract").

Most cases call :func:`gaitopt.cli.main` in-process (fast); one runs the installed console script.
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import run_cli

from gaitopt.cli import SUBCOMMANDS, main
from gaitopt.models import REGISTRY

# Keys of `solve --json` promised by docs/design.md (public contract); the library may add more.
SOLVE_KEYS = {
    "model", "params", "success", "message", "period", "steps", "state_names", "fixed_point",
    "multipliers", "stable", "residual", "verified",
}  # fmt: skip


def run_json(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, object]:
    """Exit status and the single JSON document printed on stdout."""
    status, out, _ = run_cli(capsys, *argv)
    return status, json.loads(out)  # json.loads fails if stdout holds anything else


# -- list ---------------------------------------------------------------------------------------
def test_list_json_describes_every_model(capsys):
    status, models = run_json(capsys, "list", "--json")
    assert status == 0
    assert [m["name"] for m in models] == list(REGISTRY)
    for entry in models:
        assert set(entry) >= {
            "name", "title", "reference", "params", "state_names", "section_coordinates",
            "section", "inputs",
        }  # fmt: skip
        cls = REGISTRY[entry["name"]]
        assert entry["title"] == cls.title and entry["reference"] == cls.reference
        assert [p["name"] for p in entry["params"]] == [s.name for s in cls.parameter_specs()]
        for p in entry["params"]:
            assert set(p) >= {"name", "unit", "default", "doc", "source", "range"}
        assert set(entry["section_coordinates"]) <= set(entry["state_names"])
        assert entry["inputs"] == list(cls.inputs)
    compass = next(m for m in models if m["name"] == "compass_gait")
    # State order and section from docs/design.md's model table.
    assert compass["state_names"] == ["stance", "swing", "stance_dot", "swing_dot"]
    assert compass["inputs"] == ["hip_torque"]


def test_list_text_names_every_model(capsys):
    status, out, err = run_cli(capsys, "list")
    assert status == 0 and err == ""
    for name in REGISTRY:
        assert name in out


def test_subcommands_are_a_table():
    assert {"list", "solve", "simulate", "control"} <= set(SUBCOMMANDS)


# -- solve --------------------------------------------------------------------------------------
def test_solve_compass_gait_json_matches_drake(capsys):
    status, result = run_json(capsys, "solve", "compass_gait", "--json")
    assert status == 0
    assert set(result) >= SOLVE_KEYS
    assert result["model"] == "compass_gait"
    assert result["success"] is True and result["verified"] is True and result["stable"] is True
    assert result["steps"] == 1
    assert result["params"]["slope"] == 0.0525  # docs/design.md default
    assert result["state_names"] == ["stance", "swing", "stance_dot", "swing_dot"]
    # Source: docs/design.md reference numbers — Drake's CompassGait simulated to convergence at the
    # defaults: step period 0.7344606 s, post-impact state [−0.2187746, 0.3237746, 1.0928668,
    # 0.3761346]. Tolerance 1e-6 (the reference is given to 7 decimals).
    assert math.isclose(result["period"], 0.7344606, abs_tol=1e-6)
    expected = [-0.2187746, 0.3237746, 1.0928668, 0.3761346]
    for name, value in zip(result["state_names"], expected, strict=True):
        assert math.isclose(result["fixed_point"][name], value, abs_tol=1e-6), name
    multipliers = result["multipliers"]
    assert multipliers and all(len(z) == 2 for z in multipliers)  # [re, im] pairs
    # `stable` means every multiplier has modulus < 1 (docs/design.md, "Stability").
    assert max(math.hypot(re, im) for re, im in multipliers) < 1
    # The residual is the max-norm of the shooting equations; the library's default tol is 1e-10.
    assert result["residual"] <= 1e-10


def test_solve_text_summary(capsys):
    status, out, err = run_cli(capsys, "solve", "compass_gait", "--set", "slope=0.0525")
    assert status == 0 and err == ""
    for label in ("model", "params", "success", "period", "fixed point", "multipliers", "stable"):
        assert label in out
    assert "|λ|" in out and "verified" in out


def test_solve_simplest_walker_unstable_short_step_gait(capsys):
    # Source: Garcia, Chatterjee, Ruina & Coleman 1998 (docs/design.md), slope 0.009: the unstable
    # short-step gait θ* = 0.19393736960624, θ̇* = −0.20386692731962. Tolerance 1e-8: Newton
    # converges to residual < 1e-10 and the published values have 14 digits.
    status, result = run_json(
        capsys, "solve", "simplest_walker",
        "--guess", "theta=0.19393736960624", "--guess", "theta_dot=-0.20386692731962", "--json",
    )  # fmt: skip
    assert status == 0
    assert result["success"] is True and result["stable"] is False
    assert math.isclose(result["fixed_point"]["theta"], 0.19393736960624, abs_tol=1e-8)
    assert math.isclose(result["fixed_point"]["theta_dot"], -0.20386692731962, abs_tol=1e-8)
    # Unstable: some multiplier lies outside the unit circle (docs/design.md, "Stability").
    assert max(math.hypot(re, im) for re, im in result["multipliers"]) > 1


def test_solve_without_a_gait_exits_1_with_json(capsys):
    # Source: docs/design.md "Reference numbers" — the rimless wheel rolls only where ω* > ω₁; at
    # slope 0.03 (8 spokes) it has no rolling gait, so no gait may be reported.
    status, result = run_json(capsys, "solve", "rimless_wheel", "--set", "slope=0.03", "--json")
    assert status == 1
    assert result["success"] is False
    assert set(result) >= SOLVE_KEYS
    assert result["message"]


def test_solve_ipopt_json_stdout_is_only_json(capfd):
    # IPOPT prints a banner on the C-level stdout; `--json` must still print one JSON object.
    status = main(["solve", "compass_gait", "--method", "ipopt", "--json"])
    out, _ = capfd.readouterr()
    assert status == 0
    result = json.loads(out)
    # Source: docs/design.md (Drake's CompassGait), as above; tolerance 1e-6.
    assert math.isclose(result["period"], 0.7344606, abs_tol=1e-6)


# -- simulate -----------------------------------------------------------------------------------
def test_simulate_compass_gait_json(capsys):
    status, report = run_json(capsys, "simulate", "compass_gait", "--steps", "3", "--json")
    assert status == 0
    assert set(report) >= {
        "model", "params", "success", "status", "message", "steps", "section_coordinates",
        "returns", "events",
    }  # fmt: skip
    assert report["model"] == "compass_gait"
    assert report["success"] is True and report["status"] == "completed"
    assert report["steps"] == 3
    returns, events = report["returns"], report["events"]
    assert len(returns) == 4  # the start and three returns
    assert returns[0]["t"] == 0.0
    for entry in returns:
        assert list(entry["state"]) == ["stance", "swing", "stance_dot", "swing_dot"]
    assert [e["transition"] for e in events] == ["heel strike"] * 3
    # Each return to the section is a heel strike; same floats, so exact equality.
    assert [e["t"] for e in events] == [r["t"] for r in returns[1:]]
    # On the section swing = 2·slope − stance (docs/design.md, compass-gait guard); tolerance 1e-12,
    # the reset is exact up to rounding.
    for entry in returns:
        state = entry["state"]
        assert math.isclose(state["swing"], 2 * 0.0525 - state["stance"], abs_tol=1e-12)


def test_simulate_from_section_coordinates_text(capsys):
    status, out, err = run_cli(
        capsys, "simulate", "compass_gait", "--x0", "stance=-0.21", "--steps", "1"
    )
    assert status == 0 and err == ""
    assert "completed" in out and "-0.21000000" in out


def test_simulate_that_falls_exits_1(capsys):
    # A slow start (stance_dot 0.1 rad/s) does not carry the hip over the stance foot: it falls.
    status, report = run_json(
        capsys, "simulate", "compass_gait", "--x0", "stance_dot=0.1", "--steps", "3", "--json"
    )
    assert status == 1
    assert report["success"] is False and report["status"] != "completed"
    assert report["steps"] < 3


# -- bad input: exit 2, one line on stderr naming the argument and its value --------------------
BAD_INPUT = [
    # (argv, text the single stderr line must contain)
    (["solve", "walkr"], ["'walkr'", "'simplest_walker'", "'kneed_walker'"]),
    (["solve", "compass_gait", "--set", "slop=0.1"], ["--set slop=0.1", "'slope'"]),
    (["solve", "compass_gait", "--set", "slope=abc"], ["--set slope=abc", "not a number"]),
    (["solve", "compass_gait", "--set", "slope=-1"], ["--set slope=-1", "out of range"]),
    (["solve", "compass_gait", "--set", "slope"], ["--set slope", "NAME=VALUE"]),
    (["solve", "compass_gait", "--guess", "swing=0.3"], ["--guess swing=0.3", "section"]),
    (["solve", "compass_gait", "--guess", "stance=abc"], ["--guess stance=abc", "not a number"]),
    (["simulate", "compass_gait", "--x0", "stnce=0.1"], ["--x0 stnce=0.1", "'stance'"]),
    (["simulate", "compass_gait", "--x0", "swing=0.1"], ["--x0 swing=0.1", "missing"]),
    (["solve", "rimless_wheel", "--set", "spokes=2"], ["--set spokes=2", "out of range"]),
    (["solve", "compass_gait", "--steps", "0"], ["--steps", "'0'"]),
    (["solve", "compass_gait", "--method", "newtn"], ["--method", "'newtn'"]),
    (["frobnicate"], ["'frobnicate'"]),
    (["continue", "compass_gait", "--param", "slop", "--to", "0.06"], ["--param slop", "'slope'"]),
    (["continue", "compass_gait", "--param", "slope", "--to", "9"], ["--to 9", "out of range"]),
    (["continue", "compass_gait", "--param", "slope", "--to", "x"], ["--to x", "not a number"]),
    (["continue", "compass_gait", "--param", "slope"], ["--to"]),
]


@pytest.mark.parametrize(("argv", "expected"), BAD_INPUT, ids=lambda v: " ".join(v))
def test_bad_input_is_one_line_and_exit_2(capsys, argv, expected):
    status, out, err = run_cli(capsys, *argv)
    assert status == 2
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("gaitopt: error: ")
    for text in expected:
        assert text in lines[0]


def test_guess_that_leads_nowhere_is_bad_input(capsys):
    # From stance = 3 rad the compass gait never strikes its heel: the library's GuessError.
    status, out, err = run_cli(capsys, "solve", "compass_gait", "--guess", "stance=3", "--json")
    assert status == 2 and out == ""
    assert len(err.splitlines()) == 1
    assert err.startswith("gaitopt: error: --guess stance=3: ") and "leads nowhere" in err


def test_console_script_bad_input(tmp_path):
    # The script next to this interpreter (the project's .venv), else the one on PATH.
    beside = Path(sys.executable).parent / "gaitopt"
    script = str(beside) if beside.exists() else shutil.which("gaitopt")
    assert script, "the `gaitopt` console script is not installed"
    proc = subprocess.run(
        [script, "solve", "compass_gait", "--set", "slope=abc"],
        capture_output=True, text=True, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.splitlines()) == 1, proc.stderr
    assert proc.stderr.startswith("gaitopt: error: --set slope=abc: ")


# -- running and control (issue 3) --------------------------------------------------------------
@pytest.mark.parametrize(("z", "stable"), [(0.87, True), (0.92, False)])
def test_solve_slip_textbook_fixed_points(capsys, z, stable):
    # Source: docs/design.md (Tedrake's SLIP apex map): a stable fixed point near
    # z = 0.87 m and an unstable one near 0.92 m; "near": within 1 cm.
    status, result = run_json(capsys, "solve", "slip", "--guess", f"z={z}", "--json")
    assert status == 0 and result["success"] is True
    assert abs(result["fixed_point"]["z"] - z) < 0.01
    assert result["stable"] is stable and len(result["multipliers"]) == 1


def test_control_slip_deadbeat_from_a_state(capsys):
    status, report = run_json(capsys, "control", "slip", "--kind", "deadbeat", "--from", "z=0.9",
                              "--json")  # fmt: skip
    assert status == 0
    assert set(report) >= {"fixed_point", "gain", "closed_loop_multipliers", "input", "next"}
    assert list(report["input"]) == ["touchdown_angle"]
    # One deadbeat step lands on the target apex: 1e-9 (shooting accuracy 1e-10, rtol 1e-11).
    assert abs(report["next"]["z"] - report["fixed_point"]["z"]) < 1e-9
    assert max(math.hypot(*z) for z in report["closed_loop_multipliers"]) < 1e-12


def test_control_compass_gait_lqr_closed_loop_multipliers(capsys):
    status, report = run_json(capsys, "control", "compass_gait", "--kind", "lqr", "--q", "1,1,1",
                              "--r", "0.1", "--set", "slope=0.09", "--json")  # fmt: skip
    assert status == 0
    A, B, K = (np.array(report[k]) for k in ("A", "B", "gain"))
    expected = np.sort(np.abs(np.linalg.eigvals(A - B @ K)))
    got = np.sort([math.hypot(*z) for z in report["closed_loop_multipliers"]])
    np.testing.assert_allclose(got, expected, atol=1e-12)
    assert got.max() < 1 < max(math.hypot(*z) for z in report["open_loop_multipliers"])


def test_control_from_outside_the_deadbeat_range_exits_1(capsys):
    status, out, err = run_cli(capsys, "control", "slip", "--kind", "deadbeat", "--from", "z=0.8")
    assert status == 1 and err == ""
    assert "deadbeat infeasible" in out and "deadbeat works for" in out


def test_simulate_with_controller_on_rough_terrain(capsys):
    status, report = run_json(capsys, "simulate", "slip", "--controller", "deadbeat", "--target",
                              "z=1.0", "--x0", "z=1.0", "--terrain", "4:0.02", "--steps", "3",
                              "--json")  # fmt: skip
    assert status == 0 and report["steps"] == 3
    assert report["controller"]["kind"] == "deadbeat"
    assert len(report["inputs"]) == 3 and len(report["terrain"]) == 3
    assert all(abs(t["ground_height"]) <= 0.02 for t in report["terrain"])


BAD_CONTROL_INPUT = [
    (["control", "compass_gait", "--kind", "deadbeat"], ["--kind deadbeat", "as many inputs"]),
    (["control", "vanderpol", "--kind", "lqr"], ["--kind lqr", "no per-step input"]),
    (["control", "slip", "--kind", "lqr", "--q", "abc"], ["--q abc", "not a number"]),
    (["control", "slip", "--kind", "acker", "--q", "1"], ["--q", "--kind lqr"]),
    (["control", "slip", "--kind", "lqr", "--from", "x_dot=1"], ["--from x_dot=1", "'z'"]),
    (["control", "slip", "--kind", "pid"], ["--kind", "'pid'"]),
    (["simulate", "slip", "--terrain", "1"], ["--terrain 1", "SEED:AMPLITUDE"]),
    (["simulate", "vanderpol", "--terrain", "1:0.1"], ["--terrain 1:0.1", "no ground parameter"]),
    (["simulate", "compass_gait", "--controller", "blind"], ["--controller blind", "slip only"]),
]


@pytest.mark.parametrize(("argv", "expected"), BAD_CONTROL_INPUT, ids=lambda v: " ".join(v))
def test_bad_control_input_is_one_line_and_exit_2(capsys, argv, expected):
    test_bad_input_is_one_line_and_exit_2(capsys, argv, expected)


# -- continue ------------------------------------------------------------------------------------
def test_continue_json_contract_and_period_doubling(capsys, tmp_path):
    # docs/design.md's contract: `continue --json` prints model, param, points (param, period,
    # fixed_point, multipliers, stable) and special_points (kind, param).  The compass gait's
    # first period doubling lies at slope 0.0766356 (located by continuation to 1e-10 and checked
    # against a bisection on the multiplier in tests/test_continuation.py): tolerance 1e-7.
    status, data = run_json(
        capsys,
        "continue",
        "compass_gait",
        "--param",
        "slope",
        "--to",
        "0.08",
        "--max-period",
        "2",
        "--json",
        "--out",
        str(tmp_path),
    )
    assert status == 0
    assert {"model", "param", "points", "special_points"} <= set(data)
    assert data["model"] == "compass_gait" and data["param"] == "slope"
    for point in data["points"]:
        assert {"param", "period", "fixed_point", "multipliers", "stable"} <= set(point)
        assert all(len(z) == 2 for z in point["multipliers"])
    kinds = [sp["kind"] for sp in data["special_points"]]
    assert kinds == ["PD"]
    assert data["special_points"][0]["param"] == pytest.approx(0.0766356, abs=1e-7)
    assert data["branches"][0]["steps"] == 2  # the period-2 branch after switching
    for name in ("branch.json", "branch.csv", "branch.png"):
        assert (tmp_path / name).stat().st_size > 0
    assert json.loads((tmp_path / "branch.json").read_text())["param"] == "slope"


def test_continue_reports_a_boundary(capsys):
    # The rimless wheel's rolling gait stops existing at slope 0.06822945 (closed form ω* = ω₁,
    # Tedrake): a `boundary` special point (its precision is tested in test_continuation.py).
    status, data = run_json(
        capsys, "continue", "rimless_wheel", "--param", "slope", "--to", "0.05", "--json"
    )
    assert status == 0
    assert [sp["kind"] for sp in data["special_points"]] == ["boundary"]
    assert data["special_points"][0]["param"] == pytest.approx(0.06822945, abs=1e-7)
