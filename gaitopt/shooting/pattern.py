"""The block pattern of a shooting Jacobian ``∂F/∂w`` (:mod:`gaitopt.orbit.structured`).

Rows and unknowns follow :class:`~gaitopt.shooting.problem.ShootingProblem`'s layout: stage
``k`` of the chain owns the rows of its gaps (``n_k`` each, ``S − 1`` of them), its guard (one)
and its link to the next stage (``n_{k+1}``; after the last stage the periodicity rows, ``m``).
The gap after segment ``j`` touches segment starts ``j`` and ``j + 1`` and the duration ``T_k``;
the guard and the link touch the last segment's start, ``T_k`` and the next stage's first node
(after the last stage: ``s``); the first stage's first start is ``lift(s)``, so its columns are
``s`` (:mod:`gaitopt.kernels.assemble` writes nothing else)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..orbit import structured
from ..orbit.structured import BlockPattern

__all__ = ["pattern_of", "shooting_pattern"]


def shooting_pattern(problem: Any) -> BlockPattern | None:
    """The pattern of ``problem``'s ``∂F/∂w`` (None where its rows do not add up to the layout's,
    e.g. a guard of more than one equation: then every solve stays dense)."""
    m, size = problem.m, problem.size
    S = problem.disc.segments
    stages = [
        (problem.layout[2 * k][2], problem.layout[2 * k + 1][2]) for k in range(len(problem.chain))
    ]
    n = [problem.phases[i].n for i in problem.chain]
    section = np.arange(m)
    blocks, row = [], 0
    for k, (off, off_T) in enumerate(stages):
        nk, last = n[k], k + 1 == len(stages)

        def start(j: int, k: int = k, off: int = off, nk: int = nk) -> np.ndarray:
            """Columns of segment start ``j`` (the first stage's first start is lift(s))."""
            if k == 0:
                return section if j == 0 else np.arange(off + nk * (j - 1), off + nk * j)
            return np.arange(off + nk * j, off + nk * (j + 1))

        for j in range(S - 1):  # the gap after segment j: its start, the next start, T
            cols = np.concatenate([start(j), start(j + 1), [off_T]])
            blocks.append((np.arange(row, row + nk), cols))
            row += nk
        # the guard and the link (or periodicity): the last segment's start, T, what follows
        follows = section if last else np.arange(stages[k + 1][0], stages[k + 1][0] + n[k + 1])
        rows = 1 + follows.size
        blocks.append(
            (np.arange(row, row + rows), np.concatenate([start(S - 1), [off_T], follows]))
        )
        row += rows
    if row != size:
        return None
    return BlockPattern(size, blocks)


def pattern_of(problem: Any) -> BlockPattern | None:
    """:func:`shooting_pattern` of ``problem``, kept on it, where its system is large enough for
    the structured solve (:data:`gaitopt.orbit.structured.STRUCTURED_MIN_SIZE`); else None."""
    if problem.size < structured.STRUCTURED_MIN_SIZE:
        return None
    cache = problem.__dict__
    if "_block_pattern" not in cache:
        cache["_block_pattern"] = shooting_pattern(problem)
    return cache["_block_pattern"]
