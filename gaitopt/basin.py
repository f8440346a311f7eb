"""Regions of attraction of a gait on its Poincaré section, every start confirmed by simulation.

Three estimates, each from hybrid simulations (:func:`gaitopt.simulate`), never from the
linearisation:

* :func:`basin` — a star-shaped inner estimate: along each of many rays from the fixed point the
  largest radius from which a simulation is confirmed to converge, below the first radius found to
  fail (a coarse scan, then bisection).  It is an inner estimate of the basin **only under the
  assumption that the basin is star-shaped along each ray** (every point between the fixed point
  and a converging start converges too, which is sampled, not proven); rays where a larger radius
  converges after a failure contradict that assumption and are reported as flags;
* :func:`basin_slice` — a grid over two section coordinates (the others at the fixed point),
  every point simulated;
* :func:`basin_fraction` — the fraction of a box on the section from which the gait converges,
  from uniform random starts, with its Wilson confidence interval.

A start *converges* if its simulation of ``steps + hold`` periods completes and, from a period at
most ``steps`` on, every return of a period lies within ``tol`` of the fixed point (it arrives
within ``steps`` periods and stays to the end, at least ``hold`` more).
Distances are in *scaled* section coordinates: coordinate ``i`` divided by ``scale[i]`` (default:
``|x*_i|`` of the fixed point, 1 where that is 0), so radii, windows and ``tol`` are
dimensionless fractions of the scale.

Each estimate runs on :func:`gaitopt.sweep.sweep`, one point per ray or start, sent to Dask
``chunk`` points per task (the sweep's chunking):
serially by default (``scheduler=None``), on a local Dask cluster (``"local"``) or a running
scheduler (``"tcp://host:8786"``).  The starts are classified by the batch simulation
(:func:`gaitopt.simulation.batch.simulate_batch`, the algorithm of :func:`gaitopt.simulate` on
many starts at once): serially every start of an estimate in one batch, on Dask each task's
chunk (the tasks' ``batched`` versions); the rays' scans in one batch and their bisection
several halvings per batch; fewer than ``_SMALL`` starts one by one.
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .arguments import check_count, check_positive, check_scheduler
from .errors import GaitoptInputError
from .threads import single_blas_thread

__all__ = [
    "basin",
    "basin_slice",
    "basin_fraction",
    "classify_starts",
    "Basin",
    "BasinSlice",
    "BasinFraction",
]

#: Most rays, grid points per axis and samples: each is at least one simulation of
#: ``steps + hold`` periods.
MAX_RAYS = 4096
MAX_POINTS = 400
MAX_SAMPLES = 100_000
#: Most points per Dask task (the sweep's limit).
MAX_CHUNK = 10_000
MAX_STEPS = 10_000
_LIMIT = "each is one simulation of up to steps + hold periods; run several smaller estimates"
#: Two-sided 95 % normal quantile of the Wilson interval.
_Z95 = 1.959963984540054


# -- results ---------------------------------------------------------------------------------
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


# -- checks and the simulation of one start ---------------------------------------------------
@dataclass(frozen=True)
class _Setup:
    """What every task needs: JSON-able, so that a chunk is a point of :func:`sweep`."""

    model: str
    params: dict[str, float]
    coordinates: list[str]  # every section coordinate, in the section's order
    centre: list[float]  # the fixed point in those
    inputs: list[float] | None
    period: int  # returns per period of the gait
    steps: int
    hold: int
    tol: float
    scale: list[float]  # per section coordinate

    def point(self, **extra: Any) -> dict[str, Any]:
        return {"setup": self.__dict__, **extra}


def _setup(gait: Any, steps: Any, hold: Any, tol: Any, scale: Any) -> _Setup:
    """Check the gait and the shared settings; one-line errors naming the argument."""
    from .models import model as make_model

    if not all(hasattr(gait, name) for name in ("model", "section_point", "success")):
        raise GaitoptInputError(
            f"`gait` must be a gait (from gaitopt.find_limit_cycle), got {type(gait).__name__}"
        )
    if not gait.success:
        reason = " ".join(str(getattr(gait, "message", "")).split())[:160]
        raise GaitoptInputError(f"`gait` is not a gait (success is False: {reason})")
    steps = check_count("steps", steps, 1, MAX_STEPS, _LIMIT)
    hold = check_count("hold", hold, 1, MAX_STEPS, _LIMIT)
    tol = check_positive("tol", tol, "1e-4")
    model = gait.model
    coordinates = list(model.section.coordinates)
    centre = np.asarray(gait.section_point, dtype=float).ravel()
    if scale is None:
        scale = np.where(np.abs(centre) > 0, np.abs(centre), 1.0)
    else:
        scale = _per_coordinate("scale", scale, coordinates)
    try:
        rebuilt = make_model(model.name, **model.params)
    except GaitoptInputError:
        rebuilt = None
    if rebuilt is None or rebuilt.params != model.params:
        raise GaitoptInputError(
            f"`gait`: its model {model.name!r} cannot be rebuilt by name and parameters for the "
            f"simulation tasks; register it (gaitopt.register)"
        )
    inputs = np.asarray(getattr(gait, "inputs", ()), dtype=float).ravel()
    return _Setup(
        model.name,
        dict(model.params),
        coordinates,
        centre.tolist(),
        inputs.tolist() if inputs.size else None,
        int(getattr(gait, "steps", 1) or 1),
        steps,
        hold,
        tol,
        [float(s) for s in scale],
    )


def _per_coordinate(name: str, value: Any, coordinates: Sequence[str]) -> np.ndarray:
    """``scale`` (or a window's half width): a positive number, one per coordinate, or a mapping
    by coordinate name (missing names: error)."""
    if isinstance(value, Mapping):
        unknown = set(value) - set(coordinates)
        if unknown:
            raise GaitoptInputError(
                f"`{name}`: {sorted(unknown)[0]!r} is not a section coordinate "
                f"({', '.join(coordinates)})"
            )
        missing = [c for c in coordinates if c not in value]
        if missing:
            raise GaitoptInputError(f"`{name}` has no entry for {missing[0]!r}")
        value = [value[c] for c in coordinates]
    if isinstance(value, numbers.Real):
        value = [value] * len(coordinates)
    values = list(np.asarray(value, dtype=object).ravel())
    if len(values) != len(coordinates):
        raise GaitoptInputError(
            f"`{name}` needs {len(coordinates)} values ({', '.join(coordinates)}), got "
            f"{len(values)}"
        )
    return np.array([check_positive(name, v, "0.1") for v in values])


def _unstable(gait: Any) -> str | None:
    """Why no neighbourhood of the fixed point converges (a multiplier outside the unit circle)."""
    multipliers = np.abs(np.asarray(getattr(gait, "multipliers", ()), dtype=complex))
    if multipliers.size and multipliers.max() > 1:
        return (
            f"the gait is unstable: a multiplier has |λ| = {multipliers.max():.6g} > 1, so no "
            f"neighbourhood of the fixed point converges; the basin is empty"
        )
    return None


def _classify(setup: Mapping[str, Any], model: Any, start: np.ndarray) -> str:
    """``"converged"`` or why not, for one start in section coordinates (every coordinate).

    One simulation of ``steps + hold`` periods (one call, so that the simulator sees an
    accumulation of impacts whole): converged if it completes and, from some period at most
    ``steps`` on, every period's return is within ``tol`` (scaled) of the fixed point."""
    from .errors import StateError
    from .simulation import simulate

    centre, scale = np.asarray(setup["centre"]), np.asarray(setup["scale"])
    period, tol = setup["period"], setup["tol"]
    x = dict(zip(setup["coordinates"], map(float, start), strict=True))
    try:
        sim = simulate(
            model, x, steps=(setup["steps"] + setup["hold"]) * period, inputs=setup["inputs"]
        )
    except (GaitoptInputError, StateError):  # not a start of this model (off its section)
        return "invalid start"
    if not sim.success:
        return sim.status
    returns = sim.section_states[period::period]
    offsets = np.array([model.section_coordinates_of(r) for r in returns]) - centre
    within = np.all(np.abs(offsets) <= tol * scale, axis=1)  # NaN compares False
    outside = np.flatnonzero(~within)
    arrival = outside[-1] + 1 if outside.size else 0  # index of the first period that stays
    return "converged" if arrival < setup["steps"] else "not converged"


#: Starts per call of the batch simulation (bounds its memory: about 2 kB per start and step).
_BLOCK = 4096
#: Fewer starts than this go one by one (gaitopt.simulate): a batch costs about 1.4 ms of CPU
#: per step try of all its starts together, a compass-gait start alone about 36 ms in all, so
#: below some 40 starts the loop is faster (bench/basin.py's anatomy).
_SMALL = 48


def _classify_many(setup: Mapping[str, Any], model: Any, starts: np.ndarray) -> list[str]:
    """:func:`_classify` for many starts at once: the same simulations (the algorithm of
    :func:`gaitopt.simulate`), all starts stepped together by
    :func:`gaitopt.simulation.batch.simulate_batch`, and the same rule."""
    from .simulation.batch import simulate_batch

    centre, scale = np.asarray(setup["centre"]), np.asarray(setup["scale"])
    period, tol, steps = setup["period"], setup["tol"], setup["steps"]
    index = [model.state_names.index(c) for c in setup["coordinates"]]
    outcomes: list[str] = []
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    if len(starts) < _SMALL:  # too few to repay the batch's fixed cost per step try
        return [_classify(setup, model, start) for start in starts]
    for k in range(0, len(starts), _BLOCK):
        block = starts[k : k + _BLOCK]
        sim = simulate_batch(
            model, block, steps=(steps + setup["hold"]) * period, inputs=setup["inputs"]
        )
        returns = sim.section_states[:, period::period][:, :, index]  # starts × periods × s
        within = np.all(np.abs(returns - centre) <= tol * scale, axis=2)  # NaN compares False
        outside = ~within
        last = np.where(
            outside.any(axis=1), outside.shape[1] - 1 - np.argmax(outside[:, ::-1], axis=1), -1
        )
        arrival = last + 1  # index of the first period that stays
        for status, arrived in zip(sim.status, arrival, strict=True):
            if status != "completed":
                outcomes.append(str(status))
            else:
                outcomes.append("converged" if arrived < steps else "not converged")
    return outcomes


def _model_of(setup: Mapping[str, Any]) -> Any:
    from .models import model as make_model

    return make_model(setup["model"], **setup["params"])


def _starts_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Starts (section coordinates) → their outcomes (a point of :func:`sweep`)."""
    setup = point["setup"]
    model = _model_of(setup)
    return {"outcomes": [_classify(setup, model, np.asarray(s)) for s in point["starts"]]}


def _starts_batch(points: list[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """:func:`_starts_task` on many points (one setup): every start in one batch simulation."""
    if not points:
        return []
    setup = points[0]["setup"]
    if any(point["setup"] != setup for point in points):
        return [_starts_task(point) for point in points]
    sizes = [len(point["starts"]) for point in points]
    starts = np.array([s for point in points for s in point["starts"]], dtype=float)
    outcomes = _classify_many(setup, _model_of(setup), starts) if len(starts) else []
    bounds = np.cumsum([0, *sizes])
    return [{"outcomes": outcomes[a:b]} for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


_starts_task.batched = _starts_batch  # type: ignore[attr-defined]


def _rays_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Rays → per ray the radius, first failure and scan (a point of :func:`sweep`)."""
    setup = point["setup"]
    model = _model_of(setup)
    centre, scale = np.asarray(setup["centre"]), np.asarray(setup["scale"])
    index = [setup["coordinates"].index(c) for c in point["coordinates"]]
    scan, bisections, top = point["scan"], point["bisections"], point["max_radius"]
    rays = []
    for direction in point["directions"]:
        step = np.zeros_like(centre)
        step[index] = np.asarray(direction) * scale[index]

        def converges(r: float, step: np.ndarray = step) -> bool:
            return _classify(setup, model, centre + r * step) == "converged"

        grid = [top * k / scan for k in range(1, scan + 1)]
        fates = [converges(r) for r in grid]
        runs = len(grid)
        failed = [r for r, ok in zip(grid, fates, strict=True) if not ok]
        if not failed:
            rays.append({"radius": top, "first_failure": None, "beyond": [], "runs": runs})
            continue
        high = failed[0]
        low = max([0.0] + [r for r, ok in zip(grid, fates, strict=True) if ok and r < high])
        for _ in range(bisections):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if converges(middle) else (low, middle)
            runs += 1
        beyond = [r for r, ok in zip(grid, fates, strict=True) if ok and r > failed[0]]
        rays.append({"radius": low, "first_failure": high, "beyond": beyond, "runs": runs})
    return {"rays": rays}


def _rays_batch(points: list[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """:func:`_rays_task` on many points (one setup), the rays in lockstep: every ray's scan in
    one batch simulation, then each round of bisection (one radius per ray still bracketing)
    in one batch.  The same radii, the same rule, every start simulated."""
    if not points:
        return []
    setup = points[0]["setup"]
    keys = ("setup", "coordinates", "scan", "bisections", "max_radius")
    if any(any(p[k] != points[0][k] for k in keys) for p in points):
        return [_rays_task(point) for point in points]
    model = _model_of(setup)
    centre, scale = np.asarray(setup["centre"]), np.asarray(setup["scale"])
    index = [setup["coordinates"].index(c) for c in points[0]["coordinates"]]
    scan, bisections, top = points[0]["scan"], points[0]["bisections"], points[0]["max_radius"]
    directions = np.array([d for p in points for d in p["directions"]], dtype=float)
    steps = np.zeros((len(directions), len(centre)))
    steps[:, index] = directions * scale[index]
    grid = np.array([top * k / scan for k in range(1, scan + 1)])

    def converges(rows: np.ndarray, radii: np.ndarray) -> np.ndarray:
        starts = centre + radii[:, None] * steps[rows]
        return np.array(_classify_many(setup, model, starts)) == "converged"

    n = len(directions)
    fates = converges(np.repeat(np.arange(n), scan), np.tile(grid, n)).reshape(n, scan)
    low, high = np.zeros(n), np.full(n, np.nan)
    for i in range(n):
        failed = grid[~fates[i]]
        if failed.size:
            high[i] = failed[0]
            below = grid[fates[i] & (grid < failed[0])]
            low[i] = below.max() if below.size else 0.0
    open_ = np.flatnonzero(~np.isnan(high))
    left, runs = bisections if open_.size else 0, np.zeros(n, dtype=int)
    while left:
        # several halvings per batch: every midpoint the next `levels` halvings of each ray can
        # visit (2**levels - 1, by the same 0.5 * (low + high) as one halving at a time, so the
        # radii are those of sequential bisection), enough for a batch of _BISECT starts
        # (few rays: one halving at a time, start by start, as many simulations as one by one)
        levels = max(1, min(left, _LEVELS, int(np.log2(_BISECT / open_.size + 1))))
        if 3 * open_.size < _SMALL:
            levels = 1
        tree = _midpoints(low[open_], high[open_], levels)  # rays × (2**levels − 1), in order
        fate = converges(np.repeat(open_, tree.shape[1]), tree.ravel()).reshape(tree.shape)
        runs[open_] += tree.shape[1]
        node = np.zeros(open_.size, dtype=int)  # heap index of the midpoint taken next
        for _ in range(levels):
            middle = tree[np.arange(open_.size), node]
            ok = fate[np.arange(open_.size), node]
            low[open_] = np.where(ok, middle, low[open_])
            high[open_] = np.where(ok, high[open_], middle)
            node = 2 * node + np.where(ok, 2, 1)
        left -= levels
    rays = []
    for i in range(n):
        if np.isnan(high[i]):
            rays.append({"radius": top, "first_failure": None, "beyond": [], "runs": scan})
            continue
        failed_first = grid[~fates[i]][0]
        beyond = [float(r) for r, ok in zip(grid, fates[i], strict=True) if ok and r > failed_first]
        rays.append({"radius": float(low[i]), "first_failure": float(high[i]),
                     "beyond": beyond, "runs": scan + int(runs[i])})  # fmt: skip
    sizes = np.cumsum([0, *(len(p["directions"]) for p in points)])
    return [{"rays": rays[a:b]} for a, b in zip(sizes[:-1], sizes[1:], strict=True)]


_rays_task.batched = _rays_batch  # type: ignore[attr-defined]
#: Starts per round of the rays' bisection in a batch (several halvings per round), and the most
#: halvings per round (each costs twice the simulations of the one before).
_BISECT = 256
_LEVELS = 3


def _midpoints(low: np.ndarray, high: np.ndarray, levels: int) -> np.ndarray:
    """Every midpoint ``levels`` halvings of ``[low, high]`` can visit, per row, in heap order
    (node k's halves are 2k + 1, the lower, and 2k + 2), each ``0.5 * (a + b)`` of its bracket."""
    count = 2**levels - 1
    tree = np.empty((low.size, count))
    brackets = {0: (low, high)}
    for k in range(count):
        a, b = brackets.pop(k)
        tree[:, k] = m = 0.5 * (a + b)
        if 2 * k + 2 < count:
            brackets[2 * k + 1], brackets[2 * k + 2] = (a, m), (m, b)
    return tree


def _run(
    task: Any, points: list[dict[str, Any]], scheduler: str | None, chunk: int
) -> list[dict[str, Any]]:
    """``task`` on every point through :func:`gaitopt.sweep.sweep`, which sends them to Dask
    ``chunk`` points per task (serially: one after another)."""
    from .sweep import sweep

    check_scheduler(scheduler, serial=True)
    result = sweep(
        task,
        points,
        scheduler=scheduler or "serial",
        chunk=chunk,
        progress=False,
        description="basin",
    )
    return result.results


def _directions(rays: int, dimension: int, seed: int) -> np.ndarray:
    """Unit vectors: ±1 in one dimension, equal angles in two, otherwise pairs ±v of normalised
    Gaussian vectors (seeded) so that every direction has its opposite."""
    if dimension == 1:
        return np.array([[1.0], [-1.0]])[: min(rays, 2)]
    if dimension == 2:
        angles = 2 * np.pi * np.arange(rays) / rays
        return np.column_stack([np.cos(angles), np.sin(angles)])
    rng = np.random.default_rng(seed)
    half = rng.standard_normal(((rays + 1) // 2, dimension))
    half /= np.linalg.norm(half, axis=1, keepdims=True)
    return np.concatenate([half, -half])[:rays]


def _chosen(name: str, given: Sequence[str] | None, coordinates: Sequence[str], n: int | None):
    """Coordinates named by ``given`` (all if None), each a section coordinate."""
    chosen = list(coordinates) if given is None else list(given)
    for c in chosen:
        if c not in coordinates:
            raise GaitoptInputError(
                f"`{name}`: {c!r} is not a section coordinate ({', '.join(coordinates)})"
            )
    if len(set(chosen)) != len(chosen) or not chosen or (n is not None and len(chosen) != n):
        count = f"{n} different" if n else "different"
        raise GaitoptInputError(f"`{name}` must name {count} section coordinates, got {chosen}")
    return chosen


# -- the estimates ---------------------------------------------------------------------------
@single_blas_thread
def basin(
    gait: Any,
    *,
    rays: int = 16,
    steps: int = 40,
    hold: int = 5,
    tol: float = 1e-4,
    scale: float | Sequence[float] | Mapping[str, float] | None = None,
    max_radius: float = 1.0,
    scan: int = 8,
    bisections: int = 10,
    coordinates: Sequence[str] | None = None,
    seed: int = 0,
    chunk: int = 4,
    scheduler: str | None = None,
) -> Basin:
    """Star-shaped inner estimate of a gait's basin on its Poincaré section, by bisection along
    rays, every classified start confirmed by simulation.

    Along each ray ``x* + r · scale ⊙ d`` the radii ``max_radius · k / scan`` (k = 1…scan) are
    simulated; between the largest converging radius below the first failure and that failure,
    ``bisections`` halvings follow.  The ray's radius is the largest radius confirmed to
    converge below the first failure found.  The set of segments is an inner estimate of the
    basin **only if the basin is star-shaped along each ray**; a ray on which a scan radius
    beyond the first failure converges is flagged (non-monotone).

    Parameters
    ----------
    gait : LimitCycle
        A successful gait (``model``, ``section_point``, ``multipliers``; ``inputs``, the per-step
        input, and ``steps``, its period in returns, if it has them).
    rays : int
        Number of rays (one coordinate: 2, up and down).
    steps : int
        Periods within which a start must come within ``tol`` of the fixed point.
    hold : int
        Further periods it must stay within ``tol``.
    tol : float
        Tolerance (dimensionless: a fraction of ``scale`` in each coordinate).
    scale : float, sequence or mapping, optional
        Scale of each section coordinate (its unit: rad, rad/s, m…); default ``|x*_i|`` (1 where
        that is 0).
    max_radius : float
        Largest radius probed (dimensionless, in units of ``scale``).
    scan : int
        Radii of the coarse scan along each ray.
    bisections : int
        Halvings of the bracket of the first failure: radii are exact to ``max_radius / scan /
        2**bisections`` (scaled), on the ray's samples.
    coordinates : sequence of str, optional
        Section coordinates the rays span (default all; the others stay at the fixed point).
    seed : int
        Seed of the directions in three or more coordinates.
    chunk : int
        Rays per task of the sweep.
    scheduler : str, optional
        None (serial, in this process), ``"local"`` (a local Dask cluster) or a Dask address.

    Returns
    -------
    Basin

    Raises
    ------
    GaitoptInputError
        For a gait that is not a success, a count below 1 or a ``tol``, ``scale`` or
        ``max_radius`` that is not positive (one line naming the argument).
    """
    started = time.perf_counter()
    setup = _setup(gait, steps, hold, tol, scale)
    rays = check_count("rays", rays, 1, MAX_RAYS, _LIMIT)
    scan = check_count("scan", scan, 1, 1000, _LIMIT)
    bisections = check_count("bisections", bisections, 0, 60, "halvings beyond 60 reach rounding")
    chunk = check_count("chunk", chunk, 1, MAX_RAYS, _LIMIT)
    max_radius = check_positive("max_radius", max_radius, "0.5")
    chosen = _chosen("coordinates", coordinates, setup.coordinates, None)
    check_scheduler(scheduler, serial=True)
    index = [setup.coordinates.index(c) for c in chosen]
    directions = _directions(rays, len(chosen), seed)
    n = len(directions)
    settings = {
        "steps": setup.steps,
        "hold": setup.hold,
        "tol": setup.tol,
        "scan": scan,
        "bisections": bisections,
        "seed": seed,
    }
    common = dict(
        model=gait.model,
        coordinates=tuple(chosen),
        fixed_point=dict(zip(setup.coordinates, setup.centre, strict=True)),
        scale=np.asarray(setup.scale)[index],
        directions=directions,
        max_radius=max_radius,
        settings=settings,
    )
    reason = _unstable(gait)
    if reason is not None:
        zeros = np.zeros(n)
        return Basin(
            False,
            reason,
            radii=zeros,
            first_failure=np.zeros(n),
            capped=np.zeros(n, bool),
            elapsed=time.perf_counter() - started,
            **common,
        )
    points = [
        setup.point(
            directions=[direction],
            coordinates=chosen,
            scan=scan,
            bisections=bisections,
            max_radius=max_radius,
        )
        for direction in directions.tolist()
    ]
    found = [ray for r in _run(_rays_task, points, scheduler, chunk) for ray in r["rays"]]
    radii = np.array([ray["radius"] for ray in found], dtype=float)
    failure = np.array(
        [np.nan if ray["first_failure"] is None else ray["first_failure"] for ray in found],
        dtype=float,
    )
    flags = [
        {"ray": i, "first_failure": ray["first_failure"], "converges_at": ray["beyond"]}
        for i, ray in enumerate(found)
        if ray["beyond"]
    ]
    capped = np.isnan(failure)
    message = (
        f"{n} rays in ({', '.join(chosen)}): radius {radii.min():.4g}…{radii.max():.4g} (scaled), "
        f"{int(capped.sum())} reach max_radius {max_radius:g}; an inner estimate only if the "
        f"basin is star-shaped along each ray"
        + (f"; {len(flags)} non-monotone ray(s) flagged (not star-shaped)" if flags else "")
    )
    return Basin(
        True,
        message,
        radii=radii,
        first_failure=failure,
        capped=capped,
        flags=flags,
        simulations=sum(ray["runs"] for ray in found),
        elapsed=time.perf_counter() - started,
        **common,
    )


def _window(setup: _Setup, window: Any) -> dict[str, tuple[float, float]]:
    """The box: ``{name: (low, high)}`` given, or ``x* ± half widths · scale`` from a number or
    one half width per coordinate (scaled)."""
    if isinstance(window, Mapping) and all(
        isinstance(v, Sequence) and not isinstance(v, str) for v in window.values()
    ):
        box = {}
        for c in setup.coordinates:
            if c not in window:
                raise GaitoptInputError(f"`window` has no range for {c!r}")
            low, high = (float(v) for v in window[c])
            if not (math.isfinite(low) and math.isfinite(high) and low < high):
                raise GaitoptInputError(
                    f"`window` range of {c!r} must be low < high, got {window[c]!r}"
                )
            box[c] = (low, high)
        return box
    half = _per_coordinate("window", window, setup.coordinates) * np.asarray(setup.scale)
    return {
        c: (float(x - h), float(x + h))
        for c, x, h in zip(setup.coordinates, setup.centre, half, strict=True)
    }


def _outcomes(setup: _Setup, starts: np.ndarray, chunk: int, scheduler: str | None) -> list[str]:
    points = [setup.point(starts=[start]) for start in starts.tolist()]
    return [o for r in _run(_starts_task, points, scheduler, chunk) for o in r["outcomes"]]


def classify_starts(
    gait: Any,
    starts: Any,
    *,
    steps: int = 40,
    hold: int = 5,
    tol: float = 1e-4,
    scale: Any = None,
    chunk: int = 20,
    scheduler: str | None = None,
) -> list[str]:
    """Simulate each start and say whether it converges to the gait: ``"converged"`` or why not
    (``"fell"``, ``"standing"``, ``"timeout"``, ``"not converged"``, ``"invalid start"``).

    Parameters
    ----------
    gait : LimitCycle
        A successful gait.
    starts : array_like
        Rows of section coordinates (every coordinate, in the section's order; their units).
    steps, hold, tol, scale, chunk, scheduler
        As in :func:`basin_fraction`.

    Returns
    -------
    list of str
    """
    setup = _setup(gait, steps, hold, tol, scale)
    chunk = check_count("chunk", chunk, 1, MAX_CHUNK, _LIMIT)
    check_scheduler(scheduler, serial=True)
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    if starts.shape[1] != len(setup.coordinates) or not np.all(np.isfinite(starts)):
        raise GaitoptInputError(
            f"`starts` must be finite rows of {len(setup.coordinates)} section coordinates "
            f"({', '.join(setup.coordinates)}), got shape {starts.shape}"
        )
    return _outcomes(setup, starts, chunk, scheduler)


def basin_slice(
    gait: Any,
    coordinates: Sequence[str],
    *,
    points: int = 21,
    window: Any = 1.0,
    steps: int = 40,
    hold: int = 5,
    tol: float = 1e-4,
    scale: Any = None,
    chunk: int = 20,
    scheduler: str | None = None,
) -> BasinSlice:
    """Every start of a grid over two section coordinates simulated (the others at the fixed
    point): which converge to the gait.

    Parameters
    ----------
    gait : LimitCycle
        A successful gait.
    coordinates : (str, str)
        The two section coordinates varied.
    points : int
        Grid points per axis (the window's ends included).
    window : float, sequence or mapping
        Half widths (scaled: fractions of ``scale``) around the fixed point, or ``{name: (low,
        high)}`` in the coordinates' units.
    steps, hold, tol, scale
        As in :func:`basin`.
    chunk : int
        Starts per task of the sweep.
    scheduler : str, optional
        As in :func:`basin`.

    Returns
    -------
    BasinSlice
    """
    started = time.perf_counter()
    setup = _setup(gait, steps, hold, tol, scale)
    points = check_count("points", points, 2, MAX_POINTS, _LIMIT)
    chunk = check_count("chunk", chunk, 1, MAX_CHUNK, _LIMIT)
    pair = _chosen("coordinates", coordinates, setup.coordinates, 2)
    check_scheduler(scheduler, serial=True)
    box = _window(setup, window)
    values = tuple(np.linspace(*box[c], points) for c in pair)
    a, b = np.meshgrid(*values)
    starts = np.tile(np.asarray(setup.centre), (a.size, 1))
    starts[:, setup.coordinates.index(pair[0])] = a.ravel()
    starts[:, setup.coordinates.index(pair[1])] = b.ravel()
    outcomes = np.array(_outcomes(setup, starts, chunk, scheduler)).reshape(a.shape)
    return BasinSlice(
        tuple(pair),
        values,
        outcomes == "converged",
        outcomes,
        dict(zip(setup.coordinates, setup.centre, strict=True)),
        gait.model,
        {"steps": setup.steps, "hold": setup.hold, "tol": setup.tol, "window": box},
        time.perf_counter() - started,
    )


def basin_fraction(
    gait: Any,
    *,
    samples: int = 200,
    window: Any = 1.0,
    steps: int = 40,
    hold: int = 5,
    tol: float = 1e-4,
    scale: Any = None,
    seed: int = 0,
    chunk: int = 20,
    scheduler: str | None = None,
) -> BasinFraction:
    """Fraction of a box on the section from which the gait converges, from uniform random
    starts (each simulated), with its 95 % Wilson interval.

    Parameters
    ----------
    gait : LimitCycle
        A successful gait.
    samples : int
        Starts drawn uniformly in the box (seeded).
    window : float, sequence or mapping
        Half widths (scaled) around the fixed point, or ``{name: (low, high)}`` for every
        section coordinate (their units).
    steps, hold, tol, scale
        As in :func:`basin`.
    seed : int
        Seed of the starts.
    chunk : int
        Starts per task of the sweep.
    scheduler : str, optional
        As in :func:`basin`.

    Returns
    -------
    BasinFraction
        For an unstable gait the starts are still simulated (none converges near it).
    """
    started = time.perf_counter()
    setup = _setup(gait, steps, hold, tol, scale)
    samples = check_count("samples", samples, 1, MAX_SAMPLES, _LIMIT)
    chunk = check_count("chunk", chunk, 1, MAX_CHUNK, _LIMIT)
    check_scheduler(scheduler, serial=True)
    box = _window(setup, window)
    low = np.array([box[c][0] for c in setup.coordinates])
    high = np.array([box[c][1] for c in setup.coordinates])
    starts = low + (high - low) * np.random.default_rng(seed).random((samples, len(low)))
    outcomes = _outcomes(setup, starts, chunk, scheduler)
    k = sum(o == "converged" for o in outcomes)
    return BasinFraction(
        k / samples,
        wilson_interval(k, samples),
        0.95,
        samples,
        k,
        box,
        {"steps": setup.steps, "hold": setup.hold, "tol": setup.tol, "seed": seed},
        time.perf_counter() - started,
        starts,
        np.array(outcomes),
    )
