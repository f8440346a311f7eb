"""The gait optimisation problem: what is minimised, what is fixed, what is bounded.

A :class:`GaitProblem` is the statement only (no discretisation): a model, a running cost
integrated over one orbit of ``steps`` returns to the section, and the gait constraints of
issue 11 — period, step length, average speed (fixed or free), bounds on the inputs and states,
parameters made decision variables.  The transcription (:mod:`gaitopt.optimize.collocation`)
turns it into a nonlinear program.

Costs (all integrated over the whole orbit, ``t ∈ [0, period]``):

* ``"effort"``: ``∫ Σᵢ uᵢ² dt`` (N²·m²·s for torques);
* ``"work"``: positive actuator work ``∫ Σᵢ max(0, uᵢ ωᵢ) dt`` (J), with ``ωᵢ`` the rate input ``i``
  does work on (:meth:`gaitopt.HybridModel.input_rates`).  Every input must be bounded: without
  a bound, impulsive inputs lower the positive work without limit towards its infimum (on the
  level-ground compass gait the least work fell from 0.571 J to 0.495 J as an effort
  regularisation went from 1e-3 to 1e-5, the torque spike growing from 72 to 319 N·m), so no
  optimum exists.  Solved in two stages (:mod:`gaitopt.optimize.collocation`): slack powers
  ``pᵢ⁺ − pᵢ⁻ = uᵢ ωᵢ``, ``pᵢ± ≥ 0``, cost ``∫ Σ pᵢ⁺`` (at an optimum one of each pair vanishes)
  find the arcs of the power signs; the switching-time transcription then integrates
  ``Σ_{σ=+} uᵢωᵢ`` on arcs of free duration, a smooth integrand;
* ``"cot"``: cost of transport, positive work / (total mass · g · distance travelled), with the
  distance the sum of the step lengths;
* a callable ``cost(x, u, p) -> scalar`` of CasADi symbols: the integrand, user's units.

Impulsive inputs (:attr:`gaitopt.HybridModel.impulsive_inputs`, Kuo's push-off) act only in a
reset: each is one value per step (held constant over the step's profile), left out of the effort,
and its work (:meth:`gaitopt.HybridModel.impulse_work`, positive) is added to the positive work
of the work-based costs; it needs no bound (its work grows with its size).  A bound of 0
(``bounds={"push_off": 0}``) switches an input off.

Step length is the distance between the feet at heel strike: the norm of the new foothold (the
phase point named by the cycle transition's ``foothold``, positions relative to the stance foot)
at the end of the phase.  Speed is the total step length over the period.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..arguments import check_count
from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from .spectral_bound import check_max_multiplier
from .statement import (
    COSTS,
    MAX_STEPS,
    WHY_STEPS,
    all_state_names,
    bound_pair,
    check_bounds,
    check_cost,
    check_footholds,
    check_free,
    check_lengths,
    check_margins,
    check_model,
    check_not_standing,
    check_path_constraints,
    check_state_bounds,
    declared_limits,
)

__all__ = [
    "GaitProblem",
    "COSTS",
    "cost_unit",
    "MAX_STEPS",
    "all_state_names",
    "declared_limits",
]

#: The older private name of :data:`~gaitopt.optimize.statement.WHY_STEPS`.
_WHY_STEPS = WHY_STEPS
_UNITS = {"effort": "N^2*m^2*s", "work": "J", "cot": "1"}


def cost_unit(kind: str) -> str:
    """Unit of a named cost (``"effort"``: N²·m²·s for torques)."""
    return _UNITS.get(kind, "user units")


@dataclass(frozen=True)
class GaitProblem:
    """An optimal gait problem (the statement, without discretisation).

    Attributes
    ----------
    model : HybridModel
        The model, with its parameters (the free ones are initial values).
    cost : str or callable
        ``"effort"``, ``"work"``, ``"cot"`` or ``cost(x, u, p) -> scalar`` (the integrand).
    period : float or None
        Duration of the orbit (s); ``None`` leaves it free.
    step_length : float or None
        Distance between the feet at heel strike, averaged over the steps (m); ``None``: free.
    speed : float or None
        Total step length over the period (m/s); ``None``: free.
    bounds : mapping of str to float or (float, float)
        ``{input: max}``: ``|u_input| ≤ max``, or ``{input: (low, high)}``: ``low ≤ u_input ≤
        high`` (input units) at every collocation point, within the model's own
        :attr:`~gaitopt.HybridModel.input_bounds`; 0 switches the input off.
    state_bounds : mapping of str to (float, float)
        ``{state: (low, high)}``, ``low < high`` (one side may be infinite; state units: joint
        limits, rate limits), in every phase that has a state of that name (the kneed walker's
        ``q3`` only before its knee locks), at every node of the collocation (interval starts
        and Radau points, the section's lifted state too).  Input bounds stay in ``bounds``: a
        state named there is an error pointing here.
    path_constraints : tuple of str
        Names of limits the model declares (:attr:`gaitopt.hybrid.Phase.limits`: the five-link
        biped's and the kneed walker's ``"knee_flexion"``, a knee that does not hyperextend),
        imposed at every collocation node of each phase that declares them.  Off unless named
        (the model's gait without them is the reference: OptimTraj's logged five-link optimum has
        no knee limit).
    free : tuple of str
        Parameters made decision variables, within their declared ranges.
    steps : int
        Returns to the section per orbit.
    max_phase_time : float
        Upper bound of every phase duration (s).
    regularisation : float
        Weight ε of ``ε ∫Σuᵢ² dt`` added to the objective of the *first* (slack) stage of the
        work-based costs only (units of the cost per N²·m²·s; default 0): it can smooth the
        guess of the arcs; the second, exact stage, whose optimum is reported, has none.
    braking_effort : float
        Weight ε of ``ε ∫uᵢ² dt`` over the arcs where input ``i`` brakes (negative power) added
        to the objective of the *exact* stage of the work-based costs (units of the cost per
        N²·m²·s; default 0).  Negative work is free, so a braking arc is singular: any torque
        that keeps the power's sign costs the same, and the refinement need not settle.  The
        term picks the least-effort braking torque; the reported cost is the positive work
        alone (or its cost of transport), and the term's value is reported with it
        (``OptimalGait.problem["braking_effort"]``, the message).
    min_crossing_rate : float
        Least rate at which each phase's guard is crossed at its end, ``direction · ġ`` (guard
        units per second): a transversal touchdown, not a graze, which no simulation could
        locate robustly.  Reported among the active constraints when it binds.
    clearance : float
        Least margin ``c`` (m) of the model's length-valued unilateral constraints (unit
        ``"m"``: a swing foot above the ground) over each step: ``h(x) ≥ c · sin(π t / T)`` at
        every collocation node, ``t`` the time since the step's section and ``T`` the step's
        duration (0 where the foot leaves and meets the ground, ``c`` at mid-step).  Default 0:
        a foot may skim the ground, ``h = 0`` over a stretch (a boundary arc), which neither the
        dense check between the nodes nor a simulation can confirm; a real foot needs a margin.
    guard_margin : float
        Margin ``m`` (the guard's unit) by which a guard without an admissibility test (the
        kneed walker's knee strike, rad) stays short of its crossing inside the phase it ends:
        ``direction · g ≤ −m · sin(π t / T)`` at the interior nodes, ``t`` the time since the
        phase began and ``T`` its duration.  Default 0: ``direction · g ≤ 0``, where a guard may
        touch 0 over a stretch (a knee held straight by its torque before it locks), which no
        simulation can confirm.
    continuous_inputs : bool
        Inputs other than impulses are continuous where one phase of a step hands over to the
        next (the kneed walker's knee strike): the profile, a function of the time since the
        section, has no jump inside a step.  With a jump there, a perturbed step whose phase
        change comes a little later sees the next phase's input for that while, so the return
        map has different derivatives on either side and no Floquet multipliers; an actuator's
        torque cannot jump either.  Default True; it constrains only models with more than one
        phase per step.
    max_multiplier : float or None
        Bound ``R > 0`` on the spectral radius of the return map's Jacobian (its largest
        multiplier modulus), ``ρ(A) ≤ R``, imposed inside the NLP
        (:mod:`gaitopt.optimize.spectral`: the variational equations collocated with the orbit
        and the Schur–Cohn–Jury conditions on ``A/R``'s characteristic polynomial); ``R < 1``
        asks for an open-loop stable gait.  ``None`` (default): no bound.  Sections of at most
        4 coordinates, least effort or a callable cost.
    max_roughness : float or None
        With ``max_multiplier``: bound ``S`` on the input profile's roughness ``∫ Σᵣ u̇ᵣ² dt``
        over the orbit ((input unit)²/s; the inputs also continuous between mesh intervals),
        without which the bound is met by a torque spike at impact and has no optimum
        (:mod:`gaitopt.optimize.spectral_bound`).  ``None``: twice the roughness of the optimum
        without the bound, solved first (:func:`gaitopt.optimize_gait`).
    """

    model: HybridModel
    cost: str | Callable[..., Any] = "effort"
    period: float | None = None
    step_length: float | None = None
    speed: float | None = None
    bounds: Mapping[str, float] = field(default_factory=dict)
    state_bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    path_constraints: tuple[str, ...] = ()
    free: tuple[str, ...] = ()
    steps: int = 1
    max_phase_time: float = 10.0
    regularisation: float = 0.0
    braking_effort: float = 0.0
    min_crossing_rate: float = 1e-2
    clearance: float = 0.0
    guard_margin: float = 0.0
    continuous_inputs: bool = True
    max_multiplier: float | None = None
    max_roughness: float | None = None

    def __post_init__(self) -> None:
        # Each check raises a one-line GaitoptInputError (gaitopt.optimize.statement), in this
        # order: the first wrong argument is the one named.
        def set_(name: str, value: Any) -> None:
            object.__setattr__(self, name, value)

        check_model(self.model)
        check_cost(self.model, self.cost, self.bounds)
        set_("steps", check_count("steps", self.steps, 1, MAX_STEPS, WHY_STEPS))
        lengths = check_lengths(self.period, self.step_length, self.speed, self.steps)
        for name, value in zip(("period", "step_length", "speed"), lengths, strict=True):
            set_(name, value)
        clearance, margin = check_margins(self.clearance, self.guard_margin,
                                          self.continuous_inputs)  # fmt: skip
        set_("clearance", clearance)
        set_("guard_margin", margin)
        check_bounds(self.model, self.bounds)
        set_("state_bounds", check_state_bounds(self.model, self.state_bounds))
        set_("path_constraints", check_path_constraints(self.model, self.path_constraints))
        set_("free", check_free(self.model, self.free))
        check_footholds(self)
        check_not_standing(self)
        bound, budget = check_max_multiplier(self)
        set_("max_multiplier", bound)
        set_("max_roughness", budget)

    # -- names and sizes ---------------------------------------------------------------------
    @property
    def cost_kind(self) -> str:
        """``"effort"``, ``"work"``, ``"cot"`` or ``"custom"``."""
        return self.cost if isinstance(self.cost, str) else "custom"

    @property
    def chain(self) -> list[int]:
        """Phase indices of the orbit, in order (``steps`` cycles)."""
        return [i for _ in range(self.steps) for i in range(len(self.model.phases))]

    @property
    def free_index(self) -> list[int]:
        """Positions of the free parameters in ``p``."""
        names = [s.name for s in self.model.parameter_specs()]
        return [names.index(n) for n in self.free]

    def free_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Declared ranges of the free parameters (open ends nudged inside by 1e-9)."""
        specs = {s.name: s for s in self.model.parameter_specs()}
        low, high = [], []
        for name in self.free:
            spec = specs[name]
            lo = float(spec.low) + (1e-9 if spec.low_open else 0.0)
            hi = float(spec.high) - (1e-9 if spec.high_open else 0.0)
            low.append(lo)
            high.append(hi)
        return np.array(low), np.array(high)

    def input_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` of the inputs: ``|u| ≤ bounds[input]`` within the model's declared
        :attr:`~gaitopt.HybridModel.input_bounds` (``±inf`` where unbounded)."""
        model = self.model
        pairs = [
            bound_pair(n, self.bounds[n]) if n in self.bounds else (-np.inf, np.inf)
            for n in model.inputs
        ]
        low = np.array([a for a, _ in pairs], dtype=float)
        high = np.array([b for _, b in pairs], dtype=float)
        declared = dict(model.input_bounds)
        for j, name in enumerate(model.inputs):
            if name in declared:
                low[j] = max(low[j], float(declared[name][0]))
                high[j] = min(high[j], float(declared[name][1]))
            if name in model.optional_inputs and name not in self.bounds:
                low[j] = high[j] = 0.0  # off unless named (HybridModel.optional_inputs)
        return low, high

    @property
    def impulsive_index(self) -> list[int]:
        """Positions in ``u`` of the model's impulsive inputs (acting only in resets)."""
        return [self.model.inputs.index(n) for n in self.model.impulsive_inputs]

    @property
    def flow_index(self) -> list[int]:
        """Positions in ``u`` of the inputs that act in the flow (profiles)."""
        impulsive = set(self.impulsive_index)
        return [j for j in range(len(self.model.inputs)) if j not in impulsive]

    def impulse_work(self, phase: int, x: Any, u: Any, p: Any) -> Any:
        """Work of the impulsive inputs in the cycle transition of ``phase`` from the
        pre-transition state ``x`` (model energy unit); 0 where none acts."""
        work = self.model.impulse_work(phase) if self.model.impulsive_inputs else None
        if work is None:
            return 0.0
        value = ca.sum1(work(x, u, p))
        return value if isinstance(x, (ca.MX, ca.SX)) else float(value)

    def limits_of(self, phase: int) -> list[Any]:
        """The selected limits (:attr:`path_constraints`) ``phase`` declares, as
        :class:`~gaitopt.hybrid.Constraint` objects (``c ≥ 0``), in the order named."""
        declared = self.model.phases[phase].limits
        return [c for name in self.path_constraints for c in declared.get(name, ())]

    def state_bounds_of(self, phase: int) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` of the states of ``phase`` (by name; ``±inf`` where unbounded)."""
        names = self.model.phases[phase].states
        low = np.array([float(self.state_bounds.get(n, (-np.inf, np.inf))[0]) for n in names])
        high = np.array([float(self.state_bounds.get(n, (-np.inf, np.inf))[1]) for n in names])
        return low, high

    # -- measures ----------------------------------------------------------------------------
    def footholds(self) -> list[tuple[int, int] | None] | None:
        """Per phase: (phase, column of ``points``) of the foothold its cycle transition makes,
        or None; ``None`` overall if no phase declares one."""
        out: list[tuple[int, int] | None] = []
        for i, phase in enumerate(self.model.phases):
            name = phase.transitions[0].foothold
            if name and phase.points is not None and name in phase.point_names:
                out.append((i, phase.point_names.index(name)))
            else:
                out.append(None)
        return out if any(o is not None for o in out) else None

    def step_vector(self, phase: int, x: Any, p: Any) -> Any:
        """The new foothold relative to the stance foot at the end of ``phase`` (2-vector, m),
        or None if the phase makes none."""
        feet = self.footholds()
        if feet is None or feet[phase] is None:
            return None
        _, column = feet[phase]
        return self.model.phases[phase].points(x, p)[:, column]

    def total_mass(self, p: Any) -> Any:
        """Total mass (kg) from the model's point masses (``Phase.bodies``)."""
        phase = self.model.phases[0]
        if phase.bodies is None:
            raise GaitoptInputError(
                f"cost 'cot' needs {self.model.name}'s masses (Phase.bodies), which it does not "
                f"declare; use cost='work'"
            )
        symbolic = isinstance(p, (ca.MX, ca.SX))
        x = ca.MX.zeros(phase.n) if symbolic else ca.DM.zeros(phase.n)
        total = ca.sum1(phase.bodies(x, p)[0])
        return total if symbolic else float(total)

    def gravity(self, p: Any) -> Any:
        """Gravitational acceleration (m/s²) from the parameter ``gravity`` or ``g``."""
        names = [s.name for s in self.model.parameter_specs()]
        for name in ("gravity", "g"):
            if name in names:
                return p[names.index(name)]
        raise GaitoptInputError(
            f"cost 'cot' needs {self.model.name}'s gravity parameter (`gravity` or `g`); "
            f"use cost='work'"
        )

    def integrand(self, phase: int, x: Any, u: Any, p: Any) -> Any:
        """Running cost of a smooth cost at one point (effort or custom; work uses slacks)."""
        if self.cost == "effort":  # the inputs acting in the flow (not the impulses)
            flow = self.flow_index
            return ca.sumsqr(u) if len(flow) == u.shape[0] else ca.sumsqr(u[flow])
        if callable(self.cost):
            value = self.cost(x, u, p)
            return value if not isinstance(value, (int, float)) else ca.MX(value)
        raise AssertionError("work-based costs are built from slack powers")

    def power(self, phase: int, x: Any, u: Any, p: Any) -> Any:
        """Actuator powers ``uᵢ ωᵢ`` (W), one per input."""
        rates = self.model.input_rates(phase)
        return u * rates(x, p)

    def describe(self) -> dict[str, Any]:
        """The statement as plain data (for messages and JSON)."""
        return {
            "cost": self.cost_kind,
            "period": self.period,
            "step_length": self.step_length,
            "speed": self.speed,
            "bounds": {
                k: (list(v) if isinstance(v, (tuple, list)) else v)
                for k, v in dict(self.bounds).items()
            },
            "state_bounds": {k: list(v) for k, v in dict(self.state_bounds).items()},
            **({"path_constraints": list(self.path_constraints)} if self.path_constraints else {}),
            "free": list(self.free),
            "steps": self.steps,
            **({"clearance": self.clearance} if self.clearance else {}),
            **({"guard_margin": self.guard_margin} if self.guard_margin else {}),
            **({"braking_effort": self.braking_effort} if self.braking_effort else {}),
            **({} if self.continuous_inputs else {"continuous_inputs": False}),
            **({} if self.max_multiplier is None else {"max_multiplier": self.max_multiplier}),
            **({} if self.max_roughness is None else {"max_roughness": self.max_roughness}),
        }


def as_problem(model: HybridModel, **kwargs: Any) -> GaitProblem:
    """A :class:`GaitProblem` from keyword arguments (the public API's names; ``None`` is an
    empty mapping or tuple).  The arguments are checked by :class:`GaitProblem` itself."""
    for name, empty in (("bounds", {}), ("state_bounds", {}), ("path_constraints", ()),
                        ("free", ())):  # fmt: skip
        if kwargs.get(name) is None:
            kwargs[name] = empty
    return GaitProblem(model, **kwargs)
