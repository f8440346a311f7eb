"""Which constraints of an optimal gait are active, and which one a failed solve cannot meet
(the ``active_constraints`` of a result; the message of an infeasible problem).  An input bound
of a least-effort optimum solved with the arcs of its bounds (:func:`gaitopt.optimize.arcs.
detect_bound_arcs`) is listed with its arcs: ``"arcs of the input bounds [lo free lo]"``; a
limit whose touch points are junctions (:func:`gaitopt.optimize.state_arcs.detect_touches`) as
``"touch points of stance knee flexion >= 0 (single support)"``."""

from __future__ import annotations

import numpy as np

from .arcs import bound_arcs_of
from .collocation import Collocation
from .state_arcs import describe_touches


def _violation(col: Collocation, w: np.ndarray, p: np.ndarray) -> tuple[str, float]:
    """The constraint group with the largest violation at ``w`` and its size."""
    g = np.asarray(col.constraints(w, p), dtype=float).ravel()
    worst, name = 0.0, ""
    for group in col.groups:
        sl = slice(group.start, group.start + group.size)
        v = np.maximum(col.lbg[sl] - g[sl], g[sl] - col.ubg[sl])
        v = float(np.max(v)) if v.size else 0.0
        if v > worst:
            worst, name = v, group.name
    return name, worst


def _active(col: Collocation, w: np.ndarray, p: np.ndarray) -> list[str]:
    """Inequality groups and variable bounds that are active (within 1e-6) at ``w``."""
    out = []
    problem = col.problem
    g = np.asarray(col.constraints(w, p), dtype=float).ravel()
    for group in col.groups:
        sl = slice(group.start, group.start + group.size)
        if group.equality:
            if group.name in ("period", "step length", "speed"):
                out.append(f"{group.name} (fixed)")
            continue
        near = np.minimum(np.abs(g[sl] - col.lbg[sl]), np.abs(g[sl] - col.ubg[sl]))
        if near.size and np.min(near) < 1e-6:
            out.append(group.name)
    B = col.blocks
    names = problem.model.inputs
    lows, highs = problem.input_bounds()
    for k in range(len(col.chain)):
        U = B.get(w, f"U{k}")
        for i, name in enumerate(names):
            low, high = lows[i], highs[i]
            if name not in problem.bounds or high <= low:  # unbounded, or switched off
                continue
            tol = 1e-6 * max(abs(low), abs(high))
            count = int(np.sum(U[i] > high - tol) + np.sum(U[i] < low + tol))
            label = f"|{name}| <= {high:g}" if low == -high else f"{low:g} <= {name} <= {high:g}"
            if count and label not in out:
                out.append(label)
        phase = problem.model.phases[col.chain[k]]
        X = B.get(w, f"X{k}")
        for j, state in enumerate(phase.states):
            if state in problem.state_bounds:
                low, high = problem.state_bounds[state]
                tol = 1e-6 * (1 + abs(low) + abs(high))
                hit = np.any(X[j] < low + tol) or np.any(X[j] > high - tol)
                label = f"{low:g} <= {state} <= {high:g}"
                if hit and label not in out:
                    out.append(label)
    # The arcs of active input bounds (least effort's exact stage): where each input sits at
    # its bound, after the bound itself.
    out.extend(bound_arcs_of(col, w, p))
    # Touch points of state bounds and limits made junctions (state_arcs.detect_touches).
    labels = [col._phase_label(k) for k in range(len(col.chain))]
    out.extend(describe_touches(col.structure, labels))
    if problem.free:
        values = B.get(w, "free").ravel()
        lo, hi = problem.free_bounds()
        for name, v, a, b in zip(problem.free, values, lo, hi, strict=True):
            if v < a + 1e-6 * (1 + abs(a)) or v > b - 1e-6 * (1 + abs(b)):
                out.append(f"range of parameter {name}")
    return out


# -- guesses -----------------------------------------------------------------------------------
