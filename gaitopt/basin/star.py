"""The star-shaped inner estimate of a gait's basin, by bisection along rays: :func:`basin`."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..arguments import check_count, check_positive, check_scheduler
from ..threads import single_blas_thread
from .checks import LIMIT, MAX_RAYS, check_setup, chosen_coordinates, unstable
from .classify import run_tasks
from .rays import ray_directions, rays_task
from .results import Basin

__all__ = ["basin"]


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
    setup = check_setup(gait, steps, hold, tol, scale)
    rays = check_count("rays", rays, 1, MAX_RAYS, LIMIT)
    scan = check_count("scan", scan, 1, 1000, LIMIT)
    bisections = check_count("bisections", bisections, 0, 60, "halvings beyond 60 reach rounding")
    chunk = check_count("chunk", chunk, 1, MAX_RAYS, LIMIT)
    max_radius = check_positive("max_radius", max_radius, "0.5")
    chosen = chosen_coordinates("coordinates", coordinates, setup.coordinates, None)
    check_scheduler(scheduler, serial=True)
    index = [setup.coordinates.index(c) for c in chosen]
    directions = ray_directions(rays, len(chosen), seed)
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
    reason = unstable(gait)
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
    found = [ray for r in run_tasks(rays_task, points, scheduler, chunk) for ray in r["rays"]]
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
