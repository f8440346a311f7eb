"""The hybrid-system abstraction: phases, flows, guards, resets, the Poincaré section.

A gait is a periodic orbit of a hybrid system: a cycle of *phases*, each a smooth flow
``ẋ = f(x, u, p)`` that ends when a *guard* ``g(x, u, p)`` crosses zero in a stated direction,
after which a *reset* ``x⁺ = r(x⁻, u, p)`` maps the state into the next phase (whose state may
have another dimension).  An *admissibility* function excludes spurious crossings: a crossing
counts only where it is positive (the compass gait's swing foot scuffing the ground mid-swing).

Every function is a CasADi :class:`casadi.Function` of the state ``x``, the per-step input ``u``
(constant over a step; empty for passive models) and the parameter vector ``p``.  Parameters are
*symbolic* inputs, so a model class is built once and every parameter value reuses the graph.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from .errors import FrozenModelError, StateError
from .parameters import ParameterSpec, check_parameter, parameter_specs

__all__ = ["Transition", "Constraint", "Phase", "Section", "Structure", "HybridModel", "Symbols"]


@dataclass(frozen=True)
class Transition:
    """A guard and its reset.

    Attributes
    ----------
    name : str
        What happens (``"heel strike"``).
    guard : casadi.Function
        ``g(x, u, p) -> scalar``; the transition fires when it crosses zero.
    direction : int
        ``+1``: fires when ``g`` increases through zero; ``-1``: when it decreases through zero.
    reset : casadi.Function or None
        ``r(x, u, p) -> x⁺`` in the target phase's coordinates; ``None`` ends the motion (a fall).
    target : int or None
        Index of the phase entered after the reset.
    admissible : casadi.Function or None
        ``a(x, u, p) -> scalar``; a crossing counts only where ``a > 0`` (spurious-crossing rule).
    impact : bool
        Whether the reset is an impact (changes velocities) rather than a relabelling.
    foothold : str or None
        Name of the phase point (see :attr:`Phase.points`) that becomes the new contact point,
        for drawing successive steps; ``None`` if the contact does not move.
    doc : str
        The guard and reset equations, with their source.
    returns_to_section : bool
        Whether this transition, too, ends a step on the Poincaré section (``transitions[0]`` of
        the last phase always does).  The rimless wheel's backward step: the chapter's return map
        counts every impact, rocking back as well as vaulting forward.  Default ``False``.
    """

    name: str
    guard: ca.Function
    direction: int
    reset: ca.Function | None
    target: int | None
    admissible: ca.Function | None = None
    impact: bool = True
    foothold: str | None = None
    doc: str = ""
    returns_to_section: bool = False

    @property
    def terminal(self) -> bool:
        """Whether the motion ends here (a fall)."""
        return self.reset is None


@dataclass(frozen=True)
class Constraint:
    """A unilateral condition ``c(x, u, p) ≥ 0`` the physics needs throughout a phase.

    A gait must satisfy every constraint its model declares: a swing foot above the ground, a
    trailing foot that lifts off after heel strike, a leg that pushes rather than pulls, a ball
    above its paddle.  The checks are made three times, independently: by the certificate of
    both front doors (:mod:`gaitopt.orbit.certificate`) on the orbit's dense samples, by the
    verification simulation (where ``c`` falling through zero ends the motion as the event
    :attr:`outcome`), and so by continuation, which reports a ``boundary`` special point where a
    constraint becomes active.

    Attributes
    ----------
    name : str
        The condition in words (``"swing foot above the slope"``).
    function : casadi.Function
        ``c(x, u, p) -> scalar`` in a stated unit; the condition is ``c ≥ 0``.
    outcome : str
        The event that a violation is (``"trip"``, ``"leg pulls"``): the name of the terminal
        event in a simulation and of the failure in a message.
    at_start : bool
        ``c = 0`` where the phase begins, by construction (a trailing foot that starts on the
        ground): then ``c`` must rise at once, ``ċ = ∇c · f > 0`` at the start (the foot lifts
        off), and be positive after it.
    at_end : bool
        ``c = 0`` where the phase ends, by construction (a foot that touches down at the guard).
    unit : str
        Unit of ``c`` (``"m"``, ``"N"``).
    source : str
        Where the condition comes from.
    """

    name: str
    function: ca.Function
    outcome: str
    at_start: bool = False
    at_end: bool = False
    unit: str = ""
    source: str = ""


_RATES: dict[tuple[int, int], tuple[ca.Function, ca.Function, ca.Function]] = {}


def rate_along(flow: ca.Function, g: ca.Function) -> ca.Function:
    """``ġ(x, u, p) = ∇g(x) · f(x, u, p)``: the rate of change of ``g`` along the flow ``f``
    (built once per pair of functions)."""
    key = (id(flow), id(g))
    if key not in _RATES:
        x, u, p = (ca.SX.sym(n, flow.size1_in(i)) for i, n in enumerate(("x", "u", "p")))
        rate = ca.jtimes(g(x, u, p), x, flow(x, u, p))
        # Keep flow and g alive with their rate, so that their ids stay theirs.
        _RATES[key] = (ca.Function("rate", [x, u, p], [rate], ["x", "u", "p"], ["rate"]), flow, g)
    return _RATES[key][0]


@dataclass(frozen=True)
class Phase:
    """One smooth phase of the hybrid cycle.

    Attributes
    ----------
    name : str
        Phase name (``"stance"``, ``"three-link swing"``).
    states : tuple of str
        State names, in the order of the state vector.
    flow : casadi.Function
        ``f(x, u, p) -> ẋ``.
    transitions : tuple of Transition
        ``transitions[0]`` continues the gait cycle; the others (falls, backward steps) are
        exits a simulation must honour and a gait must not touch.
    conserved : mapping of str to casadi.Function
        Quantities ``c(x, p)`` constant along the passive flow (``u = 0``), e.g. energy.
    points : casadi.Function or None
        ``points(x, p) -> 2×K`` positions (m) of named points for drawing, world frame (y up),
        relative to the contact point.
    point_names : tuple of str
        Names of the columns of ``points``.
    bodies : casadi.Function or None
        ``bodies(x, p) -> (m, r, v)``: point masses (K×1, kg), positions and velocities (2×K,
        world frame, relative to the contact point); for momentum and energy checks.
    constraints : tuple of Constraint
        The unilateral conditions the physics needs in this phase (see :class:`Constraint`).
        A model that ignores one by convention says so in its docstring (the compass gait's
        mid-swing scuff).
    limits : mapping of str to tuple of Constraint
        Optional conditions ``c ≥ 0`` that are no physics but a design's choice (joint limits: a
        knee that must not hyperextend), by the name an optimiser selects them with
        (:attr:`gaitopt.optimize.problem.GaitProblem.path_constraints`, ``--constrain NAME``):
        imposed only on request, never by simulation or continuation.  ``at_start`` /
        ``at_end`` mark a condition that is 0 there by construction (not imposed at that node).
    """

    name: str
    states: tuple[str, ...]
    flow: ca.Function
    transitions: tuple[Transition, ...]
    conserved: Mapping[str, ca.Function] = field(default_factory=dict)
    points: ca.Function | None = None
    point_names: tuple[str, ...] = ()
    bodies: ca.Function | None = None
    constraints: tuple[Constraint, ...] = ()
    limits: Mapping[str, tuple[Constraint, ...]] = field(default_factory=dict)

    @property
    def n(self) -> int:
        """State dimension."""
        return len(self.states)


@dataclass(frozen=True)
class Section:
    """The Poincaré section, parametrised by free coordinates.

    The section lies in phase 0 (just after the reset that closes the cycle).  ``lift`` maps the
    free coordinates to the full state so that its image is exactly the set the return map lands
    in (the reset's image of the guard, within the level set of any conserved quantity).  The
    return map in these coordinates therefore has only the nontrivial Floquet multipliers.

    Attributes
    ----------
    coordinates : tuple of str
        Names (a subset of phase 0's states) of the free coordinates.
    lift : casadi.Function
        ``lift(s, p) -> x``.
    doc : str
        Definition of the section.
    """

    coordinates: tuple[str, ...]
    lift: ca.Function
    doc: str = ""


class Symbols:
    """Symbolic parameters and helpers for a model's ``build`` classmethod.

    ``sym.p`` is the parameter vector (CasADi SX); ``sym.slope`` etc. its named entries (a
    parameter wins over an input of the same name); ``sym.u`` the per-step input vector and
    ``sym.input(name)`` one of its entries.
    """

    def __init__(self, specs: Sequence[ParameterSpec], inputs: Sequence[str]):
        self.p = ca.SX.sym("p", len(specs))
        self.u = ca.SX.sym("u", len(inputs))
        self._names = {s.name: i for i, s in enumerate(specs)}
        self._inputs = {name: i for i, name in enumerate(inputs)}

    def __getattr__(self, name: str) -> ca.SX:
        if name.startswith("_"):
            raise AttributeError(name)
        if name in self._names:
            return self.p[self._names[name]]
        if name in self._inputs:
            return self.u[self._inputs[name]]
        raise AttributeError(f"model has no parameter or input named {name!r}")

    def input(self, name: str) -> ca.SX:
        """The per-step input ``name`` (unambiguous where a parameter has the same name, as the
        SLIP's touchdown angle: ``sym.touchdown_angle`` is the parameter)."""
        if name not in self._inputs:
            raise AttributeError(f"model has no per-step input named {name!r}")
        return self.u[self._inputs[name]]

    @staticmethod
    def states(*names: str) -> tuple[ca.SX, list[ca.SX]]:
        """A state vector and its named elements."""
        x = ca.SX.sym("x", len(names))
        return x, [x[i] for i in range(len(names))]

    def function(self, name: str, x: ca.SX, expr: Any) -> ca.Function:
        """``name(x, u, p) -> expr``."""
        return ca.Function(name, [x, self.u, self.p], [ca.SX(expr)], ["x", "u", "p"], [name])

    def constraint(
        self, name: str, x: ca.SX, expr: Any, outcome: str, **options: Any
    ) -> Constraint:
        """The unilateral condition ``expr ≥ 0`` (see :class:`Constraint` for ``options``)."""
        return Constraint(name, self.function("constraint", x, expr), outcome, **options)

    def conserved(self, name: str, x: ca.SX, expr: Any) -> ca.Function:
        """``name(x, p) -> expr`` (no input: conserved only along the passive flow)."""
        return ca.Function(name, [x, self.p], [ca.SX(expr)], ["x", "p"], [name])

    def lift(self, s: ca.SX, x_expr: Any) -> ca.Function:
        """``lift(s, p) -> x``."""
        return ca.Function("lift", [s, self.p], [ca.SX(x_expr)], ["s", "p"], ["x"])


@dataclass(frozen=True)
class Structure:
    """A model class's hybrid structure (:meth:`HybridModel.structure`): its phases, in cycle
    order starting with the one that holds the section, and its Poincaré section."""

    phases: tuple[Phase, ...]
    section: Section


@dataclass(frozen=True)
class HybridModel:
    """Base class of every model: a frozen dataclass of physical parameters.

    Subclasses declare parameters with :func:`gaitopt.parameters.parameter`, set the class
    attributes below, and implement :meth:`build` (the CasADi functions, built once per class with
    symbolic parameters) and :meth:`default_start`.  Changing a parameter makes a new model
    (:func:`dataclasses.replace` or :meth:`replace`); the built functions are shared.
    """

    name: ClassVar[str] = ""
    title: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    inputs: ClassVar[tuple[str, ...]] = ()
    input_units: ClassVar[tuple[str, ...]] = ()
    #: Unit of each state, by name (``{"theta": "rad", "theta_dot": "rad/s"}``), for axis labels;
    #: a state not listed is labelled without a unit guess (figures then say "unit not declared").
    state_units: ClassVar[dict[str, str]] = {}
    #: Unit of the model's time (``"s"``; ``"1"`` for dimensionless time).
    time_unit: ClassVar[str] = "s"
    #: Unit of the model's lengths (step length, drawn positions): ``"m"``; ``"l"`` for a
    #: model in units of its leg length.  Speeds are in ``length_unit/time_unit``.
    length_unit: ClassVar[str] = "m"
    #: Unit of the model's energies and work (``"J"``; ``"M*g*l"`` for a dimensionless model).
    energy_unit: ClassVar[str] = "J"
    #: Rate partner of a coordinate where the naming convention ``q`` → ``q_dot`` does not hold
    #: (the line juggler's ball height ``b`` has rate ``v``; its ``b_dot`` is a held pre-impact
    #: velocity, not a rate): for phase portraits.
    rates: ClassVar[dict[str, str]] = {}
    #: Polylines to draw, each a tuple of point names (``Phase.point_names``), e.g. a hopper's
    #: ``(("hip", "foot"), ("tail", "nose"))``; points in none are helpers, not drawn.  Empty:
    #: one polyline through every point in declared order.  :meth:`outline` overrides both.
    drawing: ClassVar[tuple[tuple[str, ...], ...]] = ()
    #: Whether the scene stands on the ground (walkers, hoppers: drawn over the ground line
    #: through the first contact, at :meth:`ground_slope`; animated as ``walking.gif``).  False
    #: for a scene without ground (a ball on a vibrating table, a juggler's paddle): drawn
    #: without it, its view filling the frame, animated as ``animation.gif``.
    on_ground: ClassVar[bool] = True
    #: Default shooting mesh (segments per phase, RK steps per segment); refined automatically.
    mesh: ClassVar[tuple[int, int]] = (4, 3)
    #: Whether the model can have a passive gait (with its :meth:`nominal_input`) for
    #: :func:`~gaitopt.shooting.find_limit_cycle` to look for.  False for an actuated-only
    #: model (the five-link biped: its impacts dissipate energy that only its torques supply),
    #: whose gaits come from optimisation: ``make gaits`` and the tests' passive-gait fixtures
    #: skip the passive search for it, saying why (:meth:`existence_note`).
    passive_gait: ClassVar[bool] = True
    #: Range of each per-step input, by name: ``{input: (low, high)}`` in the input's unit
    #: (controllers clip to it; the optimiser bounds by it).  Empty: unbounded.
    input_bounds: ClassVar[Mapping[str, tuple[float, float]]] = {}
    #: Range of each state, by name, that an optimised gait must keep to (joint limits).
    state_bounds: ClassVar[Mapping[str, tuple[float, float]]] = {}
    #: Longest a phase may last in simulation (s) before it counts as never ending.
    max_phase_time: ClassVar[float] = 30.0
    #: Inputs that act only in a reset, as impulses (Kuo 2002's push-off just before heel
    #: strike): the flow must not depend on them.  :func:`gaitopt.optimize_gait` makes each a
    #: constant over a step (not a profile), leaves it out of the effort ``∫Σuᵢ² dt`` and adds
    #: the work :meth:`impulse_work` says it does to the work-based costs.  Empty (default):
    #: none; every input acts in the flow.
    impulsive_inputs: ClassVar[tuple[str, ...]] = ()
    #: Inputs an optimisation leaves off (held at 0) unless its ``bounds`` name them (the kneed
    #: walker's push-off impulse: its gaits and optima with hip and knee torques stay what they
    #: were without it).  Empty (default): every input is free within its bounds.
    optional_inputs: ClassVar[tuple[str, ...]] = ()
    #: Phase 0's states, the section's free coordinates and the section's definition exactly as
    #: :meth:`build` makes them, declared so that ``gaitopt list`` shows them without building
    #: the model (the Strandbeest's linkage takes seconds): :meth:`declared_structure`.  The
    #: build checks them (a mismatch is a :class:`~gaitopt.errors.ModelDefinitionError`).  A
    #: class declares its own (a subclass does not inherit them); undeclared, ``gaitopt list``
    #: builds the model to learn them.
    declared_states: ClassVar[tuple[str, ...]] = ()
    declared_coordinates: ClassVar[tuple[str, ...]] = ()
    declared_section_doc: ClassVar[str] = ""
    _cache: ClassVar[dict[type, Structure]] = {}
    _specs: ClassVar[dict[type, tuple[ParameterSpec, ...]]] = {}

    def __post_init__(self) -> None:
        if type(self).__setattr__ is not _frozen_setattr:  # see _frozen_setattr
            type.__setattr__(type(self), "__setattr__", _frozen_setattr)
        for spec in self.parameter_specs():
            value = check_parameter(self.name, spec, getattr(self, spec.name))
            object.__setattr__(self, spec.name, value)
        self.check()

    # -- what a subclass provides ------------------------------------------------------------
    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        """Build the phases and the section from symbolic parameters."""
        raise NotImplementedError

    def default_start(self) -> dict[str, float]:
        """Section coordinates from which a simulation approaches the model's main gait."""
        raise NotImplementedError

    def check(self) -> None:
        """Cross-parameter checks (raise :class:`~gaitopt.errors.ParameterError`)."""

    def map_domain(self) -> tuple[float, float] | None:
        """Interval of a 1-D section coordinate where the return map can be defined, if the model
        knows it (for plots of the map and the feasible range of a deadbeat controller); None
        otherwise."""
        return None

    def closed_form_map(self, coordinate: float) -> float | None:
        """The return map of a 1-D section in closed form, where theory gives it (the rimless
        wheel, the line juggler, the vertical hopper), for checks and plots; None otherwise."""
        del coordinate
        return None

    def section_limits(self) -> dict[str, tuple[float, float, str]]:
        """Closed-form limits of the section coordinates at these parameters, by name:
        ``(low, high, why)``.  A point outside them does not exist (the SLIP's apex above its
        energy height) and is bad input, not a gait or a decision that fails.  Empty (default):
        no such limits."""
        return {}

    def input_box(self) -> tuple[np.ndarray, np.ndarray] | None:
        """:attr:`input_bounds` as ``(low, high)`` vectors in input order (``±inf`` where an
        input is not bounded); None for a model that bounds none."""
        if not self.input_bounds:
            return None
        lo = np.array([self.input_bounds.get(k, (-np.inf, np.inf))[0] for k in self.inputs])
        hi = np.array([self.input_bounds.get(k, (-np.inf, np.inf))[1] for k in self.inputs])
        return lo, hi

    def outline(self, phase: Phase, x: np.ndarray, points: np.ndarray) -> np.ndarray | None:
        """A drawing of the model in ``phase`` at state ``x`` (2×M, m, NaN-separated polylines,
        relative to the contact point) for shapes :attr:`drawing` cannot say (the rimless wheel's
        spokes); ``points`` are ``phase.points(x, p)``.  None (default): use :attr:`drawing`."""
        del phase, x, points
        return None

    def ground_slope(self) -> float:
        """Slope (rad, positive downhill towards +x) of the ground a drawing shows under a scene
        :attr:`on_ground`: the model's ``slope`` parameter where it declares one, else 0 (level
        ground).  A model whose ground slope is another quantity overrides this."""
        return float(self.params.get("slope", 0.0))

    def max_step_length(self) -> float | None:
        """The longest step the geometry allows: the largest distance between the feet at heel
        strike (``length_unit``), twice the leg length for a biped, or None where the model
        states none.  :func:`gaitopt.optimize_gait` refuses a longer fixed ``step_length`` at
        once, naming it, instead of letting IPOPT find that out."""
        return None

    def existence_note(self) -> str | None:
        """What closed-form theory says about the main gait's existence at these parameters, if
        anything is known (added to a failed search's message; never used to decide)."""
        return None

    def input_rates(self, phase: int) -> ca.Function | None:
        """The rates the inputs do work on in ``phase``, for the positive-work cost of
        :func:`gaitopt.optimize_gait`: ``rates(x, p) -> ω`` with one entry per input (rad/s for a
        torque, m/s for a force) such that input ``i`` delivers the power ``uᵢ ωᵢ`` (W) — for a
        joint torque, the relative rate of the two bodies it acts between.  ``None`` (the
        default): the model does not declare them, and work-based costs are unavailable."""
        del phase
        return None

    def impulse_work(self, phase: int) -> ca.Function | None:
        """The positive work the :attr:`impulsive_inputs` do in the cycle transition of
        ``phase`` (``transitions[0]``): ``work(x⁻, u, p) -> w`` with one entry per impulsive
        input, in the model's energy unit (J; ``m·g·l`` for a dimensionless model), ``x⁻`` the
        state just before the transition.  ``None`` (the default): no impulsive input acts
        there."""
        del phase
        return None

    # -- derived -----------------------------------------------------------------------------
    @classmethod
    def parameter_specs(cls) -> tuple[ParameterSpec, ...]:
        """Specifications of the parameters, in the order of the vector ``p`` (read once per
        class: a model's fields do not change)."""
        specs = HybridModel._specs.get(cls)
        if specs is None:
            specs = HybridModel._specs[cls] = parameter_specs(cls)
        return specs

    @classmethod
    def declared_structure(cls) -> tuple[tuple[str, ...], tuple[str, ...], str] | None:
        """``(states, coordinates, section definition)`` as the class itself declares them
        (:attr:`declared_states`, :attr:`declared_coordinates`, :attr:`declared_section_doc`),
        without building the model; None if the class declares none of its own."""
        if "declared_states" not in vars(cls):
            return None
        return cls.declared_states, cls.declared_coordinates, cls.declared_section_doc

    @classmethod
    def structure(cls) -> Structure:
        """The class's phases and section (``.phases``, ``.section``), built once per class from
        symbolic parameters by :meth:`build`, validated and cached; no model instance needed."""
        if cls not in HybridModel._cache:
            sym = Symbols(cls.parameter_specs(), cls.inputs)
            phases, section = cls.build(sym)
            _validate_structure(cls, tuple(phases), section)
            _check_declared(cls, tuple(phases), section)
            HybridModel._cache[cls] = Structure(tuple(phases), section)
        return HybridModel._cache[cls]

    @property
    def phases(self) -> tuple[Phase, ...]:
        """The phases of one cycle, starting with the one that contains the section."""
        return self.structure().phases

    @property
    def section(self) -> Section:
        """The Poincaré section."""
        return self.structure().section

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the states on the section (phase 0)."""
        return self.phases[0].states

    @property
    def params(self) -> dict[str, float]:
        """Parameter name → value."""
        return {s.name: getattr(self, s.name) for s in self.parameter_specs()}

    @property
    def p(self) -> np.ndarray:
        """The parameter vector, in declaration order."""
        return np.array([getattr(self, s.name) for s in self.parameter_specs()], dtype=float)

    def replace(self, **changes: float) -> HybridModel:
        """A copy with some parameters changed (checked like the constructor)."""
        return dataclasses.replace(self, **changes)

    def nominal_input(self) -> np.ndarray:
        """The per-step input used when none is given: ``u = 0`` (passive) unless a model says
        otherwise (e.g. a runner's touchdown angle parameter)."""
        return np.zeros(len(self.inputs))

    # -- states ------------------------------------------------------------------------------
    def lift(self, coordinates: Mapping[str, float] | Sequence[float]) -> np.ndarray:
        """Full phase-0 state from section coordinates (a mapping by name, or a sequence)."""
        s = self.section_vector(coordinates)
        return np.asarray(self.section.lift(s, self.p), dtype=float).ravel()

    def section_vector(self, coordinates: Mapping[str, float] | Sequence[float]) -> np.ndarray:
        """Section coordinates as a vector; missing names come from :meth:`default_start`."""
        names = self.section.coordinates
        if isinstance(coordinates, Mapping):
            unknown = [k for k in coordinates if k not in names]
            if unknown:
                other = [k for k in unknown if k in self.state_names]
                hint = (
                    f"{other[0]!r} is fixed by the section ({self.section.doc})"
                    if other
                    else f"the section coordinates are {', '.join(names)}"
                )
                raise StateError(f"{self.name}: unknown state {unknown[0]!r}; {hint}")
            values = {**self.default_start(), **coordinates}
            vec = np.array([float(values[k]) for k in names])
        else:
            vec = np.asarray(coordinates, dtype=float).ravel()
            if vec.size != len(names):
                raise StateError(
                    f"{self.name}: expected {len(names)} section coordinates "
                    f"({', '.join(names)}), got {vec.size}"
                )
        if not np.all(np.isfinite(vec)):
            raise StateError(f"{self.name}: section coordinates must be finite, got {vec}")
        return vec

    def state_vector(
        self, state: Mapping[str, float] | Sequence[float], phase: int = 0
    ) -> np.ndarray:
        """A full state of ``phase`` as a vector, from a complete mapping or sequence."""
        names = self.phases[phase].states
        if isinstance(state, Mapping):
            unknown = [k for k in state if k not in names]
            missing = [k for k in names if k not in state]
            if unknown or missing:
                bad = unknown[0] if unknown else missing[0]
                what = "unknown" if unknown else "missing"
                raise StateError(
                    f"{self.name}: {what} state {bad!r}; the states are {', '.join(names)}"
                )
            vec = np.array([float(state[k]) for k in names])
        else:
            vec = np.asarray(state, dtype=float).ravel()
        if vec.size != len(names) or not np.all(np.isfinite(vec)):
            raise StateError(
                f"{self.name}: a state needs {len(names)} finite values ({', '.join(names)})"
            )
        return vec

    def section_coordinates_of(self, x: np.ndarray) -> np.ndarray:
        """Project a phase-0 state onto the section coordinates (pick the named entries)."""
        idx = [self.state_names.index(c) for c in self.section.coordinates]
        return np.asarray(x, dtype=float)[idx]


def _frozen_setattr(self: HybridModel, name: str, value: Any) -> None:
    """``HybridModel.__setattr__``: models are immutable; raise
    :class:`~gaitopt.errors.FrozenModelError` saying how to change a parameter.

    ``@dataclass(frozen=True)`` gives each model class its own ``__setattr__`` (whose message
    says only "cannot assign to field"); :meth:`HybridModel.__post_init__` replaces it with this
    one."""
    cls = type(self)
    if name in {s.name for s in cls.parameter_specs()}:
        raise FrozenModelError(
            f"cannot assign to {cls.__name__}.{name}: models are immutable; make a new one with "
            f"model.replace({name}={value!r}) or gaitopt.model({cls.name!r}, {name}={value!r})"
        )
    raise FrozenModelError(
        f"cannot assign to {cls.__name__}.{name}: models are immutable; change a parameter with "
        f"model.replace(NAME=VALUE)"
    )


def _check_declared(cls: type, phases: tuple[Phase, ...], section: Section) -> None:
    """The structure a class declares (:meth:`HybridModel.declared_structure`) is the one its
    ``build`` made: phase 0's states, the section's coordinates and definition."""
    from .errors import ModelDefinitionError

    declared = cls.declared_structure()
    built = (tuple(phases[0].states), tuple(section.coordinates), section.doc)
    if declared is None or tuple(declared) == built:
        return
    what = ("declared_states", "declared_coordinates", "declared_section_doc")
    wrong = [
        f"{name} = {d!r} (built: {b!r})"
        for name, d, b in zip(what, declared, built, strict=True)
        if d != b
    ]
    raise ModelDefinitionError(
        f"model class {cls.__name__}: its declaration differs from its build: {'; '.join(wrong)}"
    )


def _validate_structure(cls: type, phases: tuple[Phase, ...], section: Section) -> None:
    """Check a model class's hybrid structure once, when it is built: the cycle's transitions
    enter the next phase in order (the shooting follows the cycle order, the simulation follows
    ``target``: they must agree), resets and guards have the right dimensions, and the section
    lift has phase 0's dimension and leaves its own coordinates unchanged (checked at the
    default parameters and a few section points)."""
    from .errors import ModelDefinitionError

    def fail(what: str) -> None:
        raise ModelDefinitionError(f"model class {cls.__name__}: {what}")

    if not phases:
        fail("`build` returned no phases")
    for i, phase in enumerate(phases):
        if not phase.transitions:
            fail(f"phase {phase.name!r} has no transition")
        for j, transition in enumerate(phase.transitions):
            where = f"transition {transition.name!r} of phase {phase.name!r}"
            if transition.direction not in (-1, 1):
                fail(f"{where}: direction must be +1 or -1, got {transition.direction!r}")
            if transition.guard.numel_out(0) != 1:
                fail(f"{where}: the guard must be scalar")
            if transition.reset is None:  # ends the motion (a fall; the ballistic swing's end)
                continue
            if j == 0 and transition.target != (i + 1) % len(phases):
                fail(
                    f"{where} closes the phase in the cycle, so its target must be the next phase "
                    f"({(i + 1) % len(phases)}), got {transition.target!r}"
                )
            if transition.target is None or not 0 <= transition.target < len(phases):
                fail(f"{where}: target {transition.target!r} is not a phase index")
            n_target = phases[transition.target].n
            if transition.reset.numel_out(0) != n_target:
                fail(
                    f"{where}: the reset gives {transition.reset.numel_out(0)} states, the "
                    f"target phase {phases[transition.target].name!r} has {n_target}"
                )
    first = phases[0]
    missing = [c for c in section.coordinates if c not in first.states]
    if missing:
        fail(f"section coordinate(s) {missing} are not states of phase {first.name!r}")
    if section.lift.numel_in(0) != len(section.coordinates) or section.lift.numel_out(0) != first.n:
        fail(
            f"the section lift must map {len(section.coordinates)} coordinate(s) to the "
            f"{first.n} states of phase {first.name!r}"
        )
    p = np.array([spec.default for spec in cls.parameter_specs()], dtype=float)
    index = [first.states.index(c) for c in section.coordinates]
    for scale in (0.01, 0.1):
        s = scale * np.arange(1, len(index) + 1, dtype=float)
        x = np.asarray(section.lift(s, p), dtype=float).ravel()
        if np.all(np.isfinite(x)) and np.max(np.abs(x[index] - s), initial=0.0) > 1e-12:
            fail(
                f"the section lift moves its own coordinates (lift(s)[{section.coordinates}] = "
                f"{x[index]} at s = {s}): it must return them unchanged"
            )
