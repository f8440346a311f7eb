"""Libraries and multi-starts in other processes (by a ``workers=`` map, :mod:`gaitopt.workers`):
the problem as plain data, rebuilt in each worker from the registered model and its parameters;
the tasks return plain data.  The multi-start's share (:func:`problem_data`,
:func:`problem_from`, :func:`start_task`, :func:`dask_starts`) lives in
:mod:`gaitopt.optimize.starts`, below the solver, and is re-exported here."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from ..problem import GaitProblem
from ..solve import solve_problem
from ..starts import dask_starts, problem_data, problem_from, start_task

__all__ = ["problem_data", "problem_from", "start_task", "dask_starts", "cold_task", "cold_solve"]


def cold_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Worker task: a cold :func:`solve_problem` of the problem in ``point`` (cost, success,
    message, wall-clock time)."""
    return cold_solve(problem_from(point["problem"]), float(point["tol"]))


def cold_solve(problem: GaitProblem, tol: float) -> dict[str, Any]:
    """A cold :func:`solve_problem` (no warm start) as plain data: ``success``, ``cost``,
    ``message`` and the wall-clock ``time`` (s)."""
    t0 = time.perf_counter()
    gait = solve_problem(problem, tol=tol)
    return {
        "success": gait.success,
        "cost": gait.cost,
        "message": gait.message,
        "time": time.perf_counter() - t0,
    }
