"""The defining condition of a declared unilateral constraint becoming active along a curve: its
lift-off rate at a phase start, or the grazing of an interior minimum (with the time of the
minimum an extra unknown)."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import casadi as ca

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..shooting import MultipleShooting, ShootingProblem, shooting_problem

__all__ = ["CONSTRAINT_QUANTITIES", "constraint_condition", "n_extra", "phase_start"]

#: Boundary quantities of a declared unilateral constraint: ``(what, chain index, constraint
#: index)``; the others are ``(what, chain index)``.
CONSTRAINT_QUANTITIES = ("lift_off", "graze_min")


def n_extra(boundary: tuple | None) -> int:
    """Extra unknowns of a boundary's extended system: ``t*`` for ``graze_min``, else none."""
    return 1 if boundary is not None and boundary[0] == "graze_min" else 0


def phase_start(problem: ShootingProblem, w: Any, p: Any, k: int) -> Any:
    """The state where chain phase ``k`` begins, from the shooting unknowns (symbolic or
    numeric): the lifted section point for ``k = 0``, else the phase's first node."""
    if k == 0:
        return problem.section.lift(w[: problem.m], p)
    _, _, off, (n, _) = next(item for item in problem.layout if item[0] == "nodes" and item[1] == k)
    return w[off : off + n]


def constraint_condition(
    model_cls: type[HybridModel], disc: MultipleShooting, steps: int, boundary: tuple
) -> ca.Function:
    """``g(w⁺, u, p)``: the defining condition of a constraint boundary ``(what, k, j)`` —
    constraint ``j`` of chain phase ``k`` — with ``w⁺ = (w, t*)`` for ``graze_min``.

    * ``lift_off``: ``ċ(x₀) = ∇c(x₀) · f(x₀)``, the rate at the phase start of a constraint that
      starts at zero (``at_start``): the trailing foot stops lifting off where it vanishes;
    * ``graze_min``: ``(c(x(t*)), ċ(x(t*)))``, an interior minimum of ``c`` touching zero,
      ``x(t*)`` by ``S × steps`` RK steps from the phase start (the grazing condition of
      Nordmark 1991; di Bernardo et al. 2008, §7.1).
    """
    return _constraint_condition(model_cls, disc, steps, tuple(boundary))


@lru_cache(maxsize=32)
def _constraint_condition(model_cls, disc, steps, boundary) -> ca.Function:
    from ..hybrid import rate_along
    from ..integrators import segment_function

    what, k, j = boundary
    if what not in CONSTRAINT_QUANTITIES:
        raise GaitoptInputError(f"`boundary` must be one of {CONSTRAINT_QUANTITIES}, got {what!r}")
    problem = shooting_problem(model_cls, disc, steps)
    phase = problem.phases[problem.chain[k]]
    if not 0 <= j < len(phase.constraints):
        raise GaitoptInputError(
            f"phase {phase.name!r} declares {len(phase.constraints)} constraint(s); no index {j}"
        )
    constraint = phase.constraints[j]
    rate = rate_along(phase.flow, constraint.function)
    n_p, n_u = len(model_cls.parameter_specs()), len(model_cls.inputs)
    w = ca.MX.sym("w", problem.size + n_extra(boundary))
    u, p = ca.MX.sym("u", n_u), ca.MX.sym("p", n_p)
    x0 = phase_start(problem, w, p, k)
    if what == "lift_off":
        if not constraint.at_start:
            raise GaitoptInputError(
                f"constraint {constraint.name!r} is not declared at_start: it has no lift-off rate"
            )
        g = rate(x0, u, p)
    else:
        t_star = w[problem.size]
        x_star = segment_function(phase.flow, disc.segments * disc.rk_steps)(x0, u, p, t_star)
        g = ca.vertcat(constraint.function(x_star, u, p), rate(x_star, u, p))
    return ca.Function(f"constraint_{what}", [w, u, p], [g], ["w", "u", "p"], ["g"])
