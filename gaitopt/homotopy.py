"""Finding the gait the user means: homotopy from the default gait, and multi-start search.

Newton from a simulated guess finds *a* periodic orbit near the guess, which at parameters far
from the defaults may be the wrong one (the compass gait's unstable short-step gait at a small
slope) or none at all (Van der Pol at μ = 5 from the μ = 1 start).  Two remedies:

* **Homotopy** (:func:`follow_default_gait`): solve the model's default gait at its default
  parameters, then follow it along the straight path ``p(s) = p₀ + s (p₁ − p₀)``, ``s ∈ [0, 1]``,
  to the requested parameters, each step warm-started from the previous orbit (natural-parameter
  continuation, Allgower & Georg, "Numerical Continuation Methods", §1) with step control: the
  step grows after a success and halves after a failure.  Every step is certified like a gait
  (no false gaits along the way); only the last one is also verified by simulation.  If the gait
  is lost on the way (a fold, a constraint becoming active, a guard grazing), the result says where
  and why.
* **Multi-start** (:func:`multi_start`): a seeded Latin-hypercube sample of section points around
  the model's default start, each solved by Newton; the distinct gaits found are reported with
  their stability and the number of starts that reached each.  Deterministic for a given seed;
  runs serially, on a process pool or any map (``workers=``, :mod:`gaitopt.workers`).

Both call the direct solve (:func:`gaitopt.shooting.gait.direct_solve`); the public entry that
chooses between them, :func:`gaitopt.find_limit_cycle`, is above, in :mod:`gaitopt.search`.
"""

from __future__ import annotations

from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np

from .errors import GaitoptInputError
from .hybrid import HybridModel
from .result import LimitCycle
from .shooting.gait import direct_solve
from .workers import Map, worker_map

__all__ = [
    "changed_parameters",
    "follow_default_gait",
    "multi_start",
    "path_description",
    "start_gait",
]

#: Largest homotopy step (fraction of the path): at least four warm starts, so that Newton stays
#: on the gait it follows instead of jumping to a neighbouring one.
_MAX_STEP = 0.25
#: Smallest homotopy step before the gait counts as lost.
_MIN_STEP = 1e-3
#: Most solves along one path (a gait that fades away slowly must not take minutes to give up).
_MAX_SOLVES = 30


def changed_parameters(model: HybridModel) -> dict[str, tuple[float, float]]:
    """Parameters that differ from the class defaults: name → (default, requested)."""
    base = type(model)()
    return {
        name: (getattr(base, name), value)
        for name, value in model.params.items()
        if getattr(base, name) != value
    }


def path_description(changes: dict[str, tuple[float, float]]) -> str:
    """``"slope 0.0525 → 0.01, mass_hip 10 → 20"``."""
    return ", ".join(f"{k} {a:.6g} → {b:.6g}" for k, (a, b) in changes.items())


def follow_default_gait(model: HybridModel, **options: Any) -> LimitCycle | None:
    """The default gait followed from the default parameters to ``model``'s.

    Parameters
    ----------
    model : HybridModel
        The target parameters.
    **options
        ``inputs``, ``discretisation``, ``method``, ``verify``, ``tol`` of
        :func:`gaitopt.find_limit_cycle`.

    Returns
    -------
    LimitCycle or None
        The certified gait at the target (``success`` True), or a failure whose message says
        where along the path the gait was lost and why; ``None`` when the path cannot be taken (an
        integer parameter changed, or no default gait at the default parameters).
    """
    changes = changed_parameters(model)
    specs = {s.name: s for s in type(model).parameter_specs()}
    if not changes or any(specs[k].integer for k in changes):
        return None
    verify = options.pop("verify", True)
    base = type(model)()
    cycle = direct_solve(base, None, verify=False, **options)
    if not cycle.success:
        return None
    route = f"followed the default gait from the default parameters ({path_description(changes)})"

    def at(s: float) -> HybridModel:
        return model.replace(**{k: a + s * (b - a) for k, (a, b) in changes.items()})

    own_mesh = options.get("discretisation") is None
    s, h, steps, solves, reason = 0.0, _MAX_STEP, 0, 0, ""
    while s < 1.0:
        h = min(h, 1.0 - s)
        target = 1.0 if s + h >= 1.0 - 1e-12 else s + h
        last = target == 1.0
        if own_mesh:  # keep the mesh the previous gait needed (refined where the orbit is stiff)
            options["discretisation"] = cycle.discretisation
        trial = direct_solve(
            model if last else at(target), cycle, verify=verify and last, **options
        )
        solves += 1
        if trial.success:
            s, cycle, steps = target, trial, steps + 1
            h = min(2 * h, _MAX_STEP)
            continue
        reason = trial.message
        h /= 2
        if h < _MIN_STEP or solves >= _MAX_SOLVES:
            where = ", ".join(f"{k} = {a + s * (b - a):.6g}" for k, (a, b) in changes.items())
            return replace(
                trial,
                success=False,
                message=(f"the default gait was lost at {where} ({s:.3g} of the way): {reason}"),
                route=route,
            )
    return replace(
        cycle,
        message=f"{cycle.message}; {route} in {steps} homotopy steps",
        route=f"{route} in {steps} homotopy steps",
    )


def _sample(model: HybridModel, starts: int, seed: int) -> np.ndarray:
    """The default start, then a Latin-hypercube sample around it (±50 % of each coordinate,
    at least ±0.05 in its unit)."""
    from scipy.stats import qmc

    centre = model.section_vector({})
    if starts == 1:
        return centre[None, :]
    unit = qmc.LatinHypercube(d=centre.size, seed=seed).random(starts - 1)
    spread = 0.5 * np.abs(centre) + 0.05
    return np.vstack([centre, centre + (2 * unit - 1) * spread])


def _same(a: dict[str, float], b: dict[str, float]) -> bool:
    x, y = np.array(list(a.values())), np.array(list(b.values()))
    return bool(np.max(np.abs(x - y)) <= 1e-6 * (1 + np.max(np.abs(x))))


def multi_start(
    model: HybridModel,
    starts: int,
    *,
    seed: int = 0,
    steps: int = 1,
    workers: int | Map = 1,
    scheduler: Any = None,
    **options: Any,
) -> list[dict[str, Any]]:
    """Solve from ``starts`` seeded section points; the distinct gaits found.

    Parameters
    ----------
    model : HybridModel
        The model.
    starts : int
        Number of starts (the first is the model's default start).
    seed : int
        Seed of the Latin-hypercube sample: the same seed gives the same starts.
    steps : int
        Returns per orbit.
    workers : int or callable
        What runs the starts (:func:`gaitopt.workers.worker_map`): ``1`` serially in this
        process, ``n`` a pool of ``n`` processes, or a map-like ``workers(func, iterable)``.
    scheduler : str, optional
        A Dask scheduler instead (``"local"`` or an address; :func:`gaitopt.sweep.dask_map`).
    **options
        ``inputs``, ``method``, ``tol`` of :func:`gaitopt.find_limit_cycle`.

    Returns
    -------
    list of dict
        One per distinct gait, most often reached first: ``fixed_point``, ``period``,
        ``multipliers`` (``[re, im]``), ``stable``, ``starts`` (how many reached it).
    """
    names = model.section.coordinates
    sample = _sample(model, starts, seed)
    points = [dict(zip(names, map(float, row), strict=True)) for row in sample]
    task = partial(start_gait, model, steps, options)
    with worker_map(workers, scheduler) as run:
        found = [gait for gait in run(task, points) if gait is not None]
    distinct: list[dict[str, Any]] = []
    for gait in found:
        match = next((d for d in distinct if _same(d["fixed_point"], gait["fixed_point"])), None)
        if match is None:
            distinct.append({**gait, "starts": 1})
        else:
            match["starts"] += 1
    return sorted(distinct, key=lambda d: -d["starts"])


def start_gait(
    model: HybridModel, steps: int, options: dict[str, Any], guess: dict[str, float]
) -> dict[str, Any] | None:
    """One start of :func:`multi_start` (a task of its map: picklable, returns plain data): the
    direct solve from the section point ``guess``; ``None`` where no gait was found or the model
    never completes a step from there."""
    try:
        cycle = direct_solve(model, guess, steps=steps, **options)
    except GaitoptInputError:  # a start from which the model never completes a step
        return None
    if not cycle.success:
        return None
    return {
        "fixed_point": cycle.fixed_point,
        "period": cycle.period,
        "multipliers": [[z.real, z.imag] for z in cycle.multipliers],
        "stable": cycle.stable,
    }
