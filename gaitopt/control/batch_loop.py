"""Many closed-loop runs stepped together: :func:`closed_loop_batch`.

The loop of :func:`gaitopt.control.closed_loop` (a step-to-step policy deciding each step's input
at the section, a terrain changing each step's ground parameter) for N starts at once: each step,
the policy is evaluated for every start still running — in one array operation where the policy
is linear (open loop, LQR, pole placement: ``u = clip(u* − K (s − s*))``) or says it can
(``policy.batch(step, states) -> inputs``), else start by start (the deadbeat rootfinder, a blind
swing-leg law) —, each start's ground for that step is read from its own terrain, and one
:func:`gaitopt.simulation.batch.simulate_batch` call with ``steps=1`` advances every running
start by one step with its own input and parameters (compiled: one C call for all of them).
Starts that fall (or stand, time out, fail) are recorded with the reason and dropped.

It is the same simulation as :func:`closed_loop` — the same DOP853 control, events and resets
with each step's input and parameters — except that each step is integrated from time 0 (a
one-step call) where :func:`closed_loop` carries the time on: the floating-point sums of the
step times differ in their last bits, so the states agree to the integrator's tolerance, not bit
for bit (the tests check 1e-9), and an accumulation of impacts is looked for within a step only.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from .policy import StepController

__all__ = ["closed_loop_batch", "ClosedLoopBatch"]

Terrain = Callable[[int], Mapping[str, float]]


@dataclass
class ClosedLoopBatch:
    """What :func:`closed_loop_batch` returns: one row per start (columnar).

    Attributes
    ----------
    model : HybridModel
        The model simulated.
    status : numpy.ndarray of str
        Per start: ``"completed"`` (every step), ``"fell"`` (:attr:`outcome` names the event),
        ``"standing"``, ``"timeout"``, ``"failed"`` (integrator) or ``"invalid start"``.
    outcome : numpy.ndarray of str
        The terminal event's name for ``"fell"``, else ``""``.
    survived : numpy.ndarray of int
        Returns to the section completed per start (as :attr:`ClosedLoopRun.survived`).
    section : numpy.ndarray
        ``N × (steps + 1) × m`` section coordinates at each return (the start first), NaN after
        the last.
    states : numpy.ndarray
        ``N × (steps + 1) × n`` the phase-0 states there.
    times : numpy.ndarray
        ``N × (steps + 1)`` times of the returns (s), NaN after the last.
    errors : numpy.ndarray
        ``N × (steps + 1)``: max-norm distance of each return from the target, NaN after the last.
    inputs : numpy.ndarray
        ``N × steps × n_u``: the input applied at each step, NaN where no step was taken.
    t_end : numpy.ndarray
        Time (s) where each run ended.
    phase_end : numpy.ndarray of int
        Phase in which it ended.
    target : numpy.ndarray
        The section point the errors are measured from.
    elapsed : float
        Wall-clock seconds.
    settings : dict
        ``steps``, ``backend`` (of the batch simulation), ``policy_seconds`` (time in the
        policy), ``simulation_seconds``.
    """

    model: HybridModel
    status: np.ndarray
    outcome: np.ndarray
    survived: np.ndarray
    section: np.ndarray
    states: np.ndarray
    times: np.ndarray
    errors: np.ndarray
    inputs: np.ndarray
    t_end: np.ndarray
    phase_end: np.ndarray
    target: np.ndarray
    elapsed: float = 0.0
    settings: dict[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.status)

    @property
    def success(self) -> np.ndarray:
        """Per start: every step was completed."""
        return self.status == "completed"

    def message(self, i: int) -> str:
        """One run's end in words (as :attr:`gaitopt.Simulation.message` says it)."""
        status, k, t = str(self.status[i]), int(self.survived[i]), float(self.t_end[i])
        phase = self.model.phases[int(self.phase_end[i])].name
        if status == "fell":
            return f"{self.outcome[i]} at t = {t:.6g} s after {k} steps"
        if status == "standing":
            return f"at rest (standing) at t = {t:.6g} s after {k} steps"
        from ..simulation.batch import end_message

        return end_message(status, k, t, phase)

    def apex_errors(self, skip: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Per start, the RMS and the largest error over the returns after the first ``skip``
        (NaN where there are none): the rough-terrain study's columns."""
        e = self.errors[:, skip:]
        counted = np.isfinite(e)
        n = counted.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            rms = np.sqrt(np.where(counted, e**2, 0.0).sum(axis=1) / n)
        peak = np.where(n > 0, np.max(np.where(counted, e, -np.inf), axis=1), np.nan)
        return np.where(n > 0, rms, np.nan), peak


def closed_loop_batch(
    controller: StepController | Callable[[int, np.ndarray], np.ndarray] | np.ndarray | None,
    model: HybridModel,
    starts: Sequence[Sequence[float]] | np.ndarray,
    *,
    steps: int = 20,
    terrain: Terrain | Sequence[Terrain | None] | None = None,
    target: np.ndarray | None = None,
    full_state: bool = False,
    backend: str = "auto",
) -> ClosedLoopBatch:
    """:func:`gaitopt.control.closed_loop` for N starts at once, each with its own terrain.

    Parameters
    ----------
    controller : StepController, callable, array_like or None
        The policy ``u = controller(step, x)`` (``x`` the phase-0 state at the section), a
        constant input, or ``None`` (the model's nominal input).  A linear
        :class:`StepController` (LQR, acker) is evaluated for all starts in one array operation,
        as is any policy with a method ``batch(step, states) -> inputs`` (rows); others
        (deadbeat, :class:`gaitopt.terrain.BlindPolicy`) are called start by start.
    model : HybridModel
        The model simulated.
    starts : array_like
        N rows: section coordinates (or, with ``full_state``, phase-0 states).
    steps : int
        Returns to the section to simulate.
    terrain : callable or sequence, optional
        ``terrain(step) -> {parameter: value}`` for every start, or one such callable (or None)
        per start (:func:`gaitopt.terrain.random_terrain` with a seed each): those parameters
        hold for that step, as in :func:`gaitopt.simulate`.
    target : array_like, optional
        Section point the errors are measured from; default the controller's target (required
        when ``controller`` is not a :class:`StepController`).
    full_state : bool
        Whether ``starts`` are full phase-0 states.
    backend : str
        Of :func:`gaitopt.simulation.batch.simulate_batch`.

    Returns
    -------
    ClosedLoopBatch
    """
    from ..arguments import check_count
    from ..errors import MAX_SIMULATION_STEPS
    from ..models import as_model
    from ..simulation.batch import simulate_batch

    started = time.perf_counter()
    model = as_model(model)
    steps = check_count("steps", steps, 0, MAX_SIMULATION_STEPS, "simulate in pieces")
    if target is None:
        if not isinstance(controller, StepController):
            raise GaitoptInputError("`target` is needed when `controller` is not a StepController")
        target = controller.target
    coords = model.section.coordinates
    target = np.asarray(target, dtype=float).ravel()
    if target.size != len(coords) or not np.all(np.isfinite(target)):
        raise GaitoptInputError(
            f"`target` must be {len(coords)} finite section coordinates ({', '.join(coords)}), "
            f"got {np.asarray(target).tolist()!r}"
        )
    # the starts lifted to phase-0 states (a zero-step batch: its first section state)
    first = simulate_batch(model, starts, steps=0, full_state=full_state, backend=backend)
    N, n = len(first), model.phases[0].n
    terrains = _terrains(terrain, N)
    policy = _policy(controller, model)
    pick = [model.state_names.index(c) for c in coords]
    n_u = len(model.inputs)
    status = np.where(first.status == "invalid start", first.status, "completed").astype(object)
    outcome = np.full(N, "", dtype=object)
    states = np.full((N, steps + 1, n), np.nan)
    times = np.full((N, steps + 1), np.nan)
    inputs = np.full((N, steps, n_u), np.nan)
    survived = np.zeros(N, dtype=int)
    t_end, phase_end = np.zeros(N), np.zeros(N, dtype=int)
    states[:, 0], times[:, 0] = first.section_states[:, 0], 0.0
    live = np.flatnonzero(status == "completed")
    spent = {"policy": 0.0, "simulation": 0.0}
    names = [s.name for s in model.parameter_specs()]
    chosen = "numpy"
    for k in range(steps):
        if not live.size:
            break
        x = states[live, k]
        clock = time.perf_counter()
        u = policy(k, x)
        spent["policy"] += time.perf_counter() - clock
        if u.shape != (live.size, n_u) or not np.all(np.isfinite(u)):
            raise GaitoptInputError(
                f"`controller` must give {n_u} finite inputs ({', '.join(model.inputs)}) per "
                f"start, got {np.asarray(u).tolist()!r} at step {k}"
            )
        p = _step_parameters(model, names, terrains, live, k)
        clock = time.perf_counter()
        sim = simulate_batch(model, x, steps=1, inputs=u, params=p, full_state=True,
                             backend=backend)  # fmt: skip
        spent["simulation"] += time.perf_counter() - clock
        chosen = sim.settings["backend"]
        inputs[live, k] = u
        ok = sim.status == "completed"
        done, gone = live[ok], live[~ok]
        states[done, k + 1] = sim.section_states[ok, 1]
        times[done, k + 1] = times[done, k] + sim.section_times[ok, 1]
        survived[done] = k + 1
        status[gone], outcome[gone] = sim.status[~ok], sim.outcome[~ok]
        t_end[gone] = times[gone, k] + sim.t_end[~ok]
        phase_end[gone] = sim.phase_end[~ok]
        live = done
    t_end[live] = times[live, survived[live]]
    section = states[:, :, pick]
    with np.errstate(invalid="ignore"):
        errors = np.max(np.abs(section - target), axis=2)
    return ClosedLoopBatch(
        model=model,
        status=status.astype(str),
        outcome=outcome.astype(str),
        survived=survived,
        section=section,
        states=states,
        times=times,
        errors=errors,
        inputs=inputs,
        t_end=t_end,
        phase_end=phase_end,
        target=target,
        elapsed=time.perf_counter() - started,
        settings={
            "steps": steps,
            "backend": chosen,
            "policy_seconds": spent["policy"],
            "simulation_seconds": spent["simulation"],
        },  # fmt: skip
    )


def _terrains(terrain, n: int) -> list:
    """One terrain (or None) per start."""
    if terrain is None or callable(terrain):
        return [terrain] * n
    if isinstance(terrain, (str, bytes, Mapping)) or not isinstance(terrain, Sequence):
        raise GaitoptInputError(
            f"`terrain` must be a callable terrain(step) -> {{parameter: value}}, or one (or None) "
            f"per start, got {type(terrain).__name__}"
        )
    terrains = list(terrain)
    if len(terrains) != n or not all(t is None or callable(t) for t in terrains):
        raise GaitoptInputError(
            f"`terrain` must give one callable (or None) per start: {n}, got {len(terrains)} "
            f"entries"
        )
    return terrains


def _step_parameters(model, names, terrains, live, k):
    """The parameter rows of the running starts for step ``k`` (each start's terrain), or None
    where no start has a terrain."""
    if all(terrains[i] is None for i in live):
        return None
    rows = np.tile(model.p, (live.size, 1))
    for r, i in enumerate(live):
        if terrains[i] is None:
            continue
        for key, value in dict(terrains[i](k)).items():
            if key not in names:
                raise GaitoptInputError(
                    f"`terrain` returned unknown parameter {key!r} at step {k}; "
                    f"{model.name}'s parameters: {', '.join(names)}"
                )
            rows[r, names.index(key)] = float(value)
    return rows


def _policy(controller, model) -> Callable[[int, np.ndarray], np.ndarray]:
    """``inputs(step, states) -> rows``: the controller evaluated for many starts."""
    n_u = len(model.inputs)
    if controller is None or not callable(controller):
        u = model.nominal_input() if controller is None else np.asarray(controller, float).ravel()
        if u.size != n_u:
            raise GaitoptInputError(
                f"`controller` as a constant input must have {n_u} entries "
                f"({', '.join(model.inputs) or 'none'}), got {u.size}"
            )
        return lambda k, x: np.tile(u, (x.shape[0], 1))
    if isinstance(controller, StepController) and controller.deadbeat_solver is None:
        c = controller
        pick = [c.model.state_names.index(name) for name in c.model.section.coordinates]

        def linear(k: int, x: np.ndarray) -> np.ndarray:
            # StepController.decide: u = clip(u* − K (s − s*)), every row at once
            u = c.nominal_input[None, :] - (x[:, pick] - c.target[None, :]) @ c.gain.T
            return u if c.input_limits is None else np.clip(u, *c.input_limits)

        return linear
    batch = getattr(controller, "batch", None)
    if callable(batch):
        return lambda k, x: np.asarray(batch(k, x), dtype=float).reshape(x.shape[0], n_u)

    def each(k: int, x: np.ndarray) -> np.ndarray:
        out = np.empty((x.shape[0], n_u))
        for r in range(x.shape[0]):
            u = np.asarray(controller(k, x[r]), dtype=float).ravel()
            if u.size != n_u:
                raise GaitoptInputError(
                    f"`controller` must give {n_u} inputs ({', '.join(model.inputs)}), got "
                    f"{u.tolist()!r} at step {k}"
                )
            out[r] = u
        return out

    return each
