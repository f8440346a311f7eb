"""Structured linear solves for long (period-k) orbits: a sparse LU on the known block pattern.

The shooting Jacobian of a period-k orbit is a cyclic block chain: each stage's rows (its gaps,
its guard, the reset into the next stage) touch only that stage's unknowns, the next stage's
first node and, for the first stage's lift and the periodicity rows, the section coordinates
``s`` (a block-bordered matrix; Ascher, Mattheij & Russell, "Numerical Solution of Boundary
Value Problems for ODEs", §4.3 on multiple shooting's block structure).  A dense LU costs
``O(k³)``; an LU that follows the pattern (SuperLU, :func:`scipy.sparse.linalg.splu`, with a
COLAMD column order and partial pivoting) fills in only along the chain and the border, so its
work and memory grow linearly in ``k`` (the compass gait's factors hold 1.32–1.39× the
pattern's entries at k = 4 … 64, about 210 per step).

Small systems stay dense: below :data:`STRUCTURED_MIN_SIZE` unknowns LAPACK's dense solve costs
no more than gathering the pattern and factoring it (the compass gait's period-8 system has 135
unknowns).  The same threshold holds for every caller, so which solve runs depends on the size
alone; the two agree to rounding (``tests/test_structured_solve.py``: Newton's iterates to 1e-12).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["STRUCTURED_MIN_SIZE", "BlockPattern", "solve"]

#: Systems with at least this many unknowns are solved on their pattern (sparse LU); smaller ones
#: densely.  Measured per solve (one BLAS thread, the shared 2-core machine; ``python -m
#: bench.branches``, ``results/bench_cascade.json``, "structured_solves"): the compass gait's
#: period-8 system (135 unknowns) 0.21 ms dense vs 0.25 ms structured, period 16 (271) 0.87 vs
#: 0.36 ms, period 32 (543) 3.9 vs 0.44 ms, period 64 (1087) 27 vs 0.87 ms.  Below 200 every
#: built-in period-1 system stays dense (the largest, the planar quadruped's, has 194 unknowns).
STRUCTURED_MIN_SIZE = 200


class BlockPattern:
    """The positions a square matrix may have nonzeros at: the union of dense blocks ``rows ×
    cols``, in compressed-column order (with the matching flat indices into a C-ordered dense
    matrix, so that the nonzeros are gathered in ``O(nnz)``).

    Parameters
    ----------
    size : int
        Rows (= columns).
    blocks : sequence of (range or array, array)
        Row indices and column indices of each block.
    """

    def __init__(self, size: int, blocks: Sequence[tuple[Sequence[int], Sequence[int]]]):
        self.size = int(size)
        keys = [
            (
                np.asarray(c, dtype=np.int64)[None, :] * self.size
                + np.asarray(r, dtype=np.int64)[:, None]
            ).ravel()
            for r, c in blocks
        ]
        key = np.unique(np.concatenate(keys)) if keys else np.zeros(0, np.int64)
        cols, rows = np.divmod(key, self.size)
        self.indices = rows.astype(np.int32)
        self.indptr = np.searchsorted(cols, np.arange(self.size + 1)).astype(np.int32)
        self.flat = rows * self.size + cols  # into a C-ordered (row-major) dense matrix
        self.blocks = list(blocks)
        self._bordered: BlockPattern | None = None

    @property
    def nnz(self) -> int:
        return int(self.flat.size)

    def bordered(self) -> BlockPattern:
        """The pattern of ``[[M, c], [rᵀ, d]]``: one more row and column, both full (the
        pseudo-arclength corrector's system: the parameter's column and the arclength row), built
        once."""
        if self._bordered is None:
            n = self.size + 1
            everything = np.arange(n)
            blocks = [*self.blocks, ([n - 1], everything), (everything, [n - 1])]
            self._bordered = BlockPattern(n, blocks)
        return self._bordered

    def covers(self, matrix: np.ndarray) -> bool:
        """Whether every nonzero of ``matrix`` lies on the pattern."""
        outside = np.ones(self.size * self.size, dtype=bool)
        outside[self.flat] = False
        return not np.any(np.asarray(matrix).ravel()[outside])

    def sparse(self, matrix: np.ndarray):
        """``matrix`` (dense, ``size × size``) as a SciPy CSC matrix on this pattern."""
        from scipy.sparse import csc_matrix

        data = np.ascontiguousarray(matrix, dtype=float).ravel()[self.flat]
        return csc_matrix((data, self.indices, self.indptr), shape=(self.size, self.size))


def solve(matrix: np.ndarray, rhs: np.ndarray, pattern: BlockPattern | None = None) -> np.ndarray:
    """``matrix⁻¹ rhs``: densely (:func:`numpy.linalg.solve`) below :data:`STRUCTURED_MIN_SIZE`
    unknowns or without a pattern, else by a sparse LU on ``pattern``.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the matrix is exactly singular (as :func:`numpy.linalg.solve`, either way).
    """
    n = matrix.shape[0]
    if pattern is None or n < STRUCTURED_MIN_SIZE or pattern.size != n:
        return np.linalg.solve(matrix, rhs)
    if not np.all(np.isfinite(matrix)):
        return np.linalg.solve(matrix, rhs)  # the dense solve's behaviour (NaN out)
    from scipy.sparse.linalg import splu

    try:
        lu = splu(pattern.sparse(matrix), permc_spec="COLAMD")
    except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
        raise np.linalg.LinAlgError(str(exc)) from None
    return lu.solve(np.asarray(rhs, dtype=float))
