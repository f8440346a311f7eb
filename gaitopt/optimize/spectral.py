"""A bound on the spectral radius of an optimal gait's return map, as rows of its NLP:
``ρ(A) ≤ R`` (:attr:`GaitProblem.max_multiplier`), so the optimum is open-loop stable by design
(cf. Ul Hassan & Hubicki 2025: open-loop stable hopping by a stability constraint in the
trajectory optimisation).

**The Jacobian.**  ``A = ∂P/∂s`` in section coordinates, with the input a feedforward in the time
since each return to the section, is the one :mod:`gaitopt.optimize.floquet` computes after the
solve by the implicit function theorem on the collocation equations — here collocated alongside
the orbit: the discrete variational equations.  Differentiating phase ``k``'s Radau defects
``X C − h F(X, U + U̇ δt₀)`` in its start state and start-time shift gives, per node, ``n × m``
sensitivity unknowns ``Σ`` (one column per section coordinate) with the linear defects
``Σ C − h (f_x Σ + f_u U̇ δt₀)`` (the same Radau IIA scheme, so at a solution ``Σ`` is the IFT
sensitivity exactly, not an approximation of it: rule 2 of :mod:`gaitopt.orbit.sensitivity`).
The first phase starts from ``∂lift/∂s`` with ``δt₀ = 0``; each phase end adds that module's
saltation (rule 3, symbolically: the time to the guard ``δτ = −(g_x δx + g_u u̇ δt₀)/ġ``, ``ġ``
bounded away from 0 by :attr:`~GaitProblem.min_crossing_rate`, then the reset's Jacobian); the
feedforward clock restarts at each section.
``A`` is a block of ``m × m`` unknowns equal to the section rows of the last ``δx⁺``.

**The bound.**  Its characteristic polynomial's coefficients (Faddeev–LeVerrier, polynomial in
``A``) scaled to ``A/R`` must pass the Schur–Cohn–Jury test in its bilinear Liénard–Chipart form
(:mod:`gaitopt.optimize.schur`): ``m + 1`` smooth inequalities ``≥ 0``, exact for the closed disc
(up to degenerate corners), one of which vanishes where a root reaches the circle (a real one at
``±R`` or a complex pair).  ``R`` is a fixed decision variable (``lbx = ubx = R``), so the bounds
of one statement share a compiled NLP like a fixed period does.  Sections of at most
:data:`~gaitopt.optimize.schur.MAX_SECTION` coordinates (4).

**Regularity** (:mod:`gaitopt.optimize.spectral_bound` says why it is needed): the inputs'
polynomials are continuous between the mesh intervals of a phase, and the roughness
``∫ Σᵣ u̇ᵣ² dt`` over the orbit (by the Radau quadrature, exact for ``u̇²``) is at most
``max_roughness``.  Both are inactive at a smooth optimum (the compass gait's unbounded optimum
jumps by 9e-7 N·m between intervals), so an inactive bound leaves it where it was.

A Lyapunov certificate (``P = LLᵀ + εI``, ``R²P − AᵀPA = MMᵀ``) would scale to larger sections
but adds ``m(m + 1)`` unknowns that are not unique where the bound is inactive (any feasible
``P`` will do), so the NLP's solution would not be isolated there; the exact test keeps every
unknown determined by the orbit.  The certificate of the reported optimum is
:func:`gaitopt.optimize.spectral_certify.certify_spectral`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..orbit.sensitivity import end_jacobians, saltation
from .radau import _derivative_matrix
from .schur import charpoly, disc_conditions, scaled

__all__ = ["SpectralRows", "add_spectral_bound", "fill_sensitivities", "profile_roughness"]


@dataclass
class SpectralRows:
    """What :func:`add_spectral_bound` added to a transcription: the bound ``R``, the names of
    the sensitivity blocks (``Sens{k}``: ``n·m × N·d`` per phase) and of ``A``'s block
    (``Amap``), the group of the Jacobian's rows, ``A(w, p)`` (the expression) and
    ``roughness(w, p)``."""

    R: float
    m: int
    blocks: list[str]
    group: str
    A: ca.Function
    roughness: ca.Function


def _phase_steps(hs: list[Any], U: Any, tau: np.ndarray) -> Any:
    """``U̇`` at the Radau points ``tau`` of each interval (``U`` times the derivative matrix
    of the input basis over the interval length)."""
    d = tau.size
    D = ca.DM(_derivative_matrix(tau, tau).T)  # du/dτ at the Radau points, d × d
    return ca.horzcat(*[ca.mtimes(U[:, j * d : (j + 1) * d], D) / h for j, h in enumerate(hs)])


def _variational(flow: ca.Function, m: int) -> ca.Function:
    """``(x, u, u̇, p, vec Σ, δt₀) -> vec(f_x Σ + f_u u̇ δt₀)``: the variational right-hand
    side at one node (``Σ``: ``n × m``)."""
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, ud, p = ca.SX.sym("x", n), ca.SX.sym("u", n_u), ca.SX.sym("ud", n_u), ca.SX.sym("p", n_p)
    S, dt0 = ca.SX.sym("S", n * m), ca.SX.sym("dt0", 1, m)
    f = flow(x, u, p)
    rhs = ca.mtimes(ca.jacobian(f, x), ca.reshape(S, n, m)) + ca.mtimes(
        ca.mtimes(ca.jacobian(f, u), ud), dt0
    )
    return ca.Function("variational", [x, u, ud, p, S, dt0], [ca.vec(rhs)])


def add_spectral_bound(
    col: Any,
    B: Any,
    add: Any,
    X: list[Any],
    U: list[Any],
    T: list[Any],
    Th: list[Any],
    p: Any,
    p_in: Any,
) -> SpectralRows:
    """Add the variational equations, ``A`` and ``ρ(A) ≤ R`` to a transcription under
    construction (:class:`~gaitopt.optimize.collocation.Collocation`: its blocks ``B``, its
    ``add(name, expr, low, high)`` and its per-phase state nodes ``X``, inputs ``U``, durations
    ``T`` and arc fractions ``Th``; ``p`` the parameter vector with free entries, ``p_in`` the
    NLP's parameter symbol)."""
    problem, model = col.problem, col.model
    R = float(problem.max_multiplier)
    m, N, d = col.m, col.N, col.d
    C = ca.DM(col.C)
    n_cycle = len(model.phases)
    s = B.syms[B.names.index("s")]
    Sx = ca.jacobian(model.section.lift(s, p), s)  # δx per unit δs at the section
    St = ca.MX.zeros(1, m)  # δt₀: the feedforward clock restarts at the section
    blocks, rough = [], []
    for k, i in enumerate(col.chain):
        phase = model.phases[i]
        tr = phase.transitions[0]
        n = phase.n
        label = col._phase_label(k)
        if col.structure is None:
            hs = [T[k] / N] * N
        else:
            hs = [
                T[k] * Th[k][a] / arc.intervals
                for a, arc in enumerate(col.structure[k])
                for _ in range(arc.intervals)
            ]
        name = f"Sens{k}"
        Sk = B.add(name, n * m, N * d)
        blocks.append(name)
        nodes = ca.horzcat(ca.vec(Sx), Sk)
        Xc, Uk = X[k][:, 1:], U[k]
        Ud = _phase_steps(hs, Uk, col.tau[1:])
        rhs = _variational(phase.flow, m).map(N * d)(Xc, Uk, Ud, p, Sk, St)
        defects = [
            ca.mtimes(nodes[:, j * d : j * d + d + 1], C) - hs[j] * rhs[:, j * d : (j + 1) * d]
            for j in range(N)
        ]
        add(f"variational equations ({label})", ca.horzcat(*defects))
        _continuity_rows(col, B, add, k, Uk, label)
        rough.append(_roughness(col, Ud, hs))
        ends = end_jacobians(phase.flow, tr.guard, tr.reset)(X[k][:, -1], Uk[:, -1], p)
        Sx, dt_event = saltation(ends, Ud[:, -1], ca.reshape(Sk[:, -1], n, m), St)
        St = ca.MX.zeros(1, m) if (k + 1) % n_cycle == 0 else dt_event
    A_expr = Sx[col.section_index, :]
    A = B.add("Amap", m, m)
    blocks.append("Amap")
    group = "return map Jacobian (variational equations)"
    add(group, A - A_expr)
    Rv = B.add("max_multiplier", 1, 1, R, R)  # fixed: the bound is its variable's bound
    c = charpoly(A, m, ca.trace, ca.mtimes, ca.MX.eye)
    conditions = disc_conditions(scaled(c, Rv))
    add(f"spectral radius <= {R:g}", ca.vertcat(*conditions), 0.0, np.inf)
    roughness = ca.sum1(ca.vertcat(*rough))
    if problem.max_roughness is not None:
        add(f"roughness <= {problem.max_roughness:g}", roughness, -np.inf, problem.max_roughness)
    w = ca.vertcat(*[ca.vec(v) for v in B.syms])
    return SpectralRows(
        R,
        m,
        blocks,
        group,
        ca.Function("A", [w, p_in], [A_expr]),
        ca.Function("roughness", [w, p_in], [roughness]),
    )


def _smooth_inputs(col: Any) -> list[int]:
    """The inputs whose profile is bounded in roughness: those acting in the flow (not
    impulses), not switched off by their bounds."""
    low, high = col.problem.input_bounds()
    return [r for r in col.problem.flow_index if low[r] < high[r]]


def _roughness(col: Any, Ud: Any, hs: list[Any]) -> Any:
    """``∫ Σᵣ u̇ᵣ² dt`` over one phase by its Radau quadrature (exact: ``u̇²`` has degree
    ``2d − 4``)."""
    d = col.d
    smooth = _smooth_inputs(col)
    if not smooth:
        return ca.MX(0)
    wq = ca.DM(col.weights)
    terms = [
        hs[j] * ca.mtimes(ca.sum1(Ud[smooth, j * d : (j + 1) * d] ** 2), wq) for j in range(col.N)
    ]
    return ca.sum1(ca.vertcat(*terms))


def _continuity_rows(col: Any, B: Any, add: Any, k: int, Uk: Any, label: str) -> None:
    """The input polynomials of consecutive mesh intervals of phase ``k`` meet: ``u`` is
    continuous inside the phase (else a jump between intervals would be free roughness).  Not
    where the values involved are all fixed (an input on a saturated arc)."""
    N, d = col.N, col.d
    slot = B.names.index(f"U{k}")
    n_u = len(col.model.inputs)
    fixed = (B.lb[slot] == B.ub[slot]).reshape((n_u, N * d), order="F")
    u0 = ca.DM(col.u_at_start)
    rows = []
    for r in _smooth_inputs(col):
        for j in range(1, N):
            if fixed[r, j * d : (j + 1) * d].all() and fixed[r, j * d - 1]:
                continue
            start = ca.mtimes(Uk[r, j * d : (j + 1) * d], u0)
            rows.append(start - Uk[r, j * d - 1])
    if rows:
        add(f"inputs continuous between intervals ({label})", ca.horzcat(*rows))


def profile_roughness(col: Any, w: np.ndarray, p: np.ndarray) -> float:
    """``∫ Σᵣ u̇ᵣ² dt`` of a solution's input profile over the orbit ((input unit)²/s), by
    the Radau quadrature of each interval (any transcription, with or without the bound)."""
    sol = col.unpack(w, p)
    d = col.d
    tau = col.tau[1:]
    D = _derivative_matrix(tau, tau)
    smooth = _smooth_inputs(col)
    total = 0.0
    for k in range(len(col.chain)):
        U = sol["U"][k][smooth]
        hs = sol["T"][k] * np.diff(sol["breaks"][k])
        for j, h in enumerate(hs):
            Ud = U[:, j * d : (j + 1) * d] @ D.T / h
            total += h * float(np.sum(Ud**2, axis=0) @ col.weights)
    return total


def fill_sensitivities(col: Any, w: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``w`` with the sensitivity blocks and ``A`` solved from its orbit (the variational
    equations are linear in them: one sparse solve), so a start or a warm start begins on
    them.  Unchanged where the orbit makes them singular (IPOPT then finds them itself)."""
    rows: SpectralRows | None = getattr(col, "spectral", None)
    if rows is None:
        return w
    G, J, index = _fill_function(col)
    w = np.array(w, dtype=float)
    w[index] = 0.0
    g = np.asarray(G(w, p), dtype=float).ravel()
    Jz = J(w, p).sparse()[:, index]
    import scipy.sparse  # here: a problem without a spectral bound never needs SciPy's sparse
    import scipy.sparse.linalg

    try:
        z = scipy.sparse.linalg.spsolve(scipy.sparse.csc_matrix(Jz), -g)
    except (RuntimeError, ValueError):
        return w
    if np.all(np.isfinite(z)):
        w[index] = z
    return w


def _fill_function(col: Any) -> tuple[ca.Function, ca.Function, np.ndarray]:
    """``G(w, p)`` (the rows of the variational equations and ``A``), ``∂G/∂z`` and the
    positions ``z`` of the unknowns they are linear in; built once per transcription."""
    cached = getattr(col, "_spectral_fill", None)
    if cached is not None:
        return cached
    rows: SpectralRows = col.spectral
    B = col.blocks
    index = np.concatenate(
        [np.arange(B.offsets[b], B.offsets[b] + np.prod(B.shapes[B.names.index(b)]))
         for b in rows.blocks]
    )  # fmt: skip
    picked = [
        np.arange(g.start, g.start + g.size)
        for g in col.groups
        if g.name.startswith("variational equations") or g.name == rows.group
    ]
    gi = np.concatenate(picked)
    wsym = col._w
    g_all = col.nlp["g"]
    G = ca.Function("G", [wsym, col._p], [g_all[gi.tolist()]])
    J = ca.Function("J", [wsym, col._p], [ca.jacobian(g_all[gi.tolist()], wsym)])
    col._spectral_fill = (G, J, index)
    return col._spectral_fill
