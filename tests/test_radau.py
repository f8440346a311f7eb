"""The Radau differentiation matrix is exact to roundoff, whatever BLAS/LAPACK the machine has.

It was a least-squares fit (``np.polyfit`` on the Vandermonde matrix): its rows summed to 6e-12
instead of 0 with OpenBLAS's SkylakeX kernels (3e-13 with its Haswell ones), a bias of the
collocation equations per mesh interval that made the optimum drift in proportion to the
number of intervals — the compass gait's bounded least effort stopped certifying.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gaitopt
import gaitopt.optimize.solve as solve
from gaitopt.optimize import optimize_gait
from gaitopt.optimize.radau import _derivative_matrix


@pytest.mark.parametrize("degree", [1, 3, 5, 6, 8])
def test_differentiation_matrix_is_exact(degree):
    """Closed form: d/dτ τᵏ = k τᵏ⁻¹ for k ≤ d (the basis of the start and d Radau points is
    exact for them), so the rows sum to 0 (k = 0).  Tolerance 1e-13: a few hundred ulps of
    the entries (≤ 40 at degree 6); measured ≤ 1.1e-14; the least-squares fit missed by 6e-12."""
    tau = np.array([0.0, *ca.collocation_points(degree, "radau")])
    D = _derivative_matrix(tau, tau[1:])  # d × (d + 1)
    assert np.max(np.abs(D.sum(axis=1))) <= 1e-13
    for k in range(1, degree + 1):
        assert np.max(np.abs(D @ tau**k - k * tau[1:] ** (k - 1))) <= 1e-13
    # Between the nodes too (the general formula, not only at the nodes).
    points = np.linspace(0.0, 1.0, 7)
    for k in range(1, degree + 1):
        exact = k * points ** (k - 1)
        assert np.max(np.abs(_derivative_matrix(tau, points) @ tau**k - exact)) <= 1e-13


def test_refined_optimum_does_not_drift():
    """The compass gait's least effort (0.3 m in 0.8 s, no bound) is smooth: Radau collocation
    of degree 6 converges spectrally, so its certified optimum (12 intervals) and the same
    transcription on 48 intervals agree to roundoff.  Tolerance 2e-11 relative (measured
    4e-13); with the fitted matrix the cost rose by 3.3e-10 from 12 to 48 intervals and kept
    doubling per mesh doubling (6e-9 absolute at 192)."""
    model = gaitopt.model("compass_gait", slope=0)
    gait = optimize_gait(model, "effort", period=0.8, step_length=0.3)
    assert gait.success, gait.message
    col, w = gait.transcription
    for _ in range(2):
        fine = solve._refined(col)
        w, stats = solve._run(fine, fine.from_solution(col, w, model.p), model.p)
        assert solve._converged(stats), stats.get("return_status")
        col = fine
    assert col.N == 4 * gait.transcription[0].N
    cost = col.unpack(w, model.p)["cost"]
    assert cost == pytest.approx(gait.cost, rel=2e-11)
