"""The arcs of a work-based cost read off the first (slack) solution, as the switching-time
transcription's structure (:class:`gaitopt.optimize.collocation.Arc`): per input, where its
power is positive or negative (and whether it sits at a bound there), where it coasts
(``u ≡ 0``) and where it holds its joint (``ω ≡ 0``, ``u ≠ 0``); the nodes of a switch caught
inside a mesh interval are shared out between their neighbours.

The arcs of active input bounds for a cost without powers (least effort,
:func:`detect_bound_arcs`): where the first solution's inputs sit at a bound.  The least-effort
input is the saturation of a smooth one, ``u = sat(−Bᵀλ/2)``: continuous, with a kink where it
meets its bound.  Inside a mesh interval that kink is beyond the input polynomial, and the
refinement stalls (the compass gait at |τ| ≤ 4 N·m: 2.5e-6 after three doublings).  With arcs
(the input fixed at its bound on a saturated arc, collocated as usual on a free one, the arcs'
durations unknowns) every kink falls on an arc boundary, where the optimum puts it, and the
refinement converges as for an unbounded optimum (the same: 8.1013036998 N²·m²·s, 5.3e-11).
The junction times alone are pinned only to third order (a junction moved by δ costs
~|u̇|²δ³): the transcription also makes the free arc's input meet the bound at each junction
(u is continuous there, :meth:`Collocation._bound_arcs`), else a first solution can hide the
kink inside the free arc's first interval.  An inactive bound (no node at it) leaves the
transcription as it is."""

from __future__ import annotations

from typing import Any

import numpy as np

from .collocation import Arc, Collocation
from .radau import BOUNDARY, COAST, HELD, NEGATIVE, POSITIVE

#: Mesh intervals per arc of the switching-time transcription, before refinement.
ARC_INTERVALS = 2


_SYMBOLS = {POSITIVE: "+", NEGATIVE: "-", COAST: "coast", HELD: "held", BOUNDARY: "boundary"}


def _describe(structure: list[list[Arc]]) -> str:
    """``+lo coast held -lo +lo`` per phase (per input, joined by ``/``; ``lo``, ``hi``: at its
    lower or upper bound)."""
    phases = []
    for arcs in structure:
        words = []
        for a in arcs:
            bounds = a.bounds or (0,) * len(a.signs)
            words.append(
                "/".join(
                    _SYMBOLS[s] + ("lo" if b < 0 else "hi" if b > 0 else "")
                    for s, b in zip(a.signs, bounds, strict=True)
                )
            )
        phases.append(" ".join(words))
    return "; ".join(f"[{p}]" for p in phases)


def detect_structure(
    col: Collocation, w: np.ndarray, p: np.ndarray, intervals: int = ARC_INTERVALS
) -> list[list[Arc]]:
    """Arcs of a slack solution: maximal runs of nodes on which every input keeps its kind,
    the switch put halfway between the last node of a run and the first of the next.

    An input's kind at a node: coasting (:data:`~gaitopt.optimize.radau.COAST`) where it is
    within 10⁻⁴ of its range of zero (or at a bound of 0), else a held joint
    (:data:`~gaitopt.optimize.radau.HELD`) where its rate is within 10⁻⁴ of its largest of
    zero, else its power sign, with the bound it sits at (within 10⁻⁴ of its range).  A run of
    at most :data:`BLIP_NODES` nodes inside a phase with no input at a bound is a switch
    falling inside a mesh interval (its nodes see the mixture), not an arc: its neighbours
    share it.  An input whose rate vanishes identically in a phase is ``−``.

    Returns, per phase of the orbit, its arcs with ``intervals`` mesh intervals each (a phase
    with fewer arcs than another gives its longest arcs the spare intervals, so that every
    phase has the same count)."""
    sol = col.unpack(w, p)
    model = col.model
    low, high = col.problem.input_bounds()
    per_phase = []
    for k, i in enumerate(col.chain):
        X, U = sol["X"][k][:, 1:], sol["U"][k]
        rates = np.asarray(model.input_rates(i).map(X.shape[1])(X, sol["p"]), dtype=float)
        power = U * rates
        # Small is 1e-4 of the input's range (its bounds, else its largest value) or of the
        # rate's largest value: the slack solution leaves an input wandering by ~1e-7 of its
        # range where the cost is flat.
        finite = np.isfinite(low) & np.isfinite(high)
        largest = np.max(np.abs(U), axis=1) + 1e-12
        span = np.where(finite, np.where(finite, high - low, 0.0), largest)[:, None]
        u_small = np.abs(U) <= 1e-4 * span
        w_small = np.abs(rates) <= 1e-4 * (np.max(np.abs(rates), axis=1, keepdims=True) + 1e-12)
        kind = np.where(
            u_small, COAST, np.where(w_small, HELD, np.where(power > 0, POSITIVE, NEGATIVE))
        )
        bound = np.where(
            U <= low[:, None] + 1e-4 * span, -1, np.where(U >= high[:, None] - 1e-4 * span, 1, 0)
        )
        bound[~np.isin(kind, (POSITIVE, NEGATIVE))] = 0
        # At a bound of 0 (a one-sided input) the input vanishes: it coasts.
        at_zero = ((bound < 0) & (low[:, None] == 0)) | ((bound > 0) & (high[:, None] == 0))
        kind[at_zero], bound[at_zero] = COAST, 0
        idle = col._idle_inputs(i)
        kind[idle, :], bound[idle, :] = NEGATIVE, 0
        times = col.node_times(sol["breaks"][k])[1:]
        runs: list[list] = []  # [first node, last node, (kinds, bounds)]
        for c in range(kind.shape[1]):
            signs = (tuple(int(v) for v in kind[:, c]), tuple(int(v) for v in bound[:, c]))
            if runs and runs[-1][2] == signs:
                runs[-1][1] = c
            else:
                runs.append([c, c, signs])
        runs = _absorb_switches(runs)
        arcs, start = [], 0.0
        for a, b in zip(runs[:-1], runs[1:], strict=True):
            switch = 0.5 * (times[a[1]] + times[b[0]])
            arcs.append((switch - start, a[2]))
            start = switch
        arcs.append((1.0 - start, runs[-1][2]))
        per_phase.append(_merge_blips(arcs, 0.5 / col.N))
    most = max(len(a) for a in per_phase)
    total = intervals * most
    structure = []
    for arcs in per_phase:
        counts = [intervals] * len(arcs)
        order = np.argsort([-f for f, _ in arcs])
        for extra in range(total - sum(counts)):
            counts[int(order[extra % len(arcs)])] += 1
        structure.append(
            [
                Arc(n, kinds, max(f, 1e-3), bounds if any(bounds) else ())
                for n, (f, (kinds, bounds)) in zip(counts, arcs, strict=True)
            ]
        )
    return structure


def structure_of(
    col: Collocation | None, w: np.ndarray | None, intervals: int = ARC_INTERVALS
) -> list[list[Arc]] | None:
    """The arcs of a solved switching-time transcription (``col``, ``w``) with ``intervals``
    mesh intervals each and its arc durations as guesses (None if it has no structure): a
    neighbour's arcs, to try where a slack solution's fail."""
    if col is None or w is None or col.structure is None:
        return None
    most = max(len(arcs) for arcs in col.structure)
    out = []
    for k, arcs in enumerate(col.structure):
        theta = col.theta_of(w, k)
        counts = [intervals] * len(arcs)
        order = np.argsort(-theta)
        for extra in range(intervals * most - sum(counts)):
            counts[int(order[extra % len(arcs)])] += 1
        out.append(
            [
                Arc(n, a.signs, max(float(f), 1e-3), a.bounds)
                for n, a, f in zip(counts, arcs, theta, strict=True)
            ]
        )
    return out


#: Runs of at most this many nodes inside a phase are switches, not arcs.
BLIP_NODES = 2


def _absorb_switches(runs: list[list]) -> list[list]:
    """Runs without the nodes of a switch: an inner run of at most :data:`BLIP_NODES` nodes
    with no input at a bound (a rate or an input passing through zero where the power changes
    sign, an input caught between its bound and zero where it jumps) is split between its
    neighbours (joined if they are alike), shortest first.  Short bang runs are kept."""
    runs = [list(r) for r in runs]
    while True:
        inner = [
            j
            for j in range(1, len(runs) - 1)
            if runs[j][1] - runs[j][0] + 1 <= BLIP_NODES and not any(runs[j][2][1])
        ]
        if not inner:
            return runs
        j = min(inner, key=lambda j: runs[j][1] - runs[j][0])
        before, blip, after = runs[j - 1], runs[j], runs[j + 1]
        if before[2] == after[2]:
            runs[j - 1 : j + 2] = [[before[0], after[1], before[2]]]
        else:
            middle = (blip[0] + blip[1]) // 2  # the first half (with the middle) goes before
            runs[j - 1 : j + 2] = [[before[0], middle, before[2]], [middle + 1, after[1], after[2]]]


def _merge_blips(arcs: list[tuple[float, Any]], shortest: float) -> list[tuple[float, Any]]:
    """Arcs without blips: an arc shorter than ``shortest`` (a fraction of the phase) between
    two arcs of the same kinds, or next to an arc of its own kinds, is merged with them — a
    node or two where the input passes between classes at a switch, or noise where the cost is
    flat, not a switch of the optimum's own — unless an input sits at a bound on it (a short
    bang, such as the kneed walker's braking pulse of the hip, is the optimum's own); then
    neighbours of the same kinds are joined (the transcription treats them alike, so a switch
    between them would be a free variable the cost does not fix).  ``kinds`` are compared
    whole (an arc's kinds and bounds)."""
    arcs = list(arcs)
    changed = True
    while changed and len(arcs) >= 2:
        changed = False
        for j, (f, signs) in enumerate(arcs):
            bang = isinstance(signs, tuple) and len(signs) == 2 and any(np.ravel(signs[1]))
            if f >= shortest or bang:
                continue
            before = arcs[j - 1][1] if j > 0 else None
            after = arcs[j + 1][1] if j + 1 < len(arcs) else None
            if before is not None and before == after:
                lo, hi, signs = j - 1, j + 1, before
            else:
                lo = j - 1 if before == signs else j
                hi = j + 1 if after == signs else j
            if lo == hi:
                continue
            arcs[lo : hi + 1] = [(sum(a[0] for a in arcs[lo : hi + 1]), signs)]
            changed = True
            break
    joined: list[tuple[float, tuple[int, ...]]] = []
    for f, signs in arcs:
        if joined and joined[-1][1] == signs:
            joined[-1] = (joined[-1][0] + f, signs)
        else:
            joined.append((f, signs))
    return joined


# -- the arcs of active input bounds (costs without powers: least effort) ----------------------

#: An input is at its bound at a node of the first solution within this fraction of its range
#: (its bound's size for a one-sided range).  Least effort is strictly convex in the input, so
#: the first solution leaves no input wandering near a bound: IPOPT puts the nodes on a bound
#: to ~1e-11 of it, and a free node this close is within ~1e-6 of the phase of the junction.
BOUND_TOL = 1e-6


def detect_bound_arcs(
    col: Collocation, w: np.ndarray, p: np.ndarray, intervals: int = ARC_INTERVALS
) -> list[list[Arc]] | None:
    """Arcs of active input bounds read off a first solution of a cost without powers
    (least effort): maximal runs of nodes on which every input keeps its side (at its upper
    bound ``+1``, its lower ``−1``, free ``0``), the junction put halfway between the last node
    of a run and the first of the next; None if no input reaches a bound at any node (the
    inactive bound leaves the transcription alone).

    Impulsive inputs (one value per step) and inputs switched off by their bounds are free
    throughout (already constant).  Each arc gets at least ``intervals`` mesh intervals; a
    phase gets at least as many as ``col`` has (the extra ones go to the longest arcs per
    interval), and every phase the same count.  The arcs' ``signs`` are empty: the
    transcription reads only their ``bounds`` (:meth:`Collocation._bound_arcs`)."""
    sol = col.unpack(w, p)
    low, high = col.problem.input_bounds()
    n_u = len(low)
    finite = np.isfinite(low) | np.isfinite(high)
    span = np.where(
        np.isfinite(low) & np.isfinite(high),
        high - low,
        np.where(np.isfinite(high), np.abs(high), np.abs(low)),
    )
    span = np.where(span > 0, span, 1.0)
    usable = finite & (high > low)
    usable[list(col.problem.impulsive_index)] = False
    if not np.any(usable):
        return None
    per_phase, touched = [], False
    for k in range(len(col.chain)):
        U = sol["U"][k]
        tol = (BOUND_TOL * span)[:, None]
        side = np.where(U >= high[:, None] - tol, 1, np.where(U <= low[:, None] + tol, -1, 0))
        side[~usable, :] = 0
        touched = touched or bool(np.any(side))
        times = col.node_times(sol["breaks"][k])[1:]
        runs: list[list] = []
        for c in range(side.shape[1]):
            key = tuple(int(v) for v in side[:, c])
            if runs and runs[-1][2] == key:
                runs[-1][1] = c
            else:
                runs.append([c, c, key])
        arcs, start = [], 0.0
        for a, b in zip(runs[:-1], runs[1:], strict=True):
            switch = 0.5 * (times[a[1]] + times[b[0]])
            arcs.append((switch - start, a[2]))
            start = switch
        arcs.append((1.0 - start, runs[-1][2]))
        per_phase.append(arcs)
    if not touched:
        return None
    most = max(len(a) for a in per_phase)
    total = max(intervals * most, col.N)
    structure = []
    for arcs in per_phase:
        counts = [intervals] * len(arcs)
        for _ in range(total - sum(counts)):  # to the arc with the longest intervals
            j = int(np.argmax([f / n for (f, _), n in zip(arcs, counts, strict=True)]))
            counts[j] += 1
        structure.append(
            [
                Arc(n, (), max(f, 1e-3), side if any(side) else (0,) * n_u)
                for n, (f, side) in zip(counts, arcs, strict=True)
            ]
        )
    return structure


def describe_bounds(structure: list[list[Arc]], inputs: tuple[str, ...] | list[str]) -> str:
    """``[free hi free lo]`` per phase (per input, joined by ``/`` when there are several:
    ``hi``, ``lo`` at its upper or lower bound, ``free`` inside)."""
    words = {1: "hi", -1: "lo", 0: "free"}
    phases = []
    for arcs in structure:
        phases.append(
            " ".join(
                "/".join(words[int(b)] for b in (a.bounds or (0,) * len(inputs))) for a in arcs
            )
        )
    return "; ".join(f"[{p}]" for p in phases)


def _has_bound_arcs(col: Collocation) -> bool:
    """Whether ``col`` is transcribed with arcs of input bounds (a structure of a cost without
    powers with an input at a bound on some arc; touch points alone are not)."""
    if col.structure is None or col.problem.cost_kind in ("work", "cot"):
        return False
    return any(any(a.bounds) for arcs in col.structure for a in arcs)


def bound_arcs_of(col: Collocation, w: np.ndarray, p: np.ndarray) -> list[str]:
    """The arcs of a solved transcription with arcs of input bounds, for the active set:
    ``["arcs of the input bounds [lo free lo]"]`` (:func:`describe_bounds`; no times, so that
    the points of a library with the same arcs have the same active set, and a new saturated
    arc is a change of it); empty without such a structure.  ``p`` is unused (the signature
    of the other active-set readers)."""
    del w, p
    if not _has_bound_arcs(col):
        return []
    return [f"arcs of the input bounds {describe_bounds(col.structure, col.model.inputs)}"]


def saturated_spans(col: Collocation, w: np.ndarray, p: np.ndarray) -> list[str]:
    """The saturated arcs of a solved transcription with arcs of input bounds, with their
    times: ``"hip_torque = -4 on [0, 0.407938] s"`` (time since the section), one per arc and
    input at a bound; empty without such a structure."""
    if not _has_bound_arcs(col):
        return []
    sol = col.unpack(w, p)
    low, high = col.problem.input_bounds()
    names = col.model.inputs
    out, t0 = [], 0.0
    for k, arcs in enumerate(col.structure):
        theta = col.theta_of(w, k)
        edges = t0 + sol["T"][k] * np.concatenate([[0.0], np.cumsum(theta)])
        for a, arc in enumerate(arcs):
            for r, b in enumerate(arc.bounds):
                if b:
                    value = high[r] if b > 0 else low[r]
                    out.append(f"{names[r]} = {value:g} on [{edges[a]:.6g}, {edges[a + 1]:.6g}] s")
        t0 += sol["T"][k]
    return out
