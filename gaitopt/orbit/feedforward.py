"""An optimal gait's open loop as an autonomous hybrid model: its input profile read on a clock.

:func:`gaitopt.optimize_gait` returns an orbit whose inputs are a profile ``u*(t)``, ``t`` the time
since the section (:class:`gaitopt.optimize.InputProfile`: piecewise polynomials, the first value
held before 0 and the last after the end).  That open loop is a non-autonomous system; with a
*clock* state ``t`` (``ṫ = 1``, reset to 0 where the orbit returns to the section and carried
through every other reset) it is an autonomous :class:`~gaitopt.hybrid.HybridModel` like any other,
so multiple shooting (:func:`gaitopt.find_limit_cycle`), continuation, two-parameter curves and
step-to-step control apply to it unchanged:

* states: the base model's, plus ``clock`` (s) in every phase; the section's lift sets it to 0 and
  the section's coordinates are the base model's (so the multipliers are the same count);
* flow, guards, resets, admissibility and unilateral constraints: the base model's, evaluated with
  the input ``u*(clock) + δ``, ``δ`` the per-step input of this model (an *offset* on the profile,
  one value per step per input, 0 nominally: what step-to-step control acts on);
* parameters: the base model's, declared and changeable (a slope, a mass); the profile is fixed,
  part of the class.  Their defaults are the optimum's values.

The clock is the optimum's own: the profile runs in the time since the section, as the
collocation's Floquet multipliers (:mod:`gaitopt.optimize.floquet`) and the referee's feedforward
(:func:`gaitopt.optimize.verify.feedforward_of`) read it, so the return map of this model *is* the
optimum's, and a gait of it at the optimum's parameters is the optimum's orbit.  (A clock reset at
every impact would read the same profile for a one-phase step and a different one wherever a step
has several phases, as the kneed walker's knee strike.)

One class per base model class and profile (:func:`feedforward_class`), built once and cached by a
hash of the profile; its compiled kernels are cached like any model's (the first use of a new
profile compiles them: about 10 s for the compass gait).  The profile's pieces are evaluated
exactly as :class:`~gaitopt.optimize.InputProfile` does (the same interval on each side of a
break, the same clamping, Horner's rule), so the two agree to rounding.
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Sequence
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel, Phase, Section, Symbols

__all__ = ["CLOCK", "FeedforwardModel", "feedforward_class", "feedforward_model", "profile_sx"]

#: Name of the clock state (s since the section) every phase of a feedforward model adds.
CLOCK = "clock"

#: How far beyond the profile's ends its end pieces continue before the values are held, as a
#: fraction of ``1 + duration`` (see :func:`profile_sx`).
HOLD_MARGIN = 1e-9
#: How far beyond its nominal ends a phase reads its own pieces (a fraction of ``1 + duration``;
#: :func:`profile_sx`): wide enough to hold the orbit's crossings (the collocation's timing
#: error, 1e-8 s on the kneed walker), narrow enough not to matter (the pieces differ there by
#: their joins' jumps, 1e-6: an effect of order 1e-12 on the orbit).
PHASE_MARGIN = 1e-6
#: How much earlier than its time each inner break of the profile switches pieces, as a fraction
#: of ``1 + duration`` (:func:`_pieces`): above the clock's rounding at a segment's end (the
#: shooting's continuity is solved to 1e-13), far below anything the orbit sees.
BREAK_SHIFT = 1e-10

_CLASSES: dict[str, type] = {}


def profile_sx(
    breaks: np.ndarray,
    coefficients: np.ndarray,
    t: ca.SX,
    span: tuple[int, int] | None = None,
) -> ca.SX:
    """The piecewise polynomial ``u(t)`` of an input profile as a CasADi expression of ``t`` (s).

    Parameters
    ----------
    breaks : numpy.ndarray
        Interval boundaries (s), increasing from 0.
    coefficients : numpy.ndarray
        ``(intervals, degree + 1, inputs)``: power-series coefficients in ``t − breaks[i]``,
        highest power first (:class:`gaitopt.optimize.InputProfile`'s layout).
    t : casadi.SX
        The time (scalar).
    span : (int, int), optional
        The intervals ``[i, j)`` of one phase of the orbit (``breaks[i]`` to ``breaks[j]`` its
        nominal start and end): within :data:`PHASE_MARGIN` of them the phase's own first and
        last pieces are continued instead of the neighbouring phase's (see below).

    Returns
    -------
    casadi.SX
        ``inputs × 1``: interval ``i`` where ``breaks[i] ≤ t < breaks[i + 1]`` (the last one up to
        and including its end), ``t`` clamped to ``[0, breaks[-1]]`` first, as
        :meth:`InputProfile.__call__` does, except that the clamp starts :data:`HOLD_MARGIN`
        beyond each end, each inner break switches :data:`BREAK_SHIFT` earlier, and with
        ``span`` the phase's pieces reach :data:`PHASE_MARGIN` beyond its ends.
    """
    breaks = np.asarray(breaks, dtype=float)
    coefficients = np.asarray(coefficients, dtype=float)
    intervals = coefficients.shape[0]
    # The held values start HOLD_MARGIN beyond each end, the end pieces continued up to there:
    # the shooting evaluates the profile at the orbit's end (its last RK stage, the clock within
    # rounding of the end), and its Jacobian is consistent only if it sees the piece's slope
    # there; seeing the hold's zero slope instead puts an O(h) error into the multipliers
    # (3e-5 on the compass optimum at 384 RK steps, against 8e-9 with the margin).  Beyond the
    # margin the end values hold, exactly InputProfile's; the two profiles differ only within
    # the margin, by at most |u̇| · margin.
    end = float(breaks[-1])
    margin = HOLD_MARGIN * (1.0 + end)
    tc = ca.if_else(t > end + margin, end, ca.if_else(t < -margin, 0.0, t))
    total = _pieces(breaks, coefficients, tc, 0, intervals)
    if span is None or tuple(span) == (0, intervals):
        return total
    # A phase that ends inside the orbit (the kneed walker's knee strike) ends where the next
    # phase's pieces begin, and the pieces join with a jump at the collocation's level (1e-7 to
    # 1e-6): read on the global profile, the phase's last RK stage would land on one side or the
    # other as Newton moves the crossing by rounding, and the shooting residual would jump with
    # it (the kneed walker's Newton stalled at 6e-8).  Within PHASE_MARGIN of its nominal ends a
    # phase reads its own pieces, as the collocation's phase does; the orbit's crossings lie
    # there (within the collocation's error, 1e-8 s), so the residual is smooth at the gait.
    i, j = span
    window = PHASE_MARGIN * (1.0 + end)
    inside = (t >= float(breaks[i]) - window) * (t <= float(breaks[j]) + window)
    return ca.if_else(inside, _pieces(breaks, coefficients, t, i, j), total)


def _pieces(breaks: np.ndarray, coefficients: np.ndarray, t: ca.SX, first: int, stop: int):
    """``Σ mask_k · piece_k(t)`` over the intervals ``first ≤ k < stop``, each holding
    ``[breaks[k], breaks[k + 1])``, the first also everything below and the last everything
    from its start on (``searchsorted(side="right") − 1``, clipped), except that each inner
    break is moved :data:`BREAK_SHIFT` · (1 + duration) earlier.

    The shooting's segments end on the breaks, and its RK stages there (the last of one
    segment, the first of the next) read the clock within rounding of them; with the break
    exactly there, that rounding would pick one piece or the other from one Newton iteration to
    the next, and the pieces' jump (1e-7 to 1e-6) would make the residual jump with it (the
    kneed walker's Newton stalled at 5e-8).  Moved a little earlier, the break leaves both
    stages in the later piece whatever the rounding.
    """
    shift = BREAK_SHIFT * (1.0 + float(breaks[-1]))
    total = ca.SX.zeros(coefficients.shape[2], 1)
    for k in range(first, stop):
        local = t - float(breaks[k])
        value = ca.DM(coefficients[k, 0, :])
        for row in coefficients[k, 1:, :]:
            value = value * local + ca.DM(row)
        inside = 1.0
        if k > first:
            inside = inside * (t >= float(breaks[k]) - shift)
        if k < stop - 1:
            inside = inside * (t < float(breaks[k + 1]) - shift)
        total = total + inside * value
    return total


class FeedforwardModel(HybridModel):
    """Base of the open-loop classes :func:`feedforward_class` makes (not a model itself).

    Class attributes set by the factory: ``base`` (the model class the profile drives),
    ``profile_breaks`` and ``profile_coefficients`` (the profile, as
    :class:`gaitopt.optimize.InputProfile`), ``section_start`` (the optimum's section point: the
    default start) and ``profile_key`` (a hash of all of them).
    """

    base: ClassVar[type]
    profile_breaks: ClassVar[np.ndarray]
    profile_coefficients: ClassVar[np.ndarray]
    section_start: ClassVar[dict[str, float]]
    profile_spans: ClassVar[tuple[tuple[int, int], ...] | None]
    profile_key: ClassVar[str]

    @property
    def base_model(self) -> HybridModel:
        """The base model at this model's parameters."""
        return self.base(**self.params)

    def check(self) -> None:
        self.base(**self.params)  # the base model's cross-parameter checks (ParameterError)

    def default_start(self) -> dict[str, float]:
        return dict(self.section_start)

    def section_limits(self) -> dict[str, tuple[float, float, str]]:
        return self.base_model.section_limits()

    def ground_slope(self) -> float:
        return self.base_model.ground_slope()

    def max_step_length(self) -> float | None:
        return self.base_model.max_step_length()

    def outline(self, phase: Phase, x: np.ndarray, points: np.ndarray) -> np.ndarray | None:
        index = next(i for i, ph in enumerate(self.phases) if ph is phase)
        base_phase = self.base.structure().phases[index]
        return self.base_model.outline(base_phase, np.asarray(x)[: base_phase.n], points)

    def profile(self, t: float) -> np.ndarray:
        """The profile's input at ``t`` s since the section (input units), offsets excluded."""
        self.structure()  # builds _profile with the phases
        return np.asarray(self._profile(float(t)), dtype=float).ravel()

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        base = cls.base.structure()
        p, delta = sym.p, sym.u
        last = len(base.phases) - 1
        phases = []
        for i, phase in enumerate(base.phases):
            n = phase.n
            x = ca.SX.sym("x", n + 1)
            xb, clock = x[:n], x[n]
            span = cls.profile_spans[i] if cls.profile_spans else None
            u = profile_sx(cls.profile_breaks, cls.profile_coefficients, clock, span) + delta

            def on(f: ca.Function | None, name: str, x=x, xb=xb, u=u) -> ca.Function | None:
                return None if f is None else sym.function(name, x, f(xb, u, p))

            transitions = []
            for j, tr in enumerate(phase.transitions):
                reset = None
                if tr.reset is not None:
                    # The clock restarts where the orbit returns to the section (the cycle's
                    # closing transition, or one that also returns there) and runs on through
                    # every other reset.
                    closes = (i == last and j == 0) or tr.returns_to_section
                    after = 0.0 if closes else clock
                    reset = sym.function("reset", x, ca.vertcat(tr.reset(xb, u, p), after))
                transitions.append(
                    dataclasses.replace(
                        tr,
                        guard=on(tr.guard, "guard"),
                        reset=reset,
                        admissible=on(tr.admissible, "admissible"),
                    )
                )
            constraints = tuple(
                dataclasses.replace(c, function=on(c.function, "constraint"))
                for c in phase.constraints
            )

            def on_x(f: ca.Function | None, name: str, x=x, xb=xb) -> ca.Function | None:
                if f is None:
                    return None
                outs = f(xb, p)
                outs = outs if isinstance(outs, tuple) else (outs,)
                return ca.Function(name, [x, p], list(outs), ["x", "p"], f.name_out())

            phases.append(
                Phase(
                    phase.name,
                    (*phase.states, CLOCK),
                    sym.function("flow", x, ca.vertcat(phase.flow(xb, u, p), 1.0)),
                    tuple(transitions),
                    {},  # the profile does work: nothing is conserved along the open loop
                    points=on_x(phase.points, "points"),
                    point_names=phase.point_names,
                    bodies=on_x(phase.bodies, "bodies"),
                    constraints=constraints,
                )
            )
        s = ca.SX.sym("s", len(base.section.coordinates))
        section = Section(
            base.section.coordinates,
            sym.lift(s, ca.vertcat(base.section.lift(s, p), 0.0)),
            f"{base.section.doc}; clock = 0 (s since the section)",
        )
        t = ca.SX.sym("t")
        cls._profile = staticmethod(
            ca.Function(
                "profile", [t], [profile_sx(cls.profile_breaks, cls.profile_coefficients, t)]
            )
        )
        return tuple(phases), section


def feedforward_class(
    base: type,
    profile: Any,
    section_start: dict[str, float],
    params: dict[str, float],
    durations: Sequence[float] | None = None,
) -> type[FeedforwardModel]:
    """The open-loop model class of ``base`` driven by ``profile`` (built once per profile).

    Parameters
    ----------
    base : type
        The model class the optimum was computed for.
    profile : InputProfile
        Its input profile (``.breaks`` in s, ``.coefficients``; one step).
    section_start : dict
        The optimum's section coordinates: the class's default start.
    params : dict
        The optimum's parameters: the class's parameter defaults (their ranges stay the base's).
    durations : sequence of float, optional
        The optimum's phase durations (s): where its phases end on breaks of the profile, each
        phase reads its own pieces near its ends (:func:`profile_sx`'s ``span``).

    Returns
    -------
    type
        A :class:`FeedforwardModel` subclass named ``<base.name>_feedforward``, not registered.
    """
    breaks = np.ascontiguousarray(np.asarray(profile.breaks, dtype=float))
    coefficients = np.ascontiguousarray(np.asarray(profile.coefficients, dtype=float))
    n_u = len(base.inputs)
    if (
        coefficients.ndim != 3
        or coefficients.shape[2] != n_u
        or breaks.size != len(coefficients) + 1
    ):
        raise GaitoptInputError(
            f"profile: coefficients of shape {coefficients.shape} and {breaks.size} breaks do not "
            f"describe a profile of {base.name}'s {n_u} input(s); pass an OptimalGait's profile"
        )
    digest = hashlib.sha256()
    for part in (base.__module__, base.__qualname__, repr(sorted(params.items())),
                 repr(sorted(section_start.items()))):  # fmt: skip
        digest.update(part.encode())
    spans = _spans(breaks, durations, len(base.structure().phases))
    digest.update(repr(spans).encode())
    digest.update(breaks.tobytes())
    digest.update(coefficients.tobytes())
    key = digest.hexdigest()[:16]
    if key in _CLASSES:
        return _CLASSES[key]
    fields = []
    for spec in base.parameter_specs():
        value = float(params.get(spec.name, spec.default))
        new_spec = dataclasses.replace(
            spec,
            default=value,
            source=f"the optimal gait's value (the base model's default {spec.default:g}: "
            f"{spec.source})",
        )
        fields.append(
            (spec.name, float, dataclasses.field(default=value, metadata={"gaitopt": new_spec}))
        )
    namespace = {
        "name": f"{base.name}_feedforward",
        "title": f"{base.title or base.name} driven by an optimal input profile on the clock",
        "reference": base.reference,
        "inputs": tuple(base.inputs),
        "input_units": tuple(base.input_units),
        "state_units": {**dict(base.state_units), CLOCK: base.time_unit},
        "time_unit": base.time_unit,
        "length_unit": base.length_unit,
        "energy_unit": base.energy_unit,
        "rates": dict(base.rates),
        "drawing": base.drawing,
        "on_ground": base.on_ground,
        "mesh": _mesh(base, breaks, spans),
        "max_phase_time": base.max_phase_time,
        "impulsive_inputs": tuple(base.impulsive_inputs),
        "input_bounds": _offset_bounds(base, breaks, coefficients),
        "base": base,
        "profile_breaks": breaks,
        "profile_coefficients": coefficients,
        "section_start": dict(section_start),
        "profile_spans": spans,
        "profile_key": key,
        "__module__": __name__,
    }
    new = dataclasses.make_dataclass(
        f"{base.__name__}Feedforward{key}",
        fields,
        bases=(FeedforwardModel,),
        namespace=namespace,
        frozen=True,
    )
    _CLASSES[key] = new
    return new


def _spans(
    breaks: np.ndarray, durations: Sequence[float] | None, phases: int
) -> tuple[tuple[int, int], ...] | None:
    """Each phase's intervals ``[i, j)`` of the profile, where the optimum's phases end on its
    breaks (within 1e-9 of the period); None with one phase, or where one does not."""
    if durations is None or phases == 1 or len(durations) != phases:
        return None
    ends = np.cumsum(np.asarray(durations, dtype=float))
    index = [0]
    for t in ends:
        k = int(np.argmin(np.abs(breaks - t)))
        if abs(breaks[k] - t) > 1e-9 * (1.0 + breaks[-1]) or k <= index[-1]:
            return None
        index.append(k)
    if index[-1] != breaks.size - 1:
        return None
    return tuple((a, b) for a, b in zip(index[:-1], index[1:], strict=True))


def _mesh(
    base: type, breaks: np.ndarray, spans: tuple[tuple[int, int], ...] | None = None
) -> tuple[int, int]:
    """The shooting mesh: as many segments per phase as the profile has intervals per phase
    (at least the base model's), so that on the collocation's uniform mesh (the same number of
    intervals in every phase, no arcs) every segment is one polynomial piece; at least 8 RK
    steps per segment (where the pieces join, the refinement is first order: see
    :func:`gaitopt.open_loop.open_loop_cycle`)."""
    segments, rk = base.mesh
    intervals = breaks.size - 1
    phases = len(base.structure().phases)
    if spans is not None:  # the phases' own interval counts (equal on a uniform mesh)
        segments = max(segments, *(j - i for i, j in spans))
    elif intervals % phases == 0:
        segments = max(segments, intervals // phases)
    return segments, max(rk, 8)


def _offset_bounds(base: type, breaks: np.ndarray, coefficients: np.ndarray) -> dict:
    """Bounds on the per-step offsets that keep profile + offset inside the base model's
    declared input bounds over the whole profile (its extremes on 64 samples per piece)."""
    if not base.input_bounds:
        return {}
    t = np.concatenate(
        [np.linspace(a, b, 64) - a for a, b in zip(breaks[:-1], breaks[1:], strict=True)]
    )
    piece = np.repeat(np.arange(len(coefficients)), 64)
    values = np.zeros((t.size, coefficients.shape[2]))
    for row in range(coefficients.shape[1]):
        values = values * t[:, None] + coefficients[piece, row, :]
    bounds = {}
    for k, name in enumerate(base.inputs):
        if name in base.input_bounds:
            lo, hi = base.input_bounds[name]
            bounds[name] = (float(lo - values[:, k].min()), float(hi - values[:, k].max()))
    return bounds


def feedforward_model(gait: Any) -> FeedforwardModel:
    """The open loop of an optimal gait as a model at the gait's parameters.

    Parameters
    ----------
    gait : OptimalGait
        A successful optimum of one step (:func:`gaitopt.optimize_gait`).

    Raises
    ------
    GaitoptInputError
        If ``gait`` is not an optimal gait, did not succeed, or has more than one step.
    """
    profiles = getattr(gait, "profiles", None)
    if profiles is None or not hasattr(gait, "cost_kind"):
        raise GaitoptInputError(
            f"gait: expected an OptimalGait (gaitopt.optimize_gait), got {type(gait).__name__}"
        )
    if not gait.success:
        raise GaitoptInputError(
            f"gait: the optimal gait given failed ({gait.status}: {gait.message}); only a "
            f"certified optimum has an open loop to analyse: solve it again (see its advice)"
        )
    if len(profiles) != 1:
        raise GaitoptInputError(
            f"gait: an optimum of {len(profiles)} steps; the open loop is built for one-step "
            f"optima (optimize with steps=1)"
        )
    base = gait.model
    start = {k: float(gait.fixed_point[k]) for k in base.section.coordinates}
    cls = feedforward_class(
        type(base), profiles[0], start, dict(base.params), getattr(gait, "durations", None)
    )
    return cls(**base.params)
