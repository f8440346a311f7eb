"""The result of :func:`gaitopt.transverse.transverse_lqr` and its JSON."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..files import jsonable

__all__ = ["TransverseLQR", "TransverseTrial"]

_GAIN_SAMPLES = 21  # gain samples per stage in the JSON


def _pairs(z: np.ndarray) -> list[list[float]]:
    return [[float(np.real(v)), float(np.imag(v))] for v in np.asarray(z, complex)]


@dataclass
class TransverseTrial:
    """The controlled walker from one perturbed start.

    Attributes
    ----------
    start : dict of str to float
        Section coordinates of the start.
    errors : list of float
        Max-norm distance of each return (per orbit) from the fixed point, the start first
        (section units).
    status, message : str
        The simulation's status (``"completed"``; ``"no_start"`` where the start is not a state
        of the model; ``"budget"`` where the run needed more evaluations of the law than its
        budget, far from the orbit) and message.
    peak_demanded, peak_applied : list of float
        Largest ``|u|`` per input the law computed, before and after clipping to the bounds.
    saturated, calls : int
        Evaluations of the law that were clipped, and all evaluations.
    outside : int
        Evaluations whose nearest orbit point was an end of an extended stage.
    """

    start: dict[str, float]
    errors: list[float]
    status: str
    message: str
    peak_demanded: list[float] = field(default_factory=list)
    peak_applied: list[float] = field(default_factory=list)
    saturated: int = 0
    calls: int = 0
    outside: int = 0

    @property
    def converged(self) -> bool:
        """Completed, and ended within 1e-2 of its initial error (and below 1e-4)."""
        return (
            self.status == "completed"
            and len(self.errors) > 1
            and self.errors[-1] <= min(1e-2 * self.errors[0], 1e-4)
        )

    def to_json(self) -> dict[str, Any]:
        return jsonable({**self.__dict__, "converged": self.converged})


@dataclass
class TransverseLQR:
    """A gait stabilised by transverse LQR, or the record of why it is not.

    Attributes
    ----------
    success : bool
        The Riccati iteration converged, the closed-loop monodromy is stable, the simulated
        closed loop's measured multipliers agree with it, and every perturbed run returned.
    message : str
        What was found, or what failed.
    gait : LimitCycle or OptimalGait
        The gait.
    linearisation : TransverseLinearisation
        Open-loop transverse dynamics and monodromy.
    riccati : PeriodicRiccati
        ``S(τ)`` and ``K(τ)``.
    law : TransverseLaw
        The feedback for :func:`gaitopt.simulate` (``feedback=result.law``).
    closed_loop_monodromy : numpy.ndarray
        ``∏ (J − J_u K) Φ_cl`` over the orbit.
    closed_loop_multipliers : numpy.ndarray
        Its eigenvalues, largest first.
    measured_multipliers : numpy.ndarray
        Eigenvalues of the simulated closed-loop return map (central differences).
    trials : list of TransverseTrial
        Runs from perturbed starts.
    timings : dict of str to float
        Seconds per part.
    """

    success: bool
    message: str
    gait: Any
    linearisation: Any
    riccati: Any
    law: Any
    Q: list[np.ndarray]
    R: np.ndarray
    closed_loop_monodromy: np.ndarray
    closed_loop_multipliers: np.ndarray
    measured_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    multiplier_gap: float | None = None
    trials: list[TransverseTrial] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    input_low: np.ndarray = field(default_factory=lambda: np.zeros(0))
    input_high: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __bool__(self) -> bool:
        return self.success

    @property
    def open_loop_multipliers(self) -> np.ndarray:
        """The transverse monodromy's eigenvalues with the input on the phase, ``u*(τ)``."""
        return self.linearisation.multipliers

    @property
    def peak_input(self) -> list[float]:
        """Largest ``|u|`` applied per input over the trials (input units)."""
        peaks = [t.peak_applied for t in self.trials if t.peak_applied]
        return np.max(np.array(peaks), axis=0).tolist() if peaks else []

    def gains(self, samples: int = _GAIN_SAMPLES) -> list[dict[str, Any]]:
        """``K(τ)`` sampled on each stage (``samples`` phases from 0 to ``T``)."""
        out = []
        for k, frame in enumerate(self.linearisation.frames):
            stage = frame.stage
            taus = np.linspace(0.0, stage.duration, samples)
            out.append(
                {
                    "stage": k,
                    "phase": self.gait.model.phases[stage.phase].name,
                    "step": stage.step,
                    "tau": taus.tolist(),
                    "K": [self.riccati.gain(k, t).tolist() for t in taus],
                    "transverse_dimension": frame.n - 1,
                }
            )
        return out

    def to_json(self, samples: int = _GAIN_SAMPLES) -> dict[str, Any]:
        """Plain JSON types: the gains (sampled), the multipliers, the trials, the timings."""
        lin = self.linearisation
        return jsonable(
            {
                "success": self.success,
                "message": self.message,
                "kind": "transverse LQR",
                "Q": [q.tolist() for q in self.Q],
                "R": self.R.tolist(),
                "coordinates": "x⊥ = Π(τ)(x − x*(τ)): the hyperplane through x*(τ) orthogonal "
                "to f*(τ), Π a Householder basis of it; τ the phase of the nearest orbit point",
                "open_loop_multipliers": _pairs(lin.multipliers),
                "clock_multipliers": _pairs(lin.clock_multipliers),
                "closed_loop_multipliers": _pairs(self.closed_loop_multipliers),
                "measured_closed_loop_multipliers": _pairs(self.measured_multipliers),
                "multiplier_gap": self.multiplier_gap,
                "riccati_orbits": self.riccati.orbits,
                "riccati_converged": self.riccati.converged,
                "input_bounds": [self.input_low.tolist(), self.input_high.tolist()],
                "peak_input": self.peak_input,
                "saturated": any(t.saturated for t in self.trials),
                "gains": self.gains(samples),
                "trials": [t.to_json() for t in self.trials],
                "timings": self.timings,
            }
        )
