"""The hybrid-system abstraction: phases, flows, guards, resets, the Poincaré section.

A gait is a periodic orbit of a hybrid system: a cycle of *phases*, each a smooth flow
``ẋ = f(x, u, p)`` that ends when a *guard* ``g(x, u, p)`` crosses zero in a stated direction,
after which a *reset* ``x⁺ = r(x⁻, u, p)`` maps the state into the next phase (whose state may
have another dimension).  An *admissibility* function excludes spurious crossings: a crossing
counts only where it is positive (the compass gait's swing foot scuffing the ground mid-swing).

Every function is a CasADi :class:`casadi.Function` of the state ``x``, the per-step input ``u``
(constant over a step; empty for passive models) and the parameter vector ``p``.  Parameters are
*symbolic* inputs, so a model class is built once and every parameter value reuses the graph.

This module is the model, :class:`HybridModel`; its parts are in :mod:`gaitopt.phases`
(:class:`Phase`, :class:`Transition`, :class:`Constraint`, :class:`Section`,
:class:`Structure`), the symbols its ``build`` works with in :mod:`gaitopt.symbols` and the checks
of a built structure in :mod:`gaitopt.model_checks`; all are importable from here too.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from .errors import FrozenModelError, StateError
from .fastcall import call1
from .model_checks import check_declared, validate_structure
from .parameters import ParameterSpec, check_parameter, parameter_specs
from .phases import Constraint, Phase, Section, Structure, Transition, rate_along
from .symbols import Symbols

__all__ = [
    "Transition",
    "Constraint",
    "Phase",
    "Section",
    "Structure",
    "HybridModel",
    "Symbols",
    "rate_along",
]


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
        symbolic parameters by :meth:`build`, validated and cached; no model instance needed.

        A built-in model's structure is also kept pickled in the kernel cache under its source
        key (:func:`gaitopt.kernels.cache.remembered`): a later process unpickles it (the same
        CasADi graphs) instead of building it, several times faster."""
        if cls not in HybridModel._cache:
            if cls._may_remember_structure():
                from .kernels.cache import remembered

                HybridModel._cache[cls] = remembered("structure", cls, cls._build_structure)
            else:
                HybridModel._cache[cls] = cls._build_structure()
        return HybridModel._cache[cls]

    @classmethod
    def _may_remember_structure(cls) -> bool:
        """Whether the structure may be unpickled instead of built: only for a built-in model's
        own class (defined at the top of a module of ``gaitopt.models``; a class made at run
        time — an HZD closed loop, an optimum's feedforward — is named alike for different
        contents) whose :meth:`build` has no side effects (``remember_structure = False``
        declares that it fills tables of its own, e.g. the three-link walker's output
        functions)."""
        if not cls.__dict__.get("remember_structure", True):
            return False
        module = sys.modules.get(cls.__module__)
        return cls.__module__.startswith("gaitopt.models.") and (
            getattr(module, cls.__qualname__, None) is cls
        )

    @classmethod
    def _build_structure(cls) -> Structure:
        """:meth:`build` on symbolic parameters, validated."""
        sym = Symbols(cls.parameter_specs(), cls.inputs)
        phases, section = cls.build(sym)
        validate_structure(cls, tuple(phases), section)
        check_declared(cls, tuple(phases), section)
        return Structure(tuple(phases), section)

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
        """The parameter vector, in declaration order (a fresh copy: a model is immutable, so
        the vector is built once)."""
        vector = self.__dict__.get("_p_vector")
        if vector is None:
            vector = np.array([getattr(self, s.name) for s in self.parameter_specs()], dtype=float)
            object.__setattr__(self, "_p_vector", vector)
        return vector.copy()

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
        return call1(self.section.lift, s, self.p).ravel()  # buffered: no DM per call

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
