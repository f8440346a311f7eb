"""Bad input to ``optimize_gait`` and ``gaitopt optimize`` is one clear error before any work
(issues 24 and 25): a failed result as a warm start, counts beyond their stated limits, ``tol``.

Every check here is input validation, so each case must fail fast: the time limits (2 s per
call) are an order below the cheapest solve they guard against (``--steps 1000`` grew past 5 GB;
``--starts 100000`` ran for hours).
"""

from __future__ import annotations

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
    # Legs of 1 m: feet at most 2 m apart, so 2.5 m is infeasible (IPOPT says so: no orbit).
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
    assert text.startswith("`guess` is a failed OptimalGait (success=False: no gait meets")
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
        (["--cold", "1000"], r"argument --cold: '1000' is above the limit 200"),
        (["--orbits", "5000"], r"argument --orbits: '5000' is above the limit 1000"),
    ],
)  # fmt: skip
def test_cli_limits(extra, pattern, capsys):
    err = _cli_error([*CLI_LEVEL, *extra], capsys)
    assert re.search(pattern, err), err
