"""Step-to-step control of a gait through its per-step input (touchdown angle, hip torque).

A gait's Poincaré map ``s[n+1] = P(s[n], u[n])`` (section coordinates ``s``, per-step input ``u``
held constant over a step) is linearised at the fixed point by the implicit function theorem on
the shooting equations (:attr:`LimitCycle.jacobian` ``A = ∂P/∂s`` and
:attr:`LimitCycle.input_jacobian` ``B = ∂P/∂u``: automatic differentiation, no finite
differences).  Around it:

* :func:`lqr` — discrete LQR ``u = u* − K (s − s*)``, ``K`` from python-control's ``dlqr`` with the
  user's ``Q`` and ``R`` (Kuo, *Digital control systems*; python-control ``statefbk.dlqr``);
* :func:`acker` — pole placement with python-control's ``acker`` (one input; ``place`` refuses
  repeated poles), by default every pole at 0 (the linearisation's deadbeat);
* :func:`deadbeat` — each step, solve ``P(s, u) = s*`` for ``u`` (as many inputs as section
  coordinates) with a CasADi Newton rootfinder on the shooting equations with ``u`` unknown, so the
  next return lands on the target exactly (to the shooting accuracy); outside its feasible range the
  decision says so (``Decision.success`` false, with the reason) and falls back to the linearised
  deadbeat gain, clipped to the input limits.

Each design returns a :class:`StepController` (result object: gain, closed-loop multipliers
``eig(A − B K)``, the fixed point) that is also a policy ``controller(step, x) -> u`` for
:func:`gaitopt.simulate`, whose closed-loop runs check it (:func:`closed_loop`; many starts, each
on its own rough ground, stepped together: :func:`closed_loop_batch`).
:meth:`Deadbeat.codegen` turns the deadbeat policy into C (CasADi ``Function.generate``, compiled
with the system's C compiler) for a robot's control loop.
"""

from __future__ import annotations

from .batch_loop import ClosedLoopBatch, closed_loop_batch
from .closed_loop import ClosedLoopRun, closed_loop
from .codegen import GeneratedPolicy
from .deadbeat_solver import Deadbeat
from .designs import KINDS, acker, deadbeat, design_controller, lqr
from .errors import ControlDesignError, NoGaitError, check_section_point
from .linearisation import Linearisation, linearise
from .policy import Decision, StepController

__all__ = [
    "KINDS",
    "Linearisation",
    "Decision",
    "StepController",
    "Deadbeat",
    "linearise",
    "lqr",
    "acker",
    "deadbeat",
    "design_controller",
    "closed_loop",
    "closed_loop_batch",
    "ClosedLoopBatch",
    "ControlDesignError",
    "NoGaitError",
    "check_section_point",
    "ClosedLoopRun",
    "GeneratedPolicy",
]
