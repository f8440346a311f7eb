"""The result of :func:`~gaitopt.optimize.stabilisation.stabilise`: :class:`Stabilisation`, an
optimal gait stabilised by a per-step input offset or why it is not, and its JSON."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...files import jsonable
from ...stability import is_stable
from ..result import OptimalGait
from .closed_loop import ClosedLoopTrial

__all__ = ["Stabilisation"]


@dataclass
class Stabilisation:
    """An optimal gait stabilised by a per-step input offset, or why it is not.

    Attributes
    ----------
    success : bool
        True only if the AD and FD linearisations agree, the closed-loop multipliers are inside
        the unit circle and agree with those measured from the simulated closed loop, and every
        controlled run completed its steps, met the constraints with the applied input (and
        the input bounds), and returned to the fixed point.
    message : str
        What was found, or what failed.
    gait : OptimalGait
        The optimum stabilised.
    controller : gaitopt.control.StepController or None
        The LQR design (``gain``, ``closed_loop_multipliers``; a policy of the offset).
    A, B : numpy.ndarray
        ``∂P/∂s`` (floquet machinery) and ``∂P/∂δ`` (AD through the transcription).
    A_fd, B_fd : numpy.ndarray or None
        The same by central differences of the simulated map.
    gain : numpy.ndarray
        ``K`` of ``δ = −K (s − s*)`` (input units per section unit).
    open_loop_multipliers, closed_loop_multipliers : numpy.ndarray
        ``eig(A)``, ``eig(A − B K)``, largest modulus first.
    measured_closed_loop_multipliers : numpy.ndarray
        Eigenvalues of the simulated controlled orbit map (central differences).
    trials : list of ClosedLoopTrial
        Controlled and uncontrolled runs from the perturbed states.
    orbits : int
        Orbits simulated per run.
    perturbation : float
        Size of the start perturbations (section units).
    """

    success: bool
    message: str
    gait: OptimalGait
    controller: Any = None
    A: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    B: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    A_fd: np.ndarray | None = None
    B_fd: np.ndarray | None = None
    gain: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    open_loop_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    closed_loop_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    measured_closed_loop_multipliers: np.ndarray = field(
        default_factory=lambda: np.zeros(0, complex)
    )
    trials: list[ClosedLoopTrial] = field(default_factory=list)
    orbits: int = 0
    perturbation: float = 0.0

    def __bool__(self) -> bool:
        return self.success

    @property
    def jacobian_errors(self) -> dict[str, float | None]:
        """``|AD − FD|∞`` of ``A`` and ``B``."""
        return {
            "A": None if self.A_fd is None else float(np.max(np.abs(self.A - self.A_fd))),
            "B": None if self.B_fd is None else float(np.max(np.abs(self.B - self.B_fd))),
        }

    def to_json(self) -> dict[str, Any]:
        """The ``stabilisation`` object of ``gaitopt optimize --stabilise --json``."""
        model = self.gait.model
        weights = self.controller.weights if self.controller is not None else {}
        return jsonable(
            {
                "success": self.success,
                "message": self.message,
                "kind": "lqr",
                "input": "offset δ added to the optimal profile, held over each step",
                "section_coordinates": list(model.section.coordinates),
                "inputs": list(model.inputs),
                "A": self.A,
                "B": self.B,
                "A_fd": self.A_fd,
                "B_fd": self.B_fd,
                "jacobian_errors": self.jacobian_errors,
                "gain": self.gain,
                "Q": weights.get("Q"),
                "R": weights.get("R"),
                "open_loop_multipliers": [complex(z) for z in self.open_loop_multipliers],
                "closed_loop_multipliers": [complex(z) for z in self.closed_loop_multipliers],
                "measured_closed_loop_multipliers": [
                    complex(z) for z in self.measured_closed_loop_multipliers
                ],
                "closed_loop_stable": bool(self.closed_loop_multipliers.size)
                and is_stable(self.closed_loop_multipliers),
                "orbits": self.orbits,
                "perturbation": self.perturbation,
                "trials": [t.to_json() for t in self.trials],
            }
        )
