"""Find a gait: :func:`find_limit_cycle`, the public entry, above the orbit and shooting layers.

It checks every argument before any work, then chooses the route: with a guess (or
``follow=False``), the direct solve of :mod:`gaitopt.shooting.gait` (the guess, the solve on the
:class:`~gaitopt.shooting.problem.ShootingProblem`, mesh refinement, the certificate); with no
guess at parameters other than the defaults, the homotopy from the default gait
(:func:`gaitopt.homotopy.follow_default_gait`), with the direct solve from the default start where
the gait is lost on the way; with ``starts > 1`` also the multi-start search
(:func:`gaitopt.homotopy.multi_start`), run by the ``workers=`` map.  Both remedies call the
direct solve, never this.  :func:`solve_task` is its sweep task (a gait at a grid point).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from .errors import GaitoptInputError
from .homotopy import changed_parameters, follow_default_gait, multi_start, path_description
from .hybrid import HybridModel
from .result import LimitCycle
from .shooting.gait import check_arguments, direct_solve, gait_task, solve_from_guess
from .shooting.problem import MultipleShooting
from .threads import single_blas_thread
from .workers import Map, check_workers

__all__ = ["MAX_STARTS", "find_limit_cycle", "solve_task"]

#: Most starts of one multi-start search (each a full solve: 1000 take minutes).
MAX_STARTS = 1000


@single_blas_thread
def find_limit_cycle(
    model: HybridModel,
    guess: Mapping[str, float] | LimitCycle | None = None,
    *,
    steps: int = 1,
    inputs: Any = None,
    discretisation: MultipleShooting | None = None,
    method: str = "newton",
    verify: bool = True,
    tol: float = 1e-10,
    follow: bool | None = None,
    starts: int = 1,
    seed: int = 0,
    workers: int | Map = 1,
    scheduler: str | None = None,
) -> LimitCycle:
    """Find a periodic orbit (gait) of a hybrid model by multiple shooting.

    Parameters
    ----------
    model : HybridModel
        The model, with its parameters.
    guess : mapping, LimitCycle or None
        Section coordinates to start from (missing ones from ``model.default_start()``): the
        shooting guess is then a simulation of ``steps`` returns from there; ``None`` starts from
        the model's default start.  Or a previous result (warm start, e.g. after a parameter
        change): its orbit seeds the nodes directly.
    steps : int
        Returns to the section per orbit (``2`` for a period-2 gait).
    inputs : array_like, optional
        Constant per-step input (``model.inputs``); default passive.
    discretisation : MultipleShooting, optional
        Segments per phase and RK steps per segment to start from (default: the model's
        ``mesh``).  After convergence the discretisation error is estimated by one Newton
        correction towards twice as many RK steps; while it exceeds ``tol`` the steps are doubled
        and the orbit re-solved (at most four times).
    method : {"newton", "ipopt"}
        CasADi Newton rootfinder on the square system, or IPOPT (``nlpsol``) with durations
        bounded positive.
    verify : bool
        Check the orbit by independent simulation (:func:`gaitopt.simulate`).
    tol : float
        Largest accepted residual of the shooting equations, target of the discretisation-error
        estimate and, scaled by 1e3, the largest accepted difference between the simulated return
        and the fixed point (the simulation runs at ``rtol = 1e-10``, and at ``1e-12`` where
        that check fails).
    follow : bool or None
        Without a ``guess``, at parameters other than the defaults: follow the model's default
        gait from its default parameters to these (a homotopy,
        :func:`gaitopt.homotopy.follow_default_gait`), so that
        the gait found is the one the defaults describe, not whichever orbit lies nearest the
        default start.  ``None`` (default): follow for period-1 gaits when no guess is given;
        where the gait is lost on the way, a direct solve from the default start is tried too.
        ``False``: solve directly.  The result's ``route`` says which was done.
    starts : int
        More than 1: also run a seeded multi-start search (the default start and ``starts − 1``
        Latin-hypercube points around it) and list every distinct gait found in ``gaits``.
    seed : int
        Seed of the multi-start sample (deterministic).
    workers : int or callable
        What runs the multi-start's solves (:func:`gaitopt.workers.worker_map`): ``1``
        (default) one after another in this process, ``n`` a pool of ``n`` processes (``-1``:
        one per CPU), or a map-like ``workers(func, iterable)`` such as
        ``multiprocessing.Pool(4).map``.  The result does not depend on it.
    scheduler : str, optional
        Run the multi-start on Dask instead (``"local"`` or a scheduler address): an adapter
        onto a Dask-backed map (:func:`gaitopt.sweep.dask_map`).

    Returns
    -------
    LimitCycle
        ``success`` is True only if the equations are solved to ``tol``, every phase duration is
        positive, each phase ends on its guard in the stated direction where the crossing is
        admissible, no guard is crossed earlier inside a phase (dense samples), for ``steps > 1``
        the orbit is not a shorter one repeated, and (with ``verify``) a simulation from the fixed
        point returns to it.  Otherwise ``message`` says what failed.

    Raises
    ------
    GuessError
        If an explicit ``guess`` never reaches the next transition in simulation.
    """
    start = time.perf_counter()
    # -- arguments: every check before any work (bad input fails fast) ----------------
    model, steps, tol, u = check_arguments(
        model, guess, steps=steps, inputs=inputs, discretisation=discretisation, method=method,
        tol=tol, scheduler=scheduler,
    )  # fmt: skip
    _check_search(starts, seed, workers, scheduler)
    options = dict(inputs=inputs, discretisation=discretisation, method=method, verify=verify,
                   tol=tol)  # fmt: skip
    if guess is None and steps == 1 and follow is not False:
        cycle = _followed_or_direct(model, options, u, start)
    else:
        cycle = solve_from_guess(model, guess, steps, u, discretisation, method, verify, tol, start)
        if starts > 1 and guess is None and not cycle.route:
            cycle = replace(cycle, route="direct from the default start")
    if starts > 1:
        cycle = _with_multi_start(model, cycle, starts, seed, steps, workers, scheduler, options)
    return replace(cycle, solve_time=time.perf_counter() - start)


def _check_search(starts: Any, seed: Any, workers: Any, scheduler: Any) -> None:
    """The multi-start's arguments (the solve's are :func:`check_arguments`')."""
    if not isinstance(starts, int) or isinstance(starts, bool) or not 1 <= starts <= MAX_STARTS:
        raise GaitoptInputError(
            f"`starts` must be an integer from 1 to {MAX_STARTS}, got {starts!r}; e.g. starts=8"
        )
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise GaitoptInputError(f"`seed` must be an integer, got {seed!r}; e.g. seed=0")
    check_workers(workers, scheduler)


def _followed_or_direct(
    model: HybridModel, options: dict[str, Any], u: Any, start: float
) -> LimitCycle:
    """No guess, one step: the default gait followed from the default parameters (where they
    differ), else — or where it is lost on the way — the direct solve from the default start
    (the arguments as :func:`check_arguments` returned them: checked once; ``u`` the inputs,
    ``start`` the search's ``time.perf_counter()``)."""
    followed = follow_default_gait(model, **options)
    if followed is not None and followed.success:
        return followed
    o = options
    cycle = solve_from_guess(model, None, 1, u, o["discretisation"], o["method"], o["verify"],
                             o["tol"], start)  # fmt: skip
    if followed is None:
        return cycle if cycle.route else replace(cycle, route="direct from the default start")
    lost = followed.message
    if cycle.success:
        return replace(
            cycle,
            message=f"{cycle.message}; found from the default start ({lost})",
            route=f"direct from the default start; {lost}",
        )
    return replace(
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


def _with_multi_start(model, cycle, starts, seed, steps, workers, scheduler, options):
    """``cycle`` with the multi-start's distinct gaits (``gaits``); where ``cycle`` failed and
    the search found a gait, the direct solve from the one reached most often instead."""
    gaits = multi_start(
        model, starts, seed=seed, steps=steps, workers=workers, scheduler=scheduler,
        **{k: v for k, v in options.items() if k in ("inputs", "method", "tol")},
    )  # fmt: skip
    if not cycle.success and gaits:  # the multi-start found what the default route did not
        best = gaits[0]
        guess = {k: best["fixed_point"][k] for k in model.section.coordinates}
        cycle = direct_solve(model, guess, steps=steps, **options)
    count = f"{len(gaits)} distinct gait(s) from {starts} starts (seed {seed})"
    return replace(cycle, gaits=gaits, message=f"{cycle.message}; multi-start: {count}")


def solve_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """A limit cycle at ``point`` (a task of :func:`gaitopt.sweep.sweep`): ``{"model": name,
    "params": {...}, "guess": {...} | None, "steps": k}`` → success, period, fixed point,
    multipliers, max |multiplier|, stable."""
    return gait_task(point, find_limit_cycle)
