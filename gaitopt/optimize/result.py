"""The result of :func:`gaitopt.optimize_gait`: an optimal gait, or why there is none."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..files import jsonable
from ..result import STATUS, Gait

__all__ = ["OptimalGait", "Minimum", "StartRecord", "START_STATUS"]

#: How one start of a multi-start ended (:attr:`StartRecord.status`): the three codes of the one
#: table :data:`gaitopt.result.STATUS` a start can end in, with its advice.
START_STATUS = {code: STATUS[code] for code in ("converged", "not_converged", "no_start")}


@dataclass
class Minimum:
    """A distinct local minimum found by a multi-start.

    Attributes
    ----------
    Every minimum is refined and certified like the reported optimum; where that succeeds the
    values are the refined ones, otherwise those on the starts' mesh.

    cost : float
        Optimal cost (units of the cost kind).
    period : float
        Period (s).
    fixed_point : dict of str to float
        State on the section.
    starts : list of int
        The starts (0-based) that reached it.
    verified : bool
        Certified: the dense checks, the independent simulation and the refinement target all
        met (:attr:`OptimalGait.success` of its own refinement).
    discretisation_error : float or None
        Its refinement's estimate (relative), None where it was not certified.
    message : str
        What its certification found.
    """

    cost: float
    period: float
    fixed_point: dict[str, float]
    starts: list[int] = field(default_factory=list)
    verified: bool = False
    discretisation_error: float | None = None
    message: str = ""

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types."""
        return jsonable(
            {
                "cost": self.cost,
                "period": self.period,
                "fixed_point": self.fixed_point,
                "starts": self.starts,
                "count": len(self.starts),
                "verified": self.verified,
                "discretisation_error": self.discretisation_error,
                "message": self.message,
            }
        )


@dataclass
class StartRecord:
    """How one start of a multi-start ended; every start has one, failed or not.

    Attributes
    ----------
    start : int
        The start's index (0: the model's default start or the warm start).
    status : str
        ``"converged"``, ``"not_converged"`` or ``"no_start"`` (:data:`START_STATUS`).
    message : str
        Why it failed, or what it reached.
    cost : float or None
        Its cost on the starts' mesh where IPOPT converged.
    minimum : int or None
        The index in :attr:`OptimalGait.minima` of the minimum it reached (0-based).
    iterations : int
        IPOPT iterations (0 for a start that could not begin).
    """

    start: int
    status: str
    message: str = ""
    cost: float | None = None
    minimum: int | None = None
    iterations: int = 0

    @property
    def advice(self) -> str:
        """What :data:`gaitopt.result.STATUS` says about :attr:`status`."""
        return STATUS[self.status]

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types."""
        return jsonable(
            {
                "start": self.start,
                "status": self.status,
                "message": self.message,
                "cost": self.cost,
                "minimum": self.minimum,
                "iterations": self.iterations,
            }
        )


@dataclass
class OptimalGait(Gait):
    """An optimal gait, or the record of a failed optimisation: a :class:`gaitopt.Gait`, judged
    by the same certificate and referee as a :class:`gaitopt.LimitCycle`, with the same
    :data:`gaitopt.result.STATUS` codes.

    Attributes
    ----------
    success : bool
        True only if IPOPT converged, every physical check passed on dense samples, the
        independent simulation with the input profile returned to the fixed point with the same
        cost, and the discretisation error estimate met its target.
    message : str
        What was found, or which constraint cannot be met.
    model : HybridModel
        The model with its parameters (free ones at their optimal values).
    cost_kind : str
        ``"effort"`` (N²·m²·s), ``"work"`` (J), ``"cot"`` (1) or ``"custom"``.
    cost : float or None
        Optimal cost over one orbit.
    period, step_length, speed : float or None
        Orbit duration (s), mean distance between the feet at heel strike (m), their ratio
        over the period (m/s).
    fixed_point : dict of str to float
        State on the section (phase 0, just after the reset that closes the orbit).
    inputs : dict of str to list of float
        ``{"time": [...], input: [...]}``: the input profile over one orbit, sampled.
    profiles : list of InputProfile
        One per step, in the time since that step's section (for :func:`gaitopt.simulate`'s
        ``feedforward``).
    durations : numpy.ndarray
        Phase durations (s), in orbit order.
    multipliers : numpy.ndarray
        Nontrivial Floquet multipliers (AD through the transcription), largest first.
    multipliers_fd : numpy.ndarray
        The same by finite differences of the simulated map.
    stable : bool or None
        All multipliers strictly inside the unit circle.
    verified : bool
        The independent simulation confirms the gait and its cost.
    verification : dict
        ``return_error`` (state units), ``cost_simulated``, ``cost_error`` (relative).
    discretisation_error : float or None
        Relative change of cost and orbit between the final mesh and the one before.
    discretisation : dict
        ``{"intervals", "degree", "cost_error", "orbit_error"}``.
    active_constraints : list of str
        Constraints and bounds active at the optimum.
    minima : list of Minimum
        Distinct local minima of a multi-start, best first.
    starts : list of StartRecord
        How every start ended, in start order: converged (to which minimum), not converged, or
        unable to begin; a failed start never ends the search.
    params : dict of str to float
        Parameters (free ones optimised).
    solve_time : float
        Wall-clock time (s).
    iterations : int
        IPOPT iterations of the final solve.
    problem : dict
        The statement solved (:meth:`GaitProblem.describe`).
    orbit : list of OrbitArc
        Dense samples of each phase of the orbit (with the input ``u`` at each sample).
    status : str
        One of :data:`gaitopt.result.STATUS`'s codes, as for a :class:`~gaitopt.LimitCycle`:
        ``"success"``, ``"no_start"`` (no start is a state of the model), ``"not_converged"``
        (IPOPT stopped; the message names the worst constraint), ``"not_a_gait"`` (the
        certificate refuses it), ``"not_verified"`` (the referee does not confirm it) or
        ``"discretisation"`` (the refinement did not reach ``tol``); :attr:`advice` says what
        to try.
    transcription : tuple or None
        ``(Collocation, w)``: the final transcription and its solution (the stabilising design
        differentiates it); None where no optimum was reached.
    active_spans : dict or None
        With state bounds or path constraints: the node-time spans where each is active
        (the CLI's JSON ``active_spans``); None without them.
    max_multiplier : float or None
        The bound ``R`` on the spectral radius imposed in the NLP (``max_multiplier=``), else
        None; :attr:`spectral_radius` is what the optimum reached.
    max_roughness, roughness : float or None
        With ``max_multiplier``: the bound on ``∫ Σ u̇² dt`` ((input unit)²/s) and the optimum's
        value of it.
    spectral_radius_fd_extrapolated : float or None
        With ``max_multiplier``: the spectral radius by Richardson-extrapolated finite
        differences of the simulated map, which the certificate checks against the bound
        (:mod:`gaitopt.optimize.spectral_certify`).
    """

    success: bool
    message: str
    model: Any
    cost_kind: str
    cost: float | None = None
    period: float | None = None
    step_length: float | None = None
    speed: float | None = None
    fixed_point: dict[str, float] = field(default_factory=dict)
    inputs: dict[str, list[float]] = field(default_factory=dict)
    profiles: list[Any] = field(default_factory=list)
    durations: np.ndarray = field(default_factory=lambda: np.zeros(0))
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    multipliers_fd: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    stable: bool | None = None
    verified: bool = False
    verification: dict[str, Any] = field(default_factory=dict)
    discretisation_error: float | None = None
    discretisation: dict[str, Any] = field(default_factory=dict)
    active_constraints: list[str] = field(default_factory=list)
    minima: list[Minimum] = field(default_factory=list)
    starts: list[StartRecord] = field(default_factory=list)
    params: dict[str, float] = field(default_factory=dict)
    solve_time: float = 0.0
    iterations: int = 0
    problem: dict[str, Any] = field(default_factory=dict)
    orbit: list[Any] = field(default_factory=list)
    status: str = ""
    transcription: Any = field(default=None, repr=False, compare=False)
    active_spans: dict[str, Any] | None = None
    max_multiplier: float | None = None
    max_roughness: float | None = None
    roughness: float | None = None
    spectral_radius_fd_extrapolated: float | None = None

    def __post_init__(self) -> None:
        if self.status and self.status not in STATUS:
            raise ValueError(f"OptimalGait: status {self.status!r} is not one of {list(STATUS)}")
        if not self.status:
            self.status = "success" if self.success else "not_converged"

    @property
    def x(self) -> np.ndarray:
        """The fixed point as a vector (the model's state order)."""
        return np.array([self.fixed_point[k] for k in self.model.state_names])

    def __bool__(self) -> bool:
        return self.success

    def feedforward(self, t: float, step: int = 0) -> np.ndarray:
        """The optimal input at time ``t`` since the section of step ``step`` (held after)."""
        return self.profiles[step % len(self.profiles)](t)

    @property
    def spectral_radius(self) -> float | None:
        """Largest multiplier modulus (AD), None without multipliers."""
        mu = np.asarray(self.multipliers)
        return float(np.max(np.abs(mu))) if mu.size else None

    @property
    def spectral_radius_fd(self) -> float | None:
        """Largest multiplier modulus by finite differences of the simulated map, or None."""
        mu = np.asarray(self.multipliers_fd)
        return float(np.max(np.abs(mu))) if mu.size else None

    def to_json(self, *, minima: bool | None = None) -> dict[str, Any]:
        """The ``gaitopt optimize --json`` object (``minima`` and ``starts`` included when
        there are more starts than one, or when asked)."""
        data: dict[str, Any] = {
            "model": self.model.name,
            "params": self.params or self.model.params,
            "success": self.success,
            "message": self.message,
            "cost_kind": self.cost_kind,
            "cost": self.cost,
            "period": self.period,
            "step_length": self.step_length,
            "speed": self.speed,
            "fixed_point": self.fixed_point,
            "inputs": self.inputs,
            "profiles": [prof.as_dict() for prof in self.profiles],  # exact: breaks, coefficients
            "multipliers": [complex(m) for m in self.multipliers],  # [re, im] in JSON
            "multipliers_fd": [complex(m) for m in self.multipliers_fd],
            "stable": self.stable,
            "spectral_radius": self.spectral_radius,
            "spectral_radius_fd": self.spectral_radius_fd,
            "max_multiplier": self.max_multiplier,
            "max_roughness": self.max_roughness,
            "roughness": self.roughness,
            "spectral_radius_fd_extrapolated": self.spectral_radius_fd_extrapolated,
            "verified": self.verified,
            "verification": self.verification,
            "discretisation_error": self.discretisation_error,
            "discretisation": self.discretisation,
            "active_constraints": self.active_constraints,
            "durations": self.durations,
            "problem": self.problem,
            "solve_time": self.solve_time,
            "iterations": self.iterations,
        }
        if minima or (minima is None and len(self.minima) > 0 and self._multistart):
            data["minima"] = [m.to_json() for m in self.minima]
            data["starts"] = [s.to_json() for s in self.starts]
        return jsonable(data)

    @property
    def _multistart(self) -> bool:
        return len(self.starts) > 1 or len(self.minima) > 1
