"""Test functions of codimension-two points along a curve of special points (maps).

Kuznetsov, "Elements of Applied Bifurcation Theory", 3rd ed., §9 (codimension-two bifurcations
of fixed points) and §10.2.2 (their test functions); the labels are MatCont's:

* on a ``PD`` curve (multiplier −1, the *critical* one; the others ``μⱼ``):
  ``LPPD`` fold–flip where another multiplier reaches +1, ``∏(μⱼ − 1)``; ``R2`` the 1:2
  resonance, a second multiplier at −1, ``∏(μⱼ + 1)``; ``PDNS`` flip–Neimark–Sacker, another
  pair on the unit circle, ``∏_{i<j}(μᵢ μⱼ − 1)``;
* on an ``LP`` curve (+1): ``LPPD`` ``∏(μⱼ + 1)``; ``R1`` the 1:1 resonance (double +1)
  ``∏(μⱼ − 1)``; ``LPNS`` ``∏_{i<j}(μᵢ μⱼ − 1)``;
* on an ``NS`` curve (the critical pair ``μ₁ μ₂ = 1``, ``κ = (μ₁ + μ₂)/2`` — ``cos θ`` while
  the pair is complex): ``R1`` ``κ − 1``, ``R2`` ``κ + 1``, ``R3`` ``κ + ½``, ``R4`` ``κ``
  (strong resonances 1:1 … 1:4), ``LPNS`` ``∏(μⱼ − 1)``, ``PDNS`` ``∏(μⱼ + 1)``;
* on every curve, where it turns in a parameter: ``fold`` in ``λᵢ`` where ``dλᵢ/ds`` changes
  sign (a tangent component; not a bifurcation of the gait but the extreme of the curve, e.g.
  the largest slope with a stable gait).

* on a ``boundary`` curve (no critical multiplier): ``PD`` ``∏(μⱼ + 1)`` where a period doubling
  curve cuts it and ``LP`` ``∏(μⱼ − 1)`` where a fold curve does — the corners of the region
  where the gait exists and is stable.

A ``boundary`` that cuts a PD, LP or NS curve (the gait stops existing on it) is found by
certification, not by a test function (see :mod:`gaitopt.curves.follow`); followed as a curve of
its own, its crossing with the PD curve is located by the ``PD`` test above.
"""

from __future__ import annotations

import numpy as np

__all__ = ["critical", "tests", "DESCRIPTIONS"]

DESCRIPTIONS = {
    "LPPD": "fold–flip: multipliers +1 and −1 at once (a PD curve meets an LP curve)",
    "R1": "1:1 resonance: a double multiplier +1",
    "R2": "1:2 resonance: a double multiplier −1",
    "R3": "1:3 resonance: the critical pair at exp(±2πi/3)",
    "R4": "1:4 resonance: the critical pair at ±i",
    "PDNS": "flip–Neimark–Sacker: a multiplier −1 and a complex pair on the unit circle",
    "LPNS": "fold–Neimark–Sacker: a multiplier +1 and a complex pair on the unit circle",
    "PD": "the boundary cuts a period-doubling curve (a multiplier −1 where the gait ends): a "
    "corner of the stable region",
    "LP": "the boundary cuts a fold curve (a multiplier +1 where the gait ends)",
    "fold": "the curve turns back in this parameter (its tangent's component vanishes)",
    "boundary": "the gait stops existing on the curve",
}


def critical(kind: str, mu: np.ndarray) -> tuple[list[int], list[int]]:
    """Indices of the critical multiplier(s) of a curve of ``kind`` and of the others."""
    mu = np.asarray(mu, dtype=complex)
    n = len(mu)
    if kind == "PD":
        crit = [int(np.argmin(np.abs(mu + 1)))]
    elif kind == "LP":
        crit = [int(np.argmin(np.abs(mu - 1)))]
    elif kind == "NS":
        best, crit = np.inf, []
        for i in range(n):
            for j in range(i + 1, n):
                d = abs(mu[i] * mu[j] - 1)
                if d < best:
                    best, crit = d, [i, j]
    else:
        crit = []
    return crit, [i for i in range(n) if i not in crit]


def _prod(values) -> float:
    return float(np.prod(np.asarray(values, dtype=complex)).real) if len(values) else 1.0


def _pairs_product(mu: np.ndarray) -> float:
    out = 1.0 + 0j
    for i in range(len(mu)):
        for j in range(i + 1, len(mu)):
            out *= mu[i] * mu[j] - 1
    return float(out.real)


def tests(kind: str, mu: np.ndarray, tangent_lambda: np.ndarray, names: tuple[str, str]):
    """The codimension-two test functions at a curve point: label → value (a zero between two
    points, i.e. a sign change, marks the point).

    Parameters
    ----------
    kind : str
        The curve's kind.
    mu : numpy.ndarray
        The multipliers at the point.
    tangent_lambda : numpy.ndarray
        ``(dλ₁/ds, dλ₂/ds)`` (any positive scaling).
    names : (str, str)
        The two parameters' names (the fold labels are ``fold:<name>``).
    """
    mu = np.asarray(mu, dtype=complex)
    crit, others = critical(kind, mu)
    rest = mu[others]
    out: dict[str, float] = {}
    if kind == "PD":
        out = {"LPPD": _prod(rest - 1), "R2": _prod(rest + 1)}
        if len(rest) > 1:
            out["PDNS"] = _pairs_product(rest)
    elif kind == "LP":
        out = {"LPPD": _prod(rest + 1), "R1": _prod(rest - 1)}
        if len(rest) > 1:
            out["LPNS"] = _pairs_product(rest)
    elif kind == "boundary":
        out = {"PD": _prod(mu + 1), "LP": _prod(mu - 1)}
    elif kind == "NS" and len(crit) == 2:
        kappa = float(((mu[crit[0]] + mu[crit[1]]) / 2).real)
        out = {"R1": kappa - 1, "R2": kappa + 1, "R3": kappa + 0.5, "R4": kappa}
        out.update({"LPNS": _prod(rest - 1), "PDNS": _prod(rest + 1)})
    for name, value in zip(names, tangent_lambda, strict=True):
        out[f"fold:{name}"] = float(value)
    return out


def is_genuine(label: str, mu: np.ndarray, kind: str) -> bool:
    """Whether a located zero is the codimension-two point its label names (a product of
    ``μᵢ μⱼ − 1`` also vanishes at real reciprocal pairs, neutral saddles)."""
    if label not in ("PDNS", "LPNS"):
        return True
    mu = np.asarray(mu, dtype=complex)
    _, others = critical(kind, mu)
    rest = mu[others]
    return bool(np.any((np.abs(rest.imag) > 1e-8) & (np.abs(np.abs(rest) - 1) < 1e-4)))
