"""Certify a solution of the shooting equations ("never a false gait") by the one sequence's
stage :func:`gaitopt.orbit.solve.judge` on a
:class:`~gaitopt.shooting.transcription.ShootingTranscription`: the common certificate
(:mod:`gaitopt.orbit.certificate`: durations positive, each phase ending on its guard admissibly
and in its direction, no guard crossed earlier, every unilateral constraint holding on dense
samples, the minimal period) on the RK integrator's dense samples (:mod:`gaitopt.shooting.dense`)
with the section's consistency, the Floquet multipliers, and the common referee
(:mod:`gaitopt.orbit.referee`).  :func:`limit_cycle` reads the judged solution as a
:class:`LimitCycle`; :func:`gaitopt.optimize_gait` uses the same certificate and referee."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..hybrid import HybridModel
from ..orbit import solve as sequence
from ..orbit.certificate import check_constraints as _check_constraints
from ..orbit.certificate import check_early_crossings
from ..result import LimitCycle
from ..stability import is_stable
from .dense import check_section, dense_arcs
from .problem import ShootingProblem
from .transcription import ShootingTranscription

__all__ = ["certify", "check_constraints", "check_section", "dense_arcs", "limit_cycle"]


def certify(
    model: HybridModel,
    problem: ShootingProblem,
    w: np.ndarray,
    u: np.ndarray,
    *,
    verify: bool = True,
    tol: float = 1e-10,
    iterations: int = 0,
    discretisation_error: float = float("nan"),
    note: str = "",
    start: float | None = None,
    linearisation: tuple[np.ndarray, ...] | None = None,
    evaluation: Any = None,
) -> LimitCycle:
    """Check a solution ``w`` of the shooting equations and build its :class:`LimitCycle`.

    The checks of :func:`find_limit_cycle` ("no false gaits"), by the one sequence's stage
    :func:`gaitopt.orbit.solve.judge` on a
    :class:`~gaitopt.shooting.transcription.ShootingTranscription`: the certificate (positive
    durations, admissible directional crossing at each phase end, no earlier crossing on dense
    samples, unilateral constraints, minimal period, the section's consistency), the
    multipliers and (with ``verify``) the independent simulation.  Used by continuation for
    every point of a branch (:func:`find_limit_cycle` runs the whole
    :func:`gaitopt.orbit.solve_gait`).

    Parameters
    ----------
    model : HybridModel
        The model at the parameters ``w`` solves for.
    problem : ShootingProblem
        The problem ``w`` solves.
    w : numpy.ndarray
        A solution of ``problem`` (``F(w, u, p) ≈ 0``).
    u : numpy.ndarray
        The per-step inputs.
    verify : bool
        Also simulate from the fixed point (:func:`gaitopt.orbit.referee`).
    tol : float
        The shooting tolerance; the simulated return must agree to ``tol · 1e3``.
    iterations, discretisation_error, note, start
        Recorded in the result (``start``: the ``perf_counter`` time the solve began).
    linearisation : tuple, optional
        ``(∂[G; P]/∂w, ∂[G; P]/∂u, F, x_return)`` where the caller has them.
    evaluation : Evaluation, optional
        :meth:`ShootingProblem.evaluate` at ``w`` where the caller has it (not recomputed).
    """

    start = time.perf_counter() if start is None else start
    t = ShootingTranscription(model, u=u, problem=problem, linearisation=linearisation)
    if evaluation is not None:
        t.remember(w, evaluation)
    ev = t.evaluate(w)
    F = np.asarray(linearisation[2] if linearisation is not None else ev.F, dtype=float)
    residual = float(np.max(np.abs(F))) if np.all(np.isfinite(F)) else float("inf")
    solved = sequence.OrbitSolution(
        False, "converged", "", t, np.asarray(w, dtype=float).ravel(), iterations,
        discretisation_error, residual=residual, evaluation=ev, last_iterations=iterations,
    )  # fmt: skip
    judged = sequence.judge(
        solved, verify=verify, guard_tol=max(tol * 1e3, 1e-8), referee_tol=tol * 1e3,
        precheck=False,
    )  # fmt: skip
    return limit_cycle(judged, verify=verify, note=note, start=start)


def limit_cycle(
    solution: Any, *, verify: bool, note: str = "", start: float | None = None
) -> LimitCycle:
    """The :class:`LimitCycle` of a judged shooting solution (:func:`gaitopt.orbit.solve.judge`
    on a :class:`~gaitopt.shooting.transcription.ShootingTranscription`): a certified gait, or
    one the certificate, the linearisation or the referee refused (``not_a_gait``,
    ``singular``, ``not_verified``), with the shooting's numbers and the model's note on where
    its gait exists."""
    start = time.perf_counter() if start is None else start
    t, w, ev = solution.transcription, solution.w, solution.evaluation
    model, problem, u = t.model, t.problem, t.u
    durations = np.asarray(ev.durations, dtype=float).ravel()
    x_star = model.lift(w[: problem.m])
    discretisation_error = solution.error
    common = dict(
        model=model,
        steps=problem.cycles,
        state_names=model.state_names,
        section_coordinates=model.section.coordinates,
        inputs=u,
        residual=solution.residual,
        iterations=solution.last_iterations,
        durations=durations,
        discretisation=problem.disc,
        discretisation_error=discretisation_error,
        period=float(np.sum(durations)),
        fixed_point=dict(zip(model.state_names, map(float, x_star), strict=True)),
        problem=problem,
        solution=np.array(w, dtype=float),
        evaluation=ev,
        orbit=t.orbit(w),
    )

    def fail(message: str, status: str) -> LimitCycle:
        note_ = model.existence_note()
        message = f"{message} [{note_}]" if note_ else message
        return LimitCycle(
            False, message, solve_time=time.perf_counter() - start, status=status, **common
        )

    if solution.status == "not_a_gait":
        return fail(solution.defect, "not_a_gait")
    if solution.status == "singular":
        return fail(
            "no isolated gait: the shooting equations are singular at the solution (the orbit "
            "is not transversal to a guard, or not isolated)",
            "singular",
        )
    A, B = solution.return_map.A, solution.return_map.B_u
    multipliers = solution.multipliers
    verdict = solution.verdict
    verified, error, vmessage = False, float("nan"), "not verified by simulation (verify=False)"
    if verify:
        verified, error, vmessage = verdict.ok, verdict.return_error, verdict.message
    success = verified or not verify
    accuracy = f"discretisation error {discretisation_error:.1g}{note}"
    message = (
        f"periodic orbit found (residual {solution.residual:.2g}, {accuracy}); " + vmessage
        if success
        else "the shooting solution is not confirmed: " + vmessage
    )
    return LimitCycle(
        success=success,
        message=message,
        status="success" if success else "not_verified",
        multipliers=multipliers if success else np.zeros(0, complex),
        stable=is_stable(multipliers) if success else None,
        verified=verified,
        verification_error=error,
        jacobian=A,
        input_jacobian=B,
        solve_time=time.perf_counter() - start,
        **common,
    )


def _check_dense(model, problem, orbit, u, p) -> str | None:
    """No guard of a phase is crossed (admissibly, in its direction) before the phase ends
    (:func:`gaitopt.orbit.certificate.check_early_crossings` on the shooting's samples)."""
    return check_early_crossings(model, dense_arcs(model, problem, orbit, u), p)


def check_constraints(model, problem, orbit, u, p) -> str | None:
    """Every unilateral constraint of every phase holds on the orbit's dense samples, by the
    certificate's one rule (:func:`gaitopt.orbit.certificate.check_constraints`):
    ``c ≥ −1e-9 · (1 + max |c|)``, and a constraint declared ``at_start`` rises where the phase
    begins (``ċ > 1e-9``: the trailing foot lifts off).  Returns the first violation in words,
    or None."""
    return _check_constraints(model, dense_arcs(model, problem, orbit, u), p)
