"""Step-to-step (Poincaré) return maps: evaluate them, and find every fixed point of a 1-D map.

The map is evaluated by independent simulation (:func:`gaitopt.simulate`), in the model's section
coordinates; where the motion does not return to the section (the walker falls, the wheel rocks
back to rest, the runner stops) the map is undefined and the value is NaN.  Its Jacobian at a
fixed point comes from the shooting equations (:attr:`LimitCycle.jacobian`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .errors import GaitoptInputError
from .hybrid import HybridModel
from .result import LimitCycle
from .shooting import find_limit_cycle
from .simulation import simulate

__all__ = ["return_map", "fixed_points_1d", "MapFixedPoints"]


def return_map(
    model: HybridModel,
    coordinates: Mapping[str, float] | Sequence[float] | float,
    *,
    steps: int = 1,
    inputs: Sequence[float] | None = None,
) -> np.ndarray:
    """Section coordinates after ``steps`` returns, by simulation; NaN where undefined.

    Parameters
    ----------
    model : HybridModel
        The model.
    coordinates : mapping, sequence or float
        Start on the section, in ``model.section.coordinates`` (a float for 1-D sections).
    steps : int
        Number of returns.
    inputs : array_like, optional
        Constant per-step input.

    Returns
    -------
    numpy.ndarray
        The section coordinates after ``steps`` returns (NaN if the motion never gets there).
    """
    if np.isscalar(coordinates):
        coordinates = [float(coordinates)]
    s = model.section_vector(coordinates)
    sim = simulate(model, model.lift(s), steps=steps, inputs=inputs)
    if not sim.success:
        return np.full(len(s), np.nan)
    return model.section_coordinates_of(sim.section_states[-1])


@dataclass
class MapFixedPoints:
    """Fixed points of a 1-D return map on an interval.

    Attributes
    ----------
    grid : numpy.ndarray
        Sampled section coordinate.
    values : numpy.ndarray
        The map on the grid (NaN where undefined).
    cycles : list of LimitCycle
        One verified limit cycle per fixed point, in increasing coordinate order; each carries its
        multiplier and ``stable``.
    """

    grid: np.ndarray
    values: np.ndarray
    cycles: list[LimitCycle]

    @property
    def points(self) -> np.ndarray:
        """The fixed points' coordinates."""
        return np.array([c.section_point[0] for c in self.cycles])


def one_dimensional(
    model: HybridModel, interval: Sequence[float], what: str
) -> tuple[float, float]:
    """``interval`` as floats ``(lo, hi)`` on the model's one section coordinate; a
    :class:`GaitoptInputError` starting with ``what`` (e.g. "fixed_points_1d needs") if the
    section is not one-dimensional, or if the interval is not increasing."""
    if len(model.section.coordinates) != 1:
        raise GaitoptInputError(
            f"{model.name}: {what} a 1-D section; this one has coordinates "
            f"{', '.join(model.section.coordinates)}"
        )
    lo, hi = map(float, interval)
    if not lo < hi:
        raise GaitoptInputError(f"`interval` must be increasing, got {interval!r}")
    return lo, hi


def fixed_points_1d(
    model: HybridModel,
    interval: tuple[float, float],
    *,
    samples: int = 60,
    inputs: Sequence[float] | None = None,
) -> MapFixedPoints:
    """Every fixed point of a 1-D return map on ``interval``, each refined and classified.

    The map is sampled by simulation; each sign change of ``P(s) − s`` between defined samples is
    bracketed, located with ``brentq`` on the simulated map, and then solved and verified as a
    limit cycle (:func:`find_limit_cycle`), which gives its multiplier.

    Raises
    ------
    GaitoptInputError
        If the model's section is not one-dimensional or the interval is empty.
    """
    lo, hi = one_dimensional(model, interval, "fixed_points_1d needs")
    grid = np.linspace(lo, hi, samples)
    values = np.array([return_map(model, [v], inputs=inputs)[0] for v in grid])
    d = values - grid
    cycles: list[LimitCycle] = []
    for j in range(samples - 1):
        if not (np.isfinite(d[j]) and np.isfinite(d[j + 1])) or d[j] * d[j + 1] > 0:
            continue
        if d[j] == 0 and j > 0 and d[j - 1] * d[j + 1] < 0:
            continue  # counted in the previous bracket
        root = (
            brentq(
                lambda v: return_map(model, [v], inputs=inputs)[0] - v,
                grid[j],
                grid[j + 1],
                xtol=1e-12,
            )
            if d[j] * d[j + 1] < 0
            else grid[j]
        )
        defect = return_map(model, [root], inputs=inputs)[0] - root
        if not abs(defect) < 1e-6 * (1 + abs(root)):
            continue  # a jump of the map (rocking vs vaulting), not a fixed point
        name = model.section.coordinates[0]
        cycle = find_limit_cycle(model, {name: root}, inputs=inputs)
        if cycle.success:
            cycles.append(cycle)
    return MapFixedPoints(grid, values, cycles)
