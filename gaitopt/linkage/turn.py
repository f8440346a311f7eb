"""One crank turn of a linkage and the foot path's numbers: extremes, ground fraction, stride,
the ride height of leg pairs on one crank and its ripple."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Protocol

import numpy as np

__all__ = ["Turn", "SIX_PAIR_PHASES", "GROUND_BAND"]

#: Deits' and Drake's six pairs on one crank (rad).
SIX_PAIR_PHASES = (0.0, 2 * math.pi / 3, 4 * math.pi / 3, math.pi / 3, math.pi, 5 * math.pi / 3)
#: The ground band of the ground fraction: within 5 mm of the foot's lowest point (m).
GROUND_BAND = 0.005


class Linkage(Protocol):
    """What a turn needs of its linkage (:class:`~gaitopt.linkage.jansen.JansenLinkage`, which
    builds turns: a protocol, so that this module does not import it back)."""

    @property
    def name(self) -> str: ...

    @property
    def params(self) -> dict[str, float]: ...

    def solve(
        self, theta: float, guess: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class Turn:
    """One crank turn of a linkage, sampled: ``thetas`` (N+1,), joints ``z`` and ``dz/dθ``
    (N+1, 5, 2; m and m/rad).  :meth:`at` solves exactly between samples."""

    linkage: Linkage
    thetas: np.ndarray
    z: np.ndarray
    dz: np.ndarray

    @property
    def foot(self) -> np.ndarray:
        """Foot path (N+1, 2) (m, relative to the crank axle)."""
        return self.z[:, 4]

    @property
    def foot_velocity(self) -> np.ndarray:
        """``dr_foot/dθ`` (N+1, 2) (m/rad) = crank torque per unit foot force (x, y) (N·m/N)."""
        return self.dz[:, 4]

    def at(self, theta: float) -> tuple[np.ndarray, np.ndarray]:
        """Joints and ``dz/dθ`` at any crank angle, on this turn's branch (Newton from the
        nearest sample, predicted along its tangent)."""
        t0 = self.thetas[0]
        period = 2 * math.pi
        phase = (theta - t0) % period
        n = int(round(phase / period * (len(self.thetas) - 1)))
        n = min(n, len(self.thetas) - 1)
        guess = self.z[n] + (phase + t0 - self.thetas[n]) * self.dz[n]
        return self.linkage.solve(theta, guess.ravel())

    def foot_y(self, theta: float) -> float:
        """Foot height at crank angle θ (m)."""
        return float(self.at(theta)[0][4, 1])

    def _extremum(self, values: np.ndarray, component: int, sign: float) -> tuple[float, float]:
        """Refined ``sign · max`` of a foot coordinate: Brent's method around the best sample."""
        from scipy.optimize import minimize_scalar  # on first use (0.5 s)

        n = int(np.argmax(sign * values))
        step = self.thetas[1] - self.thetas[0]
        res = minimize_scalar(
            lambda t: -sign * float(self.at(t)[0][4, component]),
            bounds=(self.thetas[n] - step, self.thetas[n] + step),
            method="bounded",
            options={"xatol": 1e-10},
        )
        best = max(sign * values[n], -res.fun)
        return sign * best, float(res.x)

    @cached_property
    def extremes(self) -> dict[str, tuple[float, float]]:
        """``name -> (value (m), θ (rad))`` of the foot path's x_min, x_max, y_min, y_max."""
        out = {}
        for comp, axis in ((0, "x"), (1, "y")):
            values = self.foot[:-1, comp]
            out[f"{axis}_min"] = self._extremum(values, comp, -1.0)
            out[f"{axis}_max"] = self._extremum(values, comp, +1.0)
        return out

    def ground_fraction(self, band: float = GROUND_BAND) -> float:
        """Share of a crank turn (uniform crank rate) with the foot within ``band`` (m) of its
        lowest point: the crossings of ``y = y_min + band`` refined by Brent's method."""
        from scipy.optimize import brentq  # on first use (0.5 s)

        level = self.extremes["y_min"][0] + band
        y = self.foot[:, 1] - level
        inside = 0.0
        crossings = []
        for n in range(len(y) - 1):
            if y[n] == 0 or y[n] * y[n + 1] < 0:
                t = brentq(
                    lambda s: self.foot_y(s) - level,
                    self.thetas[n],
                    self.thetas[n + 1],
                    xtol=1e-13,
                )
                crossings.append((t, 1 if y[n + 1] < 0 else -1))  # +1: entering the band
        if not crossings:
            return 1.0 if y[0] < 0 else 0.0
        crossings.sort()
        # Walk round the turn: from each entry to the next exit.
        for q, (t, kind) in enumerate(crossings):
            if kind == 1:
                t_exit, _ = crossings[(q + 1) % len(crossings)]
                inside += (t_exit - t) % (2 * math.pi)
        return inside / (2 * math.pi)

    def feet_heights(self, phases: Sequence[float], thetas: np.ndarray) -> np.ndarray:
        """Foot heights (2P, len(thetas)) (m) of P pairs at crank phases ``phases``: the legs
        ``y(θ + φ)`` then their mirror images ``y(π − θ − φ)`` (by interpolating the dense,
        exact samples with the AD tangents: a cubic Hermite spline)."""
        rows = [self._hermite_y(np.asarray(thetas) + ph) for ph in phases]
        rows += [self._hermite_y(math.pi - np.asarray(thetas) - ph) for ph in phases]
        return np.array(rows)

    def _hermite_y(self, t: np.ndarray) -> np.ndarray:
        t0, h = self.thetas[0], self.thetas[1] - self.thetas[0]
        s = ((t - t0) % (2 * math.pi)) / h
        n = np.minimum(np.floor(s).astype(int), len(self.thetas) - 2)
        u = s - n
        y0, y1 = self.foot[n, 1], self.foot[n + 1, 1]
        d0, d1 = self.dz[n, 4, 1] * h, self.dz[n + 1, 4, 1] * h
        return (
            (2 * u**3 - 3 * u**2 + 1) * y0
            + (u**3 - 2 * u**2 + u) * d0
            + (-2 * u**3 + 3 * u**2) * y1
            + (u**3 - u**2) * d1
        )

    def ride_height(self, phases: Sequence[float], thetas: np.ndarray) -> np.ndarray:
        """Height of the crank axle above the machine's lowest foot (m) at crank angles θ."""
        return -np.min(self.feet_heights(phases, thetas), axis=0)

    def ripple(self, phases: Sequence[float] = SIX_PAIR_PHASES) -> float:
        """Peak-to-peak ride height over a turn (m), pairs at ``phases``.

        The highest ride is ``−y_min`` (every foot reaches the path's lowest point); the lowest
        is found on a dense grid and refined with exact solves (Brent's method on the lower
        envelope of the feet around the best grid point).
        """
        from scipy.optimize import minimize_scalar  # on first use (0.5 s)

        grid = np.linspace(0, 2 * math.pi, 8 * (len(self.thetas) - 1), endpoint=False)
        ride = self.ride_height(phases, grid)
        n = int(np.argmin(ride))
        step = grid[1] - grid[0]

        def exact(t: float) -> float:
            heights = [self.foot_y(t + ph) for ph in phases]
            heights += [self.foot_y(math.pi - t - ph) for ph in phases]
            return -min(heights)

        res = minimize_scalar(
            exact, bounds=(grid[n] - step, grid[n] + step), method="bounded",
            options={"xatol": 1e-11},
        )  # fmt: skip
        lowest = min(float(res.fun), exact(grid[n]))
        return -self.extremes["y_min"][0] - lowest

    def numbers(self) -> dict[str, Any]:
        """The foot path's numbers (m unless stated).

        ``width``/``height``: horizontal/vertical extents of the foot path; ``ground_fraction``:
        share of a turn within 5 mm of the lowest point; ``stride``: horizontal length of the
        path inside that band; ``ripple_six_pairs``/``ripple_one_pair``: peak-to-peak ride
        height; ``lowest_point``: (x, y) of the lowest point; ``ground_speed``: foot speed
        ``|dx/dθ|`` at the lowest point (m/rad).
        """
        ex = self.extremes
        y_min, t_low = ex["y_min"]
        z_low, dz_low = self.at(t_low)
        band = self.foot[:, 1] <= y_min + GROUND_BAND
        stride = float(np.ptp(self.foot[band, 0])) if np.any(band) else 0.0
        return {
            "linkage": self.linkage.name,
            "width": ex["x_max"][0] - ex["x_min"][0],
            "height": ex["y_max"][0] - ex["y_min"][0],
            "ground_fraction": self.ground_fraction(),
            "ripple_six_pairs": self.ripple(SIX_PAIR_PHASES),
            "ripple_one_pair": self.ripple((0.0,)),
            "stride": stride,
            "lowest_point": [float(z_low[4, 0]), float(y_min)],
            "lowest_point_theta": t_low % (2 * math.pi),
            "ground_speed": float(abs(dz_low[4, 0])),
            "ground_band": GROUND_BAND,
            "six_pair_phases": list(SIX_PAIR_PHASES),
            "units": {
                "width": "m", "height": "m", "ground_fraction": "1", "ripple_six_pairs": "m",
                "ripple_one_pair": "m", "stride": "m", "lowest_point": "m",
                "lowest_point_theta": "rad", "ground_speed": "m/rad", "ground_band": "m",
                "six_pair_phases": "rad",
            },
            "params": self.linkage.params,
        }  # fmt: skip
