"""Find a gait: :func:`find_limit_cycle` — with a guess, the direct solve
(:mod:`~gaitopt.shooting.gait`: the guess, a simulation or a previous orbit, the solve on the
:class:`~gaitopt.shooting.problem.ShootingProblem`, mesh refinement until the discretisation
error is below the tolerance, and :func:`~gaitopt.shooting.certify.certify`); with no guess, the
homotopy from the default gait or a multi-start search (:mod:`gaitopt.homotopy`, which calls the
direct solve) — and :func:`solve_task`, the sweep task that finds a gait at a grid point."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from ..hybrid import HybridModel
from ..result import LimitCycle
from ..threads import single_blas_thread
from .gait import check_arguments, gait_task, solve_from_guess, solve_gait
from .problem import MultipleShooting

__all__ = ["find_limit_cycle", "solve_gait", "solve_task"]


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
        gait from its default parameters to these (a homotopy, :mod:`gaitopt.homotopy`), so that
        the gait found is the one the defaults describe, not whichever orbit lies nearest the
        default start.  ``None`` (default): follow for period-1 gaits when no guess is given;
        where the gait is lost on the way, a direct solve from the default start is tried too.
        ``False``: solve directly.  The result's ``route`` says which was done.
    starts : int
        More than 1: also run a seeded multi-start search (the default start and ``starts − 1``
        Latin-hypercube points around it) and list every distinct gait found in ``gaits``.
    seed : int
        Seed of the multi-start sample (deterministic).
    scheduler : str, optional
        Run the multi-start on the Dask sweep (``"local"`` or a scheduler address).

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
    if starts != 1 or (follow is not False and guess is None and steps == 1):
        from ..homotopy import find_the_gait_meant

        return find_the_gait_meant(
            model,
            guess,
            follow=follow,
            starts=starts,
            seed=seed,
            scheduler=scheduler,
            steps=steps,
            inputs=inputs,
            discretisation=discretisation,
            method=method,
            verify=verify,
            tol=tol,
        )
    return solve_from_guess(model, guess, steps, u, discretisation, method, verify, tol, start)


def solve_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """A limit cycle at ``point`` (a task of :func:`gaitopt.sweep.sweep`): ``{"model": name,
    "params": {...}, "guess": {...} | None, "steps": k}`` → success, period, fixed point,
    multipliers, max |multiplier|, stable."""
    return gait_task(point, find_limit_cycle)
