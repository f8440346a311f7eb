"""Stabilising an optimal gait: a per-step input offset chosen by step-to-step LQR, checked.

An optimal gait's input ``u*(t)`` is a feedforward in the time since the section; its return
map can be unstable (the level-ground least-effort compass gait: multipliers −1.34, 0.43,
−0.003).  Add a per-step input: an offset ``δₖ`` held over step ``k`` on top of the profile,
``u(t) = u*(t) + δₖ`` (``t`` since that step's section, the profile held at its last value if the
step lasts longer, as :func:`gaitopt.optimize.verify.simulate_gait` applies it).  The map
linearised at the fixed point,

    ``sₖ₊₁ − s* = A (sₖ − s*) + B δₖ``,

has ``A`` from :func:`gaitopt.optimize.floquet.return_map_jacobian` (the implicit function theorem
on the Radau collocation equations) and ``B`` by the same construction with ``δ`` as an extra
unknown: each phase's collocation residual is differentiated in ``δ`` (the nodes see
``u + δ``), the guard's crossing time moves by ``δτ = −(g_x δx + g_u (u̇ δt₀ + δ)) / ġ`` and the
reset adds ``r_u δ`` (the saltation construction of the floquet module, Hiskens & Pai 2000).
Both are checked against central finite differences of the independent event-located simulator.

The gain is the step-to-step LQR of :func:`gaitopt.control.lqr` (python-control's ``dlqr``) on
that linearisation, ``δₖ = −K (sₖ − s*)``; its closed-loop multipliers ``eig(A − B K)`` are
checked against those *measured* from the simulated closed loop (central differences of one
controlled step of the simulator), and the closed loop is simulated from perturbed states (each
section coordinate in turn, ± a small amount): it must return to the fixed point, every step
completed by the simulator (guards located, the unilateral constraints of each phase checked),
with the constraints also sampled densely with the input actually applied, ``u*(t) + δₖ``; the
uncontrolled walker is run from the same states for comparison.

With ``steps > 1`` in the problem (an orbit of several returns) the offset is decided once per
orbit and held over its returns: the map linearised is the orbit's.

The function is :func:`gaitopt.optimize.stabilise` (also ``gaitopt.stabilise``); this package
is named for the noun so that the function does not shadow a module of the same name.

* :mod:`~gaitopt.optimize.stabilisation.linearise` — ``A`` and ``B`` by AD through the
  transcription, ``B`` by central differences of the simulator;
* :mod:`~gaitopt.optimize.stabilisation.closed_loop` — the simulated closed loop: runs from
  perturbed states, the dense constraint check with the applied input, the measured map;
* :mod:`~gaitopt.optimize.stabilisation.design` — :func:`stabilise`: the LQR design and every
  check;
* :mod:`~gaitopt.optimize.stabilisation.result` — :class:`Stabilisation` and its JSON.
"""

from .closed_loop import ClosedLoopTrial
from .design import stabilise
from .linearise import offset_jacobian, offset_jacobian_fd
from .result import Stabilisation

__all__ = [
    "stabilise",
    "Stabilisation",
    "ClosedLoopTrial",
    "offset_jacobian",
    "offset_jacobian_fd",
]
