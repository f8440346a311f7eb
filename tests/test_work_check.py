"""The positive work of an exact-work optimum counted between its collocation nodes
(gaitopt/optimize/work_check.py, called by the certificate)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import gaitopt
from gaitopt.optimize import GaitProblem, solve_problem
from gaitopt.optimize.radau import NEGATIVE
from gaitopt.optimize.work_check import check_work, dense_work

# The compass gait's least positive work (README: level, 0.3 m in 0.8 s, |τ| ≤ 20 N·m).
STATEMENT = {"step_length": 0.3, "period": 0.8, "bounds": {"hip_torque": 20.0}}


@pytest.fixture(scope="module")
def gait():
    model = gaitopt.model("compass_gait", slope=0.0)
    return solve_problem(GaitProblem(model, "work", **STATEMENT))


def test_dense_work_is_the_simulated_work(gait):
    # Source: the independent simulation's work (DOP853, max(0, τω) at every Gauss point of 64
    # panels per phase; the referee's cost_simulated) against the dense quadrature of the
    # polynomials: the same to 1e-8 relative (the discretisation target; 5e-12 measured), and
    # the transcription's charged work to the check's 1e-8.
    assert gait.success, gait.message
    col, w = gait.transcription
    out = dense_work(col, col.unpack(w, gait.model.p))
    assert out["positive_work_dense"] == pytest.approx(gait.verification["cost_simulated"],
                                                       rel=1e-8)  # fmt: skip
    assert abs(out["hidden_work"]) <= 1e-8 * out["scale"]
    assert gait.verification["hidden_work"] == pytest.approx(out["hidden_work"], abs=1e-15)


def test_hidden_work_is_refused(gait):
    # A braking arc's torque flipped (its power now positive) while the charged work stays the
    # transcription's: the dense quadrature sees the work the nodes' sum does not charge, and
    # the check refuses it naming both numbers.
    col, w = gait.transcription
    sol = col.unpack(w, gait.model.p)
    assert check_work(col, sol) is None
    kinds = np.array([a.signs for a in col.structure[0] for _ in range(a.intervals)]).T[0]
    (braking,) = np.nonzero(kinds == NEGATIVE)[0][:1]
    bad = copy.deepcopy(sol)
    d = col.d
    bad["U"][0][:, braking * d : (braking + 1) * d] *= -1.0
    message = check_work(col, bad)
    assert message is not None and "between the collocation nodes" in message
    assert dense_work(col, bad)["hidden_work"] > 0
