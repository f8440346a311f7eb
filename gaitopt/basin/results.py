"""The estimates' results: :class:`Basin` (rays), :class:`BasinSlice` (a grid over two section
coordinates), :class:`BasinFraction` (random starts, with :func:`wilson_interval`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError

__all__ = ["Basin", "BasinSlice", "BasinFraction", "wilson_interval"]

#: Two-sided 95 % normal quantile of the Wilson interval.
_Z95 = 1.959963984540054


@dataclass
class Basin:
    """The star-shaped estimate of a gait's basin (:func:`basin`).

    Attributes
    ----------
    success : bool
        The estimate was computed (False for an unstable gait: its basin is empty).
    message : str
        What was found, the star-shaped assumption, or why the basin is empty.
    model : HybridModel
        The gait's model.
    coordinates : tuple of str
        Section coordinates the rays span (the others stay at the fixed point).
    fixed_point : dict of str to float
        The gait's fixed point in section coordinates (units of the model's states).
    scale : numpy.ndarray
        Scale of each coordinate of ``coordinates`` (their units): radii are in units of it.
    directions : numpy.ndarray
        Unit vectors of the rays in scaled coordinates, ``rays × len(coordinates)``.
    radii : numpy.ndarray
        Per ray, the largest radius (dimensionless, scaled) confirmed by simulation to converge
        below the first failure found; 0 if none was; ``max_radius`` if nothing failed.
    first_failure : numpy.ndarray
        Per ray, the smallest radius found to fail (NaN if none up to ``max_radius``).
    capped : numpy.ndarray
        Per ray, whether nothing failed up to ``max_radius`` (the radius is then only a bound).
    flags : list of dict
        Non-monotone rays: ``{"ray", "first_failure", "converges_at"}`` — radii beyond the first
        failure from which the simulation converges (the basin is not star-shaped there).
    max_radius : float
        Largest radius probed (scaled).
    settings : dict
        ``steps``, ``hold``, ``tol``, ``scan``, ``bisections``.
    simulations : int
        Starts simulated.
    elapsed : float
        Wall-clock seconds.
    """

    success: bool
    message: str
    model: Any
    coordinates: tuple[str, ...]
    fixed_point: dict[str, float]
    scale: np.ndarray
    directions: np.ndarray
    radii: np.ndarray
    first_failure: np.ndarray
    capped: np.ndarray
    flags: list[dict[str, Any]] = field(default_factory=list)
    max_radius: float = 1.0
    settings: dict[str, Any] = field(default_factory=dict)
    simulations: int = 0
    elapsed: float = 0.0

    def endpoints(self) -> np.ndarray:
        """The rays' end points in section coordinates of ``coordinates`` (their units)."""
        centre = np.array([self.fixed_point[c] for c in self.coordinates])
        return centre + self.radii[:, None] * self.directions * self.scale

    def claims(self, points: np.ndarray, *, next_to_flags: bool = False) -> np.ndarray:
        """Which points (rows, in ``coordinates``, their units) the estimate claims converge.

        One coordinate: between the two rays' ends.  Two: within the smaller radius of the two
        rays whose angles enclose the point's angle (a conservative sector between adjacent
        rays), except next to a flagged (non-monotone) ray, where the basin is known not to be
        star-shaped: nothing is claimed there unless ``next_to_flags``.  Both rest on the
        star-shaped assumption, and in two coordinates on the basin filling the sector between
        two rays, which is not simulated.

        Parameters
        ----------
        points : numpy.ndarray
            Rows of the coordinates ``coordinates`` (their units).
        next_to_flags : bool
            Claim the sectors next to flagged rays too (as if the basin were star-shaped there).

        Raises
        ------
        GaitoptInputError
            For rays in more than two coordinates.
        """
        centre = np.array([self.fixed_point[c] for c in self.coordinates])
        z = (np.atleast_2d(np.asarray(points, dtype=float)) - centre) / self.scale
        if z.shape[1] == 1:
            up, down = (self.radii[sign * self.directions[:, 0] > 0] for sign in (1, -1))
            up, down = (r.min() if r.size else 0.0 for r in (up, down))
            return (z[:, 0] <= up) & (z[:, 0] >= -down)
        if z.shape[1] != 2:
            raise GaitoptInputError(
                f"`points`: claims() takes rays in one or two coordinates, these span "
                f"{len(self.coordinates)}; use coordinates=(A, B) in basin()"
            )
        angles = np.arctan2(self.directions[:, 1], self.directions[:, 0]) % (2 * np.pi)
        order = np.argsort(angles)
        radii = self.radii.copy()
        if not next_to_flags:
            radii[[flag["ray"] for flag in self.flags]] = 0.0
        angles, radii = angles[order], radii[order]
        phi = np.arctan2(z[:, 1], z[:, 0]) % (2 * np.pi)
        after = np.searchsorted(angles, phi) % len(angles)
        before = (after - 1) % len(angles)
        bound = np.minimum(radii[after], radii[before])
        return np.hypot(z[:, 0], z[:, 1]) <= bound

    def as_dict(self) -> dict[str, Any]:
        """JSON-able summary (``gaitopt basin --json``)."""
        return {
            "model": self.model.name,
            "params": self.model.params,
            "success": bool(self.success),
            "message": self.message,
            "coordinates": list(self.coordinates),
            "fixed_point": dict(self.fixed_point),
            "scale": self.scale.tolist(),
            "max_radius": self.max_radius,
            "directions": self.directions.tolist(),
            "radii": self.radii.tolist(),
            "first_failure": [None if math.isnan(r) else r for r in self.first_failure],
            "capped": self.capped.tolist(),
            "endpoints": self.endpoints().tolist(),
            "flags": self.flags,
            "settings": self.settings,
            "assumption": "inner estimate only if the basin is star-shaped along each ray",
            "simulations": self.simulations,
            "elapsed_s": self.elapsed,
        }


@dataclass
class BasinSlice:
    """A grid of simulated starts over two section coordinates (:func:`basin_slice`).

    Attributes
    ----------
    coordinates : tuple of str
        The two coordinates varied (the others at the fixed point).
    values : tuple of numpy.ndarray
        Grid values of each (their units).
    converged : numpy.ndarray
        ``len(values[1]) × len(values[0])`` booleans: the start converged.
    outcomes : numpy.ndarray
        The same grid: ``"converged"`` or why not (``"fell"``, ``"standing"``, ``"not
        converged"``, ``"invalid start"``…).
    fixed_point : dict of str to float
        The gait's fixed point.
    model : HybridModel
        The gait's model.
    settings : dict
        ``steps``, ``hold``, ``tol``.
    elapsed : float
        Wall-clock seconds.
    """

    coordinates: tuple[str, str]
    values: tuple[np.ndarray, np.ndarray]
    converged: np.ndarray
    outcomes: np.ndarray
    fixed_point: dict[str, float]
    model: Any
    settings: dict[str, Any]
    elapsed: float

    @property
    def fraction(self) -> float:
        """Fraction of the grid's starts that converge."""
        return float(np.mean(self.converged))

    def points(self) -> np.ndarray:
        """The grid's starts in the two coordinates, rows in the order of ``converged.ravel()``."""
        a, b = np.meshgrid(*self.values)
        return np.column_stack([a.ravel(), b.ravel()])

    def as_dict(self) -> dict[str, Any]:
        """JSON-able summary."""
        return {
            "coordinates": list(self.coordinates),
            "values": [v.tolist() for v in self.values],
            "converged": self.converged.astype(int).tolist(),
            "outcomes": self.outcomes.tolist(),
            "fraction": self.fraction,
            "fixed_point": dict(self.fixed_point),
            "settings": self.settings,
            "elapsed_s": self.elapsed,
        }


@dataclass
class BasinFraction:
    """Sampled fraction of a window on the section that converges (:func:`basin_fraction`).

    Attributes
    ----------
    fraction : float
        Converged starts / samples.
    interval : tuple of float
        Wilson score interval of the fraction at ``confidence``.
    confidence : float
        0.95.
    samples, converged : int
        Starts simulated and how many converged.
    window : dict of str to (float, float)
        The box sampled, per section coordinate (its unit).
    settings : dict
        ``steps``, ``hold``, ``tol``, ``seed``.
    elapsed : float
        Wall-clock seconds.
    starts : numpy.ndarray or None
        The starts (rows of section coordinates, their units).
    outcomes : numpy.ndarray or None
        Each start's outcome (``"converged"`` or why not).
    """

    fraction: float
    interval: tuple[float, float]
    confidence: float
    samples: int
    converged: int
    window: dict[str, tuple[float, float]]
    settings: dict[str, Any]
    elapsed: float
    starts: np.ndarray | None = None
    outcomes: np.ndarray | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-able summary."""
        return {
            "fraction": self.fraction,
            "interval": list(self.interval),
            "confidence": self.confidence,
            "samples": self.samples,
            "converged": self.converged,
            "window": {k: list(v) for k, v in self.window.items()},
            "settings": self.settings,
            "elapsed_s": self.elapsed,
        }


def wilson_interval(successes: int, n: int, z: float = _Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion.

    >>> [round(v, 4) for v in wilson_interval(5, 10)]
    [0.2366, 0.7634]
    """
    p = successes / n
    denominator = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denominator
    half = z / denominator * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, centre - half), min(1.0, centre + half)
