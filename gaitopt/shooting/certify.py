"""Certify a solution of the shooting equations ("never a false gait"): durations positive,
each phase ending on its guard admissibly and in its direction, no guard crossed earlier and every
unilateral constraint holding on dense samples, the minimal period, and the independent simulation
(:mod:`gaitopt.shooting.verify`); then the Floquet multipliers."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..hybrid import HybridModel
from ..result import LimitCycle
from ..stability import is_stable, section_jacobians
from .problem import ShootingProblem
from .verify import verify_by_simulation

__all__ = ["certify", "check_constraints"]


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
    ends, dg, adm = ev.ends, ev.rates, ev.admissible
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

    # -- no false gaits ----------------------------------------------------------------------
    defect = _check_orbit(
        model, problem, w, u, p, ends, dg.ravel(), adm.ravel(), durations, x_return, x_star
    )
    orbit = problem.orbit(w, u, p)
    if defect is None:
        defect = _check_dense(model, problem, orbit, u, p)
    if defect is None:
        defect = check_constraints(model, problem, orbit, u, p)
    if defect is None and steps > 1:
        defect = _check_minimal_period(model, problem, w, steps)
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
    multipliers = np.linalg.eigvals(A) if A.size else np.zeros(0, complex)
    multipliers = multipliers[np.argsort(-np.abs(multipliers))]

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


def _check_orbit(model, problem, w, u, p, ends, dg, adm, durations, x_return, x_star) -> str | None:
    """Durations positive; each phase ends on its guard, admissibly and in the stated direction."""
    for k, i in enumerate(problem.chain):
        phase = model.phases[i]
        transition = phase.transitions[0]
        label = _phase_label(model, problem, k)
        if not durations[k] > 0:
            return (
                f"no gait: {label} would last {durations[k]:.3g} s (durations must be positive); "
                f"the orbit through this guess runs backwards in time — the gait may not exist "
                f"at these parameters"
            )
        if not adm[k] > 0:
            return (
                f"no gait: {label} ends on '{transition.name}' where that crossing is excluded "
                f"(spurious crossing rule: {transition.doc})"
            )
        if not transition.direction * dg[k] > 0:
            return (
                f"no gait: {label} reaches '{transition.name}' in the wrong direction "
                f"(grazing or from the other side)"
            )
    error = float(np.max(np.abs(np.asarray(x_return).ravel() - x_star)))
    if error > 1e-8 * (1 + np.max(np.abs(x_star))):
        return (
            f"internal inconsistency: the return state leaves the section parametrisation by "
            f"{error:.3g}; the model's section lift does not match its reset"
        )
    return None


def _check_dense(model, problem, orbit, u, p) -> str | None:
    """No guard of the phase is crossed (admissibly, in its direction) before the phase ends."""
    for k, arc in enumerate(orbit):
        phase = model.phases[arc.phase]
        K = arc.x.shape[1]
        for j, transition in enumerate(phase.transitions):
            guard_map, admissible_map = problem.guard_maps[arc.phase][j]
            g = transition.direction * np.asarray(guard_map(arc.x, u, p), dtype=float).ravel()
            a = (
                np.asarray(admissible_map(arc.x, u, p), dtype=float).ravel()
                if admissible_map is not None
                else np.ones(K)
            )
            scale = 1e-9 * (1 + np.max(np.abs(g)))
            armed = np.maximum.accumulate(g < -scale)
            last = K - 1 if j == 0 else K  # the cycle transition fires at the last sample
            for idx in range(1, last):
                if armed[idx - 1] and g[idx - 1] < 0 <= g[idx] and (a[idx - 1] > 0 or a[idx] > 0):
                    t = arc.t[idx]
                    label = _phase_label(model, problem, k)
                    return (
                        f"no gait: the orbit crosses '{transition.name}' inside "
                        f"{label} at t = {t:.4g} s, before the phase ends "
                        f"(e.g. a foot through the ground); not a gait with this phase sequence"
                    )
    return None


#: A unilateral constraint counts as violated where ``c < -_CONSTRAINT_TOL · (1 + max |c|)`` on
#: the dense samples (the shooting solution's own accuracy is ~1e-10), and a constraint that
#: starts active must rise faster than ``_CONSTRAINT_TOL`` per second (in its unit).
_CONSTRAINT_TOL = 1e-9


def check_constraints(model, problem, orbit, u, p) -> str | None:
    """Every unilateral constraint of every phase holds on the orbit's dense samples.

    A constraint declared ``at_start`` (zero where the phase begins: a trailing foot on the
    ground) must also rise there, ``ċ > 0`` (the foot lifts off); one declared ``at_end`` is zero
    at the phase's last sample by construction.  Returns the first violation in words, or None.
    """
    for k, arc in enumerate(orbit):
        phase = model.phases[arc.phase]
        for constraint, (c_map, rate) in zip(
            phase.constraints, problem.constraint_maps[arc.phase], strict=True
        ):
            c = np.asarray(c_map(arc.x, u, p), dtype=float).ravel()
            scale = _CONSTRAINT_TOL * (1 + float(np.max(np.abs(c))))
            unit = f" {constraint.unit}" if constraint.unit else ""
            label = _phase_label(model, problem, k)
            if constraint.at_start:
                c0_rate = float(rate(arc.x[:, 0], u, p))
                if not c0_rate > _CONSTRAINT_TOL:
                    return (
                        f"no gait: {constraint.outcome} at the start of {label}: "
                        f"'{constraint.name}' starts at 0 and must rise, but its rate is "
                        f"{c0_rate:.3g}{unit}/s ({constraint.source})"
                    )
            inner = slice(1 if constraint.at_start else 0, -1 if constraint.at_end else None)
            bad = np.nonzero(c[inner] < -scale)[0]
            if bad.size:
                j = int(bad[0]) + (1 if constraint.at_start else 0)
                return (
                    f"no gait: {constraint.outcome} in {label} at t = {arc.t[j]:.4g} s: "
                    f"'{constraint.name}' fails (value {c[j]:.3g}{unit}, lowest "
                    f"{float(np.min(c[inner])):.3g}{unit}; {constraint.source})"
                )
    return None


def _check_minimal_period(model, problem, w, steps) -> str | None:
    """A period-k orbit must not be a shorter orbit repeated."""
    starts = []
    n_phases = len(model.phases)
    for kind, k, off, shape in problem.layout:
        if kind == "nodes" and k % n_phases == 0 and k > 0:
            n = shape[0]
            starts.append(w[off : off + n])
    x0 = model.lift(w[: problem.m])
    for j, xj in enumerate(starts, start=1):
        if steps % j == 0 and np.max(np.abs(xj - x0)) < 1e-6 * (1 + np.max(np.abs(x0))):
            return (
                f"no period-{steps} gait here: the orbit found is the period-{j} gait repeated; "
                f"try a guess on the period-{steps} orbit (past its period doubling)"
            )
    return None
