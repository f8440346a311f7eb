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
many starts at once, compiled where there is a C compiler): serially every start of an estimate
in one batch, on Dask each task's chunk (the tasks' ``batched`` versions); the rays' scans in one
batch and each halving of their bisection in one (with the NumPy batch several halvings per
batch, and fewer than :data:`~gaitopt.basin.classify.SMALL` starts one by one).

Modules: :mod:`~gaitopt.basin.results` (the three results), :mod:`~gaitopt.basin.checks` (the
shared settings and limits), :mod:`~gaitopt.basin.classify` (one start's fate, the tasks, the
sweep), :mod:`~gaitopt.basin.rays` (the rays' scan and bisection), :mod:`~gaitopt.basin.star`
(:func:`basin`) and :mod:`~gaitopt.basin.grids` (:func:`basin_slice`, :func:`basin_fraction`,
:func:`classify_starts`).
"""

from __future__ import annotations

from .checks import LIMIT, MAX_CHUNK, MAX_POINTS, MAX_RAYS, MAX_SAMPLES, MAX_STEPS
from .grids import basin_fraction, basin_slice, classify_starts
from .results import Basin, BasinFraction, BasinSlice, wilson_interval
from .star import basin

#: The older private name of :data:`~gaitopt.basin.checks.LIMIT` (``gaitopt basin`` imports it).
_LIMIT = LIMIT

__all__ = [
    "basin",
    "basin_slice",
    "basin_fraction",
    "classify_starts",
    "wilson_interval",
    "Basin",
    "BasinSlice",
    "BasinFraction",
    "MAX_CHUNK",
    "MAX_POINTS",
    "MAX_RAYS",
    "MAX_SAMPLES",
    "MAX_STEPS",
]
