"""Touch points of active state bounds and path constraints as free mesh points.

A state bound or selected limit ``c(x, u, p) ≥ 0`` (:attr:`GaitProblem.state_bounds`,
:attr:`GaitProblem.path_constraints`) that is of second order in the input — a joint angle
such as the five-link biped's knee flexion, whose ``c̈`` is the first derivative the torques
reach — binds at isolated instants: touch points, where ``c = 0`` and ``ċ = 0`` (Bryson & Ho
1975, §3.11; Jacobson, Lele & Speyer 1971, "New necessary conditions of optimality for control
problems with state-variable inequality constraints").  There the costate jumps, so the
least-effort input has a kink in its slope.  Inside a mesh interval neither the kink nor the
minimum of ``c`` is a node: the polynomial meets ``c ≥ 0`` at the nodes and dips below it
between them (the knee-limited five-link step of OptimTraj: 4.6e-7 rad at 48 intervals, the
cost settling only to 1.5e-4 under mesh doubling).

As for the arcs of active input bounds (:mod:`gaitopt.optimize.arcs`), the phase is cut at each
touch point read off a first solution (:func:`detect_touches`) and the junction time becomes an
unknown (the arc fractions of the switching-time transcription): at the junction node — the
last Radau point of the interval before it, ``τ = 1``, where the collocation makes the state
polynomial's slope the flow ``f(x, u)`` — the transcription imposes ``ċ = ∇c · f = 0``
(:func:`touch_rows`) besides the node's ``c ≥ 0``.  The minimum of ``c`` is then the node,
where ``c ≥ 0`` holds, the kink is a mesh point, and the refinement converges at the
collocation's order; the dense check of :meth:`Collocation.check_limits` is unchanged.  A
constraint active only at a phase's first or last node (the compass gait's ``swing_dot ≤ 2`` at
heel strike) is already at a mesh point and adds nothing.

This module depends on no transcription module: :class:`~gaitopt.optimize.collocation.
Collocation` calls :func:`touch_rows` while it builds its rows, and
:mod:`gaitopt.optimize.solve` calls :func:`detect_touches` on a solved transcription.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from ..hybrid import rate_along
from .radau import Arc

__all__ = [
    "detect_touches",
    "touch_rows",
    "limit_functions",
    "guard_functions",
    "clearance_functions",
    "guard_touch_structure",
    "describe_touches",
    "touch_times",
]

#: Mesh intervals given to each new arc a touch point opens (before refinement).
TOUCH_INTERVALS = 2
#: A node of a first solution is at its limit within this fraction of ``1 + max |c|``.
ACTIVE_TOL = 1e-6


def limit_functions(col: Any, i: int) -> list[tuple[str, ca.Function]]:
    """``(label, c)`` of every state bound side and selected limit of model phase ``i`` that
    the transcription ``col`` imposes by rows or bounds, ``c(x, u, p) ≥ 0`` wanted; the labels
    are :meth:`Collocation._limit_values`'s (``"swing_dot <= 2"``, ``"stance knee flexion >=
    0"``).  A limit kept by a guard's rows (:meth:`Collocation._kept_by_guard`) is left out."""
    problem, phase = col.problem, col.model.phases[i]
    n, n_u, n_p = phase.n, len(col.model.inputs), phase.flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", n_u), ca.SX.sym("p", n_p)
    out = []
    lo, hi = problem.state_bounds_of(i)
    for j, state in enumerate(phase.states):
        if np.isfinite(lo[j]):
            out.append((f"{state} >= {lo[j]:g}", ca.Function("c", [x, u, p], [x[j] - lo[j]])))
        if np.isfinite(hi[j]):
            out.append((f"{state} <= {hi[j]:g}", ca.Function("c", [x, u, p], [hi[j] - x[j]])))
    for c in problem.limits_of(i):
        if not col._kept_by_guard(i, c):
            out.append((f"{c.name} >= 0", c.function))
    return out


def guard_functions(col: Any, i: int) -> list[tuple[str, ca.Function]]:
    """``(label, c)`` of the side ``c = −direction · g ≥ 0`` of model phase ``i``'s cycle
    transition guard ``g`` when it has no admissibility test (the kneed walker's knee strike:
    the knee flexion ``q3 − q2``): the transcription keeps it at the phase's interior nodes, and
    an optimum may touch it there (the knee straight for an instant before it strikes); the
    label is ``"'knee strike' guard side >= 0"``."""
    tr = col.model.phases[i].transitions[0]
    if tr.admissible is not None:
        return []
    phase = col.model.phases[i]
    n, n_u, n_p = phase.n, len(col.model.inputs), phase.flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", n_u), ca.SX.sym("p", n_p)
    c = -tr.direction * tr.guard(x, u, p)
    return [(f"'{tr.name}' guard side >= 0", ca.Function("c", [x, u, p], [c]))]


#: The label's ending of a length-valued unilateral constraint kept with the clearance margin.
CLEARANCE = ">= clearance margin"


def clearance_functions(col: Any, i: int) -> list[tuple[str, ca.Function]]:
    """``(label, h)`` of every length-valued unilateral constraint of model phase ``i`` (unit
    ``"m"``: a swing foot's height) when the problem has a clearance margin
    (:attr:`GaitProblem.clearance`): the transcription keeps ``h(x) ≥ c · sin(π t / T)`` at
    the nodes (``t`` the time since the step's section, ``T`` the step's duration), and an
    optimum may touch that margin inside a phase (the kneed walker's swing foot at mid-swing,
    0.13 s after heel strike at 0.84 m/s).  The label is ``"'swing foot above the slope' >=
    clearance margin"``; :func:`detect_touches` subtracts the margin from ``h`` and
    :func:`touch_rows` its rate from ``ḣ``."""
    if not col.problem.clearance:
        return []
    return [
        (f"'{c.name}' {CLEARANCE}", c.function)
        for c in col.model.phases[i].constraints
        if c.unit == "m"
    ]


def guard_functions_and_clearance(col: Any, i: int) -> list[tuple[str, ca.Function]]:
    """:func:`guard_functions` and :func:`clearance_functions` of model phase ``i``."""
    return guard_functions(col, i) + clearance_functions(col, i)


def guard_touch_structure(col: Any, w: np.ndarray, p: np.ndarray) -> list[list[Arc]] | None:
    """The arcs of a solved exact-work transcription ``col`` (``w``) cut at the interior touch
    points of its guards' sides (:func:`guard_functions`) and of its clearance margins
    (:func:`clearance_functions`), the touches made junctions with ``ċ = 0`` there
    (:func:`touch_rows`); None without a structure or a touch."""
    if col.structure is None:
        return None
    return detect_touches(col, w, p, col.structure, functions=guard_functions_and_clearance)


def _step_times(col: Any, T: Any, k: int) -> tuple[Any, Any]:
    """``(t₀, T_step)``: the time from phase ``k``'s step section to the phase's start and the
    step's duration, from the phase durations ``T`` (numbers or symbols)."""
    n_cycle = len(col.model.phases)
    first = n_cycle * (k // n_cycle)
    before = sum((T[j] for j in range(first, k)), 0.0 * T[k])
    return before, sum((T[j] for j in range(first + 1, first + n_cycle)), T[first])


def margin_samples(col: Any, T: np.ndarray, k: int, tn: np.ndarray) -> np.ndarray:
    """The clearance margin ``c · sin(π t / T_step)`` (m) at normalised times ``tn`` of phase
    ``k`` (durations ``T``, s)."""
    before, step = _step_times(col, list(T), k)
    return col.problem.clearance * np.sin(np.pi * (before + tn * T[k]) / step)


def margin_rate(col: Any, T: list[Any], hs: list[Any], k: int, end: int) -> Any:
    """The clearance margin's rate ``c π / T_step · cos(π t / T_step)`` (m/s) at the end of
    mesh interval ``end − 1`` of phase ``k`` (``T``: the phases' durations, ``hs``: phase
    ``k``'s interval lengths, symbols)."""
    before, step = _step_times(col, T, k)
    t = before + sum(hs[:end], 0.0 * hs[0])
    return col.problem.clearance * np.pi / step * ca.cos(np.pi * t / step)


def _interior_minima(c: np.ndarray, tol: float) -> list[int]:
    """Indices of the interior local minima of the samples ``c`` at most ``tol``, one per run
    of samples below ``tol`` (its lowest), a run that reaches either end excluded: there the
    constraint binds at the phase's first or last node, already a mesh point."""
    low = c <= tol
    out, j = [], 0
    while j < c.size:
        if not low[j]:
            j += 1
            continue
        e = j
        while e + 1 < c.size and low[e + 1]:
            e += 1
        if j > 0 and e < c.size - 1:
            out.append(j + int(np.argmin(c[j : e + 1])))
        j = e + 1
    return out


def detect_touches(
    col: Any,
    w: np.ndarray,
    p: np.ndarray,
    structure: list[list[Arc]] | None,
    samples: int = 64,
    intervals: int = TOUCH_INTERVALS,
    functions: Any = None,
) -> list[list[Arc]] | None:
    """The arcs of a solved transcription ``col`` (``w``) cut at the interior touch points of
    its state bounds and selected limits; None if there are none (``structure`` then stands).

    A touch point: an interior local minimum of ``c`` on ``samples`` uniform samples per mesh
    interval of the solution's polynomials that is at most ``ACTIVE_TOL (1 + max |c|)`` — at
    its limit, or below it between the nodes.  Its time is the lowest sample's.  ``structure``
    (the arcs of active input bounds, or None: one arc per phase) is cut there; the arc a
    touch ends carries its label in :attr:`Arc.touches`.  The two parts of a cut arc share its
    intervals and ``intervals`` more by length (each at least ``intervals``); every phase then
    gets as many as the one with the most, the extra ones going to the arcs with the longest
    intervals.  ``functions(col, i)``: the constraints to look at (default
    :func:`limit_functions`; :func:`guard_functions` for the guards' sides)."""
    functions = limit_functions if functions is None else functions
    sol = col.unpack(w, p)
    n_u = len(col.model.inputs)
    tn = np.linspace(0.0, 1.0, col.N * samples + 1)
    cuts: list[list[tuple[float, str]]] = []
    for k, i in enumerate(col.chain):
        X, U = col.evaluate(sol["X"][k], sol["U"][k], tn, sol["breaks"][k])
        found = []
        for label, fn in functions(col, i):
            c = np.asarray(fn.map(tn.size)(X, U, sol["p"]), dtype=float).ravel()
            if label.endswith(CLEARANCE):  # h − c sin(π t / T_step)
                c = c - margin_samples(col, sol["T"], k, tn)
            tol = ACTIVE_TOL * (1 + float(np.max(np.abs(c))))
            found.extend((float(tn[j]), label) for j in _interior_minima(c, tol))
        cuts.append(sorted(found))
    if not any(cuts):
        return None
    per_phase = []
    for k, found in enumerate(cuts):
        if structure is not None:
            arcs = list(structure[k])
            theta = col.theta_of(w, k) if col.structure is not None else None
            fractions = list(theta) if theta is not None else [a.fraction for a in arcs]
        else:
            arcs = [Arc(col.N, (), 1.0, (0,) * n_u)]
            fractions = [1.0]
        fractions = list(np.asarray(fractions, dtype=float) / np.sum(fractions))
        counts = [a.intervals for a in arcs]
        for t, label in found:
            edges = np.concatenate([[0.0], np.cumsum(fractions)])
            a = int(np.clip(np.searchsorted(edges, t, side="right") - 1, 0, len(arcs) - 1))
            if min(t - edges[a], edges[a + 1] - t) < 1e-3:  # on a junction already
                b = a if edges[a + 1] - t < t - edges[a] else a - 1
                if 0 <= b < len(arcs) - 1 and label not in arcs[b].touches:
                    arcs[b] = replace(arcs[b], touches=(*arcs[b].touches, label))
                continue
            first, second = t - edges[a], edges[a + 1] - t
            arc = arcs[a]
            arcs[a : a + 1] = [replace(arc, touches=(label,)), arc]
            fractions[a : a + 1] = [first, second]
            # The two parts share the arc's intervals by length, each at least ``intervals``
            # (the phase gains at most ``intervals``).
            n = counts[a] + intervals
            m = int(np.clip(round(n * first / (first + second)), intervals, n - intervals))
            counts[a : a + 1] = [m, n - m]
        per_phase.append((arcs, fractions, counts))
    total = max(sum(counts) for _, _, counts in per_phase)
    out = []
    for arcs, fractions, counts in per_phase:
        for _ in range(total - sum(counts)):  # to the arc with the longest intervals
            j = int(np.argmax([f / n for f, n in zip(fractions, counts, strict=True)]))
            counts[j] += 1
        out.append(
            [
                replace(a, intervals=n, fraction=max(float(f), 1e-3))
                for a, n, f in zip(arcs, counts, fractions, strict=True)
            ]
        )
    return out


def touch_rows(
    col: Any, k: int, i: int, Xk: Any, Uk: Any, p: Any, label: str, add: Any,
    times: tuple[list[Any], list[Any]] | None = None,
) -> None:  # fmt: skip
    """Rows ``ċ = ∇c · f(x, u, p) = 0`` at each junction of phase ``k`` (model phase ``i``)
    that ends an arc with touches (:attr:`Arc.touches`): the node is the last Radau point of
    the interval before the junction, where the collocation makes the state polynomial's slope
    the flow, so the polynomial's ``c`` is stationary there.  For a clearance margin
    (:func:`clearance_functions`) ``ḣ`` less the margin's rate (:func:`margin_rate`; ``times``:
    the phases' durations and phase ``k``'s interval lengths, symbols)."""
    structure = col.structure[k]
    d = col.d
    flow = col.model.phases[i].flow
    functions = dict(limit_functions(col, i))
    if any(name not in functions for arc in structure for name in arc.touches):
        functions.update(guard_functions_and_clearance(col, i))
    end = 0
    for arc in structure[:-1]:
        end += arc.intervals
        for name in arc.touches:
            rate = rate_along(flow, functions[name])(Xk[:, end * d], Uk[:, end * d - 1], p)
            if name.endswith(CLEARANCE):
                if times is None:
                    raise ValueError(f"touch_rows: the touch of {name} needs the phase times")
                rate = rate - margin_rate(col, times[0], times[1], k, end)
            add(f"touch of '{name}' at a junction ({label})", rate)


def describe_touches(structure: list[list[Arc]] | None, labels: list[str]) -> list[str]:
    """``["touch points of stance knee flexion >= 0 (single support)"]``: the limits whose
    touch points are junctions, one per limit and phase (``labels``: the phases' names), no
    times (the active set of a library compares these)."""
    if structure is None:
        return []
    out = []
    for arcs, phase in zip(structure, labels, strict=True):
        for name in dict.fromkeys(n for a in arcs for n in a.touches):
            out.append(f"touch points of {name} ({phase})")
    return out


def arc_edges(col: Any, w: np.ndarray, p: np.ndarray) -> list[tuple[int, Any, np.ndarray]]:
    """Per phase of a solved transcription with arcs: ``(k, arcs, edges)``, the edges the arcs'
    start and end times (s since the section, len(arcs) + 1); empty without arcs."""
    if col.structure is None:
        return []
    sol = col.unpack(w, p)
    out, t0 = [], 0.0
    for k, arcs in enumerate(col.structure):
        out.append(
            (k, arcs, t0 + sol["T"][k] * np.concatenate([[0.0], np.cumsum(col.theta_of(w, k))]))
        )
        t0 += sol["T"][k]
    return out


def touch_times(col: Any, w: np.ndarray, p: np.ndarray) -> list[str]:
    """The touch points of a solved transcription with their times (s since the section):
    ``"stance knee flexion >= 0 at 0.651808 s"``; empty without touches."""
    return [
        f"{name} at {edges[a + 1]:.6g} s"
        for _, arcs, edges in arc_edges(col, w, p)
        for a, arc in enumerate(arcs)
        for name in arc.touches
    ]
