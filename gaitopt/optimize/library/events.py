"""Second-order information and the events between neighbouring library points: the reduced
Hessian of the Lagrangian (Nocedal & Wright 2006, Thm 12.6), and active-set changes, folds and
ends of the warm starts, each located by bisection."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..attempt import _solver
from ..collocation import Collocation
from ..result import OptimalGait
from .records import LibraryEvent, LibraryPoint

__all__ = ["reduced_hessian", "compare"]

_FOLD_RATIO = 1e-3  # λmin/λmax of the reduced Hessian fallen below this × its start: singular
_ACTIVE_TOL = 1e-7  # a constraint or bound within this (relative) of its limit is active


def reduced_hessian(col: Collocation, w: np.ndarray, p: np.ndarray) -> tuple[float, float]:
    """Smallest and largest eigenvalue of the reduced Hessian of the Lagrangian at ``w``.

    The active set: the equality constraints, the inequalities within 1e-7 (relative) of a
    limit and the variables at a bound.  Multipliers by least squares on the stationarity
    condition ``∇f + J_Aᵀ λ = 0`` (over the free variables); ``Z`` an orthonormal basis of the
    null space of the active Jacobian (SVD), so the eigenvalues of ``Zᵀ ∇²L Z`` do not depend on
    the basis chosen.

    Returns
    -------
    (float, float)
        ``(λ_min, λ_max)`` (cost units per decision-variable unit squared); ``(nan, nan)`` if
        the active constraints leave no freedom.
    """

    w = np.asarray(w, dtype=float).ravel()
    solver = _solver(col)  # IPOPT's own derivative functions (cached with the last solve)
    ng = col.lbg.size
    g, J = (np.asarray(v, dtype=float) for v in solver.get_function("nlp_jac_g")(w, p))
    grad = np.asarray(solver.get_function("nlp_grad_f")(w, p)[1], dtype=float)
    hess = solver.get_function("nlp_hess_l")
    g, grad = g.ravel(), grad.ravel()
    scale = 1 + np.abs(g)
    active = (col.lbg == col.ubg) | (np.abs(g - col.lbg) <= _ACTIVE_TOL * scale)
    active |= np.abs(g - col.ubg) <= _ACTIVE_TOL * scale
    at_bound = (np.abs(w - col.lbx) <= _ACTIVE_TOL * (1 + np.abs(w))) | (
        np.abs(w - col.ubx) <= _ACTIVE_TOL * (1 + np.abs(w))
    )
    free = ~at_bound
    JA = J[active][:, free]
    lam_a = np.linalg.lstsq(JA.T, -grad[free], rcond=None)[0]
    lam_full = np.zeros(ng)
    lam_full[active] = lam_a
    upper = np.asarray(hess(w, p, 1.0, lam_full), dtype=float)
    H = (upper + upper.T - np.diag(np.diag(upper)))[np.ix_(free, free)]
    _, sigma, Vt = np.linalg.svd(JA, full_matrices=True)
    rank = int(np.sum(sigma > 1e-10 * (sigma[0] if sigma.size else 1.0)))
    Z = Vt[rank:].T
    if Z.shape[1] == 0:
        return float("nan"), float("nan")
    eig = np.linalg.eigvalsh(0.5 * (Z.T @ H @ Z + (Z.T @ H @ Z).T))
    return float(eig[0]), float(eig[-1])


def compare(
    a: LibraryPoint, b: LibraryPoint, solve: Any, locate: float, reference: float
) -> LibraryEvent | None:
    """The event between a successful point ``a`` and the next point ``b``, located.

    A ``b`` that converged to an optimum which then failed a check (simulation, discretisation
    target) still has an active set to compare; one with no optimum ends the library there."""
    width = locate * abs(b.value - a.value)
    if _optimum(b.gait):
        before, after = set(a.gait.active_constraints), set(b.gait.active_constraints)
        if before != after:
            return _bisect_active(a, b, before, solve, width)
        if (
            b.gait.success
            and np.isfinite(a.hessian[0])
            and np.isfinite(b.hessian[0])
            and np.sign(a.hessian[0]) != np.sign(b.hessian[0])
        ):
            return LibraryEvent(
                "fold",
                0.5 * (a.value + b.value),
                (a.value, b.value),
                sorted(before),
                sorted(after),
                f"fold between {a.value:g} and {b.value:g}: the reduced Hessian's smallest "
                f"eigenvalue changes sign ({a.hessian[0]:.3g} → {b.hessian[0]:.3g})",
            )
        return None
    return _bisect_end(a, b, solve, width, reference)


def _optimum(gait: OptimalGait) -> bool:
    """IPOPT converged and the dense checks passed (a bisection probe, not verified by
    simulation nor held to the discretisation target: only its active set and its existence
    are used)."""
    return gait.cost is not None and not gait.message.startswith("not a gait")


def _bisect_active(
    a: LibraryPoint, b: LibraryPoint, before: set[str], solve: Any, width: float
) -> LibraryEvent:
    lo, hi, guess = a.value, b.value, a.gait
    after = set(b.gait.active_constraints)
    while abs(hi - lo) > width:
        mid = 0.5 * (lo + hi)
        gait = solve(mid, guess, verify=False)
        if _optimum(gait) and set(gait.active_constraints) == before:
            lo, guess = mid, gait
        else:
            hi = mid
    gained = sorted(after - before)
    lost = sorted(before - after)
    what = ", ".join(
        [f"'{c}' becomes active" for c in gained] + [f"'{c}' becomes inactive" for c in lost]
    )
    return LibraryEvent(
        "active set",
        0.5 * (lo + hi),
        (lo, hi),
        sorted(before),
        sorted(after),
        f"active set changes at {0.5 * (lo + hi):.6g} (± {0.5 * abs(hi - lo):.2g}): {what}",
    )


def _bisect_end(
    a: LibraryPoint, b: LibraryPoint, solve: Any, width: float, reference: float
) -> LibraryEvent:
    lo, hi, last = a.value, b.value, a
    reason = b.gait.message
    while abs(hi - lo) > width:
        mid = 0.5 * (lo + hi)
        gait = solve(mid, last.gait, verify=False)
        if _optimum(gait):
            point = LibraryPoint(mid, gait, True, 0.0)
            col, w = gait.transcription
            point.hessian = reduced_hessian(col, w, col.model.p)
            lo, last = mid, point
        else:
            hi, reason = mid, gait.message
    ratio = last.hessian_ratio
    # Near singular relative to the library's first point (the ratio carries the mesh's
    # quadrature weights, so only its fall along the library means something).
    fold = bool(np.isfinite(ratio) and np.isfinite(reference) and ratio < _FOLD_RATIO * reference)
    kind = "fold" if fold else "end"
    detail = (
        f"the reduced Hessian becomes singular there (λmin/λmax {ratio:.2g}, against "
        f"{reference:.2g} at the library's start): a fold"
        if fold
        else f"λmin/λmax of the reduced Hessian {ratio:.2g} at the last optimum ({reference:.2g} "
        f"at the library's start): not a fold; {reason}"
    )
    return LibraryEvent(
        kind,
        0.5 * (lo + hi),
        (lo, hi),
        sorted(last.gait.active_constraints),
        [],
        f"warm starts stop converging at {0.5 * (lo + hi):.6g} (± {0.5 * abs(hi - lo):.2g}); "
        + detail,
    )
