"""Bézier polynomials of the normalised phase, the shape of a virtual constraint.

Westervelt, Grizzle, Chevallereau, Choi & Morris 2007, *Feedback Control of Dynamic Bipedal Robot
Locomotion*, eq. (6.16): a degree-``M`` Bézier polynomial with coefficients ``α_0 … α_M``,

    b(s) = Σ_k α_k M! / (k! (M − k)!) s^k (1 − s)^(M − k),   s ∈ [0, 1],

has ``b(0) = α_0``, ``b(1) = α_M``, ``b'(0) = M (α_1 − α_0)``, ``b'(1) = M (α_M − α_{M−1})``
(eq. (6.17)); its derivative is the degree-``M − 1`` polynomial with coefficients
``M (α_{k+1} − α_k)``.  The functions work on NumPy arrays and on CasADi expressions alike
(only ``+``, ``*`` and powers), so the same code builds the closed loop's graph and evaluates a
gait's constraints.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["bezier", "bezier_derivative", "bezier_basis", "fit_bezier"]


def bezier_basis(degree: int, s: Any) -> list[Any]:
    """The Bernstein basis ``C(M, k) s^k (1 − s)^(M − k)``, ``k = 0 … M`` (dimensionless)."""
    return [math.comb(degree, k) * s**k * (1 - s) ** (degree - k) for k in range(degree + 1)]


def bezier(alpha: Sequence[Any], s: Any) -> Any:
    """``b(s) = Σ α_k C(M, k) s^k (1 − s)^(M − k)`` (Westervelt et al. 2007, eq. (6.16)).

    Parameters
    ----------
    alpha : sequence
        The ``M + 1`` coefficients (the output's unit, rad for a joint angle).
    s : float, numpy.ndarray or casadi.SX
        The normalised phase (1).

    Returns
    -------
    Same kind as ``s``: ``b(s)`` in the coefficients' unit.
    """
    degree = len(alpha) - 1
    return sum(a * b for a, b in zip(alpha, bezier_basis(degree, s), strict=True))


def bezier_derivative(alpha: Sequence[Any], s: Any, order: int = 1) -> Any:
    """``dⁿb/dsⁿ`` (coefficients' unit): the Bézier polynomial of the differenced coefficients
    ``M (α_{k+1} − α_k)``, repeated ``order`` times; 0 past the degree."""
    coeffs = list(alpha)
    for _ in range(order):
        degree = len(coeffs) - 1
        if degree == 0:
            return 0 * s
        coeffs = [degree * (coeffs[k + 1] - coeffs[k]) for k in range(degree)]
    return bezier(coeffs, s)


def fit_bezier(s: np.ndarray, values: np.ndarray, degree: int) -> np.ndarray:
    """Least-squares Bézier coefficients of samples ``values`` at phases ``s`` (rad), with the
    end coefficients pinned to the end samples (so ``b(0)``, ``b(1)`` are exact).

    Parameters
    ----------
    s : numpy.ndarray
        Phases in [0, 1], including 0 and 1 (first and last sample).
    values : numpy.ndarray
        Samples (one per phase).
    degree : int
        Degree ``M ≥ 1``.

    Returns
    -------
    numpy.ndarray
        The ``M + 1`` coefficients.
    """
    s, values = np.asarray(s, dtype=float), np.asarray(values, dtype=float)
    basis = np.column_stack(bezier_basis(degree, s))
    alpha = np.empty(degree + 1)
    alpha[0], alpha[-1] = values[0], values[-1]
    if degree > 1:
        rhs = values - basis[:, 0] * alpha[0] - basis[:, -1] * alpha[-1]
        alpha[1:-1] = np.linalg.lstsq(basis[:, 1:-1], rhs, rcond=None)[0]
    return alpha
