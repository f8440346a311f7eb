"""Fixed-step explicit Runge–Kutta integration as CasADi expressions, for the shooting segments.

The Butcher tableau is Dormand & Prince's 8th-order DOP853 (Hairer, Nørsett & Wanner, "Solving
ODEs I", §II.10), read from :class:`scipy.integrate.DOP853` so its coefficients are not retyped.
With fixed steps the segment map is a smooth function of its start state, duration, input and
parameters, so CasADi differentiates it exactly (the sensitivities of the discrete map).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["rk_step", "segment_function", "segment_trajectory_function", "ORDER"]


def _dop853_tableau():
    """SciPy's DOP853 coefficients (``scipy/integrate/_ivp/dop853_coefficients.py``, plain NumPy
    arrays), read without importing ``scipy.integrate`` (0.4 s at start-up)."""
    from .dop853_base import coefficients

    module = coefficients()
    n = module.N_STAGES  # 12: DOP853.n_stages
    return module.A[:n, :n], module.B, module.C[:n]


_A, _B, _C = (np.asarray(v, dtype=float) for v in _dop853_tableau())
ORDER = 8  # scipy.integrate.DOP853.order


def rk_step(flow: ca.Function, x: ca.SX, u: ca.SX, p: ca.SX, h: ca.SX) -> ca.SX:
    """One explicit RK step of size ``h`` from ``x`` (autonomous flow ``f(x, u, p)``)."""
    k = []
    for i in range(len(_C)):
        xi = x
        for j in range(i):
            if _A[i, j] != 0.0:
                xi = xi + h * _A[i, j] * k[j]
        k.append(flow(xi, u, p))
    return x + h * sum(float(_B[i]) * k[i] for i in range(len(_B)) if _B[i] != 0.0)


def _symbols(flow: ca.Function):
    n = flow.size1_in(0)
    return (
        ca.SX.sym("x", n),
        ca.SX.sym("u", flow.size1_in(1)),
        ca.SX.sym("p", flow.size1_in(2)),
        ca.SX.sym("dt"),
    )


def segment_function(flow: ca.Function, steps: int) -> ca.Function:
    """``segment(x0, u, p, dt) -> x(dt)`` by ``steps`` equal RK steps (unrolled SX graph)."""
    x, u, p, dt = _symbols(flow)
    h = dt / steps
    xk = x
    for _ in range(steps):
        xk = rk_step(flow, xk, u, p, h)
    return ca.Function("segment", [x, u, p, dt], [xk], ["x0", "u", "p", "dt"], ["xf"])


def segment_trajectory_function(flow: ca.Function, steps: int) -> ca.Function:
    """``trajectory(x0, u, p, dt) -> X`` (n × (steps + 1)): the states at every RK step."""
    x, u, p, dt = _symbols(flow)
    h = dt / steps
    cols = [x]
    for _ in range(steps):
        cols.append(rk_step(flow, cols[-1], u, p, h))
    return ca.Function(
        "trajectory", [x, u, p, dt], [ca.horzcat(*cols)], ["x0", "u", "p", "dt"], ["X"]
    )
