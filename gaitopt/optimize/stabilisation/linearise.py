"""The offset linearisation ``sₖ₊₁ − s* = A (sₖ − s*) + B δₖ`` of an optimal gait's return map:
``A`` and ``B`` by AD through the Radau transcription (the floquet module's implicit-function
construction with the offset ``δ`` as an extra unknown; Hiskens & Pai 2000), ``B`` also by
central differences of the independent event-located simulator."""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import casadi as ca
import numpy as np

from ...simulation import Simulation, simulate
from ..collocation import Collocation, _derivative_matrix
from ..floquet import _end_jacobians, _lift_jacobian
from ..result import OptimalGait
from ..verify import feedforward_of

__all__ = [
    "offset_jacobian",
    "offset_jacobian_fd",
    "central_differences",
    "simulate_offsets",
    "section_point",
    "FD_STEP",
]

FD_STEP = 1e-6  # central differences of the simulated map (section units, input units)


@lru_cache(maxsize=32)
def _phase_residual(flow: ca.Function, N: int, d: int, C_key: bytes) -> ca.Function:
    """``R(Xfree, x0, dt0, delta, U, Udot, H, p)``: the collocation defects of one phase with the
    node inputs ``U + U̇ dt0 + δ``, and the Jacobians with respect to ``Xfree`` and
    ``[x0; dt0; δ]``."""
    C = np.frombuffer(C_key).reshape(d + 1, d)
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    Xf = ca.SX.sym("X", n, N * d)
    x0 = ca.SX.sym("x0", n)
    dt0 = ca.SX.sym("dt0")
    delta = ca.SX.sym("delta", n_u)
    U = ca.SX.sym("U", n_u, N * d)
    Ud = ca.SX.sym("Ud", n_u, N * d)
    H = ca.SX.sym("H", N)
    p = ca.SX.sym("p", n_p)
    X = ca.horzcat(x0, Xf)
    shift = ca.repmat(delta, 1, N * d)
    F = flow.map(N * d)(Xf, U + Ud * dt0 + shift, p)
    defects = [
        ca.mtimes(X[:, j * d : j * d + d + 1], ca.DM(C)) - H[j] * F[:, j * d : (j + 1) * d]
        for j in range(N)
    ]
    R = ca.vec(ca.horzcat(*defects))
    z = ca.vertcat(x0, dt0, delta)
    return ca.Function(
        "offset_sensitivity",
        [Xf, x0, dt0, delta, U, Ud, H, p],
        [ca.jacobian(R, ca.vec(Xf)), ca.jacobian(R, z)],
    )


def offset_jacobian(col: Collocation, w: np.ndarray, p_model: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(A, B)``: the orbit's return map differentiated in the section coordinates and in an
    input offset held over the orbit, by AD through the transcription.

    Parameters
    ----------
    col : Collocation
        The final transcription of the optimum.
    w : numpy.ndarray
        Its solution.
    p_model : numpy.ndarray
        The model's parameter vector.

    Returns
    -------
    A : numpy.ndarray
        ``∂P/∂s`` (m × m, section coordinates); the same as
        :func:`~gaitopt.optimize.floquet.return_map_jacobian`.
    B : numpy.ndarray
        ``∂P/∂δ`` (m × n_u: section units per input unit).
    """
    sol = col.unpack(w, p_model)
    p = sol["p"]
    model = col.model
    N, d = col.N, col.d
    D = _derivative_matrix(col.tau[1:], col.tau[1:])
    n_cycle = len(model.phases)
    n_u = len(model.inputs)
    L = np.asarray(_lift_jacobian(model.section.lift)(sol["s"], p), dtype=float)
    m = L.shape[1]
    n0 = L.shape[0]
    # Rows (δx, δt, δ) per unit (δs, δ); δ is carried unchanged through the orbit.
    M = np.zeros((n0 + 1 + n_u, m + n_u))
    M[:n0, :m] = L
    M[n0 + 1 :, m:] = np.eye(n_u)
    for k, i in enumerate(col.chain):
        phase = model.phases[i]
        tr = phase.transitions[0]
        n = phase.n
        X, U, T = sol["X"][k], sol["U"][k], float(sol["T"][k])
        hs = T * np.diff(sol["breaks"][k])
        Ud = np.hstack([U[:, j * d : (j + 1) * d] @ D.T / hs[j] for j in range(N)])
        sens = _phase_residual(phase.flow, N, d, col.C.tobytes())
        R_X, R_z = (
            np.asarray(v, dtype=float)
            for v in sens(X[:, 1:], X[:, 0], 0.0, np.zeros(n_u), U, Ud, hs, p)
        )
        Phi = -np.linalg.solve(R_X, R_z)[-n:, :]  # δx_end per (δx0, δt0, δ)
        f, g_x, g_u, r_x, r_u = (
            np.asarray(v, dtype=float)
            for v in _end_jacobians(phase.flow, tr.guard, tr.reset)(X[:, -1], U[:, -1], p)
        )
        f, udot = f.ravel(), Ud[:, -1]
        e_t = np.zeros((1, n + 1 + n_u))
        e_t[0, n] = 1.0
        e_d = np.zeros((n_u, n + 1 + n_u))
        e_d[:, n + 1 :] = np.eye(n_u)
        g_rate = float((g_x @ f + g_u @ udot).ravel()[0])
        # The crossing moves by δτ = −(g_x δx + g_u (u̇ δt0 + δ)) / ġ (the input at the end is
        # u + u̇ (δt0 + δτ) + δ); the reset sees that input.
        dtau = -(g_x @ Phi + g_u @ (np.outer(udot, e_t) + e_d)) / g_rate
        dx_minus = Phi + np.outer(f, dtau)
        dt_event = e_t + dtau
        dx_plus = r_x @ dx_minus + r_u @ (np.outer(udot, dt_event) + e_d)
        M = np.vstack([dx_plus, dt_event, e_d]) @ M
        if (k + 1) % n_cycle == 0:
            M[n0, :] = 0.0  # the feedforward clock restarts at the section
    rows = col.section_index
    return M[:n0, :m][rows, :], M[:n0, m:][rows, :]


class _Offset:
    """``u*(t) + δₖ`` for :func:`gaitopt.simulate` (``k`` the returns so far; ``offsets[k]`` read
    when step ``k`` runs, so a policy may fill it in as the run goes), vectorised like the
    optimum's own feedforward (one CasADi call per integrator step)."""

    def __init__(self, gait: OptimalGait, offsets: dict[int, np.ndarray]):
        self.base = feedforward_of(gait.profiles)
        self.offsets = offsets

    def __call__(self, t: float, k: int) -> np.ndarray:
        return self.base(t, k) + self.offsets[k]

    def vectorised(self, times: np.ndarray, k: int) -> np.ndarray:
        return self.base.vectorised(times, k) + np.asarray(self.offsets[k], dtype=float)[:, None]

    def breaks(self, k: int) -> np.ndarray:
        return self.base.breaks(k)


def _feedforward(
    gait: OptimalGait, offsets: dict[int, np.ndarray]
) -> Callable[[float, int], np.ndarray]:
    """``u*(t) + δₖ`` for :func:`gaitopt.simulate` (see :class:`_Offset`)."""
    return _Offset(gait, offsets)


def simulate_offsets(
    gait: OptimalGait,
    s: np.ndarray,
    offsets: dict[int, np.ndarray],
    steps: int,
    inputs: Callable[[int, np.ndarray], np.ndarray] | None = None,
) -> Simulation:
    """``steps`` returns simulated from the section point ``s`` with ``u*(t) + δₖ`` applied
    (``offsets[k]``: given, or filled in by an ``inputs`` policy as the run goes)."""
    model = gait.model
    return simulate(
        model,
        model.lift(s),
        steps=steps,
        inputs=inputs,
        feedforward=_feedforward(gait, offsets),
        rtol=1e-12,
        atol=1e-13,
        max_phase_time=_max_phase_time(gait),
    )


def _max_phase_time(gait: OptimalGait) -> float:
    """The simulator's limit on a phase's duration: ten times the optimum's longest (s)."""
    return 10.0 * float(np.max(gait.durations)) + 1.0


def offset_jacobian_fd(gait: OptimalGait, h: float = FD_STEP) -> np.ndarray | None:
    """``∂P/∂δ`` by central differences of the simulated orbit map (None if a perturbed
    simulation does not complete)."""
    model = gait.model
    s_star = section_point(gait)
    steps = int(gait.problem.get("steps", 1))

    def end_of(delta: np.ndarray) -> np.ndarray | None:
        sim = simulate_offsets(gait, s_star, {k: delta for k in range(steps + 1)}, steps)
        return model.section_coordinates_of(sim.section_states[-1]) if sim.success else None

    return central_differences(end_of, np.zeros(len(model.inputs)), s_star.size, h)


def central_differences(
    end_of: Callable[[np.ndarray], np.ndarray | None], x0: np.ndarray, rows: int, h: float
) -> np.ndarray | None:
    """Jacobian (``rows`` × ``x0.size``) of a simulated map at ``x0`` by central differences,
    ``(end_of(x0 + h eⱼ) − end_of(x0 − h eⱼ)) / 2h``; None as soon as ``end_of`` returns None (a
    perturbed simulation did not complete)."""
    J = np.zeros((rows, x0.size))
    for j in range(x0.size):
        ends = []
        for sign in (1.0, -1.0):
            x = x0.copy()
            x[j] += sign * h
            end = end_of(x)
            if end is None:
                return None
            ends.append(end)
        J[:, j] = (ends[0] - ends[1]) / (2 * h)
    return J


def section_point(gait: OptimalGait) -> np.ndarray:
    """The optimum's fixed point in section coordinates."""
    model = gait.model
    return np.asarray(model.section_coordinates_of(model.state_vector(gait.fixed_point)))
