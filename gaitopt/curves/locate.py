"""Locating points along a bifurcation curve: the codimension-two points between consecutive
points (zeros of :mod:`gaitopt.curves.codim2`'s test functions, by the Illinois regula falsi that
continuation's special points use) and the curve's end where the gait stops existing (by the
same bisection as a branch's boundary): a base of
:class:`~gaitopt.curves.follower.CurveFollower`, which provides ``correct``, ``certified``,
``tangent``, ``weights``, ``lam``, ``values``, ``tests_at``, ``multipliers_at``, ``accept``,
``cycles``, ``special_points``, ``kind``."""

from __future__ import annotations

import math

import numpy as np

from ..continuation.special import LOCATE_TOL, bisect_boundary, regula_falsi
from . import codim2
from .result import CurvePoint

__all__ = ["CurvePoints"]


class CurvePoints:
    """The codimension-two points and the boundary of a curve (see the module docstring)."""

    # -- codimension two ---------------------------------------------------------------------
    def _codim2_between(self, y, t, y_new, tests, new_tests) -> None:
        W = self.weights(y)
        h_total = math.sqrt(float((y_new - y) @ (W * (y_new - y))))
        if h_total == 0:
            return
        chord = (y_new - y) / h_total
        found = []
        for label, a in tests.items():
            b = new_tests.get(label)
            if b is None or a == 0 or b == 0 or np.sign(a) == np.sign(b):
                continue
            point = self._locate(y, chord, t, h_total, label, a, b)
            if point is not None:
                found.append(point)
        found.sort(key=lambda sp: sp[0])
        self.special_points.extend(sp for _, sp in found)

    def _locate(self, y, chord, t, h_b, label, f_a, f_b):
        """Illinois regula falsi on the chord's arclength for a test function's zero, until the
        bracket is below 1e-10 in both parameters."""
        row = self.weights(y) * chord

        def evaluate(h):
            y_mid, ok, _ = self.correct(y + h * chord, row)
            if not ok:
                return None
            t_mid = self.tangent(y_mid, t)
            return self.tests_at(y_mid, t_mid)[label], self.lam(y_mid), (y_mid, h)

        located = regula_falsi(
            evaluate, h_b, f_a, f_b, self.lam(y),
            lambda lam_lo, lam_hi, lo, hi: np.max(np.abs(lam_hi - lam_lo)) < LOCATE_TOL,
        )  # fmt: skip
        if located is None:
            return None
        y_mid, h = located
        mu = self.multipliers_at(y_mid)
        if not codim2.is_genuine(label, mu, self.kind):
            return None
        cycle, _ = self.certified(y_mid)
        kind = label
        message = codim2.DESCRIPTIONS[label.split(":")[0]]
        if label.startswith("fold:"):
            message = f"the curve turns back in {label[5:]} (d{label[5:]}/ds = 0)"
        if cycle is None or not cycle.success:
            message += "; the gait there could not be certified"
        point = CurvePoint(kind, self.values(y_mid), len(self.cycles) - 1, cycle, message)
        return h, point

    def _boundary(self, y, t, h_fail, y_fail, failed) -> None:
        """Bisect between the last certified point and the failure; the curve ends there."""
        reason = failed.message if failed is not None else "the corrector cannot continue"
        last = self.cycles[-1]
        if h_fail is None:  # the failure was the landing point: bisect along the chord
            W = self.weights(y)
            h_fail = math.sqrt(float((y_fail - y) @ (W * (y_fail - y))))
            t = (y_fail - y) / h_fail if h_fail > 0 else t
        row = self.weights(y) * t

        def try_at(h):
            y_mid, ok, _ = self.correct(y + h * t, row)
            cycle, y_mid = self.certified(y_mid) if ok else (None, y_mid)
            return cycle, y_mid, self.lam(y_mid)

        _, found, y_found, reason = bisect_boundary(
            try_at, h_fail, self.lam(y), self.lam(y_fail), reason
        )
        last, y_last = (found, y_found) if found is not None else (last, y)
        if last is not self.cycles[-1]:
            self.accept(last, y_last)
        self.special_points.append(
            CurvePoint(
                "boundary", self.values(y_last), len(self.cycles) - 1, last,
                f"the gait stops existing on the curve: {reason}",
            )
        )  # fmt: skip
        self.stop = f"boundary at {self._where(y_last)}"
