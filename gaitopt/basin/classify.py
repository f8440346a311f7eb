"""One start's fate, by simulation: :func:`classify` (one start, :func:`gaitopt.simulate`) and
:func:`classify_many` (many at once, the batch simulation, the same rule); the sweep tasks of
the estimates' starts (:func:`starts_task`, with its ``batched`` version) and :func:`run_tasks`,
which sends tasks through :func:`gaitopt.sweep.sweep`."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..arguments import check_scheduler
from ..errors import GaitoptInputError

__all__ = [
    "BACKEND",
    "BLOCK",
    "SMALL",
    "classify",
    "small",
    "classify_many",
    "model_of",
    "run_tasks",
    "starts_batch",
    "starts_task",
]


def classify(setup: Mapping[str, Any], model: Any, start: np.ndarray, backend: str = "auto") -> str:
    """``"converged"`` or why not, for one start in section coordinates (every coordinate).

    One simulation of ``steps + hold`` periods (one call, so that the simulator sees an
    accumulation of impacts whole): converged if it completes and, from some period at most
    ``steps`` on, every period's return is within ``tol`` (scaled) of the fixed point.
    ``backend``: :func:`gaitopt.simulate`'s (``"python"``: SciPy's stepper from Python)."""
    from ..errors import StateError
    from ..simulation import simulate

    centre, scale = np.asarray(setup["centre"]), np.asarray(setup["scale"])
    period, tol = setup["period"], setup["tol"]
    x = dict(zip(setup["coordinates"], map(float, start), strict=True))
    try:
        sim = simulate(model, x, steps=(setup["steps"] + setup["hold"]) * period,
                       inputs=setup["inputs"], backend=backend)  # fmt: skip
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
BLOCK = 4096
#: Fewer starts than this go one by one (gaitopt.simulate) where the batch runs from NumPy: it
#: costs about 1.4 ms of CPU per step try of all its starts together, a compass-gait start alone
#: about 36 ms in all, so below some 40 starts the loop is faster (bench/basin.py's anatomy).  The
#: compiled batch (:mod:`gaitopt.simulation.batch_compiled`) has no such cost: every start goes
#: through it (:func:`small`).
SMALL = 48
#: The batch simulation's ``backend`` (:func:`gaitopt.simulation.batch.simulate_batch`):
#: ``"auto"`` (compiled where it can be), ``"compiled"`` or ``"numpy"``.
BACKEND = "auto"
#: The compiled batch's vector steps' ``sin`` and ``cos``
#: (:func:`gaitopt.kernels.vector_step.vector_math`): ``"fast"``, glibc's libmvec (≤ 4 ulp; 1.7×
#: the starts per second of ``"exact"``, the C library's per lane, on the compass gait).  The
#: verdicts need no last bit: over bench/basin.py's 16 384 starts and in the basin studies
#: (problems/*_basin.py) they are the exact math's, start for start.
MATH = "fast"


def small(model: Any) -> int:
    """Fewer starts than this are classified one by one: :data:`SMALL` for the NumPy batch, 1
    where the batch is compiled."""
    from ..simulation.batch import compiled_batch

    return 1 if BACKEND != "numpy" and compiled_batch(model) else SMALL


def classify_many(setup: Mapping[str, Any], model: Any, starts: np.ndarray) -> list[str]:
    """:func:`classify` for many starts at once: the same simulations (the algorithm of
    :func:`gaitopt.simulate`), all starts stepped together by
    :func:`gaitopt.simulation.batch.simulate_batch`, and the same rule."""
    from ..kernels.vector_step import vector_math
    from ..simulation.batch import simulate_batch

    centre, scale = np.asarray(setup["centre"]), np.asarray(setup["scale"])
    period, tol, steps = setup["period"], setup["tol"], setup["steps"]
    index = [model.state_names.index(c) for c in setup["coordinates"]]
    outcomes: list[str] = []
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    if len(starts) < small(model):  # too few to repay the NumPy batch's cost per step try
        return [classify(setup, model, start) for start in starts]
    for k in range(0, len(starts), BLOCK):
        block = starts[k : k + BLOCK]
        with vector_math(MATH):
            sim = simulate_batch(model, block, steps=(steps + setup["hold"]) * period,
                                 inputs=setup["inputs"], backend=BACKEND)  # fmt: skip
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


def model_of(setup: Mapping[str, Any]) -> Any:
    from ..models import model as make_model

    return make_model(setup["model"], **setup["params"])


def starts_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Starts (section coordinates) → their outcomes (a point of :func:`sweep`)."""
    setup = point["setup"]
    model = model_of(setup)
    return {"outcomes": [classify(setup, model, np.asarray(s)) for s in point["starts"]]}


def starts_batch(points: list[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """:func:`starts_task` on many points (one setup): every start in one batch simulation."""
    if not points:
        return []
    setup = points[0]["setup"]
    if any(point["setup"] != setup for point in points):
        return [starts_task(point) for point in points]
    sizes = [len(point["starts"]) for point in points]
    starts = np.array([s for point in points for s in point["starts"]], dtype=float)
    outcomes = classify_many(setup, model_of(setup), starts) if len(starts) else []
    bounds = np.cumsum([0, *sizes])
    return [{"outcomes": outcomes[a:b]} for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


starts_task.batched = starts_batch  # type: ignore[attr-defined]


def run_tasks(
    task: Any, points: list[dict[str, Any]], scheduler: str | None, chunk: int
) -> list[dict[str, Any]]:
    """``task`` on every point through :func:`gaitopt.sweep.sweep`, which sends them to Dask
    ``chunk`` points per task (serially: one after another)."""
    from ..sweep import sweep

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
