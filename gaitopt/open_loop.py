"""An optimal gait as a found gait: its open loop's limit cycle, for the analyses written once.

Continuation (:func:`gaitopt.continuation`), two-parameter curves
(:func:`gaitopt.bifurcation_curve`) and step-to-step control (:mod:`gaitopt.control`) act on a
:class:`~gaitopt.LimitCycle`: the shooting problem, its solution and Jacobians.  An
:class:`~gaitopt.optimize.OptimalGait` is the same kind of orbit driven by an input profile; here
it becomes one.  :func:`gaitopt.orbit.feedforward.feedforward_model` makes the open loop an
autonomous model (the profile read on a clock since the section, the model's parameters still
declared, the per-step input an offset on the profile), and :func:`open_loop_cycle` finds its
limit cycle by multiple shooting from the optimum's fixed point.  That cycle is the optimum's
orbit, found and certified a second, independent way (shooting against collocation): it is
accepted only if its period and fixed point agree with the optimum's to :data:`MATCH_TOL`.
Measured on the level compass optimum (0.3 m in 0.8 s, least effort; ``tests/
test_optimal_analyses.py``): period and fixed point to 2e-12 and 2e-11, multipliers to 8e-9.

:func:`as_limit_cycle` is what the entry points call: a LimitCycle passes through, an optimal
gait becomes its open-loop cycle, anything else is left to the caller.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .orbit.feedforward import FeedforwardModel, feedforward_model
from .result import LimitCycle
from .shooting import find_limit_cycle

__all__ = ["MATCH_TOL", "is_optimal_gait", "is_open_loop", "open_loop_cycle", "as_limit_cycle"]

#: The open-loop cycle must reproduce the optimum: period within ``MATCH_TOL · period`` and fixed
#: point within ``MATCH_TOL · (1 + max |x*|)`` (the referee's tolerance for an optimum's return).
MATCH_TOL = 1e-6


def is_optimal_gait(obj: Any) -> bool:
    """Whether ``obj`` is an :class:`~gaitopt.optimize.OptimalGait` (by its profile and cost
    kind: this module does not import the optimiser)."""
    return hasattr(obj, "profiles") and hasattr(obj, "cost_kind") and hasattr(obj, "model")


def open_loop_cycle(gait: Any, *, tol: float = 1e-10, verify: bool = True) -> LimitCycle:
    """The limit cycle of an optimal gait's open loop, found by multiple shooting.

    Parameters
    ----------
    gait : OptimalGait
        A successful one-step optimum (:func:`gaitopt.optimize_gait`).
    tol : float
        Residual and discretisation-error tolerance of the shooting
        (:func:`gaitopt.find_limit_cycle`).  The profile's pieces join with jumps at the
        collocation's level (1e-7 to 1e-6 in value on the compass optimum), which the RK steps
        meet at their ends, so the mesh refinement converges at first order there (32 RK steps
        per interval of the compass optimum's profile for 1e-10; the kneed walker's optimum
        reaches 3.1e-9 after 128 and needs ``tol=1e-8``).
    verify : bool
        Verify by independent simulation (as :func:`gaitopt.find_limit_cycle`).

    Returns
    -------
    LimitCycle
        A gait of :func:`gaitopt.orbit.feedforward.feedforward_model` at the optimum's parameters:
        states with ``clock``, section coordinates and multipliers as the optimum's, per-step
        inputs the offsets on the profile (nominally 0).  ``success`` is False (status
        ``not_verified``) where the shooting finds another orbit than the optimum's.

    Raises
    ------
    GaitoptInputError
        If ``gait`` is not an optimal gait, failed, or has more than one step.
    """
    model = feedforward_model(gait)
    start = model.default_start()
    cycle = find_limit_cycle(model, start, tol=tol, verify=verify)
    if cycle.success:
        mismatch = _mismatch(gait, cycle)
        if mismatch:
            cycle.success = False
            cycle.status = "not_verified"
            cycle.message = (
                f"the open loop's limit cycle is not the optimum's orbit: {mismatch}; "
                f"{cycle.message}"
            )
    return cycle


def _mismatch(gait: Any, cycle: LimitCycle) -> str:
    """What differs between the optimum and the cycle beyond :data:`MATCH_TOL` ("" if nothing)."""
    names = list(gait.fixed_point)
    x_opt = np.array([gait.fixed_point[k] for k in names])
    x_cyc = np.array([cycle.fixed_point[k] for k in names])
    dx = float(np.max(np.abs(x_cyc - x_opt)))
    dT = abs(float(cycle.period) - float(gait.period))
    words = []
    if dT > MATCH_TOL * float(gait.period):
        words.append(f"period {cycle.period:.10g} against {gait.period:.10g}")
    if dx > MATCH_TOL * (1.0 + float(np.max(np.abs(x_opt)))):
        words.append(f"fixed point {dx:.3g} away")
    return ", ".join(words)


def as_limit_cycle(gait: Any, *, tol: float = 1e-10, verify: bool = True) -> Any:
    """``gait`` as the entry points take it: an optimal gait becomes :func:`open_loop_cycle`'s
    cycle; anything else (a LimitCycle, a model, a guess) is returned unchanged.

    Raises
    ------
    GaitoptInputError
        For an optimal gait that failed or has more than one step (one line naming it).
    """
    if is_optimal_gait(gait):
        return open_loop_cycle(gait, tol=tol, verify=verify)
    return gait


def is_open_loop(model: Any) -> bool:
    """Whether ``model`` is an optimal gait's open loop (:class:`FeedforwardModel`)."""
    return isinstance(model, FeedforwardModel)
