"""The parts of a hybrid model: :class:`Phase` (a flow, its guards and resets,
:class:`Transition`; its unilateral conditions, :class:`Constraint`), the Poincaré
:class:`Section`, and a model class's :class:`Structure` (its phases and section).  The model
itself, :class:`~gaitopt.hybrid.HybridModel`, puts them together."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import casadi as ca

__all__ = ["Transition", "Constraint", "Phase", "Section", "Structure", "rate_along"]


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


@dataclass(frozen=True)
class Structure:
    """A model class's hybrid structure (:meth:`HybridModel.structure`): its phases, in cycle
    order starting with the one that holds the section, and its Poincaré section."""

    phases: tuple[Phase, ...]
    section: Section
