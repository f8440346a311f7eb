"""A gait from a guess: the direct solve below :func:`~gaitopt.search.find_limit_cycle`
— the argument checks, the guess (a simulation or a previous orbit), the solve on the
:class:`~gaitopt.shooting.problem.ShootingProblem` (:func:`solve_gait`: the one sequence
:func:`gaitopt.orbit.solve_gait` — mesh refinement until the discretisation error is below the
tolerance, the certificate, the referee — on its
:class:`~gaitopt.shooting.transcription.ShootingTranscription`), and the record of a search
that found nothing (:func:`failed`).  No homotopy, no multi-start: those
(:mod:`gaitopt.homotopy`) call this, and :func:`~gaitopt.search.find_limit_cycle` puts them
together."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ..errors import GaitoptInputError, GuessError
from ..hybrid import HybridModel
from ..orbit import solve as sequence
from ..orbit.solve import Solved
from ..result import LimitCycle
from ..simulation import simulate
from .certify import limit_cycle
from .newton import METHODS
from .problem import MultipleShooting, ShootingProblem, shooting_problem
from .transcription import ShootingTranscription

__all__ = [
    "check_arguments",
    "direct_solve",
    "direct_task",
    "failed",
    "gait_task",
    "shooting_solver",
    "solve_from_guess",
    "solve_gait",
]

_MAX_REFINEMENTS = 4


def check_arguments(
    model: HybridModel | str,
    guess: Mapping[str, float] | LimitCycle | None,
    *,
    steps: int,
    inputs: Any,
    discretisation: MultipleShooting | None,
    method: str,
    tol: float,
    scheduler: str | None = None,
) -> tuple[HybridModel, int, float, np.ndarray]:
    """The checks of :func:`~gaitopt.search.find_limit_cycle`'s arguments, before any
    work (bad input fails fast): the model (a name is looked up), ``steps``, ``tol`` and the
    inputs as they are used; raises :class:`~gaitopt.errors.GaitoptInputError` (a
    :class:`~gaitopt.errors.GuessError` for an explicit guess the model cannot start from)."""
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
    return model, steps, tol, u


def direct_solve(
    model: HybridModel | str,
    guess: Mapping[str, float] | LimitCycle | None = None,
    *,
    steps: int = 1,
    inputs: Any = None,
    discretisation: MultipleShooting | None = None,
    method: str = "newton",
    verify: bool = True,
    tol: float = 1e-10,
) -> LimitCycle:
    """:func:`~gaitopt.search.find_limit_cycle` with ``follow=False`` and one start: the
    solve from the guess itself (a simulation of ``steps`` returns from the section point, the
    default start when ``guess`` is None, or a previous orbit's nodes), the arguments as there."""
    start = time.perf_counter()
    model, steps, tol, u = check_arguments(
        model, guess, steps=steps, inputs=inputs, discretisation=discretisation, method=method,
        tol=tol,
    )  # fmt: skip
    return solve_from_guess(model, guess, steps, u, discretisation, method, verify, tol, start)


def solve_from_guess(
    model: HybridModel,
    guess: Mapping[str, float] | LimitCycle | None,
    steps: int,
    u: np.ndarray,
    discretisation: MultipleShooting | None,
    method: str,
    verify: bool,
    tol: float,
    start: float,
) -> LimitCycle:
    """:func:`direct_solve` after :func:`check_arguments` (``model``, ``steps``, ``tol`` and
    ``u`` as it returns them; ``start`` the ``time.perf_counter()`` of the search's start)."""
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
    until the discretisation error is below ``tol``, and certify the orbit: the one sequence
    :func:`gaitopt.orbit.solve_gait` on a
    :class:`~gaitopt.shooting.transcription.ShootingTranscription` with the shooting's own
    solver (Newton, then Newton with line search; or IPOPT), read as a :class:`LimitCycle`.

    The part of :func:`~gaitopt.search.find_limit_cycle` after the guess, for callers
    that build the unknowns themselves (branch switching at a period doubling, warm starts).

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
        As :func:`~gaitopt.search.find_limit_cycle`.
    start : float, optional
        ``time.perf_counter()`` when the search began (for ``solve_time``).

    Returns
    -------
    LimitCycle
        As :func:`~gaitopt.search.find_limit_cycle`.
    """
    start = time.perf_counter() if start is None else start
    steps = problem.cycles
    t = ShootingTranscription(model, u=u, problem=problem)
    solution = sequence.solve_gait(
        t, w0, solver=shooting_solver(method), tol=tol, max_refinements=_MAX_REFINEMENTS,
        verify=verify, guard_tol=max(tol * 1e3, 1e-8), referee_tol=tol * 1e3,
    )  # fmt: skip
    if solution.status in ("success", "not_a_gait", "not_verified") or (
        solution.status == "singular" and solution.return_map is None and solution.defect
    ):  # judged: the certificate, the linearisation or the referee decided
        return limit_cycle(solution, verify=verify, start=start)
    return _unsolved(model, steps, u, start, solution, method, tol)


def shooting_solver(method: str) -> Callable[[Any, np.ndarray], Solved]:
    """The shooting's solver for :func:`gaitopt.orbit.solve_gait`:
    :meth:`ShootingProblem.solve` (Newton, then Newton with line search; or IPOPT) at the
    transcription's ``u`` and ``p``, its last evaluation kept by the transcription."""

    def solver(t: Any, w0: np.ndarray) -> Solved:
        solution = t.problem.solve(w0, t.u, t.model.p, method=method)
        w = solution.w
        # One Jacobian per Newton step: the last one (at the solution) serves the error
        # estimate, the multipliers and the input Jacobian.
        ev = solution.evaluation
        ev = ev if ev is not None else t.problem.evaluate(w, t.u, t.model.p)
        t.remember(w, ev)
        # Newton's own stopping test (abstol 1e-12) is stricter than `tol`: a point that meets
        # `tol` is accepted (and certified) even where Newton stalled just above its abstol
        # (orbit.solve.refine accepts by the residual).
        return Solved(w, solution.converged, solution.iterations, ev)

    return solver


def _unsolved(model, steps, u, start, solution, method: str, tol: float) -> LimitCycle:
    """The :class:`LimitCycle` of a solve that ended before the certificate (``singular``,
    ``not_converged``, ``discretisation``, ``standing``), in the shooting's words."""
    t, ev = solution.transcription, solution.evaluation
    residual, iterations = solution.residual, solution.last_iterations
    durations = np.asarray(ev.durations, dtype=float).ravel()
    # A period only where it means something: every phase duration positive and finite.
    period = (
        float(np.sum(durations))
        if durations.size and np.all(np.isfinite(durations)) and np.all(durations > 0)
        else float("nan")
    )

    def fail(message: str, status: str, **extra: Any) -> LimitCycle:
        return failed(model, steps, u, start, message, status, **extra)

    if solution.status == "singular":
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
    if solution.status == "not_converged":
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
    if solution.status == "discretisation":
        disc_error = solution.error
        condition = float(np.linalg.cond(ev.F_w))
        return fail(
            status="discretisation",
            message=f"no certified gait: the discretisation error estimate "
            f"{disc_error:.2g} stays above "
            f"the tolerance {tol:g} after {solution.refinements} mesh refinements "
            f"({t.problem.disc.rk_steps} RK steps per segment), so the orbit is known only to "
            f"about {disc_error:.1g}; the shooting Jacobian's condition number is "
            f"{condition:.2g} (a multiplier near 1 makes the fixed point sensitive to every "
            f"error): loosen `tol` to accept that accuracy",
            residual=residual,
            iterations=iterations,
            durations=durations,
            period=period,
            discretisation_error=disc_error,
        )
    # standing (the transcription's pre-check)
    return fail(status=solution.status, message=solution.message, residual=residual,
                iterations=iterations)  # fmt: skip


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


def gait_task(point: Mapping[str, Any], solve: Callable[..., LimitCycle]) -> dict[str, Any]:
    """A limit cycle at a sweep point, by ``solve`` (:func:`direct_solve` or
    :func:`~gaitopt.search.find_limit_cycle`): ``{"model": name, "params": {...},
    "guess": {...} | None, "steps": k}`` → success, period, fixed point, multipliers,
    max |multiplier|, stable."""
    from ..models import model as make_model

    try:
        model = make_model(point["model"], **point.get("params", {}))
        cycle = solve(model, point.get("guess"), steps=int(point.get("steps", 1)))
    except GaitoptInputError as error:  # e.g. a guess that leads nowhere at these parameters
        return {"success": False, "stable": None, "message": str(error)}
    return {
        "success": cycle.success,
        "period": cycle.period if cycle.success else None,
        "fixed_point": cycle.fixed_point if cycle.success else None,
        "multipliers": [[z.real, z.imag] for z in cycle.multipliers],
        "max_abs_multiplier": float(np.max(np.abs(cycle.multipliers))) if cycle.success else None,
        "stable": cycle.stable,
        "message": cycle.message,
    }


def direct_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """:func:`gait_task` by :func:`direct_solve` (the multi-start's sweep task: its guesses are
    section points, which :func:`~gaitopt.search.find_limit_cycle` solves directly)."""
    return gait_task(point, direct_solve)
