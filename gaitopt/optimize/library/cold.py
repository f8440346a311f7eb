"""The library against cold starts (the model's default start, no warm start) at a few of its
points: the same optimal cost to 1e-8 relative, else another local minimum."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...errors import GaitoptInputError
from ...hybrid import HybridModel
from ...workers import Map, worker_map
from ..problem import as_problem
from .records import CONSTRAINTS, ColdCheck, GaitLibrary
from .workers import cold_solve, cold_task, problem_data

__all__ = ["cold_values", "cold_checks"]

_COLD_RTOL = 1e-8  # library against cold starts: relative cost difference


def cold_values(grid: np.ndarray, cold: int | Sequence[float]) -> list[float]:
    """The library values to check against cold starts (``cold`` as :func:`gait_library`
    takes it)."""
    if isinstance(cold, (int, np.integer)) and not isinstance(cold, bool):
        if cold < 0:
            raise GaitoptInputError(f"`cold` must be >= 0, got {cold!r}; e.g. cold=2")
        if cold == 0:
            return []
        idx = np.unique(np.round(np.linspace(0, grid.size - 1, min(cold, grid.size))).astype(int))
        return [float(grid[i]) for i in idx]
    try:
        chosen = [float(v) for v in cold]  # type: ignore[union-attr]
    except (TypeError, ValueError):
        chosen = [float("nan")]
    for v in chosen:
        if not np.any(np.isclose(grid, v, rtol=0, atol=1e-12 * (1 + abs(v)))):
            raise GaitoptInputError(
                f"`cold` value {v!r} is not one of the library's values "
                f"{np.round(grid, 12).tolist()}; choose among them"
            )
    return chosen


def cold_checks(
    library: GaitLibrary,
    values: list[float],
    model: HybridModel,
    vary: str,
    fixed: Mapping[str, float | None],
    cost: str,
    options: Mapping[str, Any],
    scheduler: str | None,
    workers: int | Map = 1,
) -> list[ColdCheck]:
    """One :class:`ColdCheck` per value: the problem there solved cold (by the ``workers`` map,
    or on Dask when ``scheduler`` is given: :func:`gaitopt.workers.worker_map`), its cost
    against the library's nearest point."""
    if not values:
        return []
    by_value = {pt.value: pt for pt in library.points}
    problems = []
    for v in values:
        if vary in CONSTRAINTS:
            problems.append(as_problem(model, cost=cost, **{**fixed, vary: v}, **_opts(options)))
        else:
            problems.append(
                as_problem(model.replace(**{vary: v}), cost=cost, **fixed, **_opts(options))
            )
    tol = float(options["tol"])
    if scheduler is not None or workers != 1:  # in other processes: the problems as data
        points = [{"problem": problem_data(p), "tol": tol} for p in problems]
        with worker_map(workers, scheduler) as run:
            outcomes = list(run(cold_task, points))
    else:
        outcomes = [cold_solve(p, tol) for p in problems]
    checks = []
    for v, out in zip(values, outcomes, strict=True):
        point = min(by_value.values(), key=lambda pt, v=v: abs(pt.value - v))
        lib_cost = point.gait.cost if point.gait.success else None
        cold_cost = out["cost"] if out["success"] else None
        rel = (
            abs(lib_cost - cold_cost) / max(abs(cold_cost), 1e-300)
            if lib_cost is not None and cold_cost is not None
            else None
        )
        agree = rel is not None and (rel <= _COLD_RTOL or abs(lib_cost - cold_cost) <= 1e-12)
        if agree:
            message = f"same cost to {rel:.2g} relative"
        elif rel is not None:
            message = (
                f"the cold start finds cost {cold_cost:.10g} against the library's "
                f"{lib_cost:.10g}: another local minimum"
            )
        else:
            message = f"no comparison: {out['message'] if not out['success'] else 'library failed'}"
        checks.append(ColdCheck(v, lib_cost, cold_cost, rel, agree, float(out["time"]), message))
    return checks


def _opts(options: Mapping[str, Any]) -> dict[str, Any]:
    return {k: options[k] for k in ("bounds", "state_bounds", "free", "steps")}
