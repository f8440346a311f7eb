"""Pseudo-arclength continuation of a special point in two parameters.

The curve is followed in ``y = (w, ℓ₁, ℓ₂)`` (see :mod:`gaitopt.curves.system`): predict along the
tangent ``t`` (null vector of ``∂H/∂y``), correct with Newton on ``H(y) = 0, ⟨t, y − y_pred⟩_W
= 0`` (Keller's pseudo-arclength method; Allgower & Georg, "Numerical Continuation Methods",
§2.1), the inner product weighting the ``N`` shooting unknowns by ``1/N`` as in
:mod:`gaitopt.continuation`; the step adapts to the corrector's work.  Every accepted point is
certified like a solved gait (:func:`gaitopt.shooting.certify`: the orbit's physical checks on
dense samples and an independent simulation) and its discretisation error estimated (the mesh is
refined when it exceeds the tolerance).  The curve ends exactly on the target of the second
parameter (the last point is corrected at that value, not overshot), where the gait stops
existing on it (a ``boundary``, located by bisection), or where the corrector cannot continue.
Codimension-two points between consecutive points (:mod:`gaitopt.curves.codim2`) are located by
regula falsi (Illinois) on the arclength.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..continuation import PseudoArclength, SpecialPoint, continuation
from ..errors import GaitoptInputError, ParameterError
from ..hybrid import HybridModel
from ..open_loop import as_limit_cycle, is_optimal_gait
from ..result import LimitCycle
from ..shooting import ShootingProblem, shooting_problem
from ..threads import single_blas_thread
from .follower import CurveFollower
from .result import Curve
from .system import (
    BOUNDARY_QUANTITIES,
    CONSTRAINT_QUANTITIES,
    CURVE_KINDS,
    ParameterPath,
    phase_start,
)

__all__ = ["bifurcation_curve", "curve_from"]

#: Default step control along a curve (scaled arclength) and of the one-parameter search.
CURVE_STEPS = PseudoArclength(step=0.05, max_step=0.2)
BRANCH_STEPS = PseudoArclength()


@single_blas_thread
def bifurcation_curve(
    model: HybridModel | Any,
    kind: str,
    param: str,
    param2: str | ParameterPath,
    *,
    to: float,
    param_to: float | None = None,
    start: SpecialPoint | Mapping[str, float] | LimitCycle | Any | None = None,
    steps: int = 1,
    at: Sequence[float] = (),
    bounds: tuple[float, float] | None = None,
    options: PseudoArclength = CURVE_STEPS,
    branch_options: PseudoArclength = BRANCH_STEPS,
    verify: bool = True,
    tol: float = 1e-10,
) -> Curve:
    """Follow a period doubling, fold, Neimark–Sacker point or existence boundary of a gait
    through two parameters.

    The first special point of ``kind`` on the gait's branch in ``param`` (continued from the
    model's parameters towards ``param_to``, :func:`gaitopt.continuation`) is followed in
    ``(param, param2)`` until ``param2`` reaches ``to`` exactly, or the curve ends.

    Parameters
    ----------
    model : HybridModel or OptimalGait
        The model; its parameters are the start of the one-parameter search.  Or an optimal gait
        (:func:`gaitopt.optimize_gait`): its open loop, the input profile held fixed
        (:func:`gaitopt.open_loop.open_loop_cycle`), is the model and its cycle the start.
    kind : {"PD", "LP", "NS", "boundary"}
        The special point to follow.
    param : str
        The model parameter of the one-parameter search, and the curve's first parameter.
    param2 : str or ParameterPath
        The second parameter: a model parameter, or a path that sets several (e.g. the compass
        gait's leg-mass position ``a`` with ``b = 1 − a``).
    to : float
        Value of ``param2`` where the curve ends (in the units of ``param2``).
    param_to : float, optional
        End of the one-parameter search in ``param`` (default: the end of its valid range above
        the model's value).
    start : SpecialPoint, mapping, LimitCycle or OptimalGait, optional
        A special point of ``kind`` to start from (skips the search), or the gait (guess,
        solved cycle or optimal gait, as ``model``) to start the search from.
    steps : int
        Period of the gait in steps.
    at : sequence of float
        Values of ``param2`` at which curve points are also located exactly (e.g. to compare
        with a grid).
    bounds : (float, float), optional
        Interval of ``param`` the curve stays in (default its valid range).
    options : PseudoArclength
        Step control along the curve.
    branch_options : PseudoArclength
        Step control of the one-parameter search.
    verify : bool
        Verify every point by independent simulation.
    tol : float
        Residual, discretisation-error and location tolerance.

    Returns
    -------
    Curve
        ``success`` False with a message when there is no special point of ``kind`` to start from.

    Raises
    ------
    GaitoptInputError
        Unknown ``kind`` or parameters, ``to`` out of ``param2``'s range or equal to its start.
    """
    if kind not in CURVE_KINDS:
        raise GaitoptInputError(f"`kind` must be one of {', '.join(CURVE_KINDS)}, got {kind!r}")
    if is_optimal_gait(model) or is_optimal_gait(start):  # its open loop (profile held fixed)
        start = as_limit_cycle(start if is_optimal_gait(start) else model, tol=tol, verify=verify)
        model = start.model
    path1 = ParameterPath.of(model, param)
    path2 = param2 if isinstance(param2, ParameterPath) else ParameterPath.of(model, param2)
    if path2.name == path1.name or set(path1.parameters) & set(path2.parameters):
        raise GaitoptInputError(
            f"`param2` = {path2.name!r} must differ from `param` = {param!r}; choose another "
            f"second parameter"
        )
    to = float(to)
    q0 = path2.value_of(model)
    try:
        model.replace(**path2.values(to))
    except ParameterError as exc:
        raise ParameterError(f"`to` = {to:g} for {path2.name}: {exc}") from None
    if to == q0:
        raise GaitoptInputError(
            f"`to` = {to:g} equals the start value of `{path2.name}`; nothing to follow"
        )
    for value in at:
        if not (min(q0, to) < float(value) < max(q0, to)):
            raise GaitoptInputError(
                f"`at` value {value!r} must lie strictly between {path2.name} = {q0:g} and "
                f"`to` = {to:g}"
            )
    if isinstance(start, SpecialPoint):
        if start.kind != kind:
            raise GaitoptInputError(f"`start` is a {start.kind} point, not {kind}")
        special, first = start, None
    else:
        branch = continuation(
            model,
            param,
            to=param_to,
            start=start,
            steps=steps,
            cascade=False,
            options=branch_options,
            verify=verify,
            tol=tol,
        )
        curve = Curve(model, kind, (path1, path2), steps=steps)
        if not branch.success:
            curve.success, curve.message, curve.status = False, branch.message, branch.status
            return curve
        special = next((sp for sp in branch.special_points if sp.kind == kind), None)
        first = branch.cycles[0]
        if special is None:
            curve.success, curve.status = False, "no_special_point"
            found = ", ".join(f"{sp.kind} at {sp.param:.8g}" for sp in branch.special_points)
            curve.message = (
                f"no {kind} point on the branch in {param} from {branch.params[0]:.6g} to "
                f"{branch.params[-1]:.6g} ({branch.message}); special points found: "
                f"{found or 'none'}"
            )
            return curve
    return curve_from(
        special, kind, (path1, path2), to, first=first, at=at, bounds=bounds, options=options,
        verify=verify, tol=tol,
    )  # fmt: skip


def curve_from(
    special: SpecialPoint,
    kind: str,
    paths: tuple[ParameterPath, ParameterPath],
    to: float,
    *,
    first: LimitCycle | None = None,
    at: Sequence[float] = (),
    bounds: tuple[float, float] | None = None,
    options: PseudoArclength = CURVE_STEPS,
    verify: bool = True,
    tol: float = 1e-10,
) -> Curve:
    """Follow the curve through a located special point (see :func:`bifurcation_curve`)."""
    cycle = special.cycle
    curve = Curve(
        cycle.model if cycle is not None else None, kind, paths, start=special,
        steps=cycle.steps if cycle is not None else 1,
    )  # fmt: skip
    if cycle is None or not cycle.success:
        curve.success, curve.message = False, "the special point carries no certified gait"
        curve.status = "no_special_point"
        return curve
    boundary, extra = None, ()
    if kind == "boundary":
        boundary, why, extra, sigma = _vanishing_quantity(cycle, first)
        if boundary is None:
            curve.success, curve.status = False, "singular"
            curve.message = f"the boundary cannot be followed as a curve: {why}"
            curve.condition = why
            return curve
        curve.condition = why
    else:
        curve.condition = {
            "PD": "a multiplier at −1: det(A + I) = 0 (minimally augmented, bordered)",
            "LP": "a multiplier at +1: det(A − I) = 0 (minimally augmented, bordered)",
            "NS": "a pair with μᵢμⱼ = 1: det(A ⊙ A − I) = 0 (bialternate, bordered)",
        }[kind]
    follower = CurveFollower(cycle, kind, paths, boundary, to, at, bounds, options, verify, tol)
    if kind == "boundary":
        follower.extra0, follower.sigma = np.asarray(extra, dtype=float), sigma
    follower.run()
    curve.cycles, curve.special_points = follower.cycles, follower.special_points
    curve.located = follower.located
    curve.message = follower.stop
    curve.success = bool(follower.cycles)
    return curve


def _vanishing_quantity(cycle: LimitCycle, first: LimitCycle | None):
    """Which check quantity vanishes at a boundary: the one smallest relative to its value at
    the branch's first gait (or to its own size).

    Returns ``(boundary, description, extra unknowns, σ)``: ``σ g > 0`` inside the region where
    the gait exists.
    """
    model = cycle.model
    problem = shooting_problem(type(model), cycle.discretisation, cycle.steps)
    values = _check_quantities(cycle, problem)
    reference = _check_quantities(first, problem) if first is not None else None
    best, ratio_best = None, math.inf
    for key, (value, scale, _) in values.items():
        ref = reference.get(key) if reference is not None else None
        if key[0] not in CONSTRAINT_QUANTITIES and ref is not None and ref[0]:
            scale = abs(ref[0])
        ratio = abs(value) / scale
        if ratio < ratio_best:
            best, ratio_best = key, ratio
    if best is None or ratio_best > 1e-3:
        return (
            None,
            (
                "no duration, guard rate, admissibility, lift-off rate or interior minimum of "
                "a declared constraint vanishes at it (the gait ends otherwise: a diverging period "
                "or a failed simulation), so no smooth defining condition is known"
            ),
            (),
            1.0,
        )
    what, k = best[:2]
    phase = model.phases[problem.chain[k]]
    label = {
        "duration": "a phase duration vanishes",
        "grazing": "the impact grazes (the guard's rate at the phase end vanishes)",
        "admissible": "the crossing becomes inadmissible (its admissibility function vanishes)",
        "lift_off": "a constraint that starts at zero stops rising (its rate ∇c · f at the phase "
        "start vanishes)",
        "graze_min": "an interior minimum of a constraint touches zero (c(t*) = 0, ċ(t*) = 0, "
        "t* an extra unknown)",
    }[what]
    where = f"{what} of phase {k} ({phase.name}) = 0"
    if what in CONSTRAINT_QUANTITIES:
        where = f"{what} of '{phase.constraints[best[2]].name}' in phase {k} ({phase.name}) = 0"
    sigma = 1.0
    if what in ("grazing", "admissible") and reference is not None and best in reference:
        sigma = 1.0 if reference[best][0] > 0 else -1.0
    elif what in ("grazing", "admissible"):
        sigma = 1.0 if values[best][0] > 0 else -1.0
    return best, f"{label}: {where}", values[best][2], sigma


def _check_quantities(cycle: LimitCycle, problem: ShootingProblem) -> dict[tuple, tuple]:
    """Each candidate boundary quantity of a gait: ``key -> (value, scale, extra unknowns)``.

    Besides the shooting checks, each declared unilateral constraint of each phase: its rate at
    the phase start (``at_start`` constraints) and its lowest interior local minimum on the dense
    samples (refined by a parabola through the three samples around it), relative to its
    largest value on the phase."""
    from ..hybrid import rate_along

    w = problem.unknowns_from_cycle(cycle)
    p = cycle.model.p
    _, dg, adm, durations = (
        np.asarray(v, dtype=float).ravel() for v in problem.checks(w, cycle.inputs, p)
    )
    out: dict[tuple, tuple] = {}
    for k, i in enumerate(problem.chain):
        phase = cycle.model.phases[i]
        transition = phase.transitions[0]
        out[("duration", k)] = (durations[k], max(abs(durations[k]), 1.0), ())
        out[("grazing", k)] = (dg[k], max(abs(dg[k]), 1.0), ())
        if transition.admissible is not None:
            out[("admissible", k)] = (adm[k], max(abs(adm[k]), 1.0), ())
        arc = cycle.orbit[k]
        for j, constraint in enumerate(phase.constraints):
            c = np.asarray(constraint.function.map(arc.x.shape[1])(arc.x, cycle.inputs, p))
            c = c.ravel()
            size = max(float(np.max(np.abs(c))), 1e-12)
            if constraint.at_start:
                rate = rate_along(phase.flow, constraint.function)
                x0 = np.asarray(phase_start(problem, w, p, k), dtype=float).ravel()
                r0 = float(rate(x0, cycle.inputs, p))
                # relative to the rate that would reach c's size over the phase
                out[("lift_off", k, j)] = (r0, size / max(arc.t[-1] - arc.t[0], 1e-12), ())
            lo, hi = (1 if constraint.at_start else 0), len(c) - (2 if constraint.at_end else 1)
            minima = [
                idx for idx in range(max(lo, 1), min(hi, len(c) - 1))
                if c[idx] <= c[idx - 1] and c[idx] <= c[idx + 1]
            ]  # fmt: skip
            if minima:
                idx = min(minima, key=lambda m: c[m])
                t_star = _parabola_vertex(arc.t[idx - 1 : idx + 2] - arc.t[0], c[idx - 1 : idx + 2])
                out[("graze_min", k, j)] = (float(c[idx]), size, (t_star,))
    assert all(key[0] in BOUNDARY_QUANTITIES for key in out)
    return out


def _parabola_vertex(t: np.ndarray, c: np.ndarray) -> float:
    """Abscissa of the vertex of the parabola through three points (the middle one if flat)."""
    a, b, _ = np.polyfit(t, c, 2)
    return float(-b / (2 * a)) if a > 0 and t[0] <= -b / (2 * a) <= t[-1] else float(t[1])
