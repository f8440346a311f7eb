"""A compiled arc's dense output without importing :mod:`scipy.integrate` (0.3–0.5 s at start-up).

:class:`Dop853Piece` is SciPy's ``Dop853DenseOutput`` (``scipy/integrate/_ivp/rk.py``: Hairer,
Nørsett & Wanner's 7-coefficient DOP853 interpolant, *Solving ODEs I*, §II.6) and
:class:`PiecewiseSolution` SciPy's ``OdeSolution.__call__`` for increasing time stamps
(``scipy/integrate/_ivp/common.py``): the same operations in the same order, so an arc evaluates
to the same bits as with SciPy's classes (tests/test_simulation_dense.py compares them).  Only
the compiled simulation's arcs and the Python loop's DOP853 (:class:`gaitopt.dop853.CompiledDOP853`:
a feedforward's simulation, the optimiser's referee) use them; SciPy's own classes remain those
of its other methods (RK45, Radau, LSODA).  :class:`ConstantPiece` is SciPy's
``ConstantDenseOutput`` (a step of zero length), :class:`Pieces` an ``OdeSolution`` of given
pieces.
"""

from __future__ import annotations

from itertools import groupby

import numpy as np

__all__ = ["ConstantPiece", "Dop853Piece", "Pieces", "PiecewiseSolution"]


class Dop853Piece:
    """One DOP853 step's interpolant (SciPy's ``Dop853DenseOutput``).

    Parameters
    ----------
    t_old, t : float
        The step's start and end (s).
    y_old : numpy.ndarray
        The state at ``t_old``.
    F : numpy.ndarray
        The 7 dense-output coefficient vectors (7 × n).
    """

    def __init__(self, t_old: float, t: float, y_old: np.ndarray, F: np.ndarray):
        self.t_old, self.t = t_old, t
        self.t_min, self.t_max = min(t, t_old), max(t, t_old)
        self.h = t - t_old
        self.F = F
        self.y_old = y_old

    def __call__(self, t) -> np.ndarray:
        """The state at ``t`` (n) or at each time of a 1-D ``t`` (n × len(t))."""
        t = np.asarray(t)
        if t.ndim > 1:
            raise ValueError("`t` must be a float or a 1-D array.")
        x = (t - self.t_old) / self.h
        if t.ndim == 0:
            y = np.zeros_like(self.y_old)
        else:
            x = x[:, None]
            y = np.zeros((len(x), len(self.y_old)), dtype=self.y_old.dtype)
        for i, f in enumerate(reversed(self.F)):
            y += f
            if i % 2 == 0:
                y *= x
            else:
                y *= 1 - x
        y += self.y_old
        return y.T


class ConstantPiece:
    """A constant interpolant (SciPy's ``ConstantDenseOutput``: a step of zero length, or a
    phase held at its start state).

    Parameters
    ----------
    t_old, t : float
        The interval's ends (s).
    value : numpy.ndarray
        The state held.
    """

    def __init__(self, t_old: float, t: float, value: np.ndarray):
        self.t_old, self.t = t_old, t
        self.t_min, self.t_max = min(t, t_old), max(t, t_old)
        self.value = value

    def __call__(self, t) -> np.ndarray:
        """The state (n), or n × len(t) copies of it for a 1-D ``t``."""
        t = np.asarray(t)
        if t.ndim > 1:
            raise ValueError("`t` must be a float or a 1-D array.")
        if t.ndim == 0:
            return self.value
        out = np.empty((self.value.shape[0], t.shape[0]))
        out[:] = self.value[:, None]
        return out


class PiecewiseSolution:
    """Pieces on consecutive, increasing time stamps, evaluated as SciPy's ``OdeSolution`` does
    (a time on a stamp belongs to the piece before it; outside, the first or last piece).

    Subclasses set ``ts`` (the stamps), ``n_segments`` and :attr:`interpolants`.
    """

    ts: np.ndarray
    n_segments: int
    t_min: float
    t_max: float

    @property
    def ts_sorted(self) -> np.ndarray:
        return self.ts

    @property
    def interpolants(self) -> list:  # pragma: no cover - set by subclasses
        raise NotImplementedError

    def _segment(self, index):
        return np.clip(index - 1, 0, self.n_segments - 1)

    def __call__(self, t) -> np.ndarray:
        """The state at ``t`` (n) or at each time of a 1-D ``t`` (n × len(t))."""
        t = np.asarray(t)
        if t.ndim == 0:
            segment = int(self._segment(np.searchsorted(self.ts, t, side="left")))
            return self.interpolants[segment](t)
        order = np.argsort(t)
        reverse = np.empty_like(order)
        reverse[order] = np.arange(order.shape[0])
        t_sorted = t[order]
        segments = self._segment(np.searchsorted(self.ts, t_sorted, side="left"))
        ys = []
        start = 0
        for segment, group in groupby(segments):
            end = start + len(list(group))
            ys.append(self.interpolants[segment](t_sorted[start:end]))
            start = end
        return np.hstack(ys)[:, reverse]


class Pieces(PiecewiseSolution):
    """SciPy's ``OdeSolution(ts, interpolants)`` for increasing time stamps (or the two equal
    stamps of a zero-length arc).

    Parameters
    ----------
    ts : array_like
        The time stamps (s), strictly increasing, or two equal ones.
    interpolants : list
        One callable piece per interval (``len(ts) − 1``).
    """

    def __init__(self, ts, interpolants: list):
        ts = np.asarray(ts)
        d = np.diff(ts)
        if not ((ts.size == 2 and ts[0] == ts[-1]) or np.all(d > 0)):
            raise ValueError("`ts` must be strictly increasing.")
        self.n_segments = len(interpolants)
        if ts.shape != (self.n_segments + 1,):
            raise ValueError("Numbers of time stamps and interpolants don't match.")
        self.ts = ts
        self._pieces = interpolants
        self.t_min, self.t_max = ts[0], ts[-1]

    @property
    def interpolants(self) -> list:
        """The pieces."""
        return self._pieces
