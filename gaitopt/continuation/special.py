"""Special points along a branch (Kuznetsov, "Elements of Applied Bifurcation Theory", §10.2,
maps): the test functions of the return map's multipliers, their zeros located by regula falsi
on the arclength, and the existence boundary located by bisection."""

from __future__ import annotations

import math

import numpy as np

from ..shooting import certify
from .branch import SpecialPoint

__all__ = [
    "LOCATE_TOL", "SpecialPoints", "bisect_boundary", "regula_falsi", "test_functions",
]  # fmt: skip

#: Parameter accuracy of located special points (absolute).
LOCATE_TOL = 1e-10


class SpecialPoints:
    """Locating special points: a base of :class:`~gaitopt.continuation.follower.Follower`,
    which provides ``correct``, ``certified``, ``lam``, ``weights``, ``multipliers_at``,
    ``model_at``, ``_u``, ``_evaluate``, ``cycles``, ``special_points``, ``problem``, ``param``."""

    # -- special points ---------------------------------------------------------------------
    def _special_points_between(self, y, t, y_new, tests, cycle, h_total, new_tests=None):
        new_tests = test_functions(cycle.multipliers) if new_tests is None else new_tests
        if h_total is None:  # the target step is not along t: use the chord
            h_total = math.sqrt(float((y_new - y) @ (self.weights(y) * (y_new - y))))
            t = (y_new - y) / h_total
        found = []
        for kind in ("LP", "PD", "NS"):
            a, b = tests[kind], new_tests[kind]
            if a == 0 or b == 0 or np.sign(a) == np.sign(b):
                continue
            located = self._locate(y, t, h_total, kind, a, b)
            if located is not None:
                found.append(located)
        for sp in sorted(found, key=lambda s: (s.param - self.lam(y)) * self.direction):
            self.special_points.append(sp)

    def _locate(self, y, t, h_b, kind, psi_a, psi_b) -> SpecialPoint | None:
        """Illinois regula falsi on the arclength for the test function's zero, until the
        bracket is below 1e-10 in the parameter and 1e-9 in the arclength."""

        def evaluate(h):
            y_mid, ok, _ = self.correct(y + h * t, t)
            if not ok:
                return None
            return test_functions(self.multipliers_at(y_mid))[kind], self.lam(y_mid), y_mid

        # Both brackets: near a fold λ is quadratic in the arclength, so a tight λ alone would
        # leave the point (and its multiplier +1) loose.
        y_mid = regula_falsi(
            evaluate, h_b, psi_a, psi_b, self.lam(y),
            lambda lam_lo, lam_hi, lo, hi: abs(lam_hi - lam_lo) < LOCATE_TOL and hi - lo < 1e-9,
        )  # fmt: skip
        if y_mid is None:
            return None
        model = self.model_at(y_mid)
        if model is None:
            return None
        cycle = certify(
            model, self.problem, y_mid[:-1], self._u(y_mid), verify=self.verify, tol=self.tol,
            evaluation=self._evaluate(y_mid),  # kept from the last correction: not recomputed
        )  # fmt: skip
        multipliers = cycle.multipliers if cycle.success else self.multipliers_at(y_mid)
        if kind == "NS" and not _has_complex_pair_on_unit_circle(multipliers):
            return None  # a neutral saddle (real μ_i μ_j = 1), not a Neimark–Sacker point
        what = {
            "LP": "fold: a multiplier passes +1 (two gaits meet)",
            "PD": "period doubling: a multiplier passes −1",
            "NS": "Neimark–Sacker: a complex pair crosses the unit circle",
        }[kind]
        return SpecialPoint(kind, self.lam(y_mid), len(self.cycles) - 1, cycle, what)

    def _boundary(self, y, t, h_fail, reason, locate=True) -> None:
        """Bisect between the last certified point and the failure; record a boundary."""
        lo, last, y_lo = 0.0, self.cycles[-1], y
        if locate:

            def try_at(h):
                y_mid, ok, _ = self.correct(y + h * t, t)
                cycle, y_at = self.certified(y_mid) if ok else (None, y_mid)
                return cycle, y_at, self.lam(y_at)

            lam_hi = self.lam(self.correct(y + h_fail * t, t)[0])
            lo, found, y_found, reason = bisect_boundary(
                try_at, h_fail, self.lam(y), lam_hi, reason
            )
            if found is not None:
                last, y_lo = found, y_found
        if last is not self.cycles[-1]:
            # Special points between the last accepted point and the boundary's last gait (a
            # period doubling just before the end would otherwise be stepped over).
            tests = test_functions(self.cycles[-1].multipliers)
            self._special_points_between(y, t, y_lo, tests, last, h_total=lo)
            self.cycles.append(last)
        lam = float(getattr(last.model, self.param))
        growth = last.period / self.first.period
        if growth > 3:
            reason = (
                f"its period grows without bound ({last.period:.4g} s here, "
                f"{self.first.period:.4g} s at the start): the orbit comes ever closer to an "
                f"unstable equilibrium; {reason}"
            )
        message = f"the gait stops existing: {reason}" if reason else "the gait stops existing"
        self.special_points.append(
            SpecialPoint("boundary", lam, len(self.cycles) - 1, last, message)
        )
        self.stop = f"boundary at {self.param} = {lam:.10g}"


def test_functions(multipliers: np.ndarray) -> dict[str, float]:
    """Kuznetsov's test functions of a map's fixed point, from its multipliers."""
    mu = np.asarray(multipliers, dtype=complex)
    ns = 1.0 + 0j
    for i in range(len(mu)):
        for j in range(i + 1, len(mu)):
            ns *= mu[i] * mu[j] - 1
    return {
        "LP": float(np.prod(mu - 1).real),
        "PD": float(np.prod(mu + 1).real),
        "NS": float(ns.real) if len(mu) > 1 else 1.0,
    }


def _has_complex_pair_on_unit_circle(multipliers: np.ndarray) -> bool:
    mu = np.asarray(multipliers, dtype=complex)
    return bool(np.any((np.abs(mu.imag) > 1e-8) & (np.abs(np.abs(mu) - 1) < 1e-4)))


def bisect_boundary(try_at, h_fail, lam_lo, lam_hi, reason: str):
    """Bisection on the arclength between the last certified point (``h = 0``) and a failure
    at ``h_fail``, until the bracket is below 1e-14 in the arclength or :data:`LOCATE_TOL` in
    the parameter(s): the existence boundary of a branch or of a bifurcation curve.

    Parameters
    ----------
    try_at : callable
        ``try_at(h) -> (cycle or None, y, lam)``: the point corrected at arclength ``h``, its
        certificate (None where the corrector fails) and its parameter value(s).
    h_fail : float
        Arclength of the failure.
    lam_lo, lam_hi : float or numpy.ndarray
        Parameter value(s) at the last certified point and at the failure.
    reason : str
        Why the failure failed (replaced by the message of the last failed certificate).

    Returns
    -------
    (lo, last, y_last, reason)
        The arclength of the last certified point, its cycle and point (None, None if the
        bisection certified none beyond ``h = 0``), and the reason the gait stops existing.
    """
    lo, hi, last, y_last = 0.0, h_fail, None, None
    while hi - lo > 1e-14 and np.max(np.abs(np.asarray(lam_hi) - lam_lo)) >= LOCATE_TOL:
        h = 0.5 * (lo + hi)
        cycle, y_at, lam = try_at(h)
        if cycle is not None and cycle.success:
            lo, last, y_last, lam_lo = h, cycle, y_at, lam
        else:
            hi, lam_hi = h, lam
            if cycle is not None:
                reason = cycle.message
    return lo, last, y_last, reason


def regula_falsi(evaluate, h_b, f_a, f_b, lam_a, converged):
    """Illinois regula falsi on the arclength ``h ∈ [0, h_b]`` for the zero of a test function
    that changes sign from ``f_a`` (at 0) to ``f_b`` (at ``h_b``): the special points of a branch
    and the codimension-two points of a curve.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(h) -> (f, lam, point)`` at the point corrected at arclength ``h``, or None
        where the corrector fails.
    h_b, f_a, f_b : float
        The bracket's far end and the test function at both ends.
    lam_a : float or numpy.ndarray
        The parameter value(s) at ``h = 0``.
    converged : callable
        ``converged(lam_lo, lam_hi, lo, hi) -> bool`` once both sides have been evaluated.

    Returns
    -------
    object or None
        The ``point`` of the last evaluation (after at most 60), or None if the corrector failed.
    """
    lo, hi, f_lo, f_hi = 0.0, h_b, f_a, f_b
    lam_lo, lam_hi = lam_a, None
    side, point = 0, None
    for _ in range(60):
        h = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        if not lo < h < hi:
            h = 0.5 * (lo + hi)
        got = evaluate(h)
        if got is None:
            return None
        f, lam, point = got
        if f == 0:
            break
        if np.sign(f) == np.sign(f_lo):
            lo, f_lo, lam_lo = h, f, lam
            if side == -1:
                f_hi /= 2
            side = -1
        else:
            hi, f_hi, lam_hi = h, f, lam
            if side == 1:
                f_lo /= 2
            side = 1
        if lam_hi is not None and converged(lam_lo, lam_hi, lo, hi):
            break
    return point
