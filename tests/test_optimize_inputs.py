"""Bad input to ``optimize_gait`` and ``gaitopt optimize`` is one clear error before any work
(issues 24 and 25): a failed result as a warm start, counts beyond their stated limits, ``tol``,
and level ground with nothing fixed (whose least effort is standing still); and the advice the
messages give names options that exist where they are shown.

Every check here is input validation, so each case must fail fast: the time limits (2 s per
call) are an order below the cheapest solve they guard against (the level-ground compass gait
took about a minute to reach its 4 mm step; ``--steps 1000`` grew past 5 GB).
"""

from __future__ import annotations

import json
import re
import time

import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.errors import GaitoptInputError, GuessError
from gaitopt.optimize import RadauMesh, WarmStartError, optimize_gait
from gaitopt.optimize.problem import MAX_STEPS, GaitProblem
from gaitopt.optimize.solve import MAX_MESH_DEGREE, MAX_MESH_INTERVALS, MAX_SEED, MAX_STARTS

LEVEL = dict(period=0.8, step_length=0.3)  # the README's level-ground compass statement
CLI_LEVEL = ["optimize", "compass_gait", "--set", "slope=0", "--fix", "period=0.8",
             "--fix", "step_length=0.3"]  # fmt: skip


def _fast(call):
    """Run ``call``, which must raise a GaitoptInputError within 2 s; return the error."""
    t0 = time.perf_counter()
    with pytest.raises(GaitoptInputError) as info:
        call()
    assert time.perf_counter() - t0 < 2.0
    return info.value


def _cli_error(argv, capsys) -> str:
    """``gaitopt ARGV`` must exit 2 within 2 s with one line on stderr and nothing on stdout."""
    t0 = time.perf_counter()
    status = main(argv)
    assert time.perf_counter() - t0 < 2.0
    captured = capsys.readouterr()
    assert status == 2 and captured.out == ""
    assert captured.err.startswith("gaitopt: error: ") and captured.err.count("\n") == 1
    assert "Traceback" not in captured.err
    return captured.err


# -- task 2: a failed result as a warm start ------------------------------------------------------
@pytest.fixture(scope="module")
def failed():
    # Legs of 1 m: feet at most 2 m apart, so 2.5 m is refused before any solve: no orbit.
    gait = optimize_gait(gaitopt.model("compass_gait", slope=0.0), period=0.8, step_length=2.5,
                         verify=False)  # fmt: skip
    assert not gait.success and gait.orbit == []
    return gait


def test_failed_result_as_guess_is_an_input_error(failed):
    model = gaitopt.model("compass_gait", slope=0.0)
    error = _fast(lambda: optimize_gait(model, guess=failed, **LEVEL))
    # It was an IndexError (gait.orbit[0] of an empty orbit); now a GuessError that names the
    # argument, says what was wrong (a failed result, no orbit, and why it failed) and the fix.
    assert isinstance(error, WarmStartError) and isinstance(error, GuessError)
    assert isinstance(error, ValueError)
    text = str(error)
    assert text.startswith("`guess` is a failed OptimalGait (success=False: no gait: a step")
    assert "no orbit" in text and "guess=None" in text and "success=True" in text


def test_other_warm_starts_that_cannot_start(failed):
    model = gaitopt.model("compass_gait", slope=0.0)
    assert "must be an OptimalGait" in str(
        _fast(lambda: optimize_gait(model, guess={"stance": 0.2}, **LEVEL))
    )
    # A result of another model or number of steps: its orbit does not fit the transcription.
    other = gaitopt.optimize.OptimalGait(True, "", gaitopt.model("kneed_walker"), "effort",
                                         orbit=[object()])  # fmt: skip
    assert "not of 'compass_gait'" in str(_fast(lambda: optimize_gait(model, guess=other, **LEVEL)))


def test_certified_result_still_warm_starts():
    # The check refuses only what cannot start: a certified optimum warm starts its neighbour
    # (the README's 0.3 m point, 6.668848535 N²·m²·s, from the 0.25 m one; same 1e-8 as the
    # library's cold-start comparison).
    model = gaitopt.model("compass_gait", slope=0.0)
    near = optimize_gait(model, period=0.8, step_length=0.25, verify=False)
    assert near.success, near.message
    gait = optimize_gait(model, guess=near, verify=False, **LEVEL)
    assert gait.success and gait.cost == pytest.approx(6.668848535, rel=1e-8)


# -- task 3: every count has a limit, checked before any work -------------------------------------
@pytest.mark.parametrize(
    ("options", "pattern"),
    [
        ({"seed": -1}, r"`seed` must be at least 0, got -1; e\.g\. seed=0"),
        ({"seed": 1.5}, r"`seed` must be an integer, got 1\.5"),
        ({"seed": MAX_SEED + 1}, rf"`seed` = {MAX_SEED + 1} is above the limit {MAX_SEED}"),
        ({"steps": 1000}, rf"`steps` = 1000 is above the limit {MAX_STEPS}: .*steps <= 4"),
        ({"steps": 0}, r"`steps` must be at least 1"),
        ({"starts": 100000}, rf"`starts` = 100000 is above the limit {MAX_STARTS}"),
        ({"starts": list(range(MAX_STARTS + 1))}, rf"lists {MAX_STARTS + 1} start indices"),
        ({"starts": [0, -3]}, r"distinct start indices from 0"),
        ({"starts": [0, 0]}, r"distinct start indices from 0"),
        ({"starts": 0}, r"`starts` must be at least 1"),
        ({"tol": 0.0}, r"`tol` must be positive and finite, got 0\.0"),
        ({"tol": -1e-8}, r"`tol` must be positive"),
        ({"tol": float("nan")}, r"`tol` must be positive and finite, got nan"),
        ({"tol": "1e-8"}, r"`tol` must be a positive number, got '1e-8'"),
        ({"tol": float("inf")}, r"`tol` must be positive and finite, got inf"),
        ({"mesh": RadauMesh(MAX_MESH_INTERVALS + 1, 6)}, r"`mesh\.intervals` = 25 is above"),
        ({"mesh": RadauMesh(6, MAX_MESH_DEGREE + 1)}, r"`mesh\.degree` = 11 is above"),
        ({"mesh": (6, 6)}, r"`mesh` must be a RadauMesh"),
        ({"verify": "no"}, r"`verify` must be True or False"),
    ],
)
def test_python_limits(options, pattern):
    model = gaitopt.model("compass_gait", slope=0.0)
    error = _fast(lambda: optimize_gait(model, **{**LEVEL, **options}))
    assert re.search(pattern, str(error)), str(error)


def test_problem_steps_limit():
    model = gaitopt.model("compass_gait", slope=0.0)
    with pytest.raises(GaitoptInputError, match=rf"above the limit {MAX_STEPS}"):
        GaitProblem(model, steps=MAX_STEPS + 1, **LEVEL)
    assert GaitProblem(model, steps=MAX_STEPS, **LEVEL).steps == MAX_STEPS  # the limit holds


@pytest.mark.parametrize(
    ("extra", "pattern"),
    [
        (["--seed", "-1"], r"argument --seed: expected an integer >= 0, got '-1'"),
        (["--steps", "1000"], r"argument --steps: '1000' is above the limit 4: .*--steps 4 or "),
        (["--starts", "100000"], r"argument --starts: '100000' is above the limit 256: "
                                 r".*--starts 256 or fewer"),
        (["--tol", "0"], r"argument --tol: expected a positive relative error, got '0'; "
                         r"e\.g\. --tol 1e-6"),
        (["--tol", "nan"], r"argument --tol: .* got 'nan'"),
        (["--tol=-1e-8"], r"argument --tol: .* got '-1e-8'"),
        (["--tol", "abc"], r"argument --tol: .* got 'abc'"),
        (["--cold", "1000"], r"argument --cold: '1000' is above the limit 200"),
        (["--orbits", "5000"], r"argument --orbits: '5000' is above the limit 1000"),
    ],
)  # fmt: skip
def test_cli_limits(extra, pattern, capsys):
    err = _cli_error([*CLI_LEVEL, *extra], capsys)
    assert re.search(pattern, err), err


def test_cli_tol_reaches_the_solve(capsys):
    # --tol is passed on.  The README's level 0.3 m optimum settles to 1e-10 in one refinement
    # (measured 9.6e-11, 6 → 12 intervals), so --tol 1e-6 certifies it; 1e-14 cannot be met
    # (IPOPT solves to 1e-11): refined three times, not certified (exit 1), and the advice names
    # the CLI's --tol, not Python's `tol`.
    status = main([*CLI_LEVEL, "--tol", "1e-6", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert status == 0 and report["success"], report["message"]
    assert report["cost"] == pytest.approx(6.668848535, rel=1e-8)  # README, 10 digits
    assert report["discretisation_error"] <= 1e-6
    status = main([*CLI_LEVEL, "--tol", "1e-14", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert status == 1 and not report["success"]
    assert "above the target 1e-14 after 3 refinements" in report["message"]
    assert "Loosen --tol" in report["message"] and "`" not in report["message"]


# -- task 4: level ground with nothing fixed ------------------------------------------------------
@pytest.mark.parametrize("name", ["compass_gait", "simplest_walker", "kneed_walker",
                                  "five_link_biped"])  # fmt: skip
def test_level_ground_with_nothing_fixed_is_refused_at_once(name):
    model = gaitopt.model(name, slope=0.0)
    error = _fast(lambda: optimize_gait(model))
    text = str(error)
    assert text.startswith(f"{name} on level ground (slope=0) with no `period`")
    assert "standing still" in text and "step_length=0.3 and period=0.8" in text


def test_level_ground_refusal_is_only_where_it_holds():
    # Anything that poses the problem is accepted: a fixed period, step length or speed, a free
    # slope, a slope, the cost of transport (per distance: not shown to vanish).
    compass = gaitopt.model("compass_gait", slope=0.0)
    for fixed in ({"period": 0.8}, {"step_length": 0.3}, {"speed": 0.375}):
        assert GaitProblem(compass, **fixed).cost == "effort"
    assert GaitProblem(compass, free=("slope",)).free == ("slope",)
    assert GaitProblem(gaitopt.model("compass_gait", slope=0.01)).period is None
    bounded = {"hip_torque": 20}
    assert GaitProblem(compass, cost="cot", bounds=bounded).cost == "cot"
    with pytest.raises(GaitoptInputError, match="least positive work is 0"):
        GaitProblem(compass, cost="work", bounds=bounded)


def test_level_ground_from_the_cli(capsys):
    # The command: it took about a minute and said "Loosen `tol`" (no such option);
    # now one line, exit 2, advice in the CLI's options.
    err = _cli_error(["optimize", "compass_gait", "--set", "slope=0"], capsys)
    assert "standing still" in err
    assert "--fix step_length=0.3 and --fix period=0.8" in err
    assert "--set slope=0.0525" in err  # the model's default slope, where it walks passively
    assert "`" not in err


# -- advice names options that exist where it is shown ---------------------------------------------
def test_python_advice_in_cli_options(capsys):
    from gaitopt.cli.optimize import for_the_cli

    assert for_the_cli("Loosen `tol` to accept it") == "Loosen --tol to accept it"
    assert for_the_cli("e.g. bounds={'hip_torque': 20}") == "e.g. --bound hip_torque=20"
    assert for_the_cli("bounds={'hip_torque': (0, 20)}") == "--bound hip_torque=0:20"
    assert for_the_cli("use cost='effort'") == "use --cost effort"
    assert for_the_cli("e.g. step_length=0.3 and period=0.8") == (
        "e.g. --fix step_length=0.3 and --fix period=0.8"
    )
    # Through the CLI: positive work without a bound names --bound, not Python's `bounds`.
    err = _cli_error(["optimize", "compass_gait", "--cost", "work", "--fix", "period=0.8"],
                     capsys)  # fmt: skip
    assert "--bound hip_torque=20" in err and "bounds=" not in err and "`" not in err


def test_every_optimize_advice_names_an_existing_cli_option():
    # Every `name` or name= the optimisation's messages mention, once translated for the CLI,
    # is an option of `gaitopt optimize` (source: the messages themselves, read from the code).
    import argparse
    import ast
    from pathlib import Path

    from gaitopt.cli.optimize import add_arguments, for_the_cli

    parser = argparse.ArgumentParser()
    add_arguments(parser)
    options = {s for a in parser._actions for s in a.option_strings}
    root = Path(gaitopt.__file__).parent
    files = [
        root / "optimize" / n
        for n in ("solve.py", "guess.py", "problem.py", "statement.py", "result.py")
    ]
    python_only = {"model", "problem", "guess", "mesh", "verify", "state_bounds", "clearance",
                   "guard_margin", "continuous_inputs", "mesh.intervals", "mesh.degree",
                   "vary", "locate", "gait.orbit", "g", "workers"}  # fmt: skip
    # Model parameters named in a message (a model lacking `gravity`) are not options.
    python_only |= {n for cls in gaitopt.REGISTRY.values() for n in cls().params}
    checked = 0
    for path in files:
        tree = ast.parse(path.read_text())
        docstrings = {
            id(node.body[0].value)
            for node in ast.walk(tree)
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef))
            and node.body
            and isinstance(node.body[0], ast.Expr)
            and isinstance(node.body[0].value, ast.Constant)
        }
        texts = [
            node.value
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and id(node) not in docstrings
        ]  # string literals and the literal parts of f-strings: the messages
        for text in texts:
            for name in re.findall(r"`([\w.]+)`", text):
                if name in python_only:
                    continue  # never reaches the CLI: its own checks or no such input there
                cli = for_the_cli(f"`{name}`")
                assert cli.split()[0] in options, (path.name, name, cli)
                checked += 1
    assert checked >= 10


@pytest.mark.parametrize(
    "arguments, needle",
    [
        ({"bounds": 5}, "`bounds` must be a mapping"),
        ({"path_constraints": 5}, "`path_constraints` must be a name or a tuple"),
        ({"free": 5}, "`free` must be a name or a tuple"),
        ({"free": ("slope", "slope")}, "`free` names a parameter twice"),
        ({"scheduler": "nope"}, "`scheduler` must be None, 'local' or a Dask"),
        ({"scheduler": 5}, "`scheduler` must be None"),
    ],
)
def test_optimize_gait_arguments_of_the_wrong_kind(arguments, needle):
    """Each raised a raw TypeError/ValueError (from tuple(), dict() or Dask's connect) before
    (issue 25, item 4: raw Python exceptions in the API); now one GaitoptInputError naming the
    argument, before any work."""
    model = gaitopt.model("compass_gait", slope=0.0)
    with pytest.raises(gaitopt.GaitoptInputError, match=re.escape(needle)):
        gaitopt.optimize_gait(model, period=0.8, step_length=0.3, **arguments)
