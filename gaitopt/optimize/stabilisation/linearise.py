"""The offset linearisation ``sₖ₊₁ − s* = A (sₖ − s*) + B δₖ`` of an optimal gait's return map:
``A`` and ``B`` by AD through the Radau transcription (:mod:`gaitopt.orbit.sensitivity`'s
construction, as the floquet module's, with the offset ``δ`` as an extra unknown; Hiskens & Pai
2000), ``B`` also by central differences of the independent event-located simulator."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...orbit.sensitivity import collocated_return_map
from ...simulation import Simulation, simulate
from ..collocation import Collocation
from ..floquet import collocated_arcs
from ..result import OptimalGait
from ..verify import feedforward_of

__all__ = [
    "offset_jacobian",
    "offset_jacobian_fd",
    "central_differences",
    "simulate_offsets",
    "section_point",
    "FD_STEP",
]

FD_STEP = 1e-6  # central differences of the simulated map (section units, input units)


def offset_jacobian(col: Collocation, w: np.ndarray, p_model: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(A, B)``: the orbit's return map differentiated in the section coordinates and in an
    input offset held over the orbit, by AD through the transcription.

    Parameters
    ----------
    col : Collocation
        The final transcription of the optimum.
    w : numpy.ndarray
        Its solution.
    p_model : numpy.ndarray
        The model's parameter vector.

    Returns
    -------
    A : numpy.ndarray
        ``∂P/∂s`` (m × m, section coordinates); the same as
        :func:`~gaitopt.optimize.floquet.return_map_jacobian`.
    B : numpy.ndarray
        ``∂P/∂δ`` (m × n_u: section units per input unit).
    """
    arcs, L, p = collocated_arcs(col, w, p_model)
    return collocated_return_map(arcs, L, col.section_index, p, offset=True)


class _Offset:
    """``u*(t) + δₖ`` for :func:`gaitopt.simulate` (``k`` the returns so far; ``offsets[k]`` read
    when step ``k`` runs, so a policy may fill it in as the run goes), vectorised like the
    optimum's own feedforward (one CasADi call per integrator step)."""

    def __init__(self, gait: OptimalGait, offsets: dict[int, np.ndarray]):
        self.base = feedforward_of(gait.profiles)
        self.offsets = offsets

    def __call__(self, t: float, k: int) -> np.ndarray:
        return self.base(t, k) + self.offsets[k]

    def vectorised(self, times: np.ndarray, k: int) -> np.ndarray:
        return self.base.vectorised(times, k) + np.asarray(self.offsets[k], dtype=float)[:, None]

    def breaks(self, k: int) -> np.ndarray:
        return self.base.breaks(k)


def _feedforward(
    gait: OptimalGait, offsets: dict[int, np.ndarray]
) -> Callable[[float, int], np.ndarray]:
    """``u*(t) + δₖ`` for :func:`gaitopt.simulate` (see :class:`_Offset`)."""
    return _Offset(gait, offsets)


def simulate_offsets(
    gait: OptimalGait,
    s: np.ndarray,
    offsets: dict[int, np.ndarray],
    steps: int,
    inputs: Callable[[int, np.ndarray], np.ndarray] | None = None,
) -> Simulation:
    """``steps`` returns simulated from the section point ``s`` with ``u*(t) + δₖ`` applied
    (``offsets[k]``: given, or filled in by an ``inputs`` policy as the run goes)."""
    model = gait.model
    return simulate(
        model,
        model.lift(s),
        steps=steps,
        inputs=inputs,
        feedforward=_feedforward(gait, offsets),
        rtol=1e-12,
        atol=1e-13,
        max_phase_time=_max_phase_time(gait),
    )


def _max_phase_time(gait: OptimalGait) -> float:
    """The simulator's limit on a phase's duration: ten times the optimum's longest (s)."""
    return 10.0 * float(np.max(gait.durations)) + 1.0


def offset_jacobian_fd(gait: OptimalGait, h: float = FD_STEP) -> np.ndarray | None:
    """``∂P/∂δ`` by central differences of the simulated orbit map (None if a perturbed
    simulation does not complete)."""
    model = gait.model
    s_star = section_point(gait)
    steps = int(gait.problem.get("steps", 1))

    def end_of(delta: np.ndarray) -> np.ndarray | None:
        sim = simulate_offsets(gait, s_star, {k: delta for k in range(steps + 1)}, steps)
        return model.section_coordinates_of(sim.section_states[-1]) if sim.success else None

    return central_differences(end_of, np.zeros(len(model.inputs)), s_star.size, h)


def central_differences(
    end_of: Callable[[np.ndarray], np.ndarray | None], x0: np.ndarray, rows: int, h: float
) -> np.ndarray | None:
    """Jacobian (``rows`` × ``x0.size``) of a simulated map at ``x0`` by central differences,
    ``(end_of(x0 + h eⱼ) − end_of(x0 − h eⱼ)) / 2h``; None as soon as ``end_of`` returns None (a
    perturbed simulation did not complete)."""
    J = np.zeros((rows, x0.size))
    for j in range(x0.size):
        ends = []
        for sign in (1.0, -1.0):
            x = x0.copy()
            x[j] += sign * h
            end = end_of(x)
            if end is None:
                return None
            ends.append(end)
        J[:, j] = (ends[0] - ends[1]) / (2 * h)
    return J


def section_point(gait: OptimalGait) -> np.ndarray:
    """The optimum's fixed point in section coordinates."""
    model = gait.model
    return np.asarray(model.section_coordinates_of(model.state_vector(gait.fixed_point)))
