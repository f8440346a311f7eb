"""Find a gait: :func:`find_limit_cycle` — the guess (a simulation or a previous orbit), the
solve on the :class:`~gaitopt.shooting.problem.ShootingProblem`, mesh refinement until the
discretisation error is below the tolerance, and :func:`~gaitopt.shooting.certify.certify`; with
no guess, the homotopy from the default gait or a multi-start search (:mod:`gaitopt.homotopy`)."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import GaitoptInputError, GuessError
from ..hybrid import HybridModel
from ..result import LimitCycle
from ..simulation import simulate
from .certify import certify
from .newton import METHODS
from .problem import MultipleShooting, ShootingProblem, shooting_problem

__all__ = ["find_limit_cycle", "solve_gait"]

_MAX_REFINEMENTS = 4
#: The finest mesh any solve may reach, as a multiple of the model's RK steps per segment: a
#: chain of warm starts (homotopy, libraries) refines from where the last one ended, up to here
#: (Van der Pol at μ = 10 needs 32×; without a bound the chain compounded to 22 GB).
_MAX_MESH_FACTOR = 64


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
    from ..arguments import (
        check_count,
        check_inputs,
        check_positive,
        check_scheduler,
        check_start,
        section_guess,
    )
    from ..errors import MAX_ORBIT_STEPS, StateError
    from ..models import as_model

    model = as_model(model)
    if method not in METHODS:
        raise GaitoptInputError(f"`method` must be one of {', '.join(METHODS)}, got {method!r}")
    steps = check_count(
        "steps", steps, 1, MAX_ORBIT_STEPS, "the shooting system of a period-k orbit grows "
        "faster than k (gaitopt.errors.MAX_ORBIT_STEPS)"
    )  # fmt: skip
    tol = check_positive("tol", tol, "1e-10")
    check_scheduler(scheduler)
    u = check_inputs(model, inputs)
    if discretisation is not None and not isinstance(discretisation, MultipleShooting):
        raise GaitoptInputError(
            f"`discretisation` must be a MultipleShooting, got {discretisation!r}; e.g. "
            f"MultipleShooting(segments=4, rk_steps=5)"
        )
    if not isinstance(guess, LimitCycle):
        x_start = model.lift(section_guess(model, guess))  # unknown names: StateError
        try:
            check_start(model, x_start, u, 0,
                        "guess" if guess is not None else "the default start")  # fmt: skip
        except StateError as exc:
            if guess is None:
                raise
            raise GuessError(str(exc)) from None
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
    disc = discretisation or MultipleShooting(*type(model).mesh)
    problem = shooting_problem(type(model), disc, steps)

    def fail(message: str, status: str, **extra: Any) -> LimitCycle:
        return failed(model, steps, u, start, message, status, **extra)

    # -- guess: a previous orbit (warm start), or a simulation ------------------------------------
    explicit = guess is not None
    warm = isinstance(guess, LimitCycle)
    s0 = guess.section_point if warm else model.section_vector(guess if explicit else {})
    if warm and problem.fits(guess):
        w0 = problem.unknowns_from_cycle(guess)
    else:
        sim = simulate(
            model,
            model.lift(s0),
            steps=steps,
            inputs=u,
            max_phase_time=float(model.max_phase_time),
            rtol=1e-8,
            atol=1e-9,  # a guess: Newton does the rest
            constraints=False,  # checked on the orbit found (certify), not on the guess
        )
        if not sim.success:
            where = ", ".join(
                f"{k}={v:.6g}" for k, v in zip(model.section.coordinates, s0, strict=True)
            )
            if explicit and not warm:
                raise GuessError(
                    f"{model.name}: `guess` {where} leads nowhere: {sim.message}; "
                    f"try another guess (e.g. from `gaitopt simulate {model.name}`)"
                )
            return fail(
                status="no_start",
                message=f"no gait found: the simulation from {where} does not complete "
                f"{steps} step(s) ({sim.message}); the gait may not exist at these parameters",
            )
        w0 = problem.unknowns_from_simulation(s0, sim)

    return solve_gait(model, problem, w0, u, method=method, verify=verify, tol=tol, start=start)


def solve_gait(
    model: HybridModel,
    problem: ShootingProblem,
    w0: np.ndarray,
    u: np.ndarray,
    *,
    method: str = "newton",
    verify: bool = True,
    tol: float = 1e-10,
    start: float | None = None,
) -> LimitCycle:
    """Solve ``problem`` from the unknowns ``w0`` at ``model``'s parameters, refine the mesh
    until the discretisation error is below ``tol``, and certify the orbit.

    The part of :func:`find_limit_cycle` after the guess, for callers that build the unknowns
    themselves (branch switching at a period doubling, warm starts).

    Parameters
    ----------
    model : HybridModel
        The model, with its parameters.
    problem : ShootingProblem
        The shooting problem (model class, discretisation, cycles).
    w0 : numpy.ndarray
        Starting unknowns (:attr:`ShootingProblem.layout`).
    u : numpy.ndarray
        Per-step inputs.
    method, verify, tol
        As :func:`find_limit_cycle`.
    start : float, optional
        ``time.perf_counter()`` when the search began (for ``solve_time``).

    Returns
    -------
    LimitCycle
        As :func:`find_limit_cycle`.
    """
    start = time.perf_counter() if start is None else start
    steps = problem.cycles
    disc = problem.disc
    p = model.p

    def fail(message: str, status: str, **extra: Any) -> LimitCycle:
        return failed(model, steps, u, start, message, status, **extra)

    # -- solve, then refine the mesh until the discretisation error is below tol ---------------
    refinements, disc_error, singular = 0, float("nan"), False
    while True:
        solution = problem.solve(w0, u, p, method=method)
        w, converged, iterations, ev = (
            solution.w, solution.converged, solution.iterations, solution.evaluation,
        )  # fmt: skip
        # One Jacobian per Newton step: the last one (at the solution) serves the error
        # estimate, the multipliers and the input Jacobian.
        ev = ev if ev is not None else problem.evaluate(w, u, p)
        F, F_w = ev.F, ev.F_w
        # Newton's own stopping test (abstol 1e-12) is stricter than `tol`: a point that meets
        # `tol` is accepted (and certified) even where Newton stalled just above its abstol.
        # A "converged" point where the equations are not even finite (e.g. a negative duration
        # reached by the line search) is no solution.
        finite = bool(np.all(np.isfinite(F_w)) and np.all(np.isfinite(F)))
        converged = finite and (converged or float(np.max(np.abs(F))) <= tol)
        if not converged:
            break
        try:
            correction = problem.newton_step(F_w, problem.fine_residual(w, u, p))
        except np.linalg.LinAlgError:  # a singular shooting Jacobian: not an isolated orbit
            converged, singular = False, True
            break
        disc_error = float(np.max(np.abs(correction)))
        # The finest mesh is bounded in absolute terms (not only per call), so that a chain of
        # warm starts (homotopy, libraries) cannot compound refinements without limit.
        finest = type(model).mesh[1] * _MAX_MESH_FACTOR
        if disc_error <= tol or refinements == _MAX_REFINEMENTS or 2 * disc.rk_steps > finest:
            break
        disc = disc.refined()
        problem, w0 = shooting_problem(type(model), disc, steps), w + correction
        refinements += 1

    residual = float(np.max(np.abs(F))) if np.all(np.isfinite(F)) else float("inf")
    durations = np.asarray(ev.durations, dtype=float).ravel()
    # A period only where it means something: every phase duration positive and finite.
    period = (
        float(np.sum(durations))
        if durations.size and np.all(np.isfinite(durations)) and np.all(durations > 0)
        else float("nan")
    )
    if singular:
        return fail(
            status="singular",
            message=f"no isolated gait: the shooting equations are solved "
            f"(residual {residual:.3g}, "
            f"tolerance {tol:g}) but their Jacobian is singular there, so the orbit is one of a "
            f"continuous family (a multiplier exactly 1: the motion does not depend on some "
            f"coordinate, or a parameter makes a restoring term vanish) and has no fixed point "
            f"or stability of its own; change the parameter that removes the restoring term",
            residual=residual,
            iterations=iterations,
            durations=durations,
            period=period,
        )
    if not converged or not residual <= tol:
        if not np.isfinite(residual):
            how = (
                f"{method} diverged: after {iterations} iterations the shooting equations are "
                f"not even finite (a phase run backwards or far outside the model's range)"
            )
        else:
            how = (
                f"{method} stopped after {iterations} iterations with residual {residual:.3g}, "
                f"above the tolerance {tol:g}"
            )
        return fail(
            status="not_converged",
            message=f"no periodic orbit found near the guess: {how}; "
            f"the gait may not exist at these parameters, or the guess is too far from it: "
            f"try a closer guess" + (" or the ipopt method" if method == "newton" else ""),
            residual=residual,
            iterations=iterations,
            durations=durations if np.isfinite(period) else np.zeros(0),
            period=float("nan"),  # not an orbit: no period
        )
    if disc_error > tol:
        condition = float(np.linalg.cond(F_w))
        return fail(
            status="discretisation",
            message=f"no certified gait: the discretisation error estimate "
            f"{disc_error:.2g} stays above "
            f"the tolerance {tol:g} after {refinements} mesh refinements "
            f"({problem.disc.rk_steps} RK steps per segment), so the orbit is known only to about "
            f"{disc_error:.1g}; the shooting Jacobian's condition number is {condition:.2g} "
            f"(a multiplier near 1 makes the fixed point sensitive to every error): loosen `tol` "
            f"to accept that accuracy",
            residual=residual,
            iterations=iterations,
            durations=durations,
            period=period,
            discretisation_error=disc_error,
        )
    x_star = model.lift(w[: problem.m])
    rate = np.asarray(model.phases[0].flow(x_star, u, p), dtype=float).ravel()
    if float(np.max(np.abs(rate))) <= 1e-8 * (1 + float(np.max(np.abs(x_star)))):
        return fail(
            status="standing",
            message="no gait: the orbit found is standing still "
            "(an equilibrium: the state does not change, zero step length), which solves the "
            "shooting equations with any phase "
            "duration but is not a gait; the gait may not exist at these parameters (a passive "
            "walker needs a slope), or try a guess with more speed",
            residual=residual,
            iterations=iterations,
        )
    disc_error_note = ""
    return certify(
        model,
        problem,
        w,
        u,
        verify=verify,
        tol=tol,
        iterations=iterations,
        discretisation_error=disc_error,
        note=disc_error_note,
        start=start,
        evaluation=ev,
    )


def failed(model, steps: int, u, start: float, message: str, status: str, **extra) -> LimitCycle:
    """The record of a search that found no gait: ``message`` (with the model's note on where its
    gait exists) and ``status`` (one of :data:`gaitopt.result.STATUS`)."""
    note = model.existence_note()
    return LimitCycle(
        False,
        f"{message} [{note}]" if note else message,
        model,
        steps=steps,
        state_names=model.state_names,
        section_coordinates=model.section.coordinates,
        inputs=u,
        solve_time=time.perf_counter() - start,
        status=status,
        **extra,
    )
