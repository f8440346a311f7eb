"""Arcs that collapse against a phase change: a phase's last arc shrunk to nothing before the
next phase of the same step begins.

With the inputs continuous where one phase of a step hands over to the next
(:attr:`GaitProblem.continuous_inputs`: the kneed walker's knee strike), an optimum that wants its
input to jump *at* the phase change cannot have it; the exact work stage then puts the jump
onto a last arc that shrinks against the phase's end (a hip torque held at its bound up to a
coasting sliver of 1e-6 of the phase before the knee strike, coasting on after it), and the
refinement creeps along that sliver without settling (the kneed walker on level ground: the
orbit moved by 1e-7 per mesh doubling).  :func:`move_collapsed_arcs` takes the sliver out and
lets the arc before it continue into the next phase instead, as that phase's first arc with a
free duration, so the input is continuous at the phase change and its jump is a junction of the
next phase where the optimum puts it.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from .arcs import ARC_INTERVALS
from .radau import COAST, NEGATIVE, Arc

__all__ = ["COLLAPSED", "move_collapsed_arcs", "warm_start"]

#: A last arc shorter than this share of its phase has collapsed.
COLLAPSED = 1e-4
#: The guess of the continued arc's share of the next phase.
CONTINUED = 0.02


def move_collapsed_arcs(col: Any, w: np.ndarray) -> list[list[Arc]] | None:
    """The structure of the solved exact-work transcription ``col`` (``w``) with each collapsed
    last arc (share below :data:`COLLAPSED`) of a phase followed by another phase of the same
    step removed (its intervals to the arc before it) and that arc continued as the next
    phase's first arc (its kinds for the inputs that act in that phase, the next arc's kinds for
    the others); every phase gets as many intervals as the one with the most (to its longest
    arcs).  None if no arc collapsed (or the inputs may jump between phases)."""
    if col.structure is None or not col.problem.continuous_inputs:
        return None
    n_cycle = len(col.model.phases)
    arcs = [list(a) for a in col.structure]
    thetas = [np.asarray(col.theta_of(w, k), dtype=float) for k in range(len(arcs))]
    changed = False
    for k in range(len(arcs) - 1):
        if (k + 1) % n_cycle == 0 or len(arcs[k]) < 2:
            continue  # a step ends here (the inputs may jump), or nothing to continue
        share = thetas[k][-1] / float(np.sum(thetas[k]))
        if share >= COLLAPSED:
            continue
        last, before = arcs[k][-1], arcs[k][-2]
        arcs[k] = [*arcs[k][:-2], replace(before, intervals=before.intervals + last.intervals)]
        thetas[k] = np.concatenate([thetas[k][:-2], [thetas[k][-2] + thetas[k][-1]]])
        first = arcs[k + 1][0]
        idle = set(col._idle_inputs(col.chain[k + 1]))
        signs = tuple(
            first.signs[r] if r in idle or before.signs[r] == COAST and first.signs[r] == NEGATIVE
            else before.signs[r]
            for r in range(len(before.signs))
        )  # fmt: skip
        bounds = tuple(
            0 if r in idle else b for r, b in enumerate(before.bounds or (0,) * len(signs))
        )
        changed = True
        if signs == first.signs and tuple(bounds) == tuple(first.bounds or (0,) * len(signs)):
            continue  # the next phase begins alike: the sliver was all there was to it
        arcs[k + 1] = [Arc(ARC_INTERVALS, signs, CONTINUED, bounds if any(bounds) else ()),
                       *arcs[k + 1]]  # fmt: skip
        thetas[k + 1] = np.concatenate([[CONTINUED * float(np.sum(thetas[k + 1]))],
                                        thetas[k + 1]])  # fmt: skip
    if not changed:
        return None
    total = max(sum(a.intervals for a in phase) for phase in arcs)
    out = []
    for phase, theta in zip(arcs, thetas, strict=True):
        counts = [a.intervals for a in phase]
        for _ in range(total - sum(counts)):  # to the arc with the longest intervals
            j = int(np.argmax(theta / np.asarray(counts)))
            counts[j] += 1
        share = theta / float(np.sum(theta))
        out.append([replace(a, intervals=n, fraction=max(float(f), 1e-3))
                    for a, n, f in zip(phase, counts, share, strict=True)])  # fmt: skip
    return out


def warm_start(new: Any, col: Any, w: np.ndarray, p: np.ndarray) -> np.ndarray:
    """A warm start of transcription ``new`` from ``col``'s solution ``w``: its polynomials, and
    ``new``'s own arc shares (:attr:`Arc.fraction`), since the arcs differ."""
    sol = col.unpack(w, p)
    br = sol["breaks"]
    states = [
        (lambda t, k=k: col.evaluate(sol["X"][k], sol["U"][k], t, br[k])[0])
        for k in range(len(new.chain))
    ]
    inputs = [
        (lambda t, k=k: col.evaluate(sol["X"][k], sol["U"][k], t, br[k])[1])
        for k in range(len(new.chain))
    ]
    return new.pack(sol["s"], sol["free"], states, inputs, sol["T"], sol["p"], None)
