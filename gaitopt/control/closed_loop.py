"""Closed-loop simulation of a controller, with the errors and inputs of each step."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..simulation import Simulation, simulate
from .policy import StepController


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
