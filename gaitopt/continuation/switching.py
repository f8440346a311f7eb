"""Branch switching at a period doubling: onto the period-2k orbit born there.

At a PD of a period-k orbit the period-k solution repeated twice solves the period-2k shooting
equations, whose Jacobian is singular there: its null vector is the direction of the new branch
(the section perturbation alternates, ``+v`` then ``−v``, with ``A v = −v``; Kuznetsov,
"Elements of Applied Bifurcation Theory", §10.2; Allgower & Georg §8.1 for switching along the
null vector).  The period-2k orbit just past the PD is found by Newton from the repeated orbit
plus ``ε`` times that null vector, with ``ε ∝ sqrt(|λ − λ_PD|)`` (the amplitude of a
period-doubled orbit grows as the square root of the distance from the PD): no simulation, and
every candidate is kept only if it was born at the PD (next to the parent orbit, with the
multiplier +1 into which the parent's −1 squares), so that an unrelated period-2k orbit nearby is
never mistaken for the new branch.  These Newton starts are tried at every parameter offset and
amplitude before any start that simulates from a displaced section point (the fallback): a
simulated start that leads to no orbit costs a whole line search stalled next to a minimum of
``‖F‖`` that is no root, which was most of the compass gait's cascade time.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import GaitoptInputError, ParameterError
from ..orbit.sensitivity import section_jacobians
from ..result import LimitCycle
from ..shooting import find_limit_cycle, shooting_problem, solve_gait
from ..shooting.newton import NEWTON_OPTIONS
from .branch import Branch, SpecialPoint

__all__ = ["doubled_unknowns", "switch_at_period_doubling"]

#: Offsets of the parameter from the PD tried, relative to ``max(|λ_PD|, 1e-3)``: not too close,
#: where the singular Jacobian amplifies the discretisation error (and the mesh needed).
OFFSETS = (1e-3, 1e-2, 1e-4)
#: Amplitudes ``a`` of ``ε = a · sqrt(offset)`` (section coordinates normalised to 1): small
#: first, large for strongly curved branches.
AMPLITUDES = (0.1, 0.03, 0.3, 1.0)
#: Born at the PD: the new orbit's section point within this distance of the parent's (relative
#: to ``1 + max |s|``) and a multiplier within this of +1.
BORN_NEAR, BORN_MULTIPLIER = 0.05, 0.25
#: A Newton start's orbit is dropped before its certificate when it misses one of the two
#: conditions by more than this factor: the certificate's refined mesh moves the orbit by about
#: its discretisation error (≤ 1e-8), far less, so the certified orbit would miss it too.
UNBORN_MARGIN = 1 + 1e-3


def doubled_unknowns(cycle: LimitCycle) -> tuple[object, np.ndarray, np.ndarray]:
    """The period-2k problem, the parent orbit repeated as its unknowns, and the null vector of
    its Jacobian at the PD (the smallest right singular vector, scaled to 1 in the section)."""
    problem = cycle.problem
    doubled = shooting_problem(problem.model_cls, problem.disc, 2 * problem.cycles)
    s, nodes, durations = problem.unpack(cycle.solution, cycle.model.p)
    w2 = doubled.pack(s, nodes + nodes, list(durations) * 2)
    F_w = doubled.evaluate(w2, cycle.inputs, cycle.model.p).F_w
    null = np.linalg.svd(F_w)[2][-1]
    return doubled, w2, null / np.max(np.abs(null[: doubled.m]))


def born_at(doubled: LimitCycle, parent: LimitCycle) -> bool:
    """Whether a period-2k orbit found next to a PD was born there (see the module docstring)."""
    scale = 1 + np.max(np.abs(parent.section_point))
    near = np.max(np.abs(doubled.section_point - parent.section_point)) < BORN_NEAR * scale
    return bool(near and np.min(np.abs(doubled.multipliers - 1)) < BORN_MULTIPLIER)


def clearly_unborn(problem, w0, u, p, parent: LimitCycle) -> tuple[bool, np.ndarray]:
    """Whether Newton from ``w0`` (the solve :func:`solve_gait` starts with) converges to an
    orbit that misses :func:`born_at` by more than :data:`UNBORN_MARGIN`, so that certifying and
    simulating it (most of a candidate's cost) can be skipped.  False wherever that is not
    certain (no convergence, a singular return map): then the full solve decides.

    Also the start for that full solve: Newton's solution where it met Newton's own residual
    test (``max |F| ≤ 1e-12``, ``NEWTON_OPTIONS["abstol"]``), from which the same Newton stops
    at once, at the same point, so that :func:`solve_gait` gives the orbit it gives from ``w0``
    bit for bit without running Newton twice; else ``w0``."""
    solution = problem.solve(w0, u, p)
    ev = solution.evaluation
    if not solution.converged or ev is None or not np.all(np.isfinite(ev.F_w)):
        return False, w0
    restart = w0
    if np.max(np.abs(ev.F)) <= NEWTON_OPTIONS["abstol"]:  # ev: Newton's own at solution.w
        restart = solution.w
    try:
        A, _ = section_jacobians(problem.map_jacobian(ev.F_w), ev.F_u, problem.m, problem.n_g)
        multipliers = np.linalg.eigvals(A)
    except np.linalg.LinAlgError:
        return False, restart
    scale = 1 + np.max(np.abs(parent.section_point))
    distance = np.max(np.abs(problem.section_point(solution.w) - parent.section_point))
    far = distance >= BORN_NEAR * scale * UNBORN_MARGIN
    unborn = far or np.min(np.abs(multipliers - 1)) >= BORN_MULTIPLIER * UNBORN_MARGIN
    return bool(unborn), restart


def switch_at_period_doubling(
    sp: SpecialPoint,
    param,
    direction,
    to,
    bounds,
    options,
    verify,
    tol,
    max_period,
    *,
    follow,
    span=(-math.inf, math.inf),
) -> tuple[Branch | None, str]:
    """Find the period-2k orbit born at a PD and follow it away from the PD (and down its own
    doublings) with ``follow`` (the continuation's branch follower).  It is sought first on the
    continuation's side of the PD (a supercritical doubling), then on the other (subcritical),
    at parameter values inside ``span``, the interval where the parent branch was certified (the
    parent orbit, and with it the one born from it, stops existing beyond its boundaries).

    Returns
    -------
    (Branch or None, str)
        The period-2k branch (``None`` when no orbit born at the PD was found) and what happened:
        on failure, what was tried and the last solver message, so that a caller can say why
        there is no period-2k branch instead of leaving it out silently.
    """
    cycle = sp.cycle
    k2 = 2 * sp.cycle.steps if sp.cycle is not None else 2
    if cycle is None or not cycle.success or cycle.problem is None:
        return None, f"no period-{k2} branch: the gait at the PD is not a certified gait"
    problem, w2, null = doubled_unknowns(cycle)
    nominal = np.allclose(cycle.inputs, cycle.model.nominal_input(), rtol=0, atol=1e-15)
    lam_pd = sp.param
    tried, last = 0, "no parameter value next to the PD lies in the allowed range"
    for side in (direction, -direction):
        starts = []  # (offset, parameter value, model, input) on this side
        for offset in OFFSETS:
            lam = lam_pd + side * offset * max(abs(lam_pd), 1e-3)
            if to is not None and side == direction and (lam - to) * direction > 0:
                continue
            if not (bounds[0] <= lam <= bounds[1] and span[0] <= lam <= span[1]):
                continue
            try:
                model = cycle.model.replace(**{param: lam})
            except ParameterError:
                continue
            # A model whose nominal input is set by the parameter (SLIP) keeps it nominal.
            u = model.nominal_input() if nominal else np.asarray(cycle.inputs, dtype=float)
            starts.append((offset, lam, model, u))
        # Newton from the doubled orbit first at every offset and amplitude (no simulation),
        # then the simulated starts (see _candidates).
        for simulated in (False, True):
            for offset, lam, model, u in starts:
                for amplitude in AMPLITUDES:
                    eps = amplitude * math.sqrt(offset)
                    candidates = _candidates(
                        cycle, model, problem, w2, null, eps, u, verify, tol, simulated
                    )
                    for doubled in candidates:
                        tried += 1
                        if isinstance(doubled, str):
                            last = doubled
                            continue
                        if doubled is not UNBORN and doubled.success and born_at(doubled, cycle):
                            break
                        last = (
                            doubled.message
                            if doubled is not UNBORN and not doubled.success
                            else f"the period-{k2} orbit found at {param} = {lam:.10g} was not "
                            f"born at the PD (too far from the parent orbit, or no multiplier "
                            f"near +1)"
                        )
                    else:
                        continue
                    child = follow(
                        doubled,
                        param,
                        side,
                        to if side == direction else None,
                        bounds,
                        options,
                        False,
                        True,
                        max_period,
                        verify,
                        tol,
                    )
                    return child, (
                        f"period-{k2} branch followed from {param} = {lam:.10g} "
                        f"({len(child.cycles)} gaits)"
                    )
    return None, (
        f"no period-{k2} branch found: {tried} starts along the PD's null vector (Newton from "
        f"the doubled orbit, and simulations from the displaced section point; parameter offsets "
        f"{', '.join(f'{o:g}' for o in OFFSETS)} relative, on both sides) failed; the last: "
        f"{last}. Try `gaitopt solve {cycle.model.name} --steps {k2}` with a "
        f"guess past the PD, or a smaller --max-step"
    )


#: What a Newton start yields when :func:`clearly_unborn` drops its orbit before the certificate.
UNBORN = object()


def _candidates(cycle, model, problem, w2, null, eps, u, verify, tol, simulated):
    """The period-2k orbits tried at one parameter value and amplitude ``eps`` (a generator, so
    the second is computed only if the first is not the orbit sought), each a
    :class:`LimitCycle` or, where the start is refused, the reason as a string.

    Without ``simulated``: Newton from the doubled parent orbit plus ``eps`` times the null
    vector (the predictor of Allgower & Georg §8.1): no simulation, but the null vector's
    duration components can be far larger than its section ones (SLIP: tens of seconds per metre
    of apex height), so this start may run backwards in time.  An orbit that clearly was not born
    at the PD is dropped before its certificate (:data:`UNBORN`, :func:`clearly_unborn`).

    With ``simulated``: the usual search from the section point displaced by ``±eps`` times the
    null vector's section part: its unknowns come from a simulation, so the durations are
    consistent.  These are the fallback: tried only after the Newton starts failed at every
    offset and amplitude, because a start that leads to no orbit costs a whole line search (up
    to 100 iterations stalled next to a minimum of ``‖F‖`` that is no root).
    """
    if not simulated:
        try:
            unborn, restart = clearly_unborn(problem, w2 + eps * null, u, model.p, cycle)
            if unborn:
                yield UNBORN
            else:  # the same orbit, certified (Newton stops at once where it had converged)
                yield solve_gait(model, problem, restart, u, verify=verify, tol=tol)
        except GaitoptInputError as exc:
            yield str(exc)
        return
    m = len(cycle.section_point)
    for sign in (1.0, -1.0):  # the orbit visits both sides; one may leave the map's domain
        shifted = cycle.section_point + sign * eps * null[:m]
        guess = dict(zip(cycle.section_coordinates, shifted, strict=True))
        try:
            yield find_limit_cycle(
                model, guess, steps=problem.cycles, inputs=u, follow=False, verify=verify, tol=tol
            )
        except GaitoptInputError as exc:
            yield str(exc)
