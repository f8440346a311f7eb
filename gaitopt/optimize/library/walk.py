"""The walk along the values: :func:`gait_library` solves the optimum at each value, warm
started from its neighbour's, compares neighbours (:mod:`~gaitopt.optimize.library.events`) and
checks against cold starts (:mod:`~gaitopt.optimize.library.cold`)."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence

import numpy as np

from ...errors import GaitoptInputError, did_you_mean
from ...hybrid import HybridModel
from ...threads import single_blas_thread
from ...workers import Map, check_workers
from ..result import OptimalGait
from ..solve import optimize_gait
from .cold import cold_checks as _cold_checks
from .cold import cold_values as _cold_values
from .events import compare, reduced_hessian
from .records import CONSTRAINTS, GaitLibrary, LibraryPoint

__all__ = ["gait_library"]


def _check_vary(model: HybridModel, vary: str, fixed: Mapping[str, float | None]) -> None:
    if vary in CONSTRAINTS:
        if fixed.get(vary) is not None:
            raise GaitoptInputError(
                f"`vary` {vary!r} is also fixed ({vary}={fixed[vary]!r}); leave {vary} out: the "
                f"library sets it at each point"
            )
        return
    if vary not in model.params:
        choices = (*CONSTRAINTS, *model.params)
        raise GaitoptInputError(
            f"`vary` must be one of {', '.join(CONSTRAINTS)} or a parameter of {model.name}, "
            f"got {vary!r}; {did_you_mean(vary, choices)}e.g. vary='step_length'"
        )


def _values(values: Sequence[float]) -> np.ndarray:
    try:
        v = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        v = np.zeros(0)
    if (
        v.size < 2
        or not np.all(np.isfinite(v))
        or not (np.all(np.diff(v) > 0) or np.all(np.diff(v) < 0))
    ):
        raise GaitoptInputError(
            f"`values` must be at least 2 finite numbers, strictly increasing or decreasing, "
            f"got {values!r}; e.g. numpy.linspace(0.2, 0.5, 7)"
        )
    return v


@single_blas_thread
def gait_library(
    model: HybridModel,
    vary: str,
    values: Sequence[float],
    cost: str = "effort",
    *,
    period: float | None = None,
    step_length: float | None = None,
    speed: float | None = None,
    bounds: Mapping[str, float] | None = None,
    state_bounds: Mapping[str, tuple[float, float]] | None = None,
    free: tuple[str, ...] | str = (),
    steps: int = 1,
    tol: float = 1e-8,
    cold: int | Sequence[float] = 2,
    locate: float = 1e-3,
    workers: int | Map = 1,
    scheduler: str | None = None,
) -> GaitLibrary:
    """Continue an optimal gait in a constraint or parameter, warm starting each point.

    Parameters
    ----------
    model : HybridModel
        The actuated model.
    vary : str
        ``"period"`` (s), ``"step_length"`` (m), ``"speed"`` (m/s) or a model parameter (e.g.
        ``"slope"``, rad).
    values : sequence of float
        Its values, in the order continued (strictly monotone).
    cost, period, step_length, speed, bounds, state_bounds, free, steps, tol
        As for :func:`gaitopt.optimize_gait` (the one varied must be left out).
    cold : int or sequence of float
        Cold-start checks: at this many library points spread over it (first and last first;
        default 2), or at these values (each must be a library value); 0 for none.
    locate : float
        Bisection of an event stops when its bracket is below ``locate`` times the spacing of
        the two neighbours (default 1e-3: about 10 solves per event).
    workers : int or callable
        What runs the cold-start checks (:func:`gaitopt.workers.worker_map`): ``1`` (default)
        serially, ``n`` a pool of ``n`` processes, or a map-like ``workers(func, iterable)``.
    scheduler : str, optional
        Run the cold-start checks on Dask instead (``"local"`` or an address;
        :func:`gaitopt.sweep.dask_map`).

    Returns
    -------
    GaitLibrary
    """
    t_start = time.perf_counter()
    fixed = {"period": period, "step_length": step_length, "speed": speed}
    _check_vary(model, vary, fixed)
    check_workers(workers, scheduler)
    grid = _values(values)
    if not (isinstance(locate, (int, float)) and 0 < locate < 1):
        raise GaitoptInputError(f"`locate` must be in (0, 1), got {locate!r}; e.g. 1e-3")
    cold_values = _cold_values(grid, cold)
    options = dict(bounds=bounds, state_bounds=state_bounds, free=free, steps=steps, tol=tol)

    def solve(value: float, guess: OptimalGait | None, verify: bool = True) -> OptimalGait:
        if vary in CONSTRAINTS:
            return optimize_gait(
                model, cost, **{**fixed, vary: value}, guess=guess, verify=verify, **options
            )
        return optimize_gait(
            model.replace(**{vary: value}), cost, **fixed, guess=guess, verify=verify, **options
        )

    library = GaitLibrary(False, "", vary)
    last: LibraryPoint | None = None
    for value in grid:
        t0 = time.perf_counter()
        gait = solve(float(value), last.gait if last is not None else None)
        point = LibraryPoint(float(value), gait, last is not None, time.perf_counter() - t0)
        if gait.success and gait.transcription is not None:
            col, w = gait.transcription
            point.hessian = reduced_hessian(col, w, col.model.p)
        library.points.append(point)
        event = None
        if last is not None:
            event = compare(last, point, solve, locate, library.points[0].hessian_ratio)
            if event is not None:
                library.events.append(event)
        if gait.success:
            last = point
        elif event is not None and event.kind in ("fold", "end"):
            break  # past a fold or the end of the branch: nothing to warm start from
    library.cold_checks = _cold_checks(library, cold_values, model, vary, fixed, cost, options,
                                       scheduler, workers)  # fmt: skip
    failed = [pt.value for pt in library.points if not pt.gait.success]
    disagree = [c.value for c in library.cold_checks if not c.agree]
    library.success = not failed and not disagree and len(library.points) == grid.size
    parts = [
        f"{sum(pt.gait.success for pt in library.points)} of {grid.size} optima in {vary} certified"
    ]
    if failed:
        parts.append(f"no certified optimum at {vary} = {', '.join(f'{v:g}' for v in failed)}")
    for e in library.events:
        parts.append(e.message)
    if library.cold_checks:
        parts.append(
            f"cold starts agree at {sum(c.agree for c in library.cold_checks)} of "
            f"{len(library.cold_checks)} points"
            + (f" (not at {', '.join(f'{v:g}' for v in disagree)})" if disagree else "")
        )
    library.message = "; ".join(parts)
    library.solve_time = time.perf_counter() - t_start
    return library
