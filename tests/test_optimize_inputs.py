"""Bad input to ``optimize_gait`` is one clear error before any work (issue 24): a failed
result as a warm start (it raised IndexError).

Every check here is input validation, so each case must fail fast: the time limit (2 s per
call) is an order below the solves it guards.
"""

from __future__ import annotations

import time

import pytest

import gaitopt
from gaitopt.errors import GaitoptInputError, GuessError
from gaitopt.optimize import WarmStartError, optimize_gait

LEVEL = dict(period=0.8, step_length=0.3)  # the README's level-ground compass statement


def _fast(call):
    """Run ``call``, which must raise a GaitoptInputError within 2 s; return the error."""
    t0 = time.perf_counter()
    with pytest.raises(GaitoptInputError) as info:
        call()
    assert time.perf_counter() - t0 < 2.0
    return info.value


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
