"""The transverse feedback law as the simulator applies it: ``u = u*(τ) − K(τ) x⊥``, with ``τ``
the phase of the nearest orbit point and ``x⊥`` the transverse coordinates there.

For a state ``x`` of phase ``i`` in step ``k`` the stage is the orbit's phase ``i`` of step
``k mod steps``.  Its nominal orbit (extended past both ends, :mod:`~gaitopt.transverse.orbit`)
is tabulated on a grid of phases with its velocity ``f*``; the nearest grid point starts a
Newton iteration on ``h(τ) = f*(τ)ᵀ (x − x*(τ)) = 0`` (the condition for the nearest point:
``x − x*(τ)`` orthogonal to the orbit) with ``x*`` the cubic Hermite interpolant of the
grid's states and velocities (fourth-order accurate), ``f*`` its derivative.  The gains are
interpolated linearly in ``τ`` between grid points (held at the stage's ends on the
extensions); ``u*`` is the gait's own input at ``τ``.

Where the model's or the gait's input bounds are finite, the input is clipped to them
(saturation); the law records the largest input it demanded and applied and how often it
saturated, so that a result can report it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .linearise import TransverseLinearisation
from .riccati import PeriodicRiccati

__all__ = ["TransverseLaw", "StageTable", "LawBudgetExceeded"]


class LawBudgetExceeded(RuntimeError):
    """A simulation called the law more often than its :attr:`TransverseLaw.budget`."""


_GRID = 240  # grid intervals per stage (and its extensions), at least


@dataclass
class StageTable:
    """A stage's nominal orbit and gains on a grid of phases ``τ`` (s)."""

    taus: np.ndarray
    X: np.ndarray  # grid × n
    F_right: np.ndarray  # velocity at each node, input from the interval after it
    F_left: np.ndarray  # velocity at each node, input from the interval before it
    K: np.ndarray  # grid × n_u × (n − 1)
    axis: int
    sign: float
    duration: float
    value: object  # u*(τ)
    breaks: np.ndarray = field(default_factory=lambda: np.zeros(0))  # where u* may jump
    K_spline: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        from scipy.interpolate import CubicSpline

        # one spline per piece between the input's breakpoints, where u̇* (so Π̇, A⊥ and the
        # gains' slope) may jump: a spline across one would smear the kink over its neighbours
        taus = self.taus
        cuts = sorted({0, taus.size - 1, *np.searchsorted(taus, self.breaks).tolist()})
        cuts = [c for c in cuts if 0 <= c < taus.size]
        coeffs = np.zeros((4, taus.size - 1, *self.K.shape[1:]))
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            if b - a >= 2:
                coeffs[:, a:b] = CubicSpline(taus[a : b + 1], self.K[a : b + 1], axis=0).c
            elif b - a == 1:  # one interval: the straight line
                coeffs[2, a] = (self.K[b] - self.K[a]) / (taus[b] - taus[a])
                coeffs[3, a] = self.K[a]
        self.K_spline = coeffs  # 4 × intervals × n_u × m
        self.keep = np.array([i for i in range(self.X.shape[1]) if i != self.axis])

    def locate(self, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, int]:
        """``(τ, x*(τ), f*(τ), interval)`` of the nearest orbit point: Newton on
        ``h(τ) = f*ᵀ (x − x*)`` with the Hermite interpolant's exact derivatives, from the
        nearest grid node moved along its velocity."""
        taus, X = self.taus, self.X
        diff = X - x
        i = int(np.argmin(np.einsum("ij,ij->i", diff, diff)))
        f = self.F_right[i]
        tau = min(max(taus[i] - float(f @ diff[i]) / float(f @ f), taus[0]), taus[-1])
        j = min(max(int(np.searchsorted(taus, tau, side="right")) - 1, 0), taus.size - 2)
        for _ in range(12):
            xs, fs, fss = self._hermite(j, tau)
            e = x - xs
            slope = float(fss @ e) - float(fs @ fs)
            if slope >= 0:  # far from the orbit: a gradient step instead
                slope = -float(fs @ fs)
            step = float(fs @ e) / -slope
            tau = min(max(tau + step, taus[0]), taus[-1])
            while tau < taus[j] and j > 0:
                j -= 1
            while tau > taus[j + 1] and j < taus.size - 2:
                j += 1
            if abs(step) < 1e-13 * self.duration:
                break
        xs, fs, _ = self._hermite(j, tau)
        return tau, xs, fs, j

    def _hermite(self, j: int, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``x*``, ``ẋ*`` and ``ẍ*`` of the cubic Hermite interpolant on interval ``j``."""
        t0, t1 = self.taus[j], self.taus[j + 1]
        h = t1 - t0
        s = (tau - t0) / h
        xa, xb = self.X[j], self.X[j + 1]
        fa, fb = self.F_right[j] * h, self.F_left[j + 1] * h
        s2, s3 = s * s, s * s * s
        x = (2 * s3 - 3 * s2 + 1) * xa + (s3 - 2 * s2 + s) * fa + (-2 * s3 + 3 * s2) * xb
        x = x + (s3 - s2) * fb
        f = (6 * s2 - 6 * s) * (xa - xb) + (3 * s2 - 4 * s + 1) * fa + (3 * s2 - 2 * s) * fb
        ff = (12 * s - 6) * (xa - xb) + (6 * s - 4) * fa + (6 * s - 2) * fb
        return x, f / h, ff / (h * h)

    def gain(self, j: int, tau: float) -> np.ndarray:
        """``K(τ)`` on interval ``j``: the cubic spline through the grid's gains (a law
        smooth in the state, so that the adaptive integrator's steps are not cut at kinks)."""
        c = self.K_spline[:, j]
        s = min(max(tau - self.taus[j], 0.0), self.taus[j + 1] - self.taus[j])
        return ((c[0] * s + c[1]) * s + c[2]) * s + c[3]


def _project(f: np.ndarray, axis: int, sign: float, e: np.ndarray, keep) -> np.ndarray:
    """``Π e``: the Householder reflection of :func:`~gaitopt.transverse.linearise.householder`
    applied to ``e`` without forming it (row ``axis`` dropped)."""
    v = f / np.sqrt(float(f @ f))
    v[axis] -= sign
    y = e - (2.0 * float(v @ e) / float(v @ v)) * v
    return y[keep]


@dataclass
class TransverseLaw:
    """``law(t, x, phase, step) -> u`` for :func:`gaitopt.simulate`'s ``feedback``.

    Attributes
    ----------
    tables : list of StageTable
        One per stage of the orbit.
    low, high : numpy.ndarray
        Input bounds (``±inf`` where none); the input is clipped to them.
    gains : bool
        False: the phase-indexed feedforward ``u*(τ)`` alone (the open loop of the law).
    peak_demanded, peak_applied : numpy.ndarray
        Largest ``|u|`` per input the law computed before and after clipping, over every call.
    calls, saturated : int
        Calls, and calls where an input was clipped.
    outside : int
        Calls where the nearest orbit point was an end of a stage's extended orbit (the state
        is farther from the impact than the extension reaches).
    budget : int or None
        Most calls a run may make (:class:`LawBudgetExceeded` past it); None: no limit.
    """

    tables: list[StageTable]
    n_phases: int
    steps: int
    low: np.ndarray
    high: np.ndarray
    gains: bool = True
    peak_demanded: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peak_applied: np.ndarray = field(default_factory=lambda: np.zeros(0))
    calls: int = 0
    saturated: int = 0
    outside: int = 0
    budget: int | None = None

    def reset_record(self) -> None:
        """Forget the recorded peaks and counts (before a new run)."""
        self.peak_demanded = np.zeros(self.low.size)
        self.peak_applied = np.zeros(self.low.size)
        self.calls = self.saturated = self.outside = 0

    def transverse(self, x: np.ndarray, phase: int, step: int) -> tuple[float, np.ndarray, int]:
        """``(τ, x⊥, stage index)`` of a state of ``phase`` in ``step``."""
        k = (step % self.steps) * self.n_phases + phase
        table = self.tables[k]
        tau, xs, fs, _ = table.locate(np.asarray(x, dtype=float))
        return tau, _project(fs, table.axis, table.sign, x - xs, table.keep), k

    def __call__(self, t: float, x: np.ndarray, phase: int, step: int) -> np.ndarray:
        del t  # the law is indexed by the phase, not the clock
        x = np.asarray(x, dtype=float)
        k = (step % self.steps) * self.n_phases + phase
        table = self.tables[k]
        tau, xs, fs, j = table.locate(x)
        if tau <= table.taus[0] or tau >= table.taus[-1]:
            self.outside += 1
        u = np.array(table.value(tau), dtype=float)
        if self.gains:
            u = u - table.gain(j, tau) @ _project(fs, table.axis, table.sign, x - xs, table.keep)
        clipped = np.minimum(np.maximum(u, self.low), self.high)
        if self.peak_demanded.size != u.size:
            self.reset_record()
        self.calls += 1
        if self.budget is not None and self.calls > self.budget:
            raise LawBudgetExceeded(
                f"more than {self.budget} evaluations of the law: far from the orbit the nearest "
                f"orbit phase jumps between distant points, and the integrator's steps collapse"
            )
        if np.any(clipped != u):
            self.saturated += 1
        self.peak_demanded = np.maximum(self.peak_demanded, np.abs(u))
        self.peak_applied = np.maximum(self.peak_applied, np.abs(clipped))
        return clipped

    @classmethod
    def build(
        cls,
        lin: TransverseLinearisation,
        riccati: PeriodicRiccati | None,
        low: np.ndarray,
        high: np.ndarray,
    ) -> TransverseLaw:
        """Tabulate each stage (the gains from ``riccati``; None: no gains)."""
        orbit = lin.orbit
        p = orbit.p
        n_u = len(orbit.model.inputs)
        tables = []
        for k, frame in enumerate(lin.frames):
            stage = frame.stage
            lo, hi = -stage.before, stage.duration + stage.after
            grid = np.linspace(lo, hi, _GRID + 1)
            taus = np.unique(np.concatenate([grid, stage.breaks]))
            X = np.array([stage.x(t) for t in taus])
            F_right, F_left = np.zeros_like(X), np.zeros_like(X)
            for i, t in enumerate(taus):
                after = float(np.nextafter(t, np.inf)) if t < hi else t
                before = float(np.nextafter(t, -np.inf)) if t > lo else t
                F_right[i] = np.asarray(frame.flow(X[i], stage.input(after)[0], p)).ravel()
                F_left[i] = np.asarray(frame.flow(X[i], stage.input(before)[0], p)).ravel()
            m = frame.n - 1
            K = np.zeros((taus.size, n_u, m))
            if riccati is not None:
                for i, t in enumerate(taus):
                    K[i] = riccati.gain(k, t)
            tables.append(
                StageTable(
                    taus,
                    X,
                    F_right,
                    F_left,
                    K,
                    frame.axis,
                    frame.sign,
                    stage.duration,
                    stage.value,
                    stage.breaks,
                )  # fmt: skip
            )
        law = cls(tables, len(orbit.model.phases), orbit.steps, np.asarray(low, float),
                  np.asarray(high, float), gains=riccati is not None)  # fmt: skip
        law.reset_record()
        return law
