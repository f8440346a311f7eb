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
:func:`gaitopt.simulate`, whose closed-loop runs check it (:func:`closed_loop`).
:meth:`Deadbeat.codegen` turns the deadbeat policy into C (CasADi ``Function.generate``, compiled
with the system's C compiler) for a robot's control loop.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import casadi as ca
import control as ct
import numpy as np

from .errors import GaitoptInputError
from .hybrid import HybridModel
from .integrators import segment_function
from .result import LimitCycle
from .shooting import find_limit_cycle, transcription
from .simulation import Simulation, simulate

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
    "ControlDesignError",
    "NoGaitError",
    "check_section_point",
    "ClosedLoopRun",
    "GeneratedPolicy",
]

_NEWTON = {
    "error_on_fail": False,
    "abstol": 1e-12,
    "abstolStep": 1e-12,
    "max_iter": 25,
    "show_eval_warnings": False,
}


class ControlDesignError(GaitoptInputError):
    """A controller that cannot be designed for this model (no input, wrong sizes)."""


class NoGaitError(RuntimeError):
    """No gait to control: the search failed (``cycle`` holds the failed search and its
    message)."""

    def __init__(self, message: str, cycle: LimitCycle | None = None):
        super().__init__(message)
        self.cycle = cycle


def check_section_point(
    model: HybridModel, state: Mapping[str, float], argument: str, label: str | None = None
) -> None:
    """A section point asked for (a target, a start) must exist at the model's parameters.

    A model whose section ends at a closed-form limit says so with a ``highest_apex()`` method:
    the SLIP's apex height ``z`` cannot exceed the energy height ``E/(m g)``, where no forward
    speed is left (``ẋ = sqrt(2 (E/m − g z))``); a state above it has more energy than the model
    and is bad input, not a gait or a decision that fails.

    Parameters
    ----------
    model : HybridModel
    state : mapping
        Section coordinates by name.
    argument : str
        The argument's name, for the message.
    label : str, optional
        What the message starts with instead of ```argument` z=VALUE`` (the CLI: ``--from z=10``).

    Raises
    ------
    ControlDesignError
        Naming ``argument``, the value and the limit.
    """
    top = getattr(model, "highest_apex", None)
    if not callable(top) or "z" not in state:
        return
    z, limit = float(state["z"]), float(top())
    if z > limit:
        label = f"`{argument}` z={z:g}" if label is None else label
        raise ControlDesignError(
            f"{label}: an apex {z:g} m high is above the energy height E/(m g) = "
            f"{limit:.6g} m (energy {model.energy:g} J), where no forward speed is left; give "
            f"z < {limit:.6g} or raise `energy`"
        )


# -- the linearised map -------------------------------------------------------------------------
@dataclass(frozen=True)
class Linearisation:
    """The return map linearised at a fixed point: ``δs[n+1] = A δs[n] + B δu[n]``.

    Attributes
    ----------
    cycle : LimitCycle
        The gait (fixed point, nominal input, Jacobians).
    A : numpy.ndarray
        ``∂P/∂s`` (m × m), section coordinates.
    B : numpy.ndarray
        ``∂P/∂u`` (m × n_u).
    """

    cycle: LimitCycle
    A: np.ndarray
    B: np.ndarray

    @property
    def model(self) -> HybridModel:
        """The model."""
        return self.cycle.model

    @property
    def fixed_point(self) -> np.ndarray:
        """``s*``: the fixed point in section coordinates."""
        return self.cycle.section_point

    @property
    def nominal_input(self) -> np.ndarray:
        """``u*``: the input the gait was computed with."""
        return np.asarray(self.cycle.inputs, dtype=float)

    @property
    def open_loop_multipliers(self) -> np.ndarray:
        """``eig(A)``: the gait's nontrivial Floquet multipliers."""
        return _sorted(np.linalg.eigvals(self.A))


def _sorted(z: np.ndarray) -> np.ndarray:
    z = np.asarray(z, dtype=complex)
    return z[np.argsort(-np.abs(z), kind="stable")]


def linearise(
    model: HybridModel | LimitCycle,
    guess: Mapping[str, float] | None = None,
    *,
    inputs: Sequence[float] | None = None,
    target: Mapping[str, float] | None = None,
) -> Linearisation:
    """Find the gait to control and linearise its return map in state and input (AD).

    Parameters
    ----------
    model : HybridModel or LimitCycle
        A model with per-step inputs (``model.inputs``), or an already solved gait.
    guess : mapping, optional
        Section coordinates to start the gait search from (default: the model's default start).
    inputs : array_like, optional
        The nominal per-step input ``u*`` (default ``model.nominal_input()``).
    target : mapping, optional
        Make this section point the fixed point: ``u*`` is solved from ``P(s*, u*) = s*``
        (needs as many inputs as section coordinates, e.g. the SLIP's apex height and touchdown
        angle); ``inputs`` is then only the first guess.

    Raises
    ------
    ControlDesignError
        If the model has no per-step input.
    NoGaitError
        If no gait is found, or no input makes ``target`` a fixed point (the message says why).
    """
    if isinstance(model, LimitCycle):
        cycle = model
        if not cycle.success:
            raise NoGaitError(f"the gait given was not found ({cycle.message})", cycle)
        _require_inputs(cycle.model)
    else:
        _require_inputs(model)
        if target is not None:
            check_section_point(model, target, "target")
        cycle = find_limit_cycle(model, guess, inputs=inputs)
        if target is not None:
            if not cycle.success:
                cycle = find_limit_cycle(model, target, inputs=inputs)
            if cycle.success:
                s_t = model.section_vector(target)
                decision = Deadbeat(cycle).solve(s_t, target=s_t)
                if not decision.success:
                    raise NoGaitError(
                        f"`target` {_fmt_point(model, s_t)}: no input makes it a fixed point "
                        f"({decision.message})"
                    )
                cycle = find_limit_cycle(model, target, inputs=decision.input)
        if not cycle.success:
            raise NoGaitError(f"{model.name}: no gait to control: {cycle.message}", cycle)
    return Linearisation(cycle, np.asarray(cycle.jacobian), np.asarray(cycle.input_jacobian))


def _require_inputs(model: HybridModel) -> None:
    if not model.inputs:
        raise ControlDesignError(
            f"{model.name} has no per-step input (it is passive): nothing to control; models "
            f"with inputs: slip (touchdown_angle), compass_gait (hip_torque)"
        )


def _fmt_point(model: HybridModel, s: np.ndarray) -> str:
    return ", ".join(
        f"{k}={v:.6g}" for k, v in zip(model.section.coordinates, np.ravel(s), strict=True)
    )


# -- decisions and controllers -----------------------------------------------------------------
@dataclass
class Decision:
    """One step's input, chosen at a return to the section.

    Attributes
    ----------
    success : bool
        The controller's law was applied as designed (deadbeat: the equation was solved, the
        solution is a valid step and the input within its limits; LQR/acker: not saturated).
    message : str
        What was decided, or why the law could not be applied and what was done instead.
    input : numpy.ndarray
        The input applied (after limits / fallback).
    state : numpy.ndarray
        Section coordinates the decision was made from.
    predicted : numpy.ndarray
        Predicted next section coordinates: the target (deadbeat), ``s* + (A − BK)(s − s*)``
        (linear laws).
    iterations : int
        Newton iterations (deadbeat).
    solve_time : float
        Seconds spent deciding.
    """

    success: bool
    message: str
    input: np.ndarray
    state: np.ndarray
    predicted: np.ndarray
    iterations: int = 0
    solve_time: float = float("nan")


@dataclass
class StepController:
    """A step-to-step controller designed around a gait; also a policy for :func:`simulate`.

    Attributes
    ----------
    kind : str
        ``"lqr"``, ``"acker"`` or ``"deadbeat"``.
    linearisation : Linearisation
        The gait and ``A``, ``B``.
    gain : numpy.ndarray
        ``K`` (n_u × m) of ``u = u* − K (s − s*)``; for deadbeat, the gain of the linearised
        deadbeat law ``K = B⁻¹ A``.
    closed_loop_multipliers : numpy.ndarray
        ``eig(A − B K)``.
    weights : dict
        Design data: ``Q``, ``R`` (LQR), ``poles`` (acker).
    input_limits : tuple of numpy.ndarray or None
        ``(low, high)``: inputs are clipped to it.
    target : numpy.ndarray
        The section point the controller drives to (the fixed point).
    """

    kind: str
    linearisation: Linearisation
    gain: np.ndarray
    closed_loop_multipliers: np.ndarray
    weights: dict[str, Any] = field(default_factory=dict)
    input_limits: tuple[np.ndarray, np.ndarray] | None = None
    deadbeat_solver: Deadbeat | None = None

    @property
    def model(self) -> HybridModel:
        """The controlled model."""
        return self.linearisation.model

    @property
    def cycle(self) -> LimitCycle:
        """The gait controlled around."""
        return self.linearisation.cycle

    @property
    def target(self) -> np.ndarray:
        """``s*`` in section coordinates."""
        return self.linearisation.fixed_point

    @property
    def nominal_input(self) -> np.ndarray:
        """``u*``."""
        return self.linearisation.nominal_input

    @property
    def stable(self) -> bool:
        """Every closed-loop multiplier inside the unit circle."""
        return bool(np.all(np.abs(self.closed_loop_multipliers) < 1))

    def decide(self, state: Mapping[str, float] | Sequence[float] | np.ndarray) -> Decision:
        """The input for the next step from a state on the section.

        Parameters
        ----------
        state : mapping or array_like
            Section coordinates (mapping by name, or vector), or a full phase-0 state vector.
        """
        start = time.perf_counter()
        s = self._section(state)
        ds = s - self.target
        linear = self.nominal_input - self.gain @ ds
        if self.deadbeat_solver is not None:
            decision = self.deadbeat_solver.solve(s, target=self.target)
            if decision.success and self._within(decision.input):
                decision.solve_time = time.perf_counter() - start
                return decision
            reason = (
                decision.message
                if not decision.success
                else f"the deadbeat input {_fmt_u(self.model, decision.input)} is outside the "
                f"input limits"
            )
            if len(s) == 1:
                span = self.deadbeat_solver.feasible_range()
                if span is not None:
                    name = self.model.section.coordinates[0]
                    reason += f" (deadbeat works for {span[0]:.6g} ≤ {name} ≤ {span[1]:.6g})"
            u = self._clip(linear)
            return Decision(
                False,
                f"deadbeat infeasible from {_fmt_point(self.model, s)}: {reason}; applied the "
                f"linearised deadbeat law, {_fmt_u(self.model, u)}",
                u,
                s,
                self.target
                + (self.linearisation.A @ ds + self.linearisation.B @ (u - self.nominal_input)),
                decision.iterations,
                time.perf_counter() - start,
            )
        u = self._clip(linear)
        saturated = not np.allclose(u, linear, rtol=0, atol=0)
        predicted = (
            self.target
            + self.linearisation.A @ ds
            + self.linearisation.B @ (u - self.nominal_input)
        )
        message = f"{self.kind}: {_fmt_u(self.model, u)}" + (
            " (saturated at the input limits)" if saturated else ""
        )
        return Decision(not saturated, message, u, s, predicted, 0, time.perf_counter() - start)

    def __call__(self, step: int, x: np.ndarray) -> np.ndarray:
        """Policy for :func:`gaitopt.simulate`: ``u`` from the phase-0 state at the section."""
        return self.decide(np.asarray(x, dtype=float)).input

    def _section(self, state) -> np.ndarray:
        model = self.model
        if isinstance(state, Mapping):  # a state typed in: it must exist (simulated ones do)
            check_section_point(model, state, "state")
            return model.section_vector(state)
        v = np.asarray(state, dtype=float).ravel()
        if v.size == len(model.state_names) and v.size != len(model.section.coordinates):
            return model.section_coordinates_of(v)
        return model.section_vector(v)

    def _within(self, u: np.ndarray) -> bool:
        if self.input_limits is None:
            return True
        lo, hi = self.input_limits
        return bool(np.all(u >= lo) and np.all(u <= hi))

    def _clip(self, u: np.ndarray) -> np.ndarray:
        if self.input_limits is None:
            return u
        return np.clip(u, *self.input_limits)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready description (``gaitopt control --json``)."""
        model = self.model
        out: dict[str, Any] = {
            "model": model.name,
            "params": model.params,
            "kind": self.kind,
            "success": True,
            "message": f"{self.kind} controller around the gait at "
            f"{_fmt_point(model, self.target)} ({self.cycle.message})",
            "section_coordinates": list(model.section.coordinates),
            "state_names": list(model.state_names),
            "fixed_point": dict(self.cycle.fixed_point),
            "inputs": list(model.inputs),
            "nominal_input": dict(zip(model.inputs, map(float, self.nominal_input), strict=True)),
            "A": self.linearisation.A.tolist(),
            "B": self.linearisation.B.tolist(),
            "gain": self.gain.tolist(),
            "open_loop_multipliers": _pairs(self.linearisation.open_loop_multipliers),
            "closed_loop_multipliers": _pairs(self.closed_loop_multipliers),
            "closed_loop_stable": self.stable,
            "weights": {k: np.asarray(v).tolist() for k, v in self.weights.items()},
            "input_limits": None
            if self.input_limits is None
            else [np.asarray(v).tolist() for v in self.input_limits],
        }
        if self.deadbeat_solver is not None and len(self.target) == 1:
            rng = self.deadbeat_solver.feasible_range()
            out["feasible_range"] = None if rng is None else {model.section.coordinates[0]: rng}
        return out


def _pairs(z: np.ndarray) -> list[list[float]]:
    return [[float(v.real), float(v.imag)] for v in np.asarray(z, dtype=complex)]


def _fmt_u(model: HybridModel, u: np.ndarray) -> str:
    return ", ".join(f"{k}={v:.6g}" for k, v in zip(model.inputs, np.ravel(u), strict=True))


def _limits(
    model: HybridModel, input_limits: tuple[Sequence[float], Sequence[float]] | None
) -> tuple[np.ndarray, np.ndarray] | None:
    """The ``(low, high)`` input box: the one given, else the model's ``input_bounds``."""
    if input_limits is None:
        input_limits = getattr(model, "input_bounds", None)
        if input_limits is None:
            return None
    try:
        lo, hi = (np.broadcast_to(np.asarray(v, dtype=float), (len(model.inputs),)).copy()
                  for v in input_limits)  # fmt: skip
    except (TypeError, ValueError):
        raise GaitoptInputError(
            f"`input_limits` must be (low, high) with {len(model.inputs)} entries each "
            f"({', '.join(model.inputs)}), got {input_limits!r}"
        ) from None
    if not np.all(lo < hi):
        raise GaitoptInputError(f"`input_limits` must have low < high, got {input_limits!r}")
    return lo, hi


def _square(name: str, value: Any, size: int, default: float = 1.0) -> np.ndarray:
    """A weight matrix from ``None`` (identity), a scalar, a diagonal or a full matrix."""
    if value is None:
        return default * np.eye(size)
    M = np.asarray(value, dtype=float)
    if M.ndim == 0:
        M = float(M) * np.eye(size)
    elif M.ndim == 1 and M.size == size:
        M = np.diag(M)
    if M.shape != (size, size) or not np.all(np.isfinite(M)):
        raise GaitoptInputError(
            f"`{name}` must be a scalar, {size} diagonal entries or a {size}×{size} matrix, got "
            f"{np.asarray(value).tolist()!r}"
        )
    if not np.allclose(M, M.T) or np.min(np.linalg.eigvalsh(0.5 * (M + M.T))) < 0:
        raise GaitoptInputError(
            f"`{name}` must be symmetric positive semidefinite, got {M.tolist()}"
        )
    return M


# -- designs ------------------------------------------------------------------------------------
def lqr(
    model: HybridModel | LimitCycle | Linearisation,
    Q: Any = None,
    R: Any = None,
    *,
    guess: Mapping[str, float] | None = None,
    target: Mapping[str, float] | None = None,
    input_limits: tuple[Sequence[float], Sequence[float]] | None = None,
) -> StepController:
    """Discrete LQR on the linearised return map, gain from python-control's ``dlqr``.

    Minimises ``Σ δsᵀ Q δs + δuᵀ R δu`` over steps for ``δs[n+1] = A δs[n] + B δu[n]``.

    Parameters
    ----------
    model : HybridModel, LimitCycle or Linearisation
        What to control (see :func:`linearise`).
    Q, R : scalar, diagonal (sequence) or matrix, optional
        State (m × m, section coordinates) and input (n_u × n_u) weights; default identity.
    guess, target : mapping, optional
        See :func:`linearise`.
    input_limits : (low, high), optional
        Clip every input to this box (default: the model's ``input_bounds``, if it has any;
        the SLIP's touchdown angle in [0, π/2]).
    """
    lin = _linearisation(model, guess, target)
    m, n_u = lin.B.shape
    Qm, Rm = _square("Q", Q, m), _square("R", R, n_u)
    if np.min(np.linalg.eigvalsh(Rm)) <= 0:
        raise GaitoptInputError(f"`R` must be positive definite, got {Rm.tolist()}")
    K, _, poles = ct.dlqr(lin.A, lin.B, Qm, Rm)
    K = np.atleast_2d(np.asarray(K, dtype=float))
    return StepController(
        "lqr",
        lin,
        K,
        _sorted(np.linalg.eigvals(lin.A - lin.B @ K)),
        {"Q": Qm, "R": Rm, "dlqr_poles": np.asarray(poles)},
        _limits(lin.model, input_limits),
    )


def acker(
    model: HybridModel | LimitCycle | Linearisation,
    poles: Sequence[complex] | None = None,
    *,
    guess: Mapping[str, float] | None = None,
    target: Mapping[str, float] | None = None,
    input_limits: tuple[Sequence[float], Sequence[float]] | None = None,
) -> StepController:
    """Pole placement for one input with python-control's ``acker`` (Ackermann's formula).

    Parameters
    ----------
    poles : sequence of complex, optional
        Desired closed-loop multipliers (m of them); default all 0 (the linear deadbeat).
    """
    lin = _linearisation(model, guess, target)
    m, n_u = lin.B.shape
    if n_u != 1:
        raise ControlDesignError(
            f"`acker` places poles for one input; {lin.model.name} has {n_u}: use lqr"
        )
    poles = np.zeros(m) if poles is None else np.asarray(poles, dtype=complex).ravel()
    if poles.size != m or not np.all(np.isfinite(poles)):
        raise GaitoptInputError(
            f"`poles` must be {m} finite values (one per section coordinate: "
            f"{', '.join(lin.model.section.coordinates)}), got {np.asarray(poles).tolist()!r}"
        )
    if np.linalg.matrix_rank(ct.ctrb(lin.A, lin.B)) < m:
        raise ControlDesignError(
            f"{lin.model.name}: the linearised map is not controllable from "
            f"{', '.join(lin.model.inputs)}; poles cannot be placed"
        )
    K = np.atleast_2d(np.real(np.asarray(ct.acker(lin.A, lin.B, poles), dtype=complex)))
    return StepController(
        "acker",
        lin,
        K,
        _sorted(np.linalg.eigvals(lin.A - lin.B @ K)),
        {"poles": poles.real if np.all(poles.imag == 0) else poles},
        _limits(lin.model, input_limits),
    )


def deadbeat(
    model: HybridModel | LimitCycle | Linearisation,
    *,
    guess: Mapping[str, float] | None = None,
    target: Mapping[str, float] | None = None,
    input_limits: tuple[Sequence[float], Sequence[float]] | None = None,
) -> StepController:
    """Deadbeat control: each step solve ``P(s, u) = s*`` for ``u`` (CasADi Newton rootfinder).

    Needs as many inputs as section coordinates (the SLIP: apex height ← touchdown angle).  Its
    linearisation is ``K = B⁻¹ A`` with every closed-loop multiplier 0.

    Raises
    ------
    ControlDesignError
        If the numbers of inputs and section coordinates differ.
    """
    lin = _linearisation(model, guess, target)
    m, n_u = lin.B.shape
    if n_u != m:
        raise ControlDesignError(
            f"deadbeat needs as many inputs as section coordinates; {lin.model.name} has "
            f"{m} ({', '.join(lin.model.section.coordinates)}) and {n_u} "
            f"({', '.join(lin.model.inputs)}): use lqr or acker"
        )
    if abs(np.linalg.det(lin.B)) < 1e-12 * max(1.0, np.max(np.abs(lin.B))):
        raise ControlDesignError(f"{lin.model.name}: ∂P/∂u is singular at the gait: no deadbeat")
    K = np.linalg.solve(lin.B, lin.A)
    return StepController(
        "deadbeat",
        lin,
        K,
        _sorted(np.linalg.eigvals(lin.A - lin.B @ K)),
        {},
        _limits(lin.model, input_limits),
        Deadbeat(lin.cycle),
    )


#: Controller designs by name (``gaitopt control --kind``).
KINDS: dict[str, Callable[..., StepController]] = {"lqr": lqr, "acker": acker, "deadbeat": deadbeat}


def design_controller(
    model: HybridModel | LimitCycle | Linearisation, kind: str, **options: Any
) -> StepController:
    """Dispatch to :func:`lqr`, :func:`acker` or :func:`deadbeat` by ``kind``."""
    if kind not in KINDS:
        raise GaitoptInputError(f"`kind` must be one of {', '.join(KINDS)}, got {kind!r}")
    return KINDS[kind](model, **options)


def _linearisation(model, guess, target) -> Linearisation:
    if isinstance(model, Linearisation):
        return model
    return linearise(model, guess, target=target)


# -- deadbeat rootfinder ------------------------------------------------------------------------
class Deadbeat:
    """``u(s)`` solving ``P(s, u) = s*``: Newton on the shooting equations with ``u`` unknown.

    The unknowns are the gait's shooting unknowns (segment starts, phase durations; the mesh of
    the solved gait, so the accuracy is its discretisation error) and the input; the equations
    are the shooting equations of one step from ``lift(s)`` and ``P = s*`` in place of
    periodicity.  The guess is the solved gait.  A solution counts only if Newton converged,
    every phase lasts a positive time and ends on its guard admissibly and in the stated
    direction.

    Parameters
    ----------
    cycle : LimitCycle
        The solved gait (its mesh, its orbit as the guess).
    """

    def __init__(self, cycle: LimitCycle):
        if not cycle.success:
            raise ControlDesignError(f"`cycle` is not a solved gait ({cycle.message})")
        self.cycle = cycle
        self.model = cycle.model
        model_cls = type(cycle.model)
        self.tr = tr = transcription(model_cls, cycle.discretisation, cycle.steps)
        self.m, self.n_u = tr.m, len(model_cls.inputs)
        self.n_z = tr.size - tr.m
        self._guess = np.concatenate([self._orbit_unknowns(), np.asarray(cycle.inputs, float)])

    def _orbit_unknowns(self) -> np.ndarray:
        """The shooting unknowns ``z`` of the solved gait (segment starts read off its orbit,
        which was sampled on the same mesh)."""
        tr, cycle = self.tr, self.cycle
        S, q = tr.disc.segments, tr.disc.dense
        nodes = [arc.x[:, 0 : S * q : q] for arc in cycle.orbit]
        w = tr.pack(cycle.section_point, nodes, [float(d) for d in cycle.durations])
        return w[tr.m :]

    @cached_property
    def equations(self) -> ca.Function:
        """``F(v, s, s_target, p)`` with ``v = [z; u]``: the step's shooting equations and
        ``P(s, u) − s_target``."""
        tr = self.tr
        v = ca.MX.sym("v", self.n_z + self.n_u)
        s = ca.MX.sym("s", self.m)
        s_t = ca.MX.sym("s_target", self.m)
        p = ca.MX.sym("p", self.model.p.size)
        F = tr.residual(ca.vertcat(s, v[: self.n_z]), v[self.n_z :], p)
        G, periodicity = F[: tr.n_g], F[tr.n_g :]
        eq = ca.vertcat(G, periodicity + s - s_t)  # periodicity = P − s: P = s_target instead
        return ca.Function(
            "deadbeat_equations", [v, s, s_t, p], [eq], ["v", "s", "s_target", "p"], ["F"]
        ).expand()

    @cached_property
    def _predictor(self) -> tuple[np.ndarray, np.ndarray]:
        """``(dv/ds, dv/ds_target)`` at the gait (implicit function theorem on the equations):
        Newton starts from the first-order prediction, which saves half the iterations."""
        eq = self.equations
        v, s, s_t, p = (ca.SX.sym(n, eq.size1_in(i)) for i, n in enumerate("vstp"))
        F = eq(v, s, s_t, p)
        J = ca.Function("predictor", [v, s, s_t, p], [ca.jacobian(F, ca.vertcat(v, s, s_t))])
        s_star = self.cycle.section_point
        Jn = np.asarray(J(self._guess, s_star, s_star, self.model.p), dtype=float)
        n_v = self._guess.size
        sens = -np.linalg.solve(Jn[:, :n_v], Jn[:, n_v:])
        return sens[:, : self.m], sens[:, self.m :]

    @cached_property
    def solver(self) -> ca.Function:
        """The CasADi Newton rootfinder ``v(v0, s, s_target, p)``."""
        return ca.rootfinder("deadbeat", "newton", self.equations, _NEWTON)

    def solve(
        self,
        s: Sequence[float] | np.ndarray,
        *,
        target: Sequence[float] | np.ndarray | None = None,
        p: np.ndarray | None = None,
        guess: np.ndarray | None = None,
    ) -> Decision:
        """The deadbeat input from section coordinates ``s``.

        Parameters
        ----------
        s : array_like
            Section coordinates now.
        target : array_like, optional
            Next section coordinates wanted (default: the gait's fixed point).
        p : numpy.ndarray, optional
            Parameter vector the step is predicted with (default: the model's; e.g. a known
            ground height).
        guess : numpy.ndarray, optional
            Start ``v = [z; u]`` for Newton (default: the first-order prediction from the gait;
            if Newton fails from there, a continuation from the gait in eight steps).
        """
        start = time.perf_counter()
        s = np.asarray(s, dtype=float).ravel()
        s_t = self.cycle.section_point if target is None else np.asarray(target, float).ravel()
        p = self.model.p if p is None else np.asarray(p, dtype=float)
        if guess is None:
            d_s, d_t = self._predictor
            s_star = self.cycle.section_point
            v0 = self._guess + d_s @ (s - s_star) + d_t @ (s_t - s_star)
        else:
            v0 = guess
        v = np.asarray(self.solver(v0, s, s_t, p), dtype=float).ravel()
        if guess is None and not self._converged(v, s, s_t, p):
            v = self._continuation(s, s_t, p)
        stats = self.solver.stats()
        iterations = int(stats.get("iter_count", 0))
        u = v[self.n_z :]
        problem = None
        if not np.all(np.isfinite(v)):
            problem = (
                "no step exists from there (the step's equations are undefined on the way, "
                "e.g. an apex below the touchdown height)"
            )
        elif not self._converged(v, s, s_t, p):
            problem = f"Newton found no input after {iterations} iterations"
        else:
            problem = self._check(s, v, u, p)
        bounds = getattr(self.model, "input_bounds", None)
        if problem is None and bounds is not None:
            lo, hi = (np.asarray(b, dtype=float) for b in bounds)
            if np.any(u < lo) or np.any(u > hi):
                problem = (
                    f"the input needed, {_fmt_u(self.model, u)}, is outside its range "
                    f"[{_fmt_u(self.model, lo)}, {_fmt_u(self.model, hi)}]"
                )
        self.last_solution = v
        elapsed = time.perf_counter() - start
        if problem is not None:
            return Decision(False, problem, u, s, s_t, iterations, elapsed)
        return Decision(
            True,
            f"deadbeat: {_fmt_u(self.model, u)} brings {_fmt_point(self.model, s)} to "
            f"{_fmt_point(self.model, s_t)}",
            u,
            s,
            s_t,
            iterations,
            elapsed,
        )

    def _converged(self, v, s, s_t, p) -> bool:
        return bool(self.solver.stats()["success"]) and self._residual(v, s, s_t, p) <= 1e-9

    def _continuation(self, s, s_t, p, pieces: int = 8) -> np.ndarray:
        """Far from the gait: walk from the gait to ``(s, s_target)`` in ``pieces`` steps, each
        Newton solve starting from the last (the last result, converged or not)."""
        s_star = self.cycle.section_point
        v = self._guess
        for k in range(1, pieces + 1):
            a = k / pieces
            s_k, t_k = s_star + a * (s - s_star), s_star + a * (s_t - s_star)
            v = np.asarray(self.solver(v, s_k, t_k, p), dtype=float).ravel()
            if not self._converged(v, s_k, t_k, p):
                break
        return v

    def _residual(self, v, s, s_t, p) -> float:
        """Max-norm of the equations at ``v`` (Newton's own success flag is not enough)."""
        F = np.asarray(self.equations(v, s, s_t, p), dtype=float)
        return float(np.max(np.abs(F))) if np.all(np.isfinite(F)) else float("inf")

    @cached_property
    def _checks(self) -> ca.Function:
        return self.tr.checks.expand()

    def _check(self, s, v, u, p) -> str | None:
        """Positive durations; each phase ends on its guard admissibly, in its direction."""
        tr = self.tr
        w = np.concatenate([s, v[: self.n_z]])
        outputs = self._checks(w, u, p)
        ends, dg, adm, durations = (np.asarray(a, dtype=float).ravel() for a in outputs)
        del ends
        model = self.model
        for k, i in enumerate(tr.chain):
            phase = model.phases[i]
            transition = phase.transitions[0]
            if not durations[k] > 0:
                return f"no valid step: phase '{phase.name}' would last {durations[k]:.3g} s"
            if not adm[k] > 0 or not transition.direction * dg[k] > 0:
                return (
                    f"no valid step: phase '{phase.name}' would not end by '{transition.name}' "
                    f"as a gait step must"
                )
        return None

    def feasible_range(
        self, interval: tuple[float, float] | None = None, *, samples: int = 41
    ) -> tuple[float, float] | None:
        """For a 1-D section: the interval around the target from which deadbeat succeeds.

        Sampled on ``interval`` (default: the model's ``apex_domain()`` if it has one, else
        ±50 % around the fixed point), its ends located by bisection to 1e-6 relative.
        ``None`` for sections of more than one coordinate.
        """
        if self.m != 1:
            return None
        key = (interval, samples)
        cache = self.__dict__.setdefault("_ranges", {})
        if key in cache:
            return cache[key]
        s_star = float(self.cycle.section_point[0])
        if interval is None:
            domain = getattr(self.model, "apex_domain", None)
            interval = (
                domain() if domain else (s_star - 0.5 * abs(s_star), s_star + 0.5 * abs(s_star))
            )
        lo, hi = map(float, interval)

        def ok(x: float) -> bool:
            return self.solve([x]).success

        if not ok(s_star):
            cache[key] = None
            return None
        ends = []
        for edge in (lo, hi):
            grid = np.linspace(s_star, edge, samples)[1:]
            good = s_star
            bad = None
            for x in grid:
                if ok(x):
                    good = x
                else:
                    bad = x
                    break
            if bad is None:
                ends.append(good)
                continue
            for _ in range(40):
                mid = 0.5 * (good + bad)
                if abs(bad - good) < 1e-6 * max(1.0, abs(mid)):
                    break
                if ok(mid):
                    good = mid
                else:
                    bad = mid
            ends.append(good)
        cache[key] = (float(ends[0]), float(ends[1]))
        return cache[key]

    # -- generated C -------------------------------------------------------------------------
    def policy_function(self, steps: Sequence[int] | None = None) -> ca.Function:
        """The deadbeat policy as one CasADi function ``u, T, residual = policy(s, s_target, p)``.

        Single shooting through the phase chain (unknowns: the phase durations and ``u``; each
        phase integrated by ``steps[k]`` fixed RK8 steps), solved by CasADi's ``fast_newton``
        (code generation supported) from the first-order prediction of the solution about the
        gait.  ``T`` (phase durations, all positive for a valid step) and ``residual`` (NaN when
        Newton diverged, far from the gait) let the caller reject a failed decision.  ``steps``
        defaults to the fewest steps per phase (1, 2, 4, …) whose end state on the gait changes
        by less than 1e-9 (relative) when they are doubled; a ballistic flight needs one.
        """
        model, tr = self.model, self.tr
        phases = [model.phases[i] for i in tr.chain]
        steps = list(steps) if steps is not None else self._policy_steps()
        if len(steps) != len(phases):
            raise GaitoptInputError(f"`steps` needs {len(phases)} entries, got {len(steps)}")
        n_p = model.p.size
        T = ca.SX.sym("T", len(phases))
        u = ca.SX.sym("u", self.n_u)
        s = ca.SX.sym("s", self.m)
        s_t = ca.SX.sym("s_target", self.m)
        p = ca.SX.sym("p", n_p)
        x = model.section.lift(s, p)
        eq = []
        for k, phase in enumerate(phases):
            x = segment_function(phase.flow, steps[k])(x, u, p, T[k])
            tr0 = phase.transitions[0]
            eq.append(tr0.guard(x, u, p))  # each phase ends on its guard
            x = tr0.reset(x, u, p)
        eq.append(x[tr.section_index] - s_t)  # the next return is the target
        v = ca.vertcat(T, u)
        F = ca.Function("deadbeat_single_shooting", [v, s, s_t, p], [ca.vertcat(*eq)])
        newton = ca.rootfinder(
            "deadbeat_newton",
            "fast_newton",
            F,
            {"abstol": 1e-13, "max_iter": 30, "error_on_fail": False},
        )
        # First-order predictor from the gait (implicit function theorem on F(v, s, s_t) = 0):
        # Newton starts at v* + dv/ds δs + dv/ds_t δs_t, so a few iterations suffice.
        v_star = np.concatenate([np.asarray(self.cycle.durations, float), self.cycle.inputs])
        s_star, p_star = self.cycle.section_point, self.model.p
        jac = ca.Function(
            "predictor", [v, s, s_t, p], [ca.jacobian(F(v, s, s_t, p), ca.vertcat(v, s, s_t))]
        )
        J = np.asarray(jac(v_star, s_star, s_star, p_star), dtype=float)
        n_v = v.numel()
        sens = -np.linalg.solve(J[:, :n_v], J[:, n_v:])  # dv/d(s, s_t)
        v0 = v_star + ca.mtimes(ca.DM(sens), ca.vertcat(s - s_star, s_t - s_star))
        sol = newton(v0, s, s_t, p)
        residual = ca.norm_2(F(sol, s, s_t, p))  # NaN if Newton failed
        return ca.Function(
            "deadbeat_policy",
            [s, s_t, p],
            [sol[len(phases) :], sol[: len(phases)], residual],
            ["s", "s_target", "p"],
            ["u", "T", "residual"],
        )

    def _policy_steps(self, tol: float = 1e-9) -> list[int]:
        steps = []
        u, p = np.asarray(self.cycle.inputs, float), self.model.p
        for arc, T in zip(self.cycle.orbit, self.cycle.durations, strict=True):
            flow = self.model.phases[arc.phase].flow
            x0 = arc.x[:, 0]
            n, prev = 1, None
            while n <= 256:
                end = np.asarray(segment_function(flow, n)(x0, u, p, T), float).ravel()
                if prev is not None and np.max(np.abs(end - prev)) < tol * (
                    1 + np.max(np.abs(end))
                ):
                    break
                prev, n = end, 2 * n
            steps.append(max(1, n // 2))
        return steps

    def codegen(
        self, directory: str | os.PathLike | None = None, *, steps: Sequence[int] | None = None
    ) -> GeneratedPolicy:
        """Generate C for :meth:`policy_function` and compile it (``cc -O3 -shared``), cached by
        the source's hash in ``directory`` (default: ``<tmp>/gaitopt-codegen``).

        Returns
        -------
        GeneratedPolicy
            The C source, the shared library and the function loaded from it
            (``casadi.external``).

        Raises
        ------
        RuntimeError
            If no C compiler is found or compiling fails.
        """
        policy = self.policy_function(steps)
        root = Path(directory or Path(tempfile.gettempdir()) / "gaitopt-codegen")
        root.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=root) as scratch:
            name = "deadbeat_policy.c"
            cwd = os.getcwd()
            os.chdir(scratch)
            try:
                policy.generate(name, {"with_header": True, "with_mem": False})
            finally:
                os.chdir(cwd)
            source = Path(scratch, name).read_text()
            header = Path(scratch, "deadbeat_policy.h").read_text()
        digest = hashlib.sha256(source.encode()).hexdigest()[:16]
        folder = root / digest
        folder.mkdir(exist_ok=True)
        c_file, h_file = folder / "deadbeat_policy.c", folder / "deadbeat_policy.h"
        library = folder / "deadbeat_policy.so"
        if not library.exists():
            c_file.write_text(source)
            h_file.write_text(header)
            compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
            if compiler is None:
                raise RuntimeError("no C compiler (cc or gcc) found for the generated policy")
            tmp = folder / f".{digest}.{os.getpid()}.so"
            proc = subprocess.run(
                [compiler, "-O3", "-fPIC", "-shared", str(c_file), "-o", str(tmp), "-lm"],
                capture_output=True,
                text=True,
            )
            if proc.returncode != 0:
                raise RuntimeError(f"compiling the generated policy failed: {proc.stderr[-500:]}")
            os.replace(tmp, library)
        return GeneratedPolicy(c_file, library, ca.external("deadbeat_policy", str(library)))


@dataclass(frozen=True)
class GeneratedPolicy:
    """A compiled deadbeat policy: ``function(s, s_target, p) -> (u, T, residual)``.

    Attributes
    ----------
    source : pathlib.Path
        The generated C file (its header beside it).
    library : pathlib.Path
        The shared library compiled from it.
    function : casadi.Function
        The library loaded with ``casadi.external``.
    """

    source: Path
    library: Path
    function: ca.Function


# -- closed loop --------------------------------------------------------------------------------
def closed_loop(
    controller: StepController | Callable[[int, np.ndarray], np.ndarray] | None,
    model: HybridModel,
    x0: Mapping[str, float] | Sequence[float] | np.ndarray,
    *,
    steps: int = 20,
    terrain: Callable[[int], Mapping[str, float]] | None = None,
    target: np.ndarray | None = None,
) -> ClosedLoopRun:
    """Simulate a controlled model and measure how it converges (or falls).

    Parameters
    ----------
    controller : StepController, callable or None
        The policy ``u = controller(step, x)``; ``None`` runs open loop at the model's nominal
        input.
    model : HybridModel
        The model simulated (a :class:`gaitopt.terrain.BlindPolicy` needs its swing-leg model).
    x0 : mapping or array_like
        Start (section coordinates or a full phase-0 state).
    steps : int
        Returns to the section to simulate.
    terrain : callable, optional
        Per-step parameter changes (:func:`gaitopt.terrain.random_terrain`).
    target : numpy.ndarray, optional
        Section point the errors are measured from; default the controller's target (required
        when ``controller`` is not a :class:`StepController`).

    Returns
    -------
    ClosedLoopRun
        The simulation, the steps survived, the error (max-norm distance to ``target``) at each
        return, and the inputs applied.
    """
    policy = controller
    if target is None:
        if isinstance(controller, StepController):
            target = controller.target
        else:
            raise GaitoptInputError("`target` is needed when `controller` is not a StepController")
    sim = simulate(model, x0, steps=steps, inputs=policy, terrain=terrain)
    coords = np.array([model.section_coordinates_of(x) for x in sim.section_states])
    errors = np.max(np.abs(coords - np.asarray(target, float)), axis=1) if len(coords) else coords
    inputs = np.array([arc.u for arc in sim.arcs if arc.phase == 0])
    return ClosedLoopRun(sim, sim.steps, coords, errors, inputs)


@dataclass
class ClosedLoopRun:
    """A closed-loop simulation and what it shows.

    Attributes
    ----------
    simulation : Simulation
    survived : int
        Returns to the section completed (the run stops at a fall).
    section : numpy.ndarray
        Section coordinates at each return (rows; the start first).
    errors : numpy.ndarray
        Max-norm distance of each return from the target.
    inputs : numpy.ndarray
        The input applied at each step (rows).
    """

    simulation: Simulation
    survived: int
    section: np.ndarray
    errors: np.ndarray
    inputs: np.ndarray
