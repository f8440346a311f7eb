"""The arcs of a work-based cost: where each input's power changes sign on the first (slack)
solution, with short blips merged, as the switching-time transcription's structure
(:class:`gaitopt.optimize.collocation.Arc`)."""

from __future__ import annotations

import numpy as np

from .collocation import Arc, Collocation

#: Mesh intervals per arc of the switching-time transcription, before refinement.
ARC_INTERVALS = 2


def _describe(structure: list[list[Arc]]) -> str:
    """``+ − +`` per phase (per input, joined by ``/``)."""
    phases = []
    for arcs in structure:
        phases.append(" ".join("/".join("+" if s > 0 else "-" for s in a.signs) for a in arcs))
    return "; ".join(f"[{p}]" for p in phases)


def detect_structure(
    col: Collocation, w: np.ndarray, p: np.ndarray, intervals: int = ARC_INTERVALS
) -> list[list[Arc]]:
    """Arcs of a slack solution: maximal runs of nodes on which every input keeps its class,
    the switch put halfway between the last node of a run and the first of the next.

    An input's class at a node is its bound (lower, upper, neither) with its power sign
    (``+``: ``uω > δ``, ``−``: ``uω < −δ``), or for a power within ``δ`` (10⁻⁶ of the largest)
    whether the input vanishes (``u ≈ 0``, a coasting arc) or the rate does (``ω ≈ 0``, a
    held joint): the input may jump wherever the class changes.  An arc's sign is ``+`` if its
    power is positive, else ``−`` (power ≤ 0, not counted).

    Returns, per phase of the orbit, its arcs with ``intervals`` mesh intervals each (a phase
    with fewer arcs than another gives its longest arcs the spare intervals, so that every
    phase has the same count)."""
    sol = col.unpack(w, p)
    problem, model = col.problem, col.model
    low, high = problem.input_bounds()
    per_phase = []
    for k, i in enumerate(col.chain):
        X, U = sol["X"][k][:, 1:], sol["U"][k]
        rates = np.asarray(model.input_rates(i).map(X.shape[1])(X, sol["p"]), dtype=float)
        power = U * rates
        scale = 1e-6 * (np.max(np.abs(power), axis=1, keepdims=True) + 1e-12)
        u_scale = 1e-6 * (np.max(np.abs(U), axis=1, keepdims=True) + 1e-12)
        # Power class: +1 positive, -1 negative, 0 input ≈ 0, 2 rate ≈ 0 (input held).
        kind = np.where(
            power > scale, 1, np.where(power < -scale, -1, np.where(np.abs(U) <= u_scale, 0, 2))
        )
        span = np.where(np.isfinite(high), high - low, 1.0)[:, None]
        bound = np.where(
            U <= low[:, None] + 1e-4 * span, -1, np.where(U >= high[:, None] - 1e-4 * span, 1, 0)
        )
        classes = [tuple(kind[:, c]) + tuple(bound[:, c]) for c in range(U.shape[1])]
        n_u = U.shape[0]

        def signs(cls: tuple[int, ...], n_u: int = n_u) -> tuple[int, ...]:
            return tuple(1 if v == 1 else -1 for v in cls[:n_u])

        times = col.node_times(sol["breaks"][k])[1:]
        arcs, start = [], 0.0
        current = classes[0]
        for c in range(1, len(classes)):
            if classes[c] != current:
                switch = 0.5 * (times[c - 1] + times[c])
                arcs.append((switch - start, signs(current)))
                start, current = switch, classes[c]
        arcs.append((1.0 - start, signs(current)))
        per_phase.append(_merge_blips(arcs, 1.0 / col.N))
    most = max(len(a) for a in per_phase)
    total = intervals * most
    structure = []
    for arcs in per_phase:
        counts = [intervals] * len(arcs)
        order = np.argsort([-f for f, _ in arcs])
        for extra in range(total - sum(counts)):
            counts[int(order[extra % len(arcs)])] += 1
        structure.append(
            [Arc(n, signs, max(f, 1e-3)) for n, (f, signs) in zip(counts, arcs, strict=True)]
        )
    return structure


def _merge_blips(
    arcs: list[tuple[float, tuple[int, ...]]], shortest: float
) -> list[tuple[float, tuple[int, ...]]]:
    """Arcs without blips: an arc shorter than ``shortest`` (a fraction of the phase) between
    two arcs of the same signs, or next to an arc of its own signs, is merged with them — a
    node or two where the input passes between classes at a switch, or noise where the cost is
    flat (a coasting arc), not a switch of the optimum's own; then neighbours of the same signs
    are joined (the transcription treats them alike, so a switch between them would be a free
    variable the cost does not fix)."""
    arcs = list(arcs)
    changed = True
    while changed and len(arcs) >= 2:
        changed = False
        for j, (f, signs) in enumerate(arcs):
            if f >= shortest:
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
