"""The offset law's closed loop as the simulator runs it: controlled and uncontrolled runs from
perturbed states, the constraints sampled densely with the applied input ``u*(t) + δₖ``, and the
closed-loop map measured by central differences."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...files import jsonable
from ...simulation import Simulation
from ..result import OptimalGait
from .linearise import FD_STEP, central_differences, section_point, simulate_offsets

__all__ = ["ClosedLoopTrial", "run", "dense_check", "measured_closed_loop"]

_SAMPLES = 200  # per arc, for the dense check of the constraints with the applied input


@dataclass
class ClosedLoopTrial:
    """The walker from one perturbed state, with and without the offset law.

    Attributes
    ----------
    start : dict of str to float
        Section coordinates of the start.
    errors : list of float
        Controlled: max-norm distance of each return (per orbit) from the fixed point, the start
        first (section units).
    offsets : list of list of float
        The offsets ``δₖ`` applied (input units), one per orbit.
    status, message : str
        The controlled simulation's status (``"completed"``) and message.
    open_loop_errors : list of float
        Uncontrolled (``δ = 0``), from the same start.
    open_loop_status, open_loop_message : str
        The uncontrolled simulation's status (``"fell"`` where it fails) and message.
    constraint_margin : float or None
        Least value of the phases' unilateral constraints sampled densely along the controlled
        run with the applied input (constraint units; ≥ 0 required).
    input_peak : list of float
        Largest ``|u*(t) + δₖ|`` applied per input (input units).
    """

    start: dict[str, float]
    errors: list[float]
    offsets: list[list[float]]
    status: str
    message: str
    open_loop_errors: list[float]
    open_loop_status: str
    open_loop_message: str
    constraint_margin: float | None
    input_peak: list[float]

    @property
    def converged(self) -> bool:
        """The controlled run completed and ended within ``1e-3`` of its initial error."""
        return (
            self.status == "completed"
            and len(self.errors) > 1
            and self.errors[-1] <= 1e-3 * self.errors[0]
        )

    @property
    def open_loop_diverged(self) -> bool:
        """The uncontrolled run fell, or ended farther from the fixed point than it began."""
        return self.open_loop_status != "completed" or self.open_loop_errors[-1] > self.errors[0]

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types."""
        return jsonable(
            {
                "start": self.start,
                "errors": self.errors,
                "offsets": self.offsets,
                "status": self.status,
                "message": self.message,
                "converged": self.converged,
                "constraint_margin": self.constraint_margin,
                "input_peak": self.input_peak,
                "open_loop_errors": self.open_loop_errors,
                "open_loop_status": self.open_loop_status,
                "open_loop_message": self.open_loop_message,
                "open_loop_diverged": self.open_loop_diverged,
            }
        )


def run(
    gait: OptimalGait, s0: np.ndarray, gain: np.ndarray | None, orbits: int
) -> tuple[Simulation, dict[int, np.ndarray], list[float]]:
    """Simulate ``orbits`` orbits from ``s0`` with ``δ = −K (s − s*)`` decided at each orbit's
    section (``gain`` None: δ = 0); the errors at each orbit's return."""
    model = gait.model
    s_star = section_point(gait)
    per = int(gait.problem.get("steps", 1))
    n_u = len(model.inputs)
    offsets: dict[int, np.ndarray] = {}

    def policy(k: int, x: np.ndarray) -> np.ndarray:
        if k % per == 0:
            ds = model.section_coordinates_of(x) - s_star
            offsets[k] = -(gain @ ds) if gain is not None else np.zeros(n_u)
        else:
            offsets[k] = offsets[k - 1]
        # Guards and constraints see the step's constant input in the simulator: zero, as in
        # the optimum's own verification; the constraints are re-checked below with u*(t) + δ.
        return np.zeros(n_u)

    sim = simulate_offsets(gait, s0, offsets, orbits * per, inputs=policy)
    states = sim.section_states[::per]
    errors = [float(np.max(np.abs(model.section_coordinates_of(x) - s_star))) for x in states]
    return sim, offsets, errors


def dense_check(
    gait: OptimalGait, sim: Simulation, offsets: dict[int, np.ndarray]
) -> tuple[float | None, np.ndarray]:
    """Least constraint value along the run, sampled with the applied input, and the largest
    ``|u|`` per input."""
    model = gait.model
    p = model.p
    times = list(sim.section_times)
    margin: float | None = None
    peak = np.zeros(len(model.inputs))
    for arc in sim.arcs:
        k = max(int(np.searchsorted(times, arc.t0, side="right")) - 1, 0)
        ts = np.linspace(arc.t0, arc.t1, _SAMPLES)
        xs = np.atleast_2d(arc.solution(ts))
        us = np.array([gait.feedforward(t - times[k], k) + offsets[k] for t in ts]).T
        peak = np.maximum(peak, np.max(np.abs(us), axis=1))
        for c in model.phases[arc.phase].constraints:
            values = np.asarray(c.function.map(_SAMPLES)(xs, us, p), dtype=float).ravel()
            # At a phase's ends a constraint may vanish by design (a foot touching down).
            inner = values[1 if c.at_start else 0 : _SAMPLES - 1 if c.at_end else _SAMPLES]
            if inner.size:
                low = float(np.min(inner))
                margin = low if margin is None else min(margin, low)
    return margin, peak


def measured_closed_loop(
    gait: OptimalGait, gain: np.ndarray, h: float = FD_STEP
) -> np.ndarray | None:
    """``∂s'/∂s`` of one simulated controlled orbit, by central differences (the closed loop
    as the simulator runs it)."""
    s_star = section_point(gait)

    def end_of(s: np.ndarray) -> np.ndarray | None:
        sim, _, _ = run(gait, s, gain, 1)
        return gait.model.section_coordinates_of(sim.section_states[-1]) if sim.success else None

    return central_differences(end_of, s_star, s_star.size, h)
