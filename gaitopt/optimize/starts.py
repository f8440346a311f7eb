"""Multi-starts in other processes, by a map (``workers=``, :mod:`gaitopt.workers`): the problem
as plain data, rebuilt in each worker from the registered model and its parameters
(:func:`problem_data`, :func:`problem_from`); :func:`start_task` runs one
:func:`~gaitopt.optimize.attempt.attempt` and returns plain data; :func:`mapped_starts` sends
the starts through whatever map it is given (a process pool, a Dask-backed map, a caller's).
Used by :func:`gaitopt.optimize.solve.optimize_gait` and the libraries' workers
(:mod:`gaitopt.optimize.library.workers`)."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..models import model as make_model
from ..workers import Map, worker_map
from .attempt import attempt
from .collocation import Collocation, RadauMesh
from .problem import GaitProblem
from .result import OptimalGait

__all__ = ["problem_data", "problem_from", "start_task", "mapped_starts", "dask_starts"]


def problem_data(problem: GaitProblem) -> dict[str, Any]:
    """The problem as JSON-able data, rebuilt by :func:`problem_from` in a worker."""
    model = problem.model
    if not isinstance(problem.cost, str):
        raise GaitoptInputError(
            "`scheduler`: a callable cost cannot be sent to Dask workers; use cost='effort', "
            "'work' or 'cot', or run without a scheduler"
        )
    try:
        rebuilt = make_model(model.name, **model.params)
    except GaitoptInputError:
        rebuilt = None
    if rebuilt is None or not np.array_equal(rebuilt.p, model.p):
        raise GaitoptInputError(
            f"`scheduler`: {model.name!r} cannot be rebuilt by name in a Dask worker (not a "
            f"registered model); gaitopt.register it, or run without a scheduler"
        )
    # The statement as GaitProblem.describe gives it (its "cost" is the cost's name, checked
    # above to be a string), and what a worker needs besides to rebuild it.
    return {
        "model": model.name,
        "params": dict(model.params),
        **problem.describe(),
        "max_phase_time": problem.max_phase_time,
        "regularisation": problem.regularisation,
        "min_crossing_rate": problem.min_crossing_rate,
    }


def problem_from(data: Mapping[str, Any]) -> GaitProblem:
    model = make_model(data["model"], **data["params"])
    return GaitProblem(
        model,
        data["cost"],
        period=data["period"],
        step_length=data["step_length"],
        speed=data["speed"],
        bounds={k: (tuple(v) if isinstance(v, list) else v) for k, v in data["bounds"].items()},
        state_bounds={k: tuple(v) for k, v in data["state_bounds"].items()},
        free=tuple(data["free"]),
        steps=int(data["steps"]),
        max_phase_time=float(data["max_phase_time"]),
        regularisation=float(data["regularisation"]),
        min_crossing_rate=float(data["min_crossing_rate"]),
        clearance=float(data.get("clearance", 0.0)),
        guard_margin=float(data.get("guard_margin", 0.0)),
        continuous_inputs=bool(data.get("continuous_inputs", True)),
        braking_effort=float(data.get("braking_effort", 0.0)),
        max_multiplier=data.get("max_multiplier"),
        max_roughness=data.get("max_roughness"),
    )


_WORKER_TRANSCRIPTIONS: dict[str, Collocation] = {}


def start_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Worker task: one start of a multi-start (:func:`gaitopt.optimize.solve.attempt`) on the
    initial mesh; the transcription is built once per worker process and problem."""
    key = json.dumps([point["problem"], point["mesh"]], sort_keys=True)
    col = _WORKER_TRANSCRIPTIONS.get(key)
    if col is None:
        _WORKER_TRANSCRIPTIONS.clear()
        col = Collocation(problem_from(point["problem"]), RadauMesh(*point["mesh"]))
        _WORKER_TRANSCRIPTIONS[key] = col
    entry = attempt(col, col.problem, int(point["start"]), int(point["seed"]), None)
    stats = entry["stats"]
    out = {
        "start": entry["start"],
        "ok": entry["ok"],
        "status": entry["status"],
        "reason": entry["reason"],
        "w": entry["w"].tolist(),
        "stats": {
            "success": bool(stats.get("success")),
            "return_status": str(stats.get("return_status")),
            "iter_count": int(stats.get("iter_count", 0)),
        },
    }
    if entry["ok"]:
        out.update(cost=entry["cost"], s=entry["s"].tolist(), period=entry["period"])
    else:
        out["violation"] = [entry["violation"][0], entry["violation"][1]]
    return out


def mapped_starts(
    problem: GaitProblem,
    mesh: RadauMesh,
    indices: Sequence[int],
    seed: int,
    run: Map,
    guess: OptimalGait | None = None,
) -> list[dict[str, Any]]:
    """The starts of a multi-start by the map ``run`` (``run(start_task, points)``, e.g. of
    :func:`gaitopt.workers.worker_map`), in start order, as
    :func:`gaitopt.optimize.solve.attempt` returns them.

    Parameters
    ----------
    run : callable
        A map-like ``run(func, iterable)`` returning the results in order.
    guess : OptimalGait, optional
        Not supported (a warm start stays in this process): an error.
    """
    if guess is not None:
        raise GaitoptInputError(
            "`workers`/`scheduler` with `guess`: a warm start is not sent to other processes; "
            "run it serially (workers=1, no scheduler)"
        )
    data = problem_data(problem)
    points = [
        {"problem": data, "mesh": [mesh.intervals, mesh.degree], "start": int(i), "seed": seed}
        for i in indices
    ]
    runs = []
    for r in run(start_task, points):
        entry = dict(r)
        entry["w"] = np.array([np.nan if v is None else v for v in r["w"]], dtype=float)
        if entry["ok"]:
            entry["s"] = np.asarray(r["s"], dtype=float)
        else:
            entry["violation"] = (r["violation"][0], float(r["violation"][1] or np.inf))
        runs.append(entry)
    return runs


def dask_starts(
    problem: GaitProblem,
    mesh: RadauMesh,
    indices: Sequence[int],
    seed: int,
    scheduler: str,
    guess: OptimalGait | None = None,
) -> list[dict[str, Any]]:
    """:func:`mapped_starts` on Dask (``"local"`` or a scheduler address;
    :func:`gaitopt.sweep.dask_map`), or ``"serial"``: in this process, through the same data."""
    workers, scheduler = (1, None) if scheduler == "serial" else (1, scheduler)
    with worker_map(workers, scheduler) as run:
        return mapped_starts(problem, mesh, indices, seed, run, guess)
