"""An input profile ``u(t)``: piecewise polynomials in the time since the section.

The transcription's inputs are, on each mesh interval, the polynomial through their values at
the interval's Radau points; this object evaluates that profile for the simulator (a
feedforward ``u(t, step)``, :func:`gaitopt.simulate`) and its time derivative for the
sensitivities.  Before ``t = 0`` the first value holds, after the orbit's end the last value
holds (a step that lasts longer keeps its final input).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["InputProfile"]


class InputProfile:
    """Piecewise-polynomial ``u(t)`` on ``[0, breaks[-1]]``.

    Parameters
    ----------
    breaks : numpy.ndarray
        Interval boundaries (s), increasing, starting at 0.
    coefficients : numpy.ndarray
        ``(intervals, degree + 1, inputs)``: power-series coefficients in the local time
        ``t − breaks[i]`` (s), highest power first.
    """

    def __init__(self, breaks: np.ndarray, coefficients: np.ndarray):
        self.breaks = np.asarray(breaks, dtype=float)
        self.coefficients = np.asarray(coefficients, dtype=float)
        self.duration = float(self.breaks[-1])

    @classmethod
    def from_nodes(
        cls, starts: np.ndarray, lengths: np.ndarray, tau: np.ndarray, values: list[np.ndarray]
    ) -> InputProfile:
        """From each interval's start time, length, local node positions ``tau`` (in [0, 1])
        and input values there (``inputs × len(tau)``)."""
        coeffs = []
        for h, U in zip(lengths, values, strict=True):
            nodes = np.asarray(tau) * h
            coeffs.append(np.polyfit(nodes, np.asarray(U, dtype=float).T, len(tau) - 1))
        breaks = np.append(np.asarray(starts, dtype=float), starts[-1] + lengths[-1])
        return cls(breaks, np.array(coeffs))

    def as_dict(self) -> dict[str, list]:
        """``{"breaks": [...], "coefficients": [...]}`` in plain JSON types (s; input units per
        power of s), exactly: :meth:`from_dict` rebuilds the same profile bit for bit."""
        return {"breaks": self.breaks.tolist(), "coefficients": self.coefficients.tolist()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> InputProfile:
        """The profile :meth:`as_dict` wrote (``ValueError`` where the arrays do not fit)."""
        breaks = np.asarray(data["breaks"], dtype=float)
        coefficients = np.asarray(data["coefficients"], dtype=float)
        if (
            breaks.ndim != 1
            or coefficients.ndim != 3
            or breaks.size != coefficients.shape[0] + 1
            or not np.all(np.diff(breaks) > 0)
            or not np.all(np.isfinite(coefficients))
        ):
            raise ValueError(
                f"an input profile needs increasing breaks and (intervals, degree + 1, inputs) "
                f"finite coefficients, one interval fewer than breaks; got {breaks.size} breaks "
                f"and coefficients of shape {coefficients.shape}"
            )
        return cls(breaks, coefficients)

    def _locate(self, t: float) -> tuple[int, float]:
        i = int(np.searchsorted(self.breaks, t, side="right")) - 1
        i = min(max(i, 0), len(self.coefficients) - 1)
        return i, t - self.breaks[i]

    def __call__(self, t: float, step: int = 0) -> np.ndarray:
        """``u(t)`` (input units); ``step`` is ignored (the same profile every step)."""
        del step
        t = min(max(float(t), 0.0), self.duration)
        i, local = self._locate(t)
        c = self.coefficients[i]
        value = c[0].copy()
        for row in c[1:]:
            value = value * local + row
        return value

    def vectorised(self, times: np.ndarray, step: int = 0) -> np.ndarray:
        """``u`` at each of ``times`` (s): inputs × ``len(times)``, each column equal to
        ``self(t)`` to the last bit (the same clipping, interval and Horner arithmetic);
        ``step`` is ignored.  The simulator's fast path evaluates a step's stage times at once
        (:class:`gaitopt.dop853.CompiledDOP853`)."""
        del step
        t = np.minimum(np.maximum(np.asarray(times, dtype=float), 0.0), self.duration)
        i = np.searchsorted(self.breaks, t, side="right") - 1
        np.minimum(np.maximum(i, 0, out=i), len(self.coefficients) - 1, out=i)
        local = (t - self.breaks[i])[:, None]
        c = self.coefficients[i]  # times × (degree + 1) × inputs
        value = c[:, 0, :]
        for power in range(1, c.shape[1]):
            value = value * local + c[:, power, :]
        return value.T

    def derivative(self, t: float) -> np.ndarray:
        """``du/dt`` (input units per second) inside the profile (left derivative at the end)."""
        t = min(max(float(t), 0.0), self.duration)
        i, local = self._locate(t)
        if t >= self.duration:
            i, local = len(self.coefficients) - 1, t - self.breaks[-2]
        c = self.coefficients[i]
        degree = c.shape[0] - 1
        value = np.zeros(c.shape[1])
        for power, row in enumerate(c[:-1]):
            value = value * local + (degree - power) * row
        return value

    def sample(self, count: int = 401) -> tuple[np.ndarray, np.ndarray]:
        """``count`` times on ``[0, duration]`` and the inputs there (``inputs × count``)."""
        t = np.linspace(0.0, self.duration, count)
        return t, np.array([self(tt) for tt in t]).T
