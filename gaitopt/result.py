"""The results of both front doors: :class:`Gait`, the interface every gait result has, with
its one :data:`STATUS` table; :class:`LimitCycle` (:func:`gaitopt.find_limit_cycle`) and
:class:`gaitopt.optimize.OptimalGait` (:func:`gaitopt.optimize_gait`) are gaits."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Gait", "LimitCycle", "OrbitArc", "STATUS", "status_of"]

#: What a search or an optimisation ended in (``Gait.status``: :attr:`LimitCycle.status`,
#: :attr:`OptimalGait.status`; :attr:`Branch.status <gaitopt.continuation.Branch.status>`,
#: :attr:`Curve.status <gaitopt.curves.Curve.status>`, :attr:`OrbitSolution.status
#: <gaitopt.orbit.solve.OrbitSolution.status>`, a multi-start's ``StartRecord.status``), and
#: what to try next (diffrax's ``RESULTS``, SciPy's ``OptimizeResult.status``): one code per
#: way of failing; the message has the details.
STATUS = {
    "success": "a certified gait: solved, refined, checked on dense samples and verified",
    "no_start": "the simulation from the guess never completes a step (an optimisation: no "
    "start is a state of the model): try another guess (`gaitopt simulate`) or seed, or the "
    "gait may not exist at these parameters",
    "not_converged": "Newton/IPOPT did not converge: try a closer guess, `--starts 16`, the "
    "ipopt method, or follow the gait from parameters where it exists (`gaitopt continue`); "
    "an optimisation: relax the constraint its message names (a larger input bound, a shorter "
    "step, a longer period) or try more starts",
    "singular": "the orbit is not isolated (a continuous family, or not transversal to a "
    "guard): change the parameter that removes the restoring term",
    "discretisation": "the orbit's discretisation error stays above `tol` at the finest mesh: "
    "loosen `tol` (an optimum: or bound the inputs so that it is smoother)",
    "standing": "the solution is an equilibrium, not a gait: give the guess more speed, or "
    "the gait may not exist (a passive walker needs a slope)",
    "not_a_gait": "the orbit breaks a physical condition (a negative duration, a guard reached "
    "the wrong way or crossed early, a foot through the ground, a leg that pulls) or repeats a "
    "shorter one: the gait does not exist with this phase sequence here",
    "not_verified": "the independent simulation does not confirm the orbit (its return, its "
    "phase timing or an optimum's cost): tighten the mesh or `tol`, or the gait is too "
    "sensitive to be trusted here",
    "converged": "one start of a multi-start (an optimisation's `starts`): the solver "
    "converged on the starts' mesh; the minimum it reached is refined and certified before it "
    "is reported",
    "no_special_point": "a bifurcation curve: the branch it starts from has no special point "
    "of the kind asked for, or the point carries no certified gait: continue the branch "
    "further (`to`), or start from another gait",
}


def status_of(result: Any) -> str:
    """The :data:`STATUS` code of any result with ``success`` and ``status`` (a gait, a
    :class:`~gaitopt.continuation.Branch`, a :class:`~gaitopt.curves.Curve`): its own code, else
    ``"success"`` or ``"not_converged"`` by ``success``."""
    code = getattr(result, "status", "") or ("success" if result.success else "not_converged")
    if code not in STATUS:
        raise ValueError(f"status {code!r} is not one of {list(STATUS)}")
    return code


class Gait:
    """What every gait result is, whichever front door found it: a :class:`LimitCycle`
    (:func:`gaitopt.find_limit_cycle`, multiple shooting) or an
    :class:`~gaitopt.optimize.OptimalGait` (:func:`gaitopt.optimize_gait`, collocation).

    Both were judged by the same certificate and referee (:mod:`gaitopt.orbit`) and share these
    attributes: ``success``, ``message``, ``status`` (a code of :data:`STATUS`), ``model``,
    ``period`` (s), ``fixed_point`` (state name → value on the section), ``durations`` (s),
    ``multipliers``, ``stable``, ``verified`` and ``orbit`` (dense samples per phase).  An
    optimal gait adds its ``cost``, its input ``profiles`` and, from a multi-start, its
    ``minima``.
    """

    __slots__ = ()

    @property
    def x(self) -> np.ndarray:
        """The fixed point as a vector (the model's state order)."""
        return np.array([self.fixed_point[k] for k in self.model.state_names])

    @property
    def section_point(self) -> np.ndarray:
        """The fixed point in section coordinates."""
        return np.array([self.fixed_point[k] for k in self.model.section.coordinates])

    @property
    def advice(self) -> str:
        """What :data:`STATUS` says about :attr:`status`: what it means and what to try."""
        return STATUS.get(self.status, "")


@dataclass
class OrbitArc:
    """One phase of the orbit, sampled densely (for plots and guard checks).

    Attributes
    ----------
    phase : int
        Phase index in ``model.phases``.
    name : str
        Phase name.
    states : tuple of str
        State names of the phase.
    t : numpy.ndarray
        Times (s), cumulative from the section.
    x : numpy.ndarray
        States, ``len(states) × len(t)``.
    transition : str
        The transition that ends the arc.
    u : numpy.ndarray or None
        Inputs at the same samples, ``len(model.inputs) × len(t)``: the per-step input held
        (a :class:`LimitCycle`), or the input profile (an :class:`~gaitopt.OptimalGait`).
    """

    phase: int
    name: str
    states: tuple[str, ...]
    t: np.ndarray
    x: np.ndarray
    transition: str
    u: np.ndarray | None = None


@dataclass
class LimitCycle(Gait):
    """A periodic orbit (gait) of a hybrid model, or the record of a failed search.

    Attributes
    ----------
    success : bool
        True only if every check passed (see :func:`gaitopt.find_limit_cycle`).
    message : str
        What was found, or what failed and what to try.
    model : HybridModel
        The model (with its parameters).
    period : float
        Duration of one full orbit (s; dimensionless time for Garcia's walker and Van der Pol).
    steps : int
        Returns to the Poincaré section per orbit (heel strikes for walkers; k of a period-k gait).
    state_names : tuple of str
        Names of the section-phase states.
    fixed_point : dict of str to float
        The orbit's state on the section.
    section_coordinates : tuple of str
        Free coordinates of the section (the return map's coordinates).
    multipliers : numpy.ndarray
        Nontrivial Floquet multipliers (complex), eigenvalues of the return map's Jacobian in
        section coordinates; empty when no gait was found.
    stable : bool or None
        Every multiplier has modulus < 1; ``None`` when no gait was found.
    residual : float
        Max-norm of the shooting equations at the solution.
    verified : bool
        An independent simulation from the fixed point returned to it.
    verification_error : float
        Max-norm difference between the simulated return and the fixed point (NaN if not run).
    durations : numpy.ndarray
        Phase durations (s), in the order of the phase cycle repeated ``steps`` times.
    jacobian : numpy.ndarray
        Jacobian of the return map in section coordinates (``steps`` returns).
    input_jacobian : numpy.ndarray
        Its derivative with respect to the per-step input (section coordinates × inputs).
    inputs : numpy.ndarray
        The per-step input the orbit was computed with.
    orbit : list of OrbitArc
        Dense samples of each phase of the orbit.
    discretisation : MultipleShooting or None
        The mesh of the accepted solution.
    discretisation_error : float
        Estimated error of the unknowns due to the fixed-step integration: the size of one Newton
        correction towards a mesh with twice as many RK steps.
    iterations : int
        Newton (or IPOPT) iterations (of the final mesh).
    solve_time : float
        Wall-clock seconds spent in :func:`find_limit_cycle`.
    route : str
        How the gait was reached when no guess was given: followed from the default gait at the
        default parameters (a homotopy), or solved directly from the default start.
    gaits : list of dict
        With ``starts > 1``: every distinct gait the multi-start search found (``fixed_point``,
        ``period``, ``multipliers``, ``stable``, ``starts``: how many starts reached it).
    status : str
        One of :data:`STATUS`'s codes (``"success"``, ``"not_converged"``, ``"not_a_gait"``, …):
        how the search ended, for programs; :data:`STATUS` says what to try next.
    problem : ShootingProblem or None
        The shooting problem solved (:class:`gaitopt.ShootingProblem`): model class,
        discretisation and cycles; None for a search that never reached the shooting equations.
    solution : numpy.ndarray or None
        The solution vector ``w`` of ``problem`` (see :attr:`ShootingProblem.layout`): the warm
        start of continuation, control design and curve following, which use it as is.
    evaluation : Evaluation or None
        The residual and its Jacobians at ``solution`` (``F``, ``F_w`` = ∂F/∂w, ``F_u`` = ∂F/∂u,
        ``F_p`` = ∂F/∂p, phase ends, guard rates, durations), from the last Newton step: reused
        for the multipliers, the error estimate and continuation's tangent, never recomputed.
    """

    success: bool
    message: str
    model: Any
    period: float = float("nan")
    steps: int = 1
    state_names: tuple[str, ...] = ()
    fixed_point: dict[str, float] = field(default_factory=dict)
    section_coordinates: tuple[str, ...] = ()
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    stable: bool | None = None
    residual: float = float("nan")
    verified: bool = False
    verification_error: float = float("nan")
    durations: np.ndarray = field(default_factory=lambda: np.zeros(0))
    jacobian: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    input_jacobian: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    inputs: np.ndarray = field(default_factory=lambda: np.zeros(0))
    orbit: list[OrbitArc] = field(default_factory=list)
    discretisation: Any = None
    discretisation_error: float = float("nan")
    iterations: int = 0
    solve_time: float = float("nan")
    route: str = ""
    gaits: list[dict[str, Any]] = field(default_factory=list)
    status: str = ""
    problem: Any = field(default=None, repr=False, compare=False)
    solution: np.ndarray | None = field(default=None, repr=False, compare=False)
    evaluation: Any = field(default=None, repr=False, compare=False)

    @property
    def x(self) -> np.ndarray:
        """The fixed point as a vector (state order)."""
        return np.array([self.fixed_point[k] for k in self.state_names])

    @property
    def section_point(self) -> np.ndarray:
        """The fixed point in section coordinates."""
        return np.array([self.fixed_point[k] for k in self.section_coordinates])

    @property
    def advice(self) -> str:
        """What :data:`STATUS` says about this search's status and what to try next."""
        return STATUS.get(self.status or ("success" if self.success else "not_converged"), "")

    def as_dict(self, timing: bool = True) -> dict[str, Any]:
        """The JSON object of ``gaitopt solve --json`` (the public contract in the README).

        Numbers that do not exist are ``None`` (JSON ``null``): the ``period`` of a failed search
        (a rejected candidate orbit has no period; its ``durations`` are kept as the evidence),
        and any period unless every phase duration is positive and finite; non-finite values.

        Parameters
        ----------
        timing : bool
            Include ``solve_time`` (wall-clock seconds, different on every run); tracked result
            files (``make gaits``) leave it out so that a rerun leaves them unchanged.
        """
        durations = np.asarray(self.durations, dtype=float).ravel()
        has_period = bool(
            durations.size and np.all(np.isfinite(durations)) and np.all(durations > 0)
        )
        out = {
            "model": self.model.name,
            "params": self.model.params,
            "success": bool(self.success),
            "message": self.message,
            "period": _num(self.period) if self.success and has_period else None,
            "steps": int(self.steps),
            "state_names": list(self.state_names),
            "fixed_point": {k: _num(v) for k, v in self.fixed_point.items()},
            "multipliers": [[_num(z.real), _num(z.imag)] for z in self.multipliers],
            "stable": self.stable,
            "residual": _num(self.residual),
            "verified": bool(self.verified),
            "section_coordinates": list(self.section_coordinates),
            "inputs": dict(zip(self.model.inputs, map(float, self._input_values()), strict=True)),
            "durations": [_num(d) for d in durations],
            "verification_error": _num(self.verification_error),
            "discretisation_error": _num(self.discretisation_error),
            "iterations": int(self.iterations),
            "route": self.route,
            "status": self.status or ("success" if self.success else "not_converged"),
            **({"gaits": self.gaits} if self.gaits else {}),
        }
        if timing:
            out["solve_time"] = _num(self.solve_time)
        return out

    def _input_values(self) -> np.ndarray:
        n = len(self.model.inputs)
        return self.inputs if len(self.inputs) == n else np.zeros(n)

    def __repr__(self) -> str:
        mods = ", ".join(f"{abs(z):.4g}" for z in self.multipliers)
        return (
            f"LimitCycle({self.model.name}, success={self.success}, period={self.period:.10g}, "
            f"|multipliers|=[{mods}], stable={self.stable}, verified={self.verified})"
        )


def _num(x: float) -> float | None:
    x = float(x)
    return x if np.isfinite(x) else None
