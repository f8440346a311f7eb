"""The return map's Jacobian of a hybrid periodic orbit: one implementation for every caller.

A gait's return map ``P`` takes the section coordinates ``s`` of one return (and the inputs) to
those of the next.  Its Jacobians ``A = ∂P/∂s`` (whose eigenvalues are the Floquet multipliers)
and ``B = ∂P/∂u`` or ``∂P/∂δ`` (per-step inputs, or an input offset held over the orbit) are
built in gaitopt from four rules, all here:

1. **Implicit function theorem on the orbit's equations** (:func:`section_jacobians`).  Split
   the unknowns of a transcription into ``s`` and the rest ``z`` (other states, free phase
   durations); the equations other than periodicity, ``G(s, z, u) = 0``, define ``z(s, u)``
   and the return is ``P(s, z, u)``, so

       ``∂P/∂s = P_s − P_z G_z⁻¹ G_s,   ∂P/∂u = P_u − P_z G_z⁻¹ G_u``.                  (1)

   With free durations ending on guards, differentiating ``G`` is what the saltation matrix
   does at each impact (rule 3), so it is included implicitly.  Multiple shooting writes
   ``F = [G; P − s]``; :func:`map_blocks` adds the identity back to ``∂F/∂w``.
2. **Phase sensitivity along an arc** (:func:`defect_jacobians`, :func:`phase_sensitivity`).
   On a Radau-collocated arc (``N`` intervals of ``d`` points, interval lengths ``h_j``,
   collocation matrix ``C``) the defects
   ``R = X_j C − h_j f(X_j, U_j + U̇_j δt₀ + δ)`` vanish; ``X`` the free node states,
   ``z = (x₀, δt₀, δ)`` the start state, a shift of the start time in the feedforward clock
   (the nodes then see ``u + u̇ δt₀``) and an input offset.  The implicit function theorem on
   them gives the discrete state-transition sensitivity

       ``∂X/∂z = −R_X⁻¹ R_z``,                                                             (2)

   whose last node is ``Φ = ∂x_end/∂z``: exactly the Radau IIA solution of the variational
   equations ``Σ̇ = f_x Σ + f_u (u̇ δt₀ + δ)`` (a Runge–Kutta method differentiated is the
   same method applied to the variational equations; Hairer, Nørsett & Wanner, *Solving
   ODEs I*), so at a solution it is the transcription's own derivative, not an approximation
   of it.  ``R_X`` and ``R_z`` are assembled from the flow's Jacobians at the nodes (a
   compiled kernel, :func:`gaitopt.kernels.nodes.flow_jacobian`), else from the symbolic
   defects; ``R_X`` is block lower bidiagonal, so eq. (2) is solved interval by interval.
3. **Saltation at a reset with a guard** (:func:`saltation`; Aizerman & Gantmacher 1958;
   Hiskens & Pai 2000, IEEE Trans. Circuits Syst. I 47(2)).  A deviation ``δx`` at the
   nominal end of a phase, with input deviation ``δu = u̇ δt₀ + δ`` there, reaches the guard
   ``g(x, u) = 0`` (crossing rate ``ġ = g_x f + g_u u̇``) after

       ``δτ = −(g_x δx + g_u δu) / ġ``,                                                   (3)

   then ``δx⁻ = δx + f δτ``, the event's clock shift ``δt_e = δt₀ + δτ`` and the reset
   ``x⁺ = r(x⁻, u)`` gives

       ``δx⁺ = r_x δx⁻ + r_u (u̇ δt_e + δ)``.                                              (4)

   With ``δt₀ = δ = 0`` this is ``S = r_x − (r_x f + r_u u̇) g_x/ġ``: the saltation matrix of
   a map whose next phase starts at the event (the classical matrix's ``f⁺ g_x/ġ`` term
   belongs to a monodromy over a fixed time and is absent here).
   ``r_x`` may be rectangular: a reset that changes the state's dimension (the kneed walker's
   knee strike) needs nothing else.
4. **Composition into the monodromy** (:func:`collocated_return_map`).  From the section's
   lift ``x₀ = ℓ(s)`` (``∂ℓ/∂s``, :func:`lift_jacobian`), each phase multiplies the stacked
   deviation ``(δx, δt, δ)`` by ``[S Φ; δt_e; δ]`` (rules 2 and 3, ``δ`` carried unchanged);
   the feedforward clock restarts where a phase returns to the section (``δt = 0``).  After
   the orbit's last phase the section rows of ``δx`` per ``δs`` are ``A``, per ``δ`` they
   are ``B``.  (:mod:`gaitopt.transverse.linearise` composes rule 3 with its own transverse
   frames and transition matrices instead of rule 2.)

Rules 1 and 3 take NumPy arrays or CasADi matrices alike (the NLP rows of
:mod:`gaitopt.optimize.spectral` use them symbolically).  The independent checks are finite
differences of the simulated return map (``tests/test_sensitivity.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

__all__ = [
    "CollocatedArc",
    "collocated_return_map",
    "defect_function",
    "defect_jacobians",
    "eliminate",
    "end_jacobians",
    "end_values",
    "lift_jacobian",
    "map_blocks",
    "multipliers",
    "phase_sensitivity",
    "saltation",
    "section_jacobians",
]


# -- rule 1: the implicit function theorem on the orbit's equations ---------------------------
def map_blocks(F_w: np.ndarray, m: int, n_g: int) -> np.ndarray:
    """``∂[G; P]/∂w`` from the shooting Jacobian ``∂F/∂w`` (``F = [G; P − s]``, ``s`` the first
    ``m`` unknowns): the identity added back to the periodicity rows' ``s`` columns."""
    J = np.array(F_w, dtype=float)
    J[n_g:, :m] += np.eye(m)
    return J


def _hstack(*blocks: Any) -> Any:
    return np.hstack(blocks) if isinstance(blocks[0], np.ndarray) else ca.horzcat(*blocks)


def eliminate(J_w: Any, J_u: Any, m: int, n_g: int) -> tuple[Any, Any]:
    """Eq. (1): ``(∂P/∂[s, u], ∂z/∂[s, u])`` from ``J_w = ∂[G; P]/∂w`` (``w = [s; z]``, shape
    ``(n_g + m) × (m + n_g)``) and ``J_u = ∂[G; P]/∂u`` (or None: ``s`` only).  NumPy arrays
    (raises ``LinAlgError`` where ``G_z`` is singular) or CasADi matrices."""
    G_s, G_z = J_w[:n_g, :m], J_w[:n_g, m:]
    P_s, P_z = J_w[n_g:, :m], J_w[n_g:, m:]
    rhs, direct = G_s, P_s
    if J_u is not None:  # (two indices: one would index a CasADi matrix as a vector)
        rhs, direct = _hstack(G_s, J_u[:n_g, :]), _hstack(P_s, J_u[n_g:, :])
    if not n_g:
        return direct, np.zeros((0, rhs.shape[1]))
    dz = np.linalg.solve(G_z, rhs) if isinstance(G_z, np.ndarray) else ca.solve(G_z, rhs)
    return direct - P_z @ dz, dz


def section_jacobians(J_w: Any, J_u: Any, m: int, n_g: int) -> tuple[Any, Any]:
    """Eq. (1): ``(A, B) = (∂P/∂s, ∂P/∂u)`` from the Jacobians of the stacked ``[G; P]``.

    Parameters
    ----------
    J_w : numpy.ndarray or casadi matrix
        ``∂[G; P]/∂w`` with ``w = [s; z]``; shape ``(n_g + m) × (m + n_g)``.
    J_u : numpy.ndarray, casadi matrix or None
        ``∂[G; P]/∂u``; shape ``(n_g + m) × n_u`` (None: ``B`` is None).
    m : int
        Number of section coordinates.
    n_g : int
        Number of equations in ``G``.
    """
    total, _ = eliminate(J_w, J_u, m, n_g)
    if J_u is None:
        return total, None
    return total[:, :m], total[:, m:]


def multipliers(A: np.ndarray) -> np.ndarray:
    """The eigenvalues of a return map's Jacobian (or a monodromy), largest modulus first (an
    empty complex array for a 0 × 0 one)."""
    if A.size == 0:
        return np.zeros(0, complex)
    mu = np.linalg.eigvals(A)
    return mu[np.argsort(-np.abs(mu))]


# -- rule 2: phase sensitivity along a collocated arc -----------------------------------------
@lru_cache(maxsize=32)
def defect_function(
    flow: ca.Function, N: int, d: int, C_key: bytes, offset: bool = False
) -> ca.Function:
    """``R(Xfree, x0, dt0, U, Udot, H, p) -> (R_X, R_z)``: the Jacobians of an arc's Radau
    defects (eq. 2) in its free node states and in ``z = [x0; dt0]`` (with ``offset``,
    ``[x0; dt0; δ]`` at ``δ = 0``), symbolically (``H``: the interval lengths, s;
    ``C_key``: the ``(d + 1) × d`` collocation matrix's bytes)."""
    C = np.frombuffer(C_key).reshape(d + 1, d)
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    Xf, x0, dt0 = ca.SX.sym("X", n, N * d), ca.SX.sym("x0", n), ca.SX.sym("dt0")
    U, Ud = ca.SX.sym("U", n_u, N * d), ca.SX.sym("Ud", n_u, N * d)
    H, p, delta = ca.SX.sym("H", N), ca.SX.sym("p", n_p), ca.SX.sym("delta", n_u)
    X = ca.horzcat(x0, Xf)
    F = flow.map(N * d)(Xf, U + Ud * dt0 + ca.repmat(delta, 1, N * d), p)
    defects = [
        ca.mtimes(X[:, j * d : j * d + d + 1], ca.DM(C)) - H[j] * F[:, j * d : (j + 1) * d]
        for j in range(N)
    ]
    R = ca.vec(ca.horzcat(*defects))
    z = ca.vertcat(x0, dt0, delta) if offset else ca.vertcat(x0, dt0)
    R_X, R_z = (ca.substitute(J, delta, ca.SX.zeros(n_u)) for J in
                (ca.jacobian(R, ca.vec(Xf)), ca.jacobian(R, z)))  # fmt: skip
    return ca.Function("phase_sensitivity", [Xf, x0, dt0, U, Ud, H, p], [R_X, R_z])


def defect_jacobians(
    flow: ca.Function,
    C: np.ndarray,
    X: np.ndarray,
    U: np.ndarray,
    Ud: np.ndarray,
    hs: np.ndarray,
    p: np.ndarray,
    *,
    label: str,
    offset: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """``(R_X, R_z)`` of :func:`defect_function` at ``δt₀ = δ = 0``, assembled in NumPy from
    the flow's Jacobians at the nodes (the compiled kernel ``flow_jacobian(flow, label)``,
    mapped over the nodes): the defect of interval ``j`` at its point ``c`` is
    ``Σ_r C[r, c] X_{jd+r} − h_j f(X_{jd+c+1}, U_{jd+c} + U̇_{jd+c} δt₀ + δ)``.  Where the flow
    has no SX form, the symbolic :func:`defect_function` (the same numbers)."""
    d = C.shape[1]
    N = hs.size
    n, n_u = X.shape[0], U.shape[0]
    from ..kernels.nodes import flow_jacobian  # here: a shooting solve needs no node kernels

    try:
        kern = flow_jacobian(flow, label)
    except (TypeError, RuntimeError, NotImplementedError):
        sens = defect_function(flow, N, d, C.tobytes(), offset)
        return tuple(np.asarray(v, dtype=float) for v in sens(X[:, 1:], X[:, 0], 0.0, U, Ud, hs, p))
    _, F_x, F_u = (np.asarray(v, dtype=float) for v in kern.map(N * d)(X[:, 1:], U, p))
    R_X = np.zeros((n * N * d, n * N * d))
    R_z = np.zeros((n * N * d, n + 1 + (n_u if offset else 0)))
    eye = np.eye(n)
    for j in range(N):
        for c in range(d):
            node = j * d + c
            rows = slice(n * node, n * node + n)
            for r in range(d + 1):
                col_x = j * d + r  # column of X (0: the arc's start x0)
                block = C[r, c] * eye
                if r == c + 1:
                    block = block - hs[j] * F_x[:, n * node : n * node + n]
                if col_x == 0:
                    R_z[rows, :n] += block
                else:
                    R_X[rows, n * (col_x - 1) : n * col_x] += block
            f_u = F_u[:, n_u * node : n_u * node + n_u]
            R_z[rows, n] = -hs[j] * f_u @ Ud[:, node]
            if offset:
                R_z[rows, n + 1 :] = -hs[j] * f_u
    return R_X, R_z


@dataclass(frozen=True)
class CollocatedArc:
    """One phase of a collocated orbit, as rule 2 and rule 3 need it.

    Attributes
    ----------
    flow, guard, reset : casadi.Function
        The phase's flow ``f(x, u, p)`` and its transition's guard and reset.
    C : numpy.ndarray
        The ``(d + 1) × d`` collocation matrix.
    X : numpy.ndarray
        Node states, ``n × (N d + 1)`` (the first column the arc's start).
    U, Ud : numpy.ndarray
        Inputs and their time derivatives at the collocation points, ``n_u × N d`` (input
        unit, input unit/s).
    hs : numpy.ndarray
        Interval lengths (s).
    label : str
        Names the compiled flow-Jacobian kernel.
    closes : bool
        The arc's end returns to the section (the feedforward clock restarts).
    """

    flow: ca.Function
    guard: ca.Function
    reset: ca.Function
    C: np.ndarray
    X: np.ndarray
    U: np.ndarray
    Ud: np.ndarray
    hs: np.ndarray
    label: str
    closes: bool


def phase_sensitivity(arc: CollocatedArc, p: np.ndarray, *, offset: bool = False) -> np.ndarray:
    """Eq. (2) at the arc's end: ``Φ = ∂x_end/∂[x₀; δt₀]`` (with ``offset``,
    ``∂x_end/∂[x₀; δt₀; δ]``), ``n × (n + 1 [+ n_u])``.

    ``R_X`` is block lower bidiagonal in the intervals (interval ``j``'s defects involve its own
    ``d`` nodes and the last node of interval ``j − 1``), so eq. (2) is solved interval by
    interval, ``Σ_j = −R_jj⁻¹ (R_z,j + R_j,j−1 Σ_{j−1})``: ``N`` solves of size ``n d``
    instead of one of size ``n N d`` (the same numbers to rounding)."""
    R_X, R_z = defect_jacobians(
        arc.flow, arc.C, arc.X, arc.U, arc.Ud, arc.hs, p, label=arc.label, offset=offset
    )
    size = arc.X.shape[0] * arc.C.shape[1]  # n d: one interval's free nodes
    S = np.zeros((0, R_z.shape[1]))
    for j in range(arc.hs.size):
        rows = slice(j * size, (j + 1) * size)
        rhs = R_z[rows] if j == 0 else R_z[rows] + R_X[rows, (j - 1) * size : j * size] @ S
        S = -np.linalg.solve(R_X[rows, rows], rhs)
    return S[-arc.X.shape[0] :, :]


# -- rule 3: saltation at a reset with a guard ------------------------------------------------
@lru_cache(maxsize=64)
def end_jacobians(flow: ca.Function, guard: ca.Function, reset: ca.Function) -> ca.Function:
    """``ends(x, u, p) -> (f, g_x, g_u, r_x, r_u)`` at a phase end: the flow and the guard's and
    reset's Jacobians that eqs. (3)–(4) need."""
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", n_u), ca.SX.sym("p", n_p)
    g, r = guard(x, u, p), reset(x, u, p)
    return ca.Function(
        "end_jacobians",
        [x, u, p],
        [flow(x, u, p), ca.jacobian(g, x), ca.jacobian(g, u), ca.jacobian(r, x), ca.jacobian(r, u)],
    )


def end_values(
    flow: ca.Function, guard: ca.Function, reset: ca.Function, x: Any, u: Any, p: Any
) -> list[np.ndarray]:
    """:func:`end_jacobians` at ``(x, u, p)``, as NumPy arrays (``f`` a column)."""
    return [np.asarray(v, dtype=float) for v in end_jacobians(flow, guard, reset)(x, u, p)]


def saltation(
    ends: Sequence[Any], udot: Any, dx: Any, dt0: Any, delta: Any = None
) -> tuple[Any, Any]:
    """Eqs. (3)–(4): ``(δx⁺, δt_e)`` after a phase end, for ``k`` deviations at once.

    Parameters
    ----------
    ends : sequence
        ``(f, g_x, g_u, r_x, r_u)`` at the nominal end (:func:`end_jacobians`; ``f`` a column).
    udot : array or casadi matrix
        ``u̇`` at the end, a column (input unit/s).
    dx : array or casadi matrix
        ``δx`` at the nominal end time, ``n × k``.
    dt0 : array or casadi matrix
        ``δt₀``, the phase's lead in the feedforward clock, ``1 × k`` (s).
    delta : array or casadi matrix, optional
        An input offset ``δ``, ``n_u × k`` (None: zero).

    Returns
    -------
    dx_plus, dt_event
        ``δx⁺`` (``n⁺ × k``) and ``δt_e = δt₀ + δτ`` (``1 × k``).
    """
    f, g_x, g_u, r_x, r_u = ends
    g_du = (g_u @ udot) @ dt0  # g_u δu
    if delta is not None:
        g_du = g_du + g_u @ delta
    rate = g_x @ f + g_u @ udot  # ġ, bounded away from 0 at a transversal crossing
    dtau = -(g_x @ dx + g_du) / rate
    dt_event = dt0 + dtau
    dx_plus = r_x @ (dx + f @ dtau) + (r_u @ udot) @ dt_event
    if delta is not None:
        dx_plus = dx_plus + r_u @ delta
    return dx_plus, dt_event


# -- rule 4: composition into the return map's Jacobian ---------------------------------------
@lru_cache(maxsize=32)
def lift_jacobian(lift: ca.Function) -> ca.Function:
    """``∂ℓ/∂s (s, p)`` of a section's lift ``x₀ = ℓ(s, p)``."""
    s, p = ca.SX.sym("s", lift.size1_in(0)), ca.SX.sym("p", lift.size1_in(1))
    return ca.Function("lift_jacobian", [s, p], [ca.jacobian(lift(s, p), s)])


def collocated_return_map(
    arcs: Sequence[CollocatedArc],
    L: np.ndarray,
    section_index: Sequence[int],
    p: np.ndarray,
    *,
    offset: bool = False,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Rule 4: ``(A, B)`` of a collocated orbit's return map, the input a feedforward in the
    time since each return to the section.

    Parameters
    ----------
    arcs : sequence of CollocatedArc
        The orbit's phases in order (all its returns).
    L : numpy.ndarray
        ``∂ℓ/∂s`` at the fixed point (``n₀ × m``).
    section_index : sequence of int
        The section coordinates' rows in the first phase's state.
    p : numpy.ndarray
        The parameter vector.
    offset : bool
        Also ``B = ∂P/∂δ`` for an input offset ``δ`` held over the orbit (else None).

    Returns
    -------
    A, B : numpy.ndarray
        ``∂P/∂s`` (``m × m``) and ``∂P/∂δ`` (``m × n_u``, section units per input unit).
    """
    n0, m = L.shape
    n_d = arcs[0].U.shape[0] if offset else 0
    # rows (δx, δt, δ) per unit (δs, δ)
    M = np.zeros((n0 + 1 + n_d, m + n_d))
    M[:n0, :m] = L
    M[n0 + 1 :, m:] = np.eye(n_d)
    for arc in arcs:
        n = arc.X.shape[0]
        Phi = phase_sensitivity(arc, p, offset=offset)  # δx_end per (δx₀, δt₀, δ)
        ends = end_values(arc.flow, arc.guard, arc.reset, arc.X[:, -1], arc.U[:, -1], p)
        e_t = np.zeros((1, n + 1 + n_d))
        e_t[0, n] = 1.0
        e_d = np.zeros((n_d, n + 1 + n_d))
        e_d[:, n + 1 :] = np.eye(n_d)
        dx_plus, dt_event = saltation(ends, arc.Ud[:, -1:], Phi, e_t, e_d if offset else None)
        M = np.vstack([dx_plus, dt_event, e_d]) @ M
        if arc.closes:
            M[dx_plus.shape[0], :] = 0.0  # the feedforward clock restarts at the section
    rows = list(section_index)
    n_end = M.shape[0] - 1 - n_d
    return M[:n_end, :m][rows, :], (M[:n_end, m:][rows, :] if offset else None)
