"""All roots of a real polynomial in the closed disc of radius ``R``: smooth conditions on its
coefficients (the Schur–Cohn–Jury question, in its bilinear Liénard–Chipart form).

For the return map's Jacobian ``A`` (``m × m``) the characteristic polynomial of ``A/R``,
``P(z) = zᵐ + a₁ zᵐ⁻¹ + … + aₘ`` with ``aₖ = cₖ / Rᵏ`` (``cₖ``: the coefficients of ``A``'s own,
by the Faddeev–LeVerrier recursion, :func:`charpoly`), has all its roots in the unit disc iff
``ρ(A) ≤ R``.  The Möbius map ``z = (1 + s)/(1 − s)`` takes the open unit disc onto the open left
half plane, so ``P`` is Schur stable iff ``Q(s) = (1 − s)ᵐ P((1 + s)/(1 − s)) = b₀ sᵐ + … + bₘ``
is Hurwitz (Jury 1964, "Theory and Application of the z-Transform Method", §3; Åström &
Wittenmark, "Computer-Controlled Systems", §3.2).  ``b₀ = (−1)ᵐ P(−1)`` and ``bₘ = P(1)``; the
``b`` are linear in the ``a``.  Liénard–Chipart (Gantmacher, "The Theory of Matrices" II, ch. XV
§13): with ``b₀ > 0``, ``Q`` is Hurwitz iff ``bₘ, bₘ₋₂, bₘ₋₄, … > 0`` and ``Δₘ₋₁, Δₘ₋₃, … > 0``
(``Δₖ``: the leading ``k × k`` minor of the Hurwitz matrix ``Hᵢⱼ = b₂ⱼ₋ᵢ``).  The variant with
``Δₘ₋₁`` is chosen because each way of reaching the circle makes exactly one condition vanish,
with a nonzero gradient in general: a real root at ``+R`` (``bₘ = P(1) = 0``), at ``−R``
(``b₀ = 0``) or a complex pair on the circle (``Δₘ₋₁ = 0``, Orlando's formula: ``Δₘ₋₁ ∝
Πᵢ<ⱼ (sᵢ + sⱼ)``).

:func:`disc_conditions` returns these ``m + 1`` values (``m = 3``: ``b₀, b₃, b₁, Δ₂``; ``m = 2``:
the triangle ``b₀, b₂, b₁``), polynomials in the ``aₖ`` (so in ``A``'s entries and ``1/R``)
that are all ``≥ 0`` on the closed disc.  The closure is exact except at degenerate corners
where two conditions vanish together (``Q(s) = s³ − s``: ``b₃ = b₁ = Δ₂ = 0`` with a root at
``s = 1``); an optimum that lands on one is caught by the certificate, which checks the
eigenvalues themselves.  Both functions take NumPy floats or CasADi symbols alike.
"""

from __future__ import annotations

from math import comb
from typing import Any

import numpy as np

__all__ = ["MAX_SECTION", "charpoly", "bilinear", "disc_conditions", "condition_names"]

#: Most section coordinates ``m`` for which the bound is formulated: ``Δₘ₋₁`` is a polynomial
#: of degree ``m − 1`` in the ``b`` (so ``m(m − 1)`` in ``A``'s entries), whose values span
#: many orders of magnitude beyond ``m = 4``; the compass gait and the kneed walker have 3.
MAX_SECTION = 4


def charpoly(A: Any, m: int, trace: Any, mtimes: Any, eye: Any) -> list[Any]:
    """``[c₁, …, cₘ]`` of ``det(zI − A) = zᵐ + c₁ zᵐ⁻¹ + … + cₘ`` by the Faddeev–LeVerrier
    recursion ``M₁ = I``, ``cₖ = −tr(A Mₖ)/k``, ``Mₖ₊₁ = A Mₖ + cₖ I`` (a polynomial in ``A``'s
    entries: no division but by ``k``).  ``trace``, ``mtimes`` and ``eye`` are NumPy's or
    CasADi's."""
    coeffs = []
    M = eye(m)
    for k in range(1, m + 1):
        AM = mtimes(A, M)
        c = -trace(AM) / k
        coeffs.append(c)
        M = AM + c * eye(m)
    return coeffs


def charpoly_numpy(A: np.ndarray) -> list[float]:
    """:func:`charpoly` of a NumPy matrix."""
    A = np.asarray(A, dtype=float)
    return [float(c) for c in charpoly(A, A.shape[0], np.trace, np.matmul, np.eye)]


def _bilinear_matrix(m: int) -> np.ndarray:
    """``T[i, k]``: the coefficient of ``sⁱ`` in ``(1 + s)ᵐ⁻ᵏ (1 − s)ᵏ``, ``i, k = 0..m``."""
    T = np.zeros((m + 1, m + 1))
    for k in range(m + 1):
        plus = [comb(m - k, j) for j in range(m - k + 1)]
        minus = [comb(k, j) * (-1) ** j for j in range(k + 1)]
        T[:, k] = np.convolve(plus, minus)
    return T


def bilinear(a: list[Any]) -> list[Any]:
    """``[b₀, …, bₘ]`` of ``Q(s) = Σₖ aₖ (1 + s)ᵐ⁻ᵏ (1 − s)ᵏ = b₀ sᵐ + … + bₘ`` (``a₀ = 1``;
    ``a = [a₁, …, aₘ]``)."""
    m = len(a)
    T = _bilinear_matrix(m)
    full = [1.0, *a]
    q = [sum(T[i, k] * full[k] for k in range(m + 1) if T[i, k] != 0) for i in range(m + 1)]
    return q[::-1]  # b_j = q_{m-j}


def _det(rows: list[list[Any]]) -> Any:
    """Determinant by cofactor expansion along the first row (sizes up to ``MAX_SECTION − 1``;
    works on CasADi scalars, which have no symbolic determinant of their own in MX)."""
    n = len(rows)
    if n == 1:
        return rows[0][0]
    total = 0
    for j in range(n):
        entry = rows[0][j]
        if isinstance(entry, (int, float)) and entry == 0:
            continue
        minor = [row[:j] + row[j + 1 :] for row in rows[1:]]
        total = total + (-1) ** j * entry * _det(minor)
    return total


def hurwitz_minor(b: list[Any], k: int) -> Any:
    """``Δₖ``: the leading ``k × k`` minor of the Hurwitz matrix ``Hᵢⱼ = b₂ⱼ₋ᵢ`` (1-based;
    ``bₗ = 0`` outside ``0..m``) of ``b₀ sᵐ + … + bₘ``."""
    m = len(b) - 1

    def entry(i: int, j: int) -> Any:
        idx = 2 * j - i
        return b[idx] if 0 <= idx <= m else 0.0

    return _det([[entry(i, j) for j in range(1, k + 1)] for i in range(1, k + 1)])


def _selection(m: int) -> tuple[list[int], list[int]]:
    """The coefficients (``b₀``, then ``bₘ, bₘ₋₂, …``) and the minors (``Δₘ₋₁, Δₘ₋₃, …``) of
    the Liénard–Chipart test with ``Δₘ₋₁``."""
    coefficients = [0] + [j for j in range(m, 0, -2)]
    minors = [k for k in range(m - 1, 0, -2)]
    return coefficients, minors


def condition_names(m: int) -> list[str]:
    """Labels of :func:`disc_conditions`' values, in order: ``b0 = (-1)^m P(-1)``, ``bm = P(1)``,
    the other coefficients, the Hurwitz minors."""
    coefficients, minors = _selection(m)
    names = []
    for j in coefficients:
        names.append(f"b0 = (-1)^{m} P(-R)" if j == 0 else (f"b{m} = P(R)" if j == m else f"b{j}"))
    return names + [f"Hurwitz minor {k}" for k in minors]


def disc_conditions(a: list[Any]) -> list[Any]:
    """The Liénard–Chipart values of ``P(z) = zᵐ + a₁zᵐ⁻¹ + … + aₘ`` after the bilinear map (see
    the module): all ``≥ 0`` iff every root lies in the closed unit disc (up to the degenerate
    corners the module names); one is 0 where a root reaches the circle."""
    m = len(a)
    b = bilinear(a)
    coefficients, minors = _selection(m)
    return [b[j] for j in coefficients] + [hurwitz_minor(b, k) for k in minors]


def scaled(c: list[Any], R: Any) -> list[Any]:
    """The coefficients of the characteristic polynomial of ``A / R`` from ``A``'s own:
    ``aₖ = cₖ / Rᵏ``."""
    return [ck / R ** (k + 1) for k, ck in enumerate(c)]
