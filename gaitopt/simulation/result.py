"""What a simulation returns: :class:`Simulation`, its :class:`Arc` (one phase each) and its
:class:`Event` (each transition, with the states before and after)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from scipy.integrate import OdeSolution

__all__ = ["Arc", "Event", "Simulation"]


@dataclass
class Arc:
    """One phase of a simulated trajectory.

    Attributes
    ----------
    phase : int
        Index of the phase in ``model.phases``.
    t0, t1 : float
        Start and end time (s).
    solution : OdeSolution-like
        Dense output on ``[t0, t1]``: ``solution(t)`` is the state at ``t`` (s) or, for a 1-D
        ``t``, states × times, with SciPy's ``OdeSolution`` attributes ``ts``,
        ``interpolants``, ``t_min``, ``t_max`` (:mod:`gaitopt.simulation.dense`, which restates
        SciPy's classes to the bit).
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
