"""Independent hybrid simulation: SciPy's adaptive integrators with located, directional events.

This is deliberately independent of the shooting integrator (adaptive steps and event location
here, fixed-step shooting with guard constraints there), so each can check the other.

The loop is SciPy's ``solve_ivp`` event logic (step, check signs, locate the root with ``brentq``
on the step's dense output), driving :class:`scipy.integrate.DOP853` (or another ``OdeSolver``)
step by step, with two additions that hybrid walking models need:

* *strict crossings*: a guard fires only after it has been strictly on its pre-crossing side in
  this phase (a phase that starts on a guard, such as Van der Pol's section, does not fire at
  once — the case ``solve_ivp`` fires at ``t0``);
* *admissibility*: a crossing where the model's rule says it is spurious (the compass gait's
  mid-swing foot scuff) is ignored and integration goes on.

After a reset the integration restarts in the target phase.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

if TYPE_CHECKING:
    from scipy.integrate import OdeSolution

from .errors import GaitoptInputError
from .hybrid import HybridModel, Phase, rate_along

__all__ = ["simulate", "Simulation", "Arc", "Event"]

#: SciPy's ``OdeSolver`` classes by name (``scipy.integrate`` is imported on first use: 0.4 s).
_METHODS = ("DOP853", "RK45", "Radau", "LSODA")
# A guard must have been below -_ARM (in units of the guard) before it can fire.
_ARM = 1e-10

InputPolicy = Callable[[int, np.ndarray], np.ndarray]
#: ``terrain(step) -> {parameter: value}``: parameters changed for one step (rough ground).
Terrain = Callable[[int], Mapping[str, float]]


@dataclass
class Arc:
    """One phase of a simulated trajectory.

    Attributes
    ----------
    phase : int
        Index of the phase in ``model.phases``.
    t0, t1 : float
        Start and end time (s).
    solution : scipy.integrate.OdeSolution
        Dense output on ``[t0, t1]``.
    u : numpy.ndarray
        Per-step input in force during the arc.
    """

    phase: int
    t0: float
    t1: float
    solution: OdeSolution
    u: np.ndarray

    def sample(self, count: int = 50) -> tuple[np.ndarray, np.ndarray]:
        """``count`` times on ``[t0, t1]`` and the states there (n × count)."""
        t = np.linspace(self.t0, self.t1, count)
        return t, self.solution(t)


@dataclass
class Event:
    """A transition that fired.

    Attributes
    ----------
    t : float
        Time (s).
    phase : int
        Phase that ended.
    transition : str
        Transition name.
    state_before, state_after : numpy.ndarray
        States just before and just after the reset (``state_after`` is None for a fall).
    """

    t: float
    phase: int
    transition: str
    state_before: np.ndarray
    state_after: np.ndarray | None


@dataclass
class Simulation:
    """Result of :func:`simulate`.

    Attributes
    ----------
    success : bool
        Whether the requested number of steps was completed.
    status : str
        ``"completed"``, ``"fell"`` (a terminal transition), ``"standing"`` (impacts
        accumulate, Zeno: the motion comes to rest in finite time, see :func:`_accumulation`),
        ``"timeout"`` (no transition within ``max_phase_time``) or ``"failed"`` (the integrator
        failed).
    message : str
        What happened, in words.
    arcs : list of Arc
        The smooth pieces, in order.
    events : list of Event
        The transitions, in order.
    section_times : numpy.ndarray
        Times of the returns to the section (the first entry is the start).
    section_states : numpy.ndarray
        Phase-0 states at those returns (rows).
    step_parameters : list of dict
        With a ``terrain``: the parameters it changed for each step begun (step k from return k).
    accumulation_time : float or None
        With ``status == "standing"``: the time (s) at which the accumulating impacts end,
        extrapolated from their geometric intervals.
    """

    success: bool
    status: str
    message: str
    arcs: list[Arc] = field(default_factory=list)
    events: list[Event] = field(default_factory=list)
    section_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    section_states: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    step_parameters: list[dict[str, float]] = field(default_factory=list)
    accumulation_time: float | None = None

    @property
    def steps(self) -> int:
        """Completed returns to the section."""
        return max(len(self.section_times) - 1, 0)


class _Buffered:
    """A CasADi function evaluated through preallocated buffers (``Function.buffer``): about
    50× less call overhead than ``f(x, u, p)``, which dominates small right-hand sides."""

    def __init__(self, f: ca.Function, u: np.ndarray, p: np.ndarray):
        self._x = np.zeros(f.size1_in(0))
        self._u = np.ascontiguousarray(u, dtype=float)
        self._p = np.ascontiguousarray(p, dtype=float)
        self._out = np.zeros(f.numel_out(0))
        self._buffer, self._trigger = f.buffer()
        for i, a in enumerate((self._x, self._u, self._p)):
            self._buffer.set_arg(i, memoryview(a))
        self._buffer.set_res(0, memoryview(self._out))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        self._x[:] = x
        self._trigger()
        return self._out.copy()


class _PhaseFunctions:
    """Numerical callables of one phase, for fixed ``u`` and ``p``.

    Events are numbered: the phase's transitions first, then its unilateral constraints, each of
    which is a terminal event where ``c`` falls through zero (a trip, a leg that pulls)."""

    def __init__(self, phase: Phase, u: np.ndarray, p: np.ndarray, constraints: bool = True):
        self.phase = phase
        self.u, self.p = u, p
        self.constraints = phase.constraints if constraints else ()
        self._flow = _Buffered(phase.flow, u, p)
        self._guards = [_Buffered(tr.guard, u, p) for tr in phase.transitions]
        self._guards += [_Buffered(c.function, u, p) for c in self.constraints]
        self._directions = [tr.direction for tr in phase.transitions]
        self._directions += [-1] * len(self.constraints)
        self._admissible = [
            _Buffered(tr.admissible, u, p) if tr.admissible is not None else None
            for tr in phase.transitions
        ] + [None] * len(self.constraints)
        self._jac = None
        self._events = [tr.guard for tr in phase.transitions]
        self._events += [c.function for c in self.constraints]

    def step_function(self) -> ca.Function:
        """One DOP853 step with this phase's event functions (:mod:`gaitopt.dop853`)."""
        from .dop853 import step_function

        return step_function(self.phase.flow, self._events, _CHECKS_PER_STEP)

    @property
    def events(self) -> int:
        """Number of events (transitions and constraints)."""
        return len(self._guards)

    _drive = None  # (feedforward, section time, step) for a time-varying input

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        if self._drive is not None:  # feedforward u(t − t_section, step) in the flow
            feedforward, t_section, step = self._drive
            self._flow._u[:] = feedforward(t - t_section, step)
        return self._flow(x)

    def jac(self, t: float, x: np.ndarray) -> np.ndarray:
        if self._jac is None:
            self._jac = self.phase.flow.factory("jac", ["x", "u", "p"], ["jac:flow:x"])
        return np.asarray(self._jac(x, self.u, self.p))

    def signed_guard(self, k: int, x: np.ndarray) -> float:
        return self._directions[k] * float(self._guards[k](x)[0])

    def admissible(self, k: int, x: np.ndarray) -> bool:
        n_tr = len(self.phase.transitions)
        if k >= n_tr and self.constraints[k - n_tr].at_end:
            # A constraint that vanishes where the phase ends (a foot touching down) reaches 0
            # with the cycle's guard: that is the touchdown, not a violation.
            return abs(float(self._guards[0](x)[0])) > _CONSTRAINT_START
        a = self._admissible[k]
        return a is None or float(a(x)[0]) > 0

    def violated_at_start(self, x: np.ndarray) -> tuple[int, str] | None:
        """A constraint that fails where the phase begins: one that starts active (``at_start``)
        and does not rise (a trailing foot that does not lift off), or one already negative."""
        n_tr = len(self.phase.transitions)
        for j, c in enumerate(self.constraints):
            value = float(self._guards[n_tr + j](x)[0])
            unit = f" {c.unit}" if c.unit else ""
            if c.at_start:
                rate = float(rate_along(self.phase.flow, c.function)(x, self.u, self.p))
                if not rate > _CONSTRAINT_RATE:
                    return (
                        n_tr + j,
                        f"'{c.name}' starts at 0 and does not rise (rate {rate:.3g}{unit}/s)",
                    )
            elif value < -_CONSTRAINT_START:
                return n_tr + j, f"'{c.name}' fails at the start ({value:.3g}{unit})"
        return None


# A constraint that starts active must rise faster than this (its unit per second); one that does
# not must not start below -_CONSTRAINT_START (its unit).  The shooting's certify uses the same.
_CONSTRAINT_RATE = 1e-9
_CONSTRAINT_START = 1e-9


def simulate(
    model: HybridModel,
    x0: Mapping[str, float] | Sequence[float] | np.ndarray | None = None,
    *,
    steps: int = 10,
    phase: int = 0,
    inputs: Sequence[float] | np.ndarray | InputPolicy | None = None,
    method: str = "DOP853",
    rtol: float = 1e-11,
    atol: float = 1e-12,
    max_phase_time: float = 30.0,
    terrain: Terrain | None = None,
    constraints: bool = True,
    feedforward: Callable[[float, int], np.ndarray] | None = None,
) -> Simulation:
    """Simulate a hybrid model for a number of steps.

    Parameters
    ----------
    model : HybridModel
        The model.
    x0 : mapping, sequence or None
        Start state of ``phase``: a full state (mapping by name or vector); for phase 0 a mapping
        may give only section coordinates (the rest from :meth:`HybridModel.lift`).  ``None``:
        the model's default start.
    steps : int
        Number of returns to the Poincaré section to simulate.
    phase : int
        Phase in which ``x0`` lies.
    inputs : array_like or callable, optional
        Per-step input: a constant vector, or ``policy(step, x_section) -> u`` called at each
        return to the section.  Default: passive (zeros).
    method : str
        SciPy integrator: ``"DOP853"`` (default), ``"RK45"``, ``"Radau"``, ``"LSODA"``.
    rtol, atol : float
        Integrator tolerances.
    max_phase_time : float
        A phase that lasts longer than this (s) ends the simulation with ``status="timeout"``.
    terrain : callable, optional
        ``terrain(step) -> {parameter: value}``, called as step ``step`` begins (at the start and
        at each return to the section, after the input policy, which does not see it): those
        parameters hold for that step, e.g. the SLIP's ``ground_height`` or a walker's ``slope``
        (unknown per-step ground changes).  Default: the model's parameters throughout.
    constraints : bool
        Whether the phases' unilateral constraints end the motion where they fail (a trip, a
        leg that pulls: status ``"fell"``, the event named by the constraint's ``outcome``).
        ``False`` only for a rough guess of an orbit, whose checks come later.
    feedforward : callable, optional
        ``feedforward(t, step) -> u``: an input that varies within a step, ``t`` the time since
        the last return to the section (s) and ``step`` the number of returns so far; it drives
        the flow and, at its time, the reset (an optimal gait's profile, held at its last value
        if a step lasts longer).  It replaces ``inputs`` in the flow and the resets; guards and
        constraints see the step's ``inputs``.

    Returns
    -------
    Simulation
    """
    # -- arguments: every check before any work (issue 9: bad input fails fast) ----------------
    from .arguments import check_count, check_inputs, check_positive, check_start
    from .errors import MAX_SIMULATION_STEPS
    from .models import as_model

    model = as_model(model)
    if method not in _METHODS:
        raise GaitoptInputError(f"`method` must be one of {', '.join(_METHODS)}, got {method!r}")
    steps = check_count(
        "steps", steps, 0, MAX_SIMULATION_STEPS, "time and memory grow with every step "
        "(gaitopt.errors.MAX_SIMULATION_STEPS); simulate in pieces, each from the last state"
    )  # fmt: skip
    phase = check_count("phase", phase, 0, len(model.phases) - 1, f"{model.name} has "
                        f"{len(model.phases)} phase(s), numbered from 0")  # fmt: skip
    rtol, atol = check_positive("rtol", rtol, "1e-11"), check_positive("atol", atol, "1e-12")
    max_phase_time = check_positive("max_phase_time", max_phase_time, "30")
    x = _initial_state(model, x0, phase)
    u0 = model.nominal_input() if callable(inputs) else check_inputs(model, inputs)
    check_start(model, x, u0, phase, "x0" if x0 is not None else "the default start")
    policy = _as_policy(model, inputs)
    step_parameters: list[dict[str, float]] = []

    def parameters(step: int) -> np.ndarray:
        if terrain is None:
            return model.p
        changes = {k: float(v) for k, v in dict(terrain(step)).items()}
        known = model.params
        unknown = [k for k in changes if k not in known]
        if unknown:
            raise GaitoptInputError(
                f"`terrain` returned unknown parameter {unknown[0]!r} at step {step}; "
                f"{model.name}'s parameters: {', '.join(known)}"
            )
        step_parameters.append(changes)
        return model.replace(**changes).p

    import scipy.integrate

    solver_cls = getattr(scipy.integrate, method)

    sim = Simulation(False, "completed", "")
    sec_t: list[float] = []
    sec_x: list[np.ndarray] = []
    t = 0.0
    u = policy(0, x)
    p = parameters(0)
    if phase == 0:
        sec_t.append(t)
        sec_x.append(x.copy())
    cycle_end = (len(model.phases) - 1, 0)  # (phase, transition) that closes a cycle
    while len(sec_t) - 1 < steps or (phase != 0 and steps > 0):
        funcs = _PhaseFunctions(model.phases[phase], u, p, constraints)
        if feedforward is not None:  # the flow gets its own input buffer, rewritten per call
            funcs._flow = _Buffered(model.phases[phase].flow, np.array(u, dtype=float), p)
            funcs._drive = (feedforward, sec_t[-1] if sec_t else 0.0, max(len(sec_t) - 1, 0))
        at_start = funcs.violated_at_start(x)
        if at_start is not None:
            constraint = model.phases[phase].constraints[at_start[0] - len(funcs.phase.transitions)]
            sim.events.append(Event(t, phase, constraint.outcome, x.copy(), None))
            sim.status = "fell"
            sim.message = (
                f"{constraint.outcome} at t = {t:.6g} s after {len(sec_t) - 1} steps: "
                f"{at_start[1]} in phase '{model.phases[phase].name}'"
            )
            break
        resting = _rests_on_guard(funcs, x)
        if resting is not None and len(sec_t) - 1 < steps:
            sim.status = "standing"
            sim.accumulation_time = t
            sim.message = (
                f"at rest against '{resting}' at t = {t:.6g} s after {len(sec_t) - 1} steps: the "
                f"state starts on that guard with zero rate and presses into it (standing)"
            )
            break
        arc, fired, x_minus, status = _integrate_phase(
            funcs, solver_cls, t, x, rtol, atol, max_phase_time, method
        )
        sim.arcs.append(Arc(phase, t, arc.t_max, arc, u))
        t = arc.t_max
        if status is not None:
            sim.status = status
            sim.message = (
                f"no transition within {max_phase_time:g} s in phase "
                f"'{model.phases[phase].name}' (t = {t:.6g})"
                if status == "timeout"
                else f"integrator failed in phase '{model.phases[phase].name}' at t = {t:.6g}"
            )
            break
        if fired >= len(model.phases[phase].transitions):  # a unilateral constraint fails
            constraint = model.phases[phase].constraints[
                fired - len(model.phases[phase].transitions)
            ]
            sim.events.append(Event(t, phase, constraint.outcome, x_minus, None))
            sim.status = "fell"
            sim.message = (
                f"{constraint.outcome} at t = {t:.6g} s after {len(sec_t) - 1} steps: "
                f"'{constraint.name}' fails in phase '{model.phases[phase].name}'"
            )
            break
        tr = model.phases[phase].transitions[fired]
        if tr.terminal:
            sim.events.append(Event(t, phase, tr.name, x_minus, None))
            sim.status = "fell"
            sim.message = f"{tr.name} at t = {t:.6g} s after {len(sec_t) - 1} steps"
            break
        if feedforward is not None:  # the reset sees the input at the event
            u = np.asarray(feedforward(t - funcs._drive[1], funcs._drive[2]), dtype=float)
        x = np.asarray(tr.reset(x_minus, u, p), dtype=float).ravel()
        sim.events.append(Event(t, phase, tr.name, x_minus, x.copy()))
        closes_cycle = (phase, fired) == cycle_end or tr.returns_to_section
        phase = tr.target
        if closes_cycle:
            sec_t.append(t)
            sec_x.append(x.copy())
            if len(sec_t) - 1 < steps:
                u = policy(len(sec_t) - 1, x)
                p = parameters(len(sec_t) - 1)
        zeno = _accumulation([e.t for e in sim.events if e.state_after is not None])
        if zeno is not None and len(sec_t) - 1 < steps:
            sim.status = "standing"
            sim.accumulation_time = zeno[1]
            sim.message = (
                f"impacts accumulate (Zeno): their intervals shrink by ×{zeno[0]:.4g} each, so "
                f"infinitely many occur before t = {zeno[1]:.6g} s, where the motion comes to "
                f"rest (standing) after {len(sec_t) - 1} steps"
            )
            break
    sim.success = sim.status == "completed"
    if sim.success:
        sim.message = f"{len(sec_t) - 1} steps in {t:.6g} s"
    sim.section_times = np.array(sec_t)
    sim.section_states = np.array(sec_x) if sec_x else np.zeros((0, len(model.state_names)))
    sim.step_parameters = step_parameters
    return sim


# -- accumulation of impacts (Zeno) ------------------------------------------------------------
# A rimless wheel that rocks to rest strikes spoke after spoke with intervals shrinking by a
# constant factor (cos 2α per impact pair, Tedrake's rocking branch): infinitely many impacts in
# finite time.  Integration cannot follow it to the end (the excursions fall below the guards'
# arming threshold and the wheel would sink through the ground), so the accumulation is detected
# and the motion ends as "standing".  The test is generic, on event times only: the last
# _ZENO_WINDOW intervals (between events, or between every second event for motions that
# alternate between two contacts) shrink by a factor r < 1 that is constant to within
# _ZENO_SPREAD·(1 − r) — a transient whose intervals converge to a positive period has ratios
# tending to 1, with (1 − r) shrinking geometrically, and is not taken for one.
_ZENO_WINDOW = 5
_ZENO_SPREAD = 0.1


def _accumulation(times: list[float]) -> tuple[float, float] | None:
    """Geometric accumulation of event times: ``(ratio per event, accumulation time)`` or None.

    For lag 1 and lag 2, the intervals ``dₖ = tₖ₊L − tₖ`` (every L-th) of the last events must all
    shrink, with ratios ``rₖ = dₖ₊₁/dₖ`` within ``_ZENO_SPREAD·(1 − r̄)`` of their mean ``r̄ < 1``;
    the accumulation time is then ``t_last + d_last · r̄/(1 − r̄)`` (the geometric series)."""
    for lag in (1, 2):
        needed = lag * (_ZENO_WINDOW + 1) + 1
        if len(times) < needed:
            return None
        t = np.asarray(times[-needed:], dtype=float)[::-1][::lag][::-1]
        d = np.diff(t)
        if not np.all(d > 0):
            continue
        r = d[1:] / d[:-1]
        mean = float(np.mean(r))
        if mean < 1.0 and np.all(np.abs(r - mean) <= _ZENO_SPREAD * (1.0 - mean)):
            return mean ** (1.0 / lag), float(t[-1] + d[-1] * mean / (1.0 - mean))
    return None


def _short_excursion(funcs: _PhaseFunctions, x0: np.ndarray, armed: np.ndarray) -> float | None:
    """A step bound that lets the guard checks see a short excursion at the phase start.

    A phase that starts on a guard (a rimless wheel rocking onto a spoke at a few mm/s) may leave
    it to the armed side and come back within a fraction of one adaptive step: the checks at
    the step's interior points would miss it, and the wheel would sink through the ground.  For
    each transition that starts unarmed and moves to its armed side (signed rate ``ġ < 0``) with
    a curvature that brings it back (``g̈ > 0``), the excursion lasts about ``τ = 2|ġ|/g̈``
    (second-order Taylor); the returned bound ``τ/4`` holds until every guard is armed.  None if
    no such excursion."""
    bound = np.inf
    for k, tr in enumerate(funcs.phase.transitions):
        if armed[k]:
            continue
        rate = rate_along(funcs.phase.flow, tr.guard)
        g1 = tr.direction * float(rate(x0, funcs.u, funcs.p))
        g2 = tr.direction * float(rate_along(funcs.phase.flow, rate)(x0, funcs.u, funcs.p))
        if g1 < 0 < g2:
            bound = min(bound, 0.5 * abs(g1) / g2)
    return float(bound) if np.isfinite(bound) and bound > 0 else None


def _rests_on_guard(funcs: _PhaseFunctions, x0: np.ndarray) -> str | None:
    """The transition whose guard the state rests on, pressing into it, or None.

    A state exactly on a guard (signed value 0), with zero rate (``ġ = 0``) and an acceleration
    toward the firing side (``g̈ > 0``), is held there by the contact the guard describes (the
    rimless wheel at rest on two spokes): the limit of the accumulating impacts, reached."""
    for k, tr in enumerate(funcs.phase.transitions):
        if tr.terminal or abs(funcs.signed_guard(k, x0)) > _ARM:
            continue
        rate = rate_along(funcs.phase.flow, tr.guard)
        g1 = tr.direction * float(rate(x0, funcs.u, funcs.p))
        g2 = tr.direction * float(rate_along(funcs.phase.flow, rate)(x0, funcs.u, funcs.p))
        if abs(g1) <= _ARM and g2 > 0:
            return tr.name
    return None


def _initial_state(model: HybridModel, x0, phase: int) -> np.ndarray:
    if x0 is None:
        if phase != 0:
            raise GaitoptInputError("`x0` is required when starting outside phase 0")
        return model.lift(model.default_start())
    names = model.phases[phase].states
    if isinstance(x0, Mapping) and phase == 0 and set(x0) != set(names):
        if set(x0) <= set(model.section.coordinates):
            return model.lift(x0)
    return model.state_vector(x0, phase)


def _as_policy(model: HybridModel, inputs) -> InputPolicy:
    if callable(inputs):
        return lambda k, x: np.asarray(inputs(k, x), dtype=float).ravel()
    u = model.nominal_input() if inputs is None else np.asarray(inputs, dtype=float).ravel()
    if u.size != len(model.inputs):
        raise GaitoptInputError(
            f"`inputs` must have {len(model.inputs)} entries ({', '.join(model.inputs) or 'none'}),"
            f" got {u.size}"
        )
    return lambda k, x: u


# Interior points per integrator step where the guards are also checked (on the dense output):
# a guard excursion shorter than a step (a wheel that rocks back onto a spoke within
# milliseconds) is still seen.
_CHECKS_PER_STEP = 4


def _integrate_phase(funcs: _PhaseFunctions, solver_cls, t0, x0, rtol, atol, max_time, method):
    """Integrate one phase until an admissible directional crossing; locate it.

    A guard fires where its signed value goes from negative to non-negative after having been
    below ``-_ARM`` in this phase (strict crossings); signs are checked at the step ends and at
    ``_CHECKS_PER_STEP - 1`` interior points of each step, roots located by ``brentq`` on the
    step's dense output."""
    from scipy.integrate import OdeSolution
    from scipy.optimize import brentq

    n_tr = funcs.events
    if method == "DOP853" and funcs._drive is None:  # one CasADi call per step (same method)
        from .dop853 import CompiledDOP853

        solver = CompiledDOP853(funcs.rhs, funcs.step_function(), funcs.u, funcs.p, t0, x0,
                                t0 + max_time, rtol=rtol, atol=atol)  # fmt: skip
    else:
        kwargs = {"jac": funcs.jac} if method in ("Radau", "LSODA") else {}
        solver = solver_cls(funcs.rhs, t0, x0, t0 + max_time, rtol=rtol, atol=atol, **kwargs)
    directions = np.array(funcs._directions, dtype=float)[:, None]
    values = np.array([funcs.signed_guard(k, x0) for k in range(n_tr)], dtype=float)
    armed = values < -_ARM
    short = _short_excursion(funcs, x0, armed)
    if short is not None:
        solver.max_step = short
    ts = [t0]
    interpolants = []
    while True:
        solver.step()
        if solver.status == "failed":
            return OdeSolution(ts + [ts[-1]], interpolants or [None]), None, None, "failed"
        t_old, t_new = solver.t_old, solver.t
        dense = solver.dense_output()
        grid = np.linspace(t_old, t_new, _CHECKS_PER_STEP + 1)
        compiled = getattr(solver, "event_values", None)
        if compiled is not None:  # the event functions at the check points, from the step call
            signed = directions * compiled
        else:
            states = [dense(tt) for tt in grid[1:-1]] + [solver.y]
            signed = np.array([[funcs.signed_guard(k, x) for x in states] for k in range(n_tr)])
        best = None
        signed = np.reshape(signed, (n_tr, _CHECKS_PER_STEP))
        before = np.concatenate([values[:, None], signed[:, :-1]], axis=1)
        crossing = bool(np.any((before < 0) & (signed >= 0)))
        if not crossing:  # no sign change in this step: only the arming and the last values
            armed |= np.any(signed < -_ARM, axis=1)
            values[:] = signed[:, -1]
        for k in range(n_tr if crossing else 0):
            previous, was_armed = values[k], armed[k]
            for j in range(1, _CHECKS_PER_STEP + 1):
                current = float(signed[k, j - 1])
                if was_armed and previous < 0 <= current and compiled is not None:
                    # confirm on the dense output itself (the bracket brentq is given)
                    ends = [
                        funcs.signed_guard(k, dense(grid[j - 1])),
                        funcs.signed_guard(k, dense(grid[j]) if j < _CHECKS_PER_STEP else solver.y),
                    ]
                    previous, current = ends
                if was_armed and previous < 0 <= current:
                    t_hit = brentq(
                        lambda tt, k=k, dense=dense: funcs.signed_guard(k, dense(tt)),
                        grid[j - 1],
                        grid[j],
                        xtol=1e-15,
                        rtol=4 * np.finfo(float).eps,
                        maxiter=200,
                    )
                    x_hit = dense(t_hit)
                    if funcs.admissible(k, x_hit):
                        if best is None or t_hit < best[0]:
                            best = (t_hit, k, x_hit)
                        break
                was_armed = was_armed or current < -_ARM
                previous = current
            armed[k] = was_armed
            values[k] = previous
        interpolants.append(dense)
        if short is not None and (
            np.all(armed[: len(funcs.phase.transitions)]) or t_new - t0 > 8 * short
        ):
            solver.max_step, short = np.inf, None  # the excursion is over: full steps
        if best is not None:
            ts.append(best[0])
            return OdeSolution(ts, interpolants), best[1], best[2], None
        ts.append(t_new)
        if solver.status == "finished":
            return OdeSolution(ts, interpolants), None, None, "timeout"
