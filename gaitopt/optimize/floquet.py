"""Floquet multipliers of an optimal gait with its input applied as a feedforward ``u(t)``.

The return map takes section coordinates ``s`` to those of the next return, with the input a
fixed function of the time since the section (so a perturbed step that lasts longer or shorter
sees the same ``u(t)``; past the profile's end the last value holds).  Its Jacobian is built
here by differentiating *the transcription itself*: on each phase, the Radau collocation
equations at the nominal duration define the discrete flow map; the implicit function theorem
on them (exact CasADi derivatives) gives its sensitivity to the phase's start state and to a
shift ``δt₀`` of its start time (which shifts the inputs the nodes see by ``u̇ δt₀``).  Each phase
end adds the time to the guard, ``δτ = −(g_x δx + g_u u̇ δt₀) / ġ`` (the saltation correction,
Aizerman & Gantmacher 1958; Hiskens & Pai 2000), and the reset's Jacobian.  The independent
check is :func:`gaitopt.optimize.verify.map_jacobian_fd`: finite differences of the simulated
map.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from ..kernels.nodes import flow_jacobian
from .collocation import Collocation, _derivative_matrix

__all__ = ["return_map_jacobian"]


@lru_cache(maxsize=32)
def _phase_residual(flow: ca.Function, N: int, d: int, C_key: bytes) -> ca.Function:
    """``R(Xfree, x0, dt0, U, Udot, H, p)`` (``H``: the interval lengths, s): collocation
    defects with shifted node inputs, and its Jacobians with respect to ``Xfree`` and
    ``[x0; dt0]``."""
    C = np.frombuffer(C_key).reshape(d + 1, d)
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    Xf = ca.SX.sym("X", n, N * d)
    x0 = ca.SX.sym("x0", n)
    dt0 = ca.SX.sym("dt0")
    U = ca.SX.sym("U", n_u, N * d)
    Ud = ca.SX.sym("Ud", n_u, N * d)
    H = ca.SX.sym("H", N)
    p = ca.SX.sym("p", n_p)
    X = ca.horzcat(x0, Xf)
    F = flow.map(N * d)(Xf, U + Ud * dt0, p)
    defects = [
        ca.mtimes(X[:, j * d : j * d + d + 1], ca.DM(C)) - H[j] * F[:, j * d : (j + 1) * d]
        for j in range(N)
    ]
    R = ca.vec(ca.horzcat(*defects))
    z = ca.vertcat(x0, dt0)
    return ca.Function(
        "phase_sensitivity",
        [Xf, x0, dt0, U, Ud, H, p],
        [ca.jacobian(R, ca.vec(Xf)), ca.jacobian(R, z)],
    )


def _sensitivity(
    col: Collocation,
    k: int,
    flow: ca.Function,
    X: np.ndarray,
    U: np.ndarray,
    Ud: np.ndarray,
    hs: np.ndarray,
    p: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``R_X``, ``R_z`` of :func:`_phase_residual` at ``δt₀ = 0``, assembled in NumPy from the
    flow's Jacobians at the nodes (a compiled kernel, :func:`gaitopt.kernels.nodes.flow_jacobian`,
    mapped over the nodes): the defect of interval ``j`` at its point ``c`` is
    ``Σ_r C[r, c] X_{jd+r} − h_j f(X_{jd+c+1}, U_{jd+c} + U̇_{jd+c} δt₀)``.  Where the flow has no
    SX form, the symbolic :func:`_phase_residual` (same numbers)."""
    N, d, C = col.N, col.d, col.C
    n, n_u = X.shape[0], U.shape[0]
    try:
        kern = flow_jacobian(flow, f"{type(col.model).__name__.lower()}_{col.chain[k]}")
    except (TypeError, RuntimeError, NotImplementedError):
        sens = _phase_residual(flow, N, d, C.tobytes())
        return tuple(np.asarray(v, dtype=float) for v in sens(X[:, 1:], X[:, 0], 0.0, U, Ud, hs, p))
    _, F_x, F_u = (np.asarray(v, dtype=float) for v in kern.map(N * d)(X[:, 1:], U, p))
    R_X = np.zeros((n * N * d, n * N * d))
    R_z = np.zeros((n * N * d, n + 1))
    eye = np.eye(n)
    for j in range(N):
        for c in range(d):
            node = j * d + c
            rows = slice(n * node, n * node + n)
            for r in range(d + 1):
                col_x = j * d + r  # column of X (0: the phase's start x0)
                block = C[r, c] * eye
                if r == c + 1:
                    block = block - hs[j] * F_x[:, n * node : n * node + n]
                if col_x == 0:
                    R_z[rows, :n] += block
                else:
                    R_X[rows, n * (col_x - 1) : n * col_x] += block
            R_z[rows, n] = -hs[j] * F_u[:, n_u * node : n_u * node + n_u] @ Ud[:, node]
    return R_X, R_z


@lru_cache(maxsize=64)
def _end_jacobians(flow: ca.Function, guard: ca.Function, reset: ca.Function) -> ca.Function:
    """``(f, g_x, g_u, r_x, r_u)`` at a phase end."""
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", n_u), ca.SX.sym("p", n_p)
    g, r = guard(x, u, p), reset(x, u, p)
    return ca.Function(
        "end_jacobians",
        [x, u, p],
        [flow(x, u, p), ca.jacobian(g, x), ca.jacobian(g, u), ca.jacobian(r, x), ca.jacobian(r, u)],
    )


@lru_cache(maxsize=32)
def _lift_jacobian(lift: ca.Function) -> ca.Function:
    s, p = ca.SX.sym("s", lift.size1_in(0)), ca.SX.sym("p", lift.size1_in(1))
    return ca.Function("lift_jacobian", [s, p], [ca.jacobian(lift(s, p), s)])


def return_map_jacobian(col: Collocation, w: np.ndarray, p_model: np.ndarray) -> np.ndarray:
    """``∂P/∂s`` of the return map (all ``steps`` returns of the orbit) in section coordinates,
    with the optimal input as a feedforward in the time since each return to the section."""
    sol = col.unpack(w, p_model)
    p = sol["p"]
    model = col.model
    N, d = col.N, col.d
    D = _derivative_matrix(col.tau[1:], col.tau[1:])  # du/dτ at the Radau points
    n_cycle = len(model.phases)
    s = sol["s"]
    L = np.asarray(_lift_jacobian(model.section.lift)(s, p), dtype=float)
    M = np.vstack([L, np.zeros((1, L.shape[1]))])  # (δx, δt) per unit δs
    for k, i in enumerate(col.chain):
        phase = model.phases[i]
        tr = phase.transitions[0]
        X, U, T = sol["X"][k], sol["U"][k], float(sol["T"][k])
        hs = T * np.diff(sol["breaks"][k])
        Ud = np.hstack([U[:, j * d : (j + 1) * d] @ D.T / hs[j] for j in range(N)])
        R_X, R_z = _sensitivity(col, k, phase.flow, X, U, Ud, hs, p)
        dX = -np.linalg.solve(R_X, R_z)  # ∂vec(Xfree)/∂[x0; dt0]
        n = phase.n
        Phi = dX[-n:, :]  # the end state: last column of Xfree
        x_end, u_end = X[:, -1], U[:, -1]
        f, g_x, g_u, r_x, r_u = (
            np.asarray(v, dtype=float)
            for v in _end_jacobians(phase.flow, tr.guard, tr.reset)(x_end, u_end, p)
        )
        udot = Ud[:, -1]
        f = f.ravel()
        g_rate = float((g_x @ f + g_u @ udot).ravel()[0])
        # (δx_end at the nominal end, δt0) -> crossing: δτ = −(g_x δx + g_u u̇ δt0)/ġ.
        dxe = Phi  # n × (n+1) in (δx0, δt0)
        dt0 = np.zeros((1, n + 1))
        dt0[0, -1] = 1.0
        dtau = -(g_x @ dxe + (g_u @ udot) * dt0) / g_rate
        dx_minus = dxe + np.outer(f, dtau)
        dt_event = dt0 + dtau
        dx_plus = r_x @ dx_minus + np.outer(r_u @ udot, dt_event)
        step = np.vstack([dx_plus, dt_event])
        M = step @ M
        if (k + 1) % n_cycle == 0:
            M[-1, :] = 0.0  # the feedforward clock restarts at the section
    return M[:-1, :][col.section_index, :]


def multipliers_of(A: np.ndarray) -> np.ndarray:
    """Eigenvalues of the return-map Jacobian, largest modulus first."""
    if A.size == 0:
        return np.zeros(0, complex)
    mu = np.linalg.eigvals(A)
    return mu[np.argsort(-np.abs(mu))]
