"""Independent hybrid simulation: SciPy's adaptive integrators with located, directional events.

This is deliberately independent of the shooting integrator (adaptive steps and event location
here, fixed-step shooting with guard constraints there), so each can check the other.

The loop is SciPy's ``solve_ivp`` event logic (step, check signs, locate the root with ``brentq``
on the step's dense output), driving SciPy's DOP853 (:class:`gaitopt.dop853.CompiledDOP853`: its
frame restated in :mod:`gaitopt.dop853_base`, so that ``scipy.integrate`` is not imported; or
another SciPy ``OdeSolver``) step by step, with two additions that hybrid walking models need:

* *strict crossings*: a guard fires only after it has been strictly on its pre-crossing side in
  this phase (a phase that starts on a guard, such as Van der Pol's section, does not fire at
  once — the case ``solve_ivp`` fires at ``t0``);
* *admissibility*: a crossing where the model's rule says it is spurious (the compass gait's
  mid-swing foot scuff) is ignored and integration goes on.

After a reset the integration restarts in the target phase.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from .phase import PhaseFunctions, _Buffered, _rests_on_guard, integrate_phase
from .result import Arc, Event, Simulation
from .zeno import accumulation

__all__ = ["simulate", "simulate_task", "simulate_batch", "Simulation", "Arc", "Event"]


def simulate_batch(*args: Any, **kwargs: Any):
    """Many starts simulated together: :func:`gaitopt.simulation.batch.simulate_batch`."""
    from .batch import simulate_batch as run

    return run(*args, **kwargs)


#: SciPy's ``OdeSolver`` classes by name (``scipy.integrate`` is imported on first use: 0.4 s).
_METHODS = ("DOP853", "RK45", "Radau", "LSODA")

#: Per thread, the :class:`PhaseFunctions` (with their buffers and compiled arc plans) of the
#: last constant-input phases simulated by compiled arcs: a solve simulates the same phases
#: twice (its guess and its referee), a continuation at every point; their construction is most
#: of a short simulation's Python.  Reused as a simulation reuses them from one step to the next.
_PHASES = threading.local()
_MAX_PHASES = 64


def _phase_functions(model, phase: int, u, p, constraints: bool, compiled: bool):
    """``PhaseFunctions(model.phases[phase], u, p, constraints, type(model), phase)``, kept per
    thread for compiled arcs (see :data:`_PHASES`)."""
    if not compiled:
        return PhaseFunctions(model.phases[phase], u, p, constraints, type(model), phase)
    cache = getattr(_PHASES, "cache", None)
    if cache is None:
        cache = _PHASES.cache = {}
    ph = model.phases[phase]
    key = (type(model), id(ph), phase, bool(constraints),
           np.asarray(u, dtype=float).tobytes(), np.asarray(p, dtype=float).tobytes())  # fmt: skip
    entry = cache.get(key)
    if entry is None:
        if len(cache) >= _MAX_PHASES:
            cache.pop(next(iter(cache)))
        u, p = np.array(u, dtype=float), np.array(p, dtype=float)  # its own: kept past this call
        entry = cache[key] = (PhaseFunctions(ph, u, p, constraints, type(model), phase), ph)
    return entry[0]


InputPolicy = Callable[[int, np.ndarray], np.ndarray]
#: ``feedback(t, x, phase, step) -> u``: a state-feedback input law (see :func:`simulate`).
Feedback = Callable[[float, np.ndarray, int, int], np.ndarray]
#: ``terrain(step) -> {parameter: value}``: parameters changed for one step (rough ground).
Terrain = Callable[[int], Mapping[str, float]]


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
    feedback: Feedback | None = None,
    backend: str = "auto",
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
        if a step lasts longer).  It replaces ``inputs`` in the flow, the resets, the guards,
        admissibility rules and unilateral constraints, each of which sees the input at its
        instant.  With ``method="DOP853"``, a feedforward that also has
        ``vectorised(t, step)`` (inputs × ``len(t)`` for an array ``t``, equal to calling it at
        each) is evaluated at a step's stage times at once and each step is one CasADi call
        (about 10× faster); with ``breaks(step)`` too (the times since the section where the
        input may jump, e.g. a piecewise-polynomial profile's breakpoints) no integrator step
        crosses one (:func:`gaitopt.optimize.verify.feedforward_of` makes such a feedforward).
        A plain callable is called once per stage in Python (same events, same semantics).
    feedback : callable, optional
        ``feedback(t, x, phase, step) -> u``: a state feedback, ``t`` the time since the last
        return to the section (s), ``x`` the state of phase ``phase`` and ``step`` the number of
        returns so far (a transverse LQR's law, :mod:`gaitopt.transverse`).  Like a
        feedforward it replaces ``inputs`` in the flow, the resets (evaluated at the state just
        before the reset), the guards, admissibility rules and unilateral constraints, each of
        which sees the input at its instant and state; each phase is integrated by SciPy's
        stepper with the law called once per stage in Python.  Not with ``feedforward`` (a law
        that needs one includes it).  :attr:`Arc.u` records the input at the arc's start.
    backend : str
        ``"compiled"``: each phase (arc) is integrated in one call of compiled C
        (:mod:`gaitopt.simulation.compiled`: the same DOP853 steps, event checks and root
        location as the Python loop, events equal to 1e-12; ``python -m bench.simulate``
        measures both); ``"python"``: SciPy's stepper driven from Python; ``"auto"``
        (default): compiled where it applies (``method "DOP853"``, no ``feedforward`` or
        ``feedback``, a C compiler present), else Python.

    Returns
    -------
    Simulation
    """
    # -- arguments: every check before any work (bad input fails fast) -------------------------
    from ..arguments import check_count, check_inputs, check_positive, check_start
    from ..errors import MAX_SIMULATION_STEPS
    from ..models import as_model

    model = as_model(model)
    if feedback is not None and (feedforward is not None or not callable(feedback)):
        raise GaitoptInputError(
            "`feedback` must be a callable feedback(t, x, phase, step) -> u, and not given "
            "with `feedforward` (include the feedforward in the law)"
        )
    if method not in _METHODS:
        raise GaitoptInputError(f"`method` must be one of {', '.join(_METHODS)}, got {method!r}")
    steps = check_count(
        "steps", steps, 0, MAX_SIMULATION_STEPS, "time and memory grow with every step "
        "(gaitopt.errors.MAX_SIMULATION_STEPS); simulate in pieces, each from the last state"
    )  # fmt: skip
    phase = check_count("phase", phase, 0, len(model.phases) - 1, f"{model.name} has "
                        f"{len(model.phases)} phase(s), numbered from 0")  # fmt: skip
    rtol, atol = check_positive("rtol", rtol, "1e-11"), check_positive("atol", atol, "1e-12")
    library = _arc_library(model, backend, method, feedforward, feedback)
    if library is not None:  # each arc one compiled call (no scipy.integrate: compiled.py)
        from .compiled import arc_plan, integrate_arc, rests_on_guard, violated_at_start
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

    # SciPy's stepper class: imported by integrate_phase only where it runs (scipy.integrate:
    # 0.3–0.5 s); DOP853 with a constant or vectorised input needs none (gaitopt.dop853)
    solver_cls = None

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
    known: dict[tuple[int, bytes, bytes], PhaseFunctions] = {}
    while len(sec_t) - 1 < steps or (phase != 0 and steps > 0):
        step_now = max(len(sec_t) - 1, 0)
        if feedback is not None:  # the input at the phase start (for the start's checks)
            u = np.asarray(feedback(t - (sec_t[-1] if sec_t else 0.0), x, phase, step_now),
                           dtype=float).ravel()  # fmt: skip
        if feedback is None and feedforward is None:  # a phase's functions at fixed u and p
            key = (phase, np.asarray(u, dtype=float).tobytes(), np.asarray(p).tobytes())
            funcs = known.get(key)
            if funcs is None:
                funcs = known[key] = _phase_functions(
                    model, phase, u, p, constraints, library is not None
                )
        else:
            funcs = PhaseFunctions(model.phases[phase], u, p, constraints, type(model), phase)
        if feedback is not None:
            funcs._feedback = (feedback, sec_t[-1] if sec_t else 0.0, step_now, phase)
        elif feedforward is not None:  # the flow gets its own input buffer, rewritten per call
            funcs._flow = _Buffered(model.phases[phase].flow, np.array(u, dtype=float), p)
            funcs._drive = (feedforward, sec_t[-1] if sec_t else 0.0, max(len(sec_t) - 1, 0))
        if library is not None:
            at_start = violated_at_start(funcs, library, phase, x)
        else:
            at_start = funcs.violated_at_start(x, t)
        if at_start is not None:
            constraint = model.phases[phase].constraints[at_start[0] - len(funcs.phase.transitions)]
            sim.events.append(Event(t, phase, constraint.outcome, x.copy(), None))
            sim.status = "fell"
            sim.message = (
                f"{constraint.outcome} at t = {t:.6g} s after {len(sec_t) - 1} steps: "
                f"{at_start[1]} in phase '{model.phases[phase].name}'"
            )
            break
        if library is not None:
            resting = rests_on_guard(funcs, library, phase, x)
        else:
            resting = _rests_on_guard(funcs, x)
        if resting is not None and len(sec_t) - 1 < steps:
            sim.status = "standing"
            sim.accumulation_time = t
            sim.message = (
                f"at rest against '{resting}' at t = {t:.6g} s after {len(sec_t) - 1} steps: the "
                f"state starts on that guard with zero rate and presses into it (standing)"
            )
            break
        if library is not None:  # the whole arc in one compiled call
            arc, fired, x_minus, status = integrate_arc(
                funcs, library, phase, t, x, rtol, atol, max_phase_time
            )
        else:
            arc, fired, x_minus, status = integrate_phase(
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
        if feedback is not None:  # the reset sees the law's input at the state before it
            u = funcs.feedback_input(t, x_minus)
        elif feedforward is not None:  # the reset sees the input at the event
            u = np.asarray(feedforward(t - funcs._drive[1], funcs._drive[2]), dtype=float)
        if library is not None:
            x = arc_plan(funcs, library, phase).reset(fired, x_minus)
        else:
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
        zeno = accumulation([e.t for e in sim.events if e.state_after is not None])
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


_BACKENDS = ("auto", "compiled", "python")


def _arc_library(model: HybridModel, backend: str, method: str, feedforward, feedback):
    """The model class's compiled arc library where ``backend`` asks for it and it applies,
    else None (the Python loop)."""
    if backend not in _BACKENDS:
        raise GaitoptInputError(f"`backend` must be one of {', '.join(_BACKENDS)}, got {backend!r}")
    if backend == "python":
        return None
    if method != "DOP853" or feedforward is not None or feedback is not None:
        if backend == "compiled":
            raise GaitoptInputError(
                f"`backend` 'compiled' needs method 'DOP853' and no feedforward or feedback "
                f"(got method {method!r}); use backend='auto', which simulates those in Python"
            )
        return None
    from ..kernels.arcs import arc_library

    library = arc_library(type(model))
    if library is None and backend == "compiled":
        raise GaitoptInputError(
            f"`backend` 'compiled': no compiled arc library for {model.name} (no C compiler: "
            f"$GAITOPT_CC, default gcc, or GAITOPT_COMPILE=0); use backend='auto' or 'python'"
        )
    return library


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


def simulate_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Simulate ``point["steps"]`` steps (a task of :func:`gaitopt.sweep.sweep`): ``{"model",
    "params", "x0": {...}, "steps": N, "record": K, "backend": B}`` → status, steps completed and
    the last ``K`` section states (``backend`` as in :func:`simulate`, default ``"auto"``)."""
    from ..models import model as make_model

    model = make_model(point["model"], **point.get("params", {}))
    backend = str(point.get("backend", "auto"))
    sim = simulate(model, point.get("x0"), steps=int(point["steps"]), backend=backend)
    keep = int(point.get("record", 1))
    return {
        "success": sim.success,
        "status": sim.status,
        "steps": sim.steps,
        "states": sim.section_states[-keep:].tolist() if sim.steps else [],
        "times": np.diff(sim.section_times)[-keep:].tolist() if sim.steps else [],
    }
