"""Boundary arcs of a guard: an input that holds its joint with the phase's guard at zero.

The kneed walker's swing knee leaves heel strike straight — its knee-strike guard, the knee
flexion ``c = q3 − q2`` kept ``≥ 0`` inside the three-link phase (:func:`gaitopt.optimize.
state_arcs.guard_functions`), is at zero with zero rate — and a powered knee may hold it there
with its torque a while before it lets the knee fold (the least cost of transport at |τ_k| ≤
5 N·m does, for 0.047 s).  That is a boundary arc of a state constraint of second order (Bryson
& Ho 1975, §3.11; Jacobson, Lele & Speyer 1971): ``c ≡ 0`` on it, so ``ċ ≡ 0`` and ``c̈ ≡ 0``,
and ``c̈ = 0`` — the first derivative the torque reaches — is the equation that gives the
torque (index reduction).  Its entry and exit are junctions: the arc's duration is an unknown of
the switching-time transcription (:class:`~gaitopt.optimize.radau.Arc`) like any other arc's.

On a boundary arc (the input's kind :data:`~gaitopt.optimize.radau.BOUNDARY`) the
transcription imposes (:func:`boundary_rows`):

* ``ċ(x) = 0`` at the arc's collocation points: with ``ċ = 0`` at the entry, the polynomial
  ``ċ(x(τ))`` (linear in the state: the knee's ``q̇3 − q̇2``) vanishes at ``d + 1`` points of
  each interval, so everywhere, and ``c`` stays at its entry value 0.  With the collocation
  equations ``ẋ(τⱼ) = f(xⱼ, uⱼ)`` these rows are the acceleration constraint ``c̈(xⱼ, uⱼ) =
  ∇ċ · f = 0`` at the Radau points (the slope of a polynomial that vanishes is zero), the
  equation that fixes the torque — but linear in the unknowns, which IPOPT keeps satisfied
  once met: from the passive-knee optimum the rows ``c̈ = 0`` themselves did not converge on
  the knee-powered statement (271 iterations, the arc grown over the whole phase) where these
  do in 22.  ``tests/test_boundary_arcs.py`` checks ``c̈ = 0`` at the points of a solution;
* ``c = 0`` and ``ċ = 0`` at its entry — unless the entry is the first node of the orbit's
  first phase and the section makes both vanish identically there (the kneed walker's section
  ``q3 = q2``, ``q̇3 = q̇2``: rows of zero gradient, which IPOPT cannot use);
* no row of the guard's side ``c ≥ 0`` at its nodes (:func:`boundary_nodes`): there ``c = 0``
  follows from the rows above, and an inequality held at its bound by equalities leaves the
  active set degenerate.

The input's power ``u ω`` vanishes on the arc (its rate is ``±ċ``), so it adds nothing to the
positive work, and it is no braking arc.  :func:`held_on_guard` finds such arcs among the held
arcs (:data:`~gaitopt.optimize.radau.HELD`: ``ω ≡ 0``) of a first solution: where the input's
rate is the guard's rate (up to sign) and the guard is at zero over the arc.  The dense check
and the simulation are unchanged (a boundary arc stays on the guard's side: the simulator's knee
strike is a crossing, not a touch).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from ..hybrid import rate_along
from .radau import BOUNDARY, HELD, Arc
from .state_arcs import arc_edges, guard_functions

__all__ = [
    "boundary_nodes",
    "boundary_rows",
    "boundary_spans",
    "guard_rate_input",
    "held_on_guard",
]

#: Samples in the first half of each held arc at which a first solution's guard side is read.
SAMPLES = 9
#: The guard side is at zero on a first solution's held arc within this fraction of
#: ``1 + max |c|``: the slack solution's own precision, with which
#: :func:`~gaitopt.optimize.arcs.detect_structure` calls a joint held (its knee flexion there
#: 3e-5 rad at most, of 0.34).
SMALL = 1e-4


def guard_rate_input(col: Any, i: int) -> tuple[ca.Function, int, int] | None:
    """``(c, r, σ)``: the side ``c ≥ 0`` of model phase ``i``'s guard (without admissibility
    test; :func:`~gaitopt.optimize.state_arcs.guard_functions`) and the input ``r`` whose
    rate is ``σ ċ`` (``σ = ±1``), with ``ċ`` free of the inputs; None if there is none."""
    guards = guard_functions(col, i)
    if not guards:
        return None
    c = guards[0][1]
    flow = col.model.phases[i].flow
    crate = rate_along(flow, c)
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", n_u), ca.SX.sym("p", n_p)
    if ca.depends_on(crate(x, u, p), u):
        return None
    rates = col.model.input_rates(i)
    if rates is None:  # a model without inputs' rates in this phase
        return None
    rng = np.random.default_rng(0)
    xs = rng.normal(size=(n, 3))
    pv = col.model.p
    cr = np.asarray(crate.map(3)(xs, np.zeros((n_u, 3)), pv), dtype=float).ravel()
    om = np.asarray(rates.map(3)(xs, pv), dtype=float)
    scale = 1e-9 * (1 + np.max(np.abs(cr)))
    for r in range(om.shape[0]):
        for sigma in (1, -1):
            if np.max(np.abs(om[r] - sigma * cr)) <= scale:
                return c, r, sigma
    return None


def held_on_guard(
    col: Any, w: np.ndarray, p: np.ndarray, structure: list[list[Arc]]
) -> list[list[Arc]]:
    """``structure`` (arcs of a first solution ``w`` of ``col``, per phase) with each held
    arc of the input whose rate is the guard's (:func:`guard_rate_input`) made a boundary arc
    (:data:`~gaitopt.optimize.radau.BOUNDARY`) where the solution's guard side is at zero —
    within :data:`SMALL` ``(1 + max |c|)`` at :data:`SAMPLES` points of the arc's first half
    (a slack solution's held arc ends a node or two late, where the joint already moves)."""
    sol = col.unpack(w, p)
    out = []
    for k, i in enumerate(col.chain):
        arcs = list(structure[k])
        found = guard_rate_input(col, i)
        if found is None or not any(a.signs[found[1]] == HELD for a in arcs):
            out.append(arcs)
            continue
        c, r, _ = found
        fractions = np.array([a.fraction for a in arcs], dtype=float)
        edges = np.concatenate([[0.0], np.cumsum(fractions / fractions.sum())])
        every = np.linspace(0.0, 1.0, col.N * 16 + 1)
        n_u = len(col.model.inputs)
        for a, arc in enumerate(arcs):
            if arc.signs[r] != HELD:
                continue
            inside = edges[a] + (edges[a + 1] - edges[a]) * np.linspace(0.0, 0.5, SAMPLES)
            tn = np.concatenate([inside, every])
            X, _ = col.evaluate(sol["X"][k], sol["U"][k], tn, sol["breaks"][k])
            values = np.asarray(c.map(tn.size)(X, np.zeros((n_u, tn.size)), sol["p"]), dtype=float)
            values = values.ravel()
            tol = SMALL * (1 + float(np.max(np.abs(values))))
            if np.max(np.abs(values[:SAMPLES])) <= tol:
                signs = tuple(BOUNDARY if j == r else s for j, s in enumerate(arc.signs))
                arcs[a] = replace(arc, signs=signs)
        out.append(arcs)
    return out


def _boundary_intervals(col: Any, k: int) -> tuple[np.ndarray, int | None]:
    """Per mesh interval of phase ``k``, whether it is on a boundary arc, and the input that
    holds it (None without one)."""
    kinds = np.array(
        [arc.signs for arc in col.structure[k] for _ in range(arc.intervals)], dtype=int
    ).T  # n_u × N
    held = np.any(kinds == BOUNDARY, axis=0)
    inputs = np.unique(np.nonzero(kinds == BOUNDARY)[0])
    return held, (int(inputs[0]) if inputs.size else None)


def boundary_nodes(col: Any, k: int) -> np.ndarray | None:
    """Mask of phase ``k``'s collocation points (``N·d``) on boundary arcs, where the guard's
    side needs no row; None without a structure or a boundary arc."""
    if col.structure is None:
        return None
    held, _ = _boundary_intervals(col, k)
    return np.repeat(held, col.d) if held.any() else None


def _vanishes_on_section(col: Any, fn: ca.Function) -> bool:
    """Whether ``fn(lift(s), 0, p)`` vanishes for every section point ``s`` (checked at three
    random points to 1e-12): then a row of it at the orbit's first node has no gradient."""
    section, model = col.model.section, col.model
    rng = np.random.default_rng(1)
    n_u = len(model.inputs)
    for _ in range(3):
        s = rng.normal(scale=0.3, size=len(section.coordinates))
        x = np.asarray(section.lift(s, model.p), dtype=float).ravel()
        if not np.all(np.isfinite(x)) or abs(float(fn(x, np.zeros(n_u), model.p))) > 1e-12:
            return False
    return True


def boundary_rows(col: Any, add: Any, k: int, i: int, Xk: Any, Uk: Any, p: Any, label: str) -> None:
    """The rows of phase ``k``'s (model phase ``i``'s) boundary arcs: ``ċ = 0`` at their
    collocation points (with the collocation equations, ``c̈ = 0`` there), ``c = 0`` and
    ``ċ = 0`` at each entry (not where the section makes them vanish identically)."""
    if col.structure is None:
        return
    held, r = _boundary_intervals(col, k)
    if r is None:
        return
    found = guard_rate_input(col, i)
    if found is None or found[1] != r:
        raise ValueError(f"boundary arcs in {label}: input {r} does not hold the phase's guard")
    c = found[0]
    crate = rate_along(col.model.phases[i].flow, c)
    d = col.d
    nodes = [j for j in range(col.N * d) if held[j // d]]
    add(f"boundary arc of the guard: its rate zero ({label})",
        crate.map(len(nodes))(Xk[:, [j + 1 for j in nodes]], Uk[:, nodes], p))  # fmt: skip
    entries = [j for j in range(col.N) if held[j] and (j == 0 or not held[j - 1])]
    rows = []
    for j in entries:
        x, u = Xk[:, j * d], Uk[:, j * d]
        for fn in (c, crate):
            if j == 0 and k == 0 and _vanishes_on_section(col, fn):
                continue
            rows.append(fn(x, u, p))
    if rows:
        add(f"boundary arc of the guard: entry on the guard ({label})", ca.vertcat(*rows))


def boundary_spans(col: Any, w: np.ndarray, p: np.ndarray) -> list[str]:
    """The boundary arcs of a solved transcription with their times (s since the section):
    ``"knee_torque holds the 'knee strike' guard on [0, 0.0473] s"``; empty without one."""
    out = []
    for k, arcs, edges in arc_edges(col, w, p):
        name = col.model.phases[col.chain[k]].transitions[0].name
        spans: list[list[float]] = []
        for a, arc in enumerate(arcs):
            if BOUNDARY not in arc.signs:
                continue
            if spans and spans[-1][1] == a:  # continues the previous boundary arc
                spans[-1][1:] = [a + 1, spans[-1][2]]
            else:
                spans.append([a, a + 1, arc.signs.index(BOUNDARY)])
        for first, last, r in spans:
            out.append(
                f"{col.model.inputs[int(r)]} holds the '{name}' guard on "
                f"[{edges[int(first)]:.6g}, {edges[int(last)]:.6g}] s"
            )
    return out
