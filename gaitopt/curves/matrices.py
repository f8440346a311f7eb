"""The matrices of the defining conditions of ``PD``, ``LP`` and ``NS`` curves: the return map's
Jacobian ``A`` from the shooting Jacobian, the matrix ``M`` that is singular on each kind of curve
(``A ⊙ A`` the bialternate product for ``NS``), and the bordering vectors of the minimally
augmented system (Govaerts 2000, §4.3; Kuznetsov, §10.2.2)."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..orbit.sensitivity import map_blocks, section_jacobians
from ..shooting import ShootingProblem

__all__ = [
    "bialternate",
    "singular_matrix",
    "bordering",
    "border_size",
    "return_map_jacobian",
]


def _pairs(m: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(m) for j in range(i + 1, m)]


def bialternate(A: Any) -> Any:
    """``A ⊙ A``: the bialternate product, entries the 2 × 2 minors
    ``a_ik a_jl − a_il a_jk`` over index pairs ``i < j``, ``k < l``; its eigenvalues are
    ``μᵢ μⱼ, i < j`` (Kuznetsov, §10.2.2).  Works on NumPy arrays and CasADi matrices."""
    m = A.shape[0]
    pairs = _pairs(m)
    if isinstance(A, np.ndarray):
        out = np.zeros((len(pairs), len(pairs)), dtype=A.dtype)
        for r, (i, j) in enumerate(pairs):
            for s, (k, l_) in enumerate(pairs):
                out[r, s] = A[i, k] * A[j, l_] - A[i, l_] * A[j, k]
        return out
    rows = []
    for i, j in pairs:
        rows.append(ca.horzcat(*[A[i, k] * A[j, l_] - A[i, l_] * A[j, k] for k, l_ in pairs]))
    return ca.vertcat(*rows)


def singular_matrix(kind: str, A: Any) -> Any:
    """The matrix ``M`` that is singular on a curve of ``kind`` (NumPy or CasADi)."""
    eye = np.eye if isinstance(A, np.ndarray) else ca.DM.eye
    if kind == "PD":
        return A + eye(A.shape[0])
    if kind == "LP":
        return A - eye(A.shape[0])
    B = bialternate(A)
    return B - eye(B.shape[0])


def bordering(kind: str, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bordering vectors ``(b, c)``: left and right singular vectors of ``M``'s smallest
    singular value (the bordered matrix is then as far from singular as it can be)."""
    M = singular_matrix(kind, np.asarray(A, dtype=float))
    U, _, Vt = np.linalg.svd(M)
    return U[:, -1].copy(), Vt[-1].copy()


def border_size(kind: str, m: int) -> int:
    """Length of the bordering vectors."""
    if kind in ("PD", "LP"):
        return m
    if kind == "NS":
        return m * (m - 1) // 2
    return 1  # boundary: unused


def return_map_jacobian(problem: ShootingProblem, F_w: np.ndarray) -> np.ndarray:
    """``A = ∂P/∂s`` from the shooting Jacobian ``∂F/∂w`` (``F = [G; P − s]``; the implicit
    function theorem, :func:`gaitopt.orbit.sensitivity.section_jacobians`)."""
    return section_jacobians(map_blocks(F_w, problem.m, problem.n_g), None, problem.m,
                             problem.n_g)[0]  # fmt: skip
