"""The positive work of an exact-work optimum counted between its collocation nodes.

The switching-time transcription (:mod:`gaitopt.optimize.arcs`) charges ``Σ_{σ=+} uᵢωᵢ`` by
Radau quadrature on its positive arcs and keeps ``σ uᵢωᵢ ≥ 0`` at the arcs' nodes, starts and
interval midpoints.  Between those points the power of the input and state polynomials — the
profile the simulator applies — could still change sign: a torque spike on a braking arc, or a
dip on a pushing arc, would do work the node quadrature does not see.  This module integrates
``max(0, uᵢωᵢ)`` of the polynomials themselves by composite Gauss–Legendre quadrature
(:data:`SUBPANELS` panels of :data:`GAUSS_POINTS` points per mesh interval, so a sign change
inside an interval costs at most the quadrature's error on one panel) and compares it with the
transcription's positive work: the certificate (:func:`gaitopt.optimize.certify._certify`)
refuses an optimum whose dense positive work exceeds the charged one by more than
:data:`WORK_RTOL` relative, the discretisation error the refinement promises.  Impulsive inputs
act only in resets: their work is the transcription's own closed form, the same on both sides.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .collocation import Collocation
from .radau import NEGATIVE, POSITIVE

#: Gauss–Legendre points per panel and panels per mesh interval of the dense quadrature.
GAUSS_POINTS = 8
SUBPANELS = 8
#: The dense positive work may exceed the transcription's by this, relative to the larger of
#: the charged work and the largest |uᵢωᵢ| times the period (an absolute floor for a near-zero
#: work, J).
WORK_RTOL = 1e-8


def dense_work(col: Collocation, sol: dict[str, Any]) -> dict[str, float]:
    """Positive work of the solution's polynomials, integrated between the nodes.

    Returns ``{"positive_work_dense", "positive_work", "hidden_work", "scale",
    "worst_sign"}``: the dense ``∫ Σ max(0, uᵢωᵢ) dt`` over the orbit's phases (J), the
    transcription's charged positive work without the impulses' (J), their difference, the
    scale the tolerance is relative to (J), and the most negative ``σ uᵢωᵢ`` on a signed arc at
    the dense points (W; 0 if none is negative)."""
    model = col.model
    p = sol["p"]
    nodes, weights = np.polynomial.legendre.leggauss(GAUSS_POINTS)
    width = 1.0 / SUBPANELS
    starts = np.arange(SUBPANELS) * width
    local = (starts[:, None] + width / 2 * (1 + nodes)).ravel()
    local_w = np.tile(width / 2 * weights, SUBPANELS)
    dense, biggest, worst = 0.0, 0.0, 0.0
    for k, i in enumerate(col.chain):
        rates = model.input_rates(i)
        breaks = np.asarray(sol["breaks"][k], dtype=float)
        T = float(sol["T"][k])
        kinds = _interval_kinds(col, k)
        for j in range(col.N):
            a, b = breaks[j], breaks[j + 1]
            times = a + (b - a) * local
            X, U = col.evaluate(sol["X"][k], sol["U"][k], times, breaks)
            omega = np.asarray(rates.map(times.size)(X, p), dtype=float)
            power = U * omega
            power[list(col.problem.impulsive_index), :] = 0.0
            dense += T * (b - a) * float(np.sum(np.maximum(0.0, power) @ local_w))
            biggest = max(biggest, float(np.max(np.abs(power))) if power.size else 0.0)
            if kinds is not None:
                sigma = kinds[:, j][:, None]
                signed = np.isin(kinds[:, j], (POSITIVE, NEGATIVE))
                if np.any(signed):
                    worst = min(worst, float(np.min((sigma * power)[signed])))
    charged = float(sol["positive_work"]) - _impulse_work(col, sol)
    scale = max(abs(charged), biggest * float(np.sum(sol["T"])) * 1e-3, 1e-12)
    return {
        "positive_work_dense": float(dense),
        "positive_work": float(charged),
        "hidden_work": float(dense - charged),
        "scale": float(scale),
        "worst_sign": float(worst),
    }


def check_work(col: Collocation, sol: dict[str, Any]) -> str | None:
    """None if the dense positive work (:func:`dense_work`) is the charged one to
    :data:`WORK_RTOL` (or the transcription is not an exact-work one); else why, naming the
    hidden work and where to look."""
    if col.structure is None or col.problem.cost_kind not in ("work", "cot"):
        return None
    out = dense_work(col, sol)
    if abs(out["hidden_work"]) <= WORK_RTOL * out["scale"]:
        return None
    return (
        f"no gait: the positive work between the collocation nodes is "
        f"{out['positive_work_dense']:.10g} J, the transcription charges "
        f"{out['positive_work']:.10g} J ({out['hidden_work']:.2g} J hidden; a power of the "
        f"wrong sign {out['worst_sign']:.2g} W on a signed arc): refine the mesh or add a "
        f"braking_effort"
    )


def _interval_kinds(col: Collocation, k: int) -> np.ndarray | None:
    """Per input and mesh interval of phase ``k``, the arc's kind (+1 pushing, −1 braking,
    else another kind), with idle inputs (rate identically 0) not signed; None without a
    structure."""
    if col.structure is None:
        return None
    kinds = np.array(
        [arc.signs for arc in col.structure[k] for _ in range(arc.intervals)], dtype=int
    ).T
    kinds[col._idle_inputs(col.chain[k]), :] = 0
    return kinds


def _impulse_work(col: Collocation, sol: dict[str, Any]) -> float:
    """The impulsive inputs' work over the orbit as the transcription charges it (J)."""
    problem = col.problem
    if not problem.model.impulsive_inputs:
        return 0.0
    total = 0.0
    for k, i in enumerate(col.chain):
        X, U = sol["X"][k], sol["U"][k]
        total += float(problem.impulse_work(i, X[:, -1], U[:, -1], sol["p"]))
    return total


def simulated_work(
    sim: Any, profile: Any, rate_index: int, *, phase: int = 0, panels: int = 64
) -> tuple[float, float]:
    """Positive and negative work (J) of a one-input feedforward ``profile`` on the arcs of
    ``phase`` of an independent simulation ``sim`` (:func:`gaitopt.simulate` with the profile):
    ``∫ max(0, u ẏ) dt`` and ``∫ min(0, u ẏ) dt`` with ``ẏ`` the state ``rate_index`` (the rate
    the input works against, e.g. a leg force's ṙ), by Gauss–Legendre quadrature
    (:data:`GAUSS_POINTS` points on ``panels`` panels per arc, split at the profile's
    breakpoints).  The studies' work–energy balances (a simulated period's W⁺ + W⁻ against the
    energy it must return) use it."""
    nodes, weights = np.polynomial.legendre.leggauss(GAUSS_POINTS)
    pos = neg = 0.0
    for arc in sim.arcs:
        if arc.phase != phase:
            continue
        inner = profile.breaks[
            (profile.breaks > arc.t0 + 1e-12) & (profile.breaks < arc.t1 - 1e-12)
        ]
        edges = np.sort(np.concatenate([np.linspace(arc.t0, arc.t1, panels + 1), inner]))
        edges = edges[np.append(True, edges[1:] != edges[:-1])]  # np.unique without numpy.ma
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            ts = (a + b) / 2 + (b - a) / 2 * nodes
            xs = arc.solution(ts)
            power = np.array([float(profile(t)[0]) for t in ts]) * xs[rate_index]
            pos += (b - a) / 2 * float(np.dot(weights, np.maximum(power, 0.0)))
            neg += (b - a) / 2 * float(np.dot(weights, np.minimum(power, 0.0)))
    return pos, neg
