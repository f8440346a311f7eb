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
  runs serially or on the Dask sweep (:func:`gaitopt.sweep.sweep`).
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from .errors import GaitoptInputError
from .hybrid import HybridModel
from .result import LimitCycle

__all__ = ["follow_default_gait", "multi_start", "path_description"]

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
    from .shooting.gait import direct_solve

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
    scheduler: str | None = None,
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
    scheduler : str, optional
        ``None``: solve serially in this process; otherwise the Dask scheduler of
        :func:`gaitopt.sweep.sweep` (``"local"`` or an address).
    **options
        ``inputs``, ``method``, ``tol`` of :func:`gaitopt.find_limit_cycle`.

    Returns
    -------
    list of dict
        One per distinct gait, most often reached first: ``fixed_point``, ``period``,
        ``multipliers`` (``[re, im]``), ``stable``, ``starts`` (how many reached it).
    """
    from .errors import GaitoptInputError
    from .shooting.gait import direct_solve

    names = model.section.coordinates
    sample = _sample(model, starts, seed)
    points = [dict(zip(names, map(float, row), strict=True)) for row in sample]
    found: list[dict[str, Any]] = []
    if scheduler is None:
        for guess in points:
            try:
                cycle = direct_solve(model, guess, steps=steps, **options)
            except GaitoptInputError:  # a start from which the model never completes a step
                continue
            if cycle.success:
                found.append(
                    {
                        "fixed_point": cycle.fixed_point,
                        "period": cycle.period,
                        "multipliers": [[z.real, z.imag] for z in cycle.multipliers],
                        "stable": cycle.stable,
                    }
                )
    else:
        from .shooting.gait import direct_task
        from .sweep import sweep

        tasks = [
            {"model": model.name, "params": model.params, "guess": g, "steps": steps}
            for g in points
        ]
        result = sweep(direct_task, tasks, scheduler=scheduler, progress=False)
        found = [
            {k: r[k] for k in ("fixed_point", "period", "multipliers", "stable")}
            for r in result.results
            if r["success"]
        ]
    distinct: list[dict[str, Any]] = []
    for gait in found:
        match = next((d for d in distinct if _same(d["fixed_point"], gait["fixed_point"])), None)
        if match is None:
            distinct.append({**gait, "starts": 1})
        else:
            match["starts"] += 1
    return sorted(distinct, key=lambda d: -d["starts"])


def find_the_gait_meant(model, guess, *, follow, starts, seed, scheduler, **options) -> LimitCycle:
    """The homotopy from the defaults and the multi-start search around
    :func:`~gaitopt.find_limit_cycle`'s direct solve (called by it; see the module docstring)."""
    from .shooting.gait import direct_solve

    if not isinstance(starts, int) or isinstance(starts, bool) or not 1 <= starts <= _MAX_STARTS:
        raise GaitoptInputError(
            f"`starts` must be an integer from 1 to {_MAX_STARTS}, got {starts!r}; e.g. starts=8"
        )
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise GaitoptInputError(f"`seed` must be an integer, got {seed!r}; e.g. seed=0")
    start = time.perf_counter()
    steps = options.pop("steps")
    direct = lambda: direct_solve(model, guess, steps=steps, **options)  # noqa: E731
    cycle = None
    if guess is None and steps == 1 and follow is not False:
        followed = follow_default_gait(model, **options)
        if followed is not None and followed.success:
            cycle = followed
        elif followed is not None:  # lost on the way: try the default start directly
            cycle = direct()
            lost = followed.message
            if cycle.success:
                cycle = replace(
                    cycle,
                    message=f"{cycle.message}; found from the default start ({lost})",
                    route=f"direct from the default start; {lost}",
                )
            else:
                cycle = replace(
                    cycle,
                    message=(
                        f"no gait found. Following the default gait from the default parameters "
                        f"({path_description(changed_parameters(model))}): {lost}. From the "
                        f"default start: {cycle.message}. Try `--starts 16` (a multi-start "
                        f"search), a --guess near a gait you know, or `gaitopt continue` to see "
                        f"where the branch ends"
                    ),
                    route="homotopy from the defaults, then direct from the default start",
                )
    if cycle is None:
        cycle = direct()
        if guess is None and not cycle.route:
            cycle = replace(cycle, route="direct from the default start")
    if starts > 1:
        gaits = multi_start(
            model, starts, seed=seed, steps=steps, scheduler=scheduler,
            **{k: v for k, v in options.items() if k in ("inputs", "method", "tol")},
        )  # fmt: skip
        if not cycle.success and gaits:  # the multi-start found what the default route did not
            best = gaits[0]
            cycle = direct_solve(
                model,
                {k: best["fixed_point"][k] for k in model.section.coordinates},
                steps=steps,
                **options,
            )
        count = f"{len(gaits)} distinct gait(s) from {starts} starts (seed {seed})"
        cycle = replace(cycle, gaits=gaits, message=f"{cycle.message}; multi-start: {count}")
    return replace(cycle, solve_time=time.perf_counter() - start)


#: Most starts of one multi-start search (each a full solve: 1000 take minutes).
_MAX_STARTS = 1000
