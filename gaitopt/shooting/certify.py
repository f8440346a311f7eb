"""Certify a solution of the shooting equations ("never a false gait"): the common certificate
(:mod:`gaitopt.orbit.certificate`: durations positive, each phase ending on its guard admissibly
and in its direction, no guard crossed earlier, every unilateral constraint holding on dense
samples, the minimal period) on the RK integrator's dense samples, the section's consistency, and
the common referee (:mod:`gaitopt.orbit.referee`, through :mod:`gaitopt.shooting.verify`); then
the Floquet multipliers.  :func:`gaitopt.optimize_gait` uses the same certificate and referee."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..hybrid import HybridModel
from ..orbit.certificate import (
    DenseArc,
    certify_orbit,
    check_durations,
    check_early_crossings,
    constant_input,
)
from ..orbit.certificate import check_constraints as _check_constraints
from ..orbit.sensitivity import multipliers as sorted_multipliers
from ..result import LimitCycle, OrbitArc
from ..stability import is_stable, section_jacobians
from .problem import ShootingProblem
from .verify import verify_by_simulation

__all__ = ["certify", "check_constraints", "dense_arcs"]


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

    The checks of :func:`find_limit_cycle` ("no false gaits"): positive durations, admissible
    directional crossing at each phase end, no earlier crossing on dense samples, minimal period,
    and (with ``verify``) the independent simulation; then the multipliers.  Used by
    :func:`find_limit_cycle` and by continuation for every point of a branch.

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
        Also simulate from the fixed point (:func:`gaitopt.shooting.verify.verify_by_simulation`).
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
    p = model.p
    ev = evaluation if evaluation is not None else problem.evaluate(w, u, p)
    if linearisation is None:
        linearisation = (problem.map_jacobian(ev.F_w), ev.F_u, ev.F, ev.x_return)
    J_w, J_u, F, x_return = (np.asarray(v, dtype=float) for v in linearisation)
    residual = float(np.max(np.abs(F))) if np.all(np.isfinite(F)) else float("inf")
    durations = np.asarray(ev.durations, dtype=float).ravel()
    x_star = model.lift(w[: problem.m])
    steps = problem.cycles
    common = dict(
        model=model,
        steps=steps,
        state_names=model.state_names,
        section_coordinates=model.section.coordinates,
        inputs=u,
        residual=residual,
        iterations=iterations,
        durations=durations,
        discretisation=problem.disc,
        discretisation_error=discretisation_error,
        period=float(np.sum(durations)),
        fixed_point=dict(zip(model.state_names, map(float, x_star), strict=True)),
        problem=problem,
        solution=np.array(w, dtype=float),
        evaluation=ev,
    )

    def fail(message: str, status: str, **extra: Any) -> LimitCycle:
        note_ = model.existence_note()
        message = f"{message} [{note_}]" if note_ else message
        return LimitCycle(
            False, message, solve_time=time.perf_counter() - start, status=status, **common,
            **extra,
        )  # fmt: skip

    # -- no false gaits: the common certificate on the RK integrator's dense samples ---------
    orbit = problem.orbit(w, u, p)
    arcs = dense_arcs(model, problem, orbit, u, durations, ev.ends)
    defect = check_durations(arcs) or _check_section(x_return, x_star)
    if defect is None:
        defect = certify_orbit(model, arcs, p, steps=steps, guard_tol=max(tol * 1e3, 1e-8))
    if defect is not None:
        return fail(defect, "not_a_gait", orbit=orbit)

    try:
        A, B = section_jacobians(J_w, J_u, problem.m, problem.n_g)
    except np.linalg.LinAlgError:
        return fail(
            "no isolated gait: the shooting equations are singular at the solution (the orbit "
            "is not transversal to a guard, or not isolated)",
            "singular",
            orbit=orbit,
        )
    multipliers = sorted_multipliers(A)

    verified, error, vmessage = False, float("nan"), "not verified by simulation (verify=False)"
    if verify:
        verified, error, vmessage = verify_by_simulation(
            model, x_star, durations, steps, u, tol * 1e3
        )
    success = verified or not verify
    accuracy = f"discretisation error {discretisation_error:.1g}{note}"
    message = (
        f"periodic orbit found (residual {residual:.2g}, {accuracy}); " + vmessage
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
        orbit=orbit,
        solve_time=time.perf_counter() - start,
        **common,
    )


def _phase_label(model: HybridModel, problem: ShootingProblem, k: int) -> str:
    name = model.phases[problem.chain[k]].name
    step = f" (step {k // len(model.phases) + 1})" if problem.cycles > 1 else ""
    return f"phase '{name}'{step}"


def dense_arcs(
    model: HybridModel,
    problem: ShootingProblem,
    orbit: list[OrbitArc],
    u: np.ndarray,
    durations: np.ndarray | None = None,
    ends: list[np.ndarray] | None = None,
) -> list[DenseArc]:
    """The shooting orbit's dense samples (the RK integrator's, :meth:`ShootingProblem.orbit`)
    as the certificate reads them: the per-step input held at every sample; ``durations`` the
    shooting's (default: each arc's time span), ``ends`` its solved phase-end states (default:
    the last samples, which a finer sampling integration puts off the solved ends by the
    discretisation error)."""
    out = []
    for k, arc in enumerate(orbit):
        K = arc.x.shape[1]
        duration = float(arc.t[-1] - arc.t[0]) if durations is None else float(durations[k])
        out.append(
            DenseArc(
                arc.phase, _phase_label(model, problem, k), duration, np.asarray(arc.t),
                np.asarray(arc.x, dtype=float), constant_input(u, K),
                None if ends is None else np.asarray(ends[k], dtype=float),
            )
        )  # fmt: skip
    return out


def _check_section(x_return, x_star) -> str | None:
    """The return state lies where the section's lift puts it (the model's own consistency)."""
    error = float(np.max(np.abs(np.asarray(x_return).ravel() - x_star)))
    if error > 1e-8 * (1 + np.max(np.abs(x_star))):
        return (
            f"internal inconsistency: the return state leaves the section parametrisation by "
            f"{error:.3g}; the model's section lift does not match its reset"
        )
    return None


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
