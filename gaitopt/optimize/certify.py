"""An optimum solved to its tolerance becomes an :class:`OptimalGait` only if it passes every check:
the certificate the shooting uses too (:mod:`gaitopt.orbit.certificate`, on the collocation
polynomials: guards, directions, admissibility, unilateral constraints with their one rule, the
minimal period), the common referee (:mod:`gaitopt.orbit.referee`: the simulation with the input
profile as a feedforward returns, with the same phase timing and the same cost), and its Floquet
multipliers by AD and by finite differences.  A
least-effort optimum solved with the arcs of its input bounds says in its message where each
input sits at its bound (``at the bound: hip_torque = -4 on [0, 0.407938] s, …``), and one with
touch points of its state bounds or limits made junctions says when each touches (``touch
points (free mesh points): stance knee flexion >= 0 at 0.651808 s``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..orbit import solve as sequence
from ..stability import is_stable
from .active import _active
from .arcs import saturated_spans
from .boundary_arcs import boundary_spans
from .collocation import Collocation
from .floquet import multipliers_of, return_map_jacobian
from .problem import GaitProblem
from .result import OptimalGait
from .state_arcs import touch_times
from .transcription import CollocationTranscription
from .verify import GUARD_TOL, map_jacobian_fd, orbit_arcs, profiles
from .work_check import check_work, dense_work

#: The simulated return must be the fixed point to this, relative to ``1 + max |x*|``.
RETURN_TOL = 1e-6


def _certify(
    problem: GaitProblem, col: Collocation, w: np.ndarray, stats: dict[str, Any], verify: bool
) -> OptimalGait:
    """Checks and the result object of a converged solution ``w``."""
    model = problem.model
    p = model.p
    sol = col.unpack(w, p)
    free_values = dict(zip(problem.free, map(float, sol["free"]), strict=True))
    gait_model = model.replace(**free_values) if free_values else model
    x_star = gait_model.lift(sol["s"])
    profs = profiles(col, sol)
    period = sol["period"]
    step_length = sol["distance"] / problem.steps if problem.footholds() else None
    orbit = orbit_arcs(col, sol)
    t_grid = [arc.t if k == 0 else arc.t[1:] for k, arc in enumerate(orbit)]
    u_grid = [arc.u if k == 0 else arc.u[:, 1:] for k, arc in enumerate(orbit)]
    t_all = np.concatenate(t_grid)
    u_all = np.hstack(u_grid)
    inputs = {"time": t_all.tolist(), **{n: u_all[j].tolist() for j, n in enumerate(model.inputs)}}
    result = OptimalGait(
        False,
        "",
        gait_model,
        problem.cost_kind,
        cost=sol["cost"],
        period=period,
        step_length=step_length,
        speed=(sol["distance"] / period) if step_length is not None else None,
        fixed_point=dict(zip(model.state_names, map(float, x_star), strict=True)),
        inputs=inputs,
        profiles=profs,
        durations=sol["T"],
        active_constraints=_active(col, w, p),
        params=gait_model.params,
        iterations=int(stats.get("iter_count", 0)),
        problem=problem.describe(),
        orbit=orbit,
    )
    # The one sequence's certificate stage (gaitopt.orbit.solve.certificate): the common
    # certificate on the collocation polynomials, then the power split's complementarity.
    t = CollocationTranscription(col=col)
    problem_msg = sequence.certificate(t, w, guard_tol=GUARD_TOL)
    if problem_msg is None:  # exact-work optima: the positive work between the nodes too
        problem_msg = check_work(col, sol)
    if problem_msg is not None:
        result.message = "not a gait: " + problem_msg.removeprefix("no gait: ")
        result.status = "not_a_gait"
        return result
    if not verify:
        result.success, result.status = True, "success"
        result.message = "optimal gait found (not verified: verify=False)"
        return result

    # The one sequence's referee stage (rule 8): the feedforward simulation must return, keep
    # the phase timing and cost the same (at the tight tolerances: its return error and cost are
    # reported figures).
    verdict = t.referee(w, RETURN_TOL)
    if verdict.simulation is None or not np.isfinite(verdict.return_error):
        result.message = "the optimum is not confirmed by simulation: " + verdict.message
        result.status = "not_verified"
        return result
    result.verification = {
        "return_error": verdict.return_error,
        "cost_simulated": verdict.cost_simulated,
        "cost_error": verdict.cost_error,
        "period_simulated": verdict.period_simulated,
    }
    if col.structure is not None and problem.cost_kind in ("work", "cot"):
        work = dense_work(col, sol)  # checked above (check_work); reported with the referee's
        result.verification["positive_work_dense"] = work["positive_work_dense"]
        result.verification["hidden_work"] = work["hidden_work"]
    result.verified = bool(verdict.ok)

    A = return_map_jacobian(col, w, p)
    result.multipliers = multipliers_of(A)
    A_fd = map_jacobian_fd(problem, gait_model, sol["s"], profs)
    if A_fd is not None:
        result.multipliers_fd = multipliers_of(A_fd)
    result.stable = is_stable(result.multipliers)
    if not result.verified:
        result.message = "the optimum is not confirmed by simulation: " + verdict.message
        result.status = "not_verified"
        return result
    result.success, result.status = True, "success"
    result.message = (
        f"optimal gait found (IPOPT {stats.get('return_status')}, {result.iterations} "
        f"iterations); {verdict.message}"
    )
    spans = saturated_spans(col, w, p)
    if spans:  # the arcs of active input bounds (least effort), with their junction times
        result.message += f"; at the bound: {', '.join(spans)}"
    if (
        problem.braking_effort > 0
        and col.structure is not None
        and problem.cost_kind in ("work", "cot")
    ):  # the braking arcs' regularisation: in the objective, not in the reported cost
        result.message += (
            f"; braking arcs regularised by {problem.braking_effort:g} ∫u² dt "
            f"(∫u² dt = {sol['braking_effort']:.6g} on them, not in the cost)"
        )
    touches = touch_times(col, w, p)
    if touches:  # touch points of state bounds and limits, made junctions
        result.message += f"; touch points (free mesh points): {', '.join(touches)}"
    held = boundary_spans(col, w, p)
    if held:  # boundary arcs of a guard (the knee held straight), entry and exit junctions
        result.message += f"; boundary arcs: {', '.join(held)}"
    return result
