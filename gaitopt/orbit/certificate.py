"""The certificate of a gait ("never a false gait"): the physical checks of a periodic orbit on
its dense samples, the same for every transcription.

Both front doors use it: :func:`gaitopt.find_limit_cycle` (multiple shooting: the RK
integrator's dense samples, :func:`gaitopt.shooting.certify`) and :func:`gaitopt.optimize_gait`
(Radau collocation: its polynomials between the nodes, :mod:`gaitopt.optimize.certify`).  Each
transcription turns its solution into :class:`DenseArc` samples (one per phase of the orbit, with
the input at each sample: constant per step, or the optimal profile) and
:func:`certify_orbit` checks, in this order:

1. every phase lasts a positive time;
2. each phase ends on its cycle guard ``g = 0``, crossing it in the stated direction
   (``direction · ġ > 0``, ``ġ = ∇g · f``) where the crossing is admissible;
3. no guard of the phase is crossed (admissibly, in its direction, after being strictly on its
   pre-crossing side) before the phase ends;
4. every declared unilateral constraint (:attr:`gaitopt.hybrid.Phase.constraints`) holds on the
   samples, ``c ≥ −1e-9 · (1 + max |c|)`` (:data:`CONSTRAINT_TOL`), and one declared
   ``at_start`` (zero where the phase begins: a trailing foot on the ground) rises there,
   ``ċ = ∇c · f > 1e-9`` (its unit per second): the foot lifts off;
5. a period-k orbit is not a shorter one repeated.

Each check returns None or the first failure in words (``"no gait: …"``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..fastcall import call1
from ..hybrid import HybridModel, rate_along

__all__ = [
    "CONSTRAINT_TOL",
    "DenseArc",
    "certify_orbit",
    "check_constraints",
    "check_durations",
    "check_early_crossings",
    "check_minimal_period",
    "check_phase_ends",
]

#: The one tolerance rule of unilateral constraints: ``c`` counts as violated on the dense
#: samples where ``c < −CONSTRAINT_TOL · (1 + max |c|)`` (the shooting solution's own accuracy is
#: ~1e-10; a converged collocation's nodes meet their constraints to IPOPT's 1e-8 and better), and
#: a constraint that starts active must rise faster than ``CONSTRAINT_TOL`` (its unit per second).
#: The simulation's start check (:mod:`gaitopt.simulation.phase`) uses the same numbers.
CONSTRAINT_TOL = 1e-9

#: A guard counts as armed (strictly on its pre-crossing side) where ``direction · g <
#: −GUARD_TOL · (1 + max |g|)`` on the samples.
GUARD_TOL = 1e-9

#: A period-k orbit is a shorter one repeated where its state at an earlier return is within
#: ``PERIOD_TOL · (1 + max |x|)`` of the section state.
PERIOD_TOL = 1e-6


@dataclass(frozen=True)
class DenseArc:
    """One phase of an orbit, densely sampled, as the certificate reads it.

    Attributes
    ----------
    phase : int
        Phase index in ``model.phases``.
    label : str
        The phase in messages (``"phase 'stance' (step 2)"``).
    duration : float
        The phase's duration (s) as the transcription has it (may be ≤ 0 for a rejected orbit).
    t : numpy.ndarray
        Sample times (s since the orbit's section), ``K``; the first sample is the phase's start,
        the last its end on the guard.
    x : numpy.ndarray
        States at the samples, ``n × K``.
    u : numpy.ndarray
        Inputs at the samples, ``n_u × K`` (the per-step input repeated, or the input profile).
    end : numpy.ndarray or None
        The phase's end state as the transcription solved it, where that is not the last sample
        (multiple shooting samples with finer RK steps than its residual's, so its last sample
        differs from the solved end by the discretisation error); None: the last sample.
    """

    phase: int
    label: str
    duration: float
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    end: np.ndarray | None = None


def constant_input(u: np.ndarray, samples: int) -> np.ndarray:
    """A per-step input ``u`` held at ``samples`` samples: ``n_u × samples``."""
    u = np.asarray(u, dtype=float).ravel()
    return np.repeat(u.reshape(-1, 1), samples, axis=1)


_MAPS: dict[tuple[int, int], tuple[ca.Function, ca.Function]] = {}


def _mapped(f: ca.Function, K: int) -> ca.Function:
    """``f`` mapped over ``K`` samples (built once per function and size; ``f`` kept alive with
    its map, so that its id stays its own)."""
    key = (id(f), K)
    if key not in _MAPS:
        _MAPS[key] = (f.map(K), f)
    return _MAPS[key][0]


def _values(f: ca.Function, arc: DenseArc, p: np.ndarray) -> np.ndarray:
    """``f(x, u, p)`` at every sample of ``arc``, a vector."""
    K = arc.x.shape[1]
    return call1(_mapped(f, K), arc.x, arc.u, p).ravel()  # buffered: no DM per call


class _Samples:
    """The guards, admissibility rules and constraints of each arc's phase at every sample,
    read by the checks: from the model class's compiled check kernels
    (:mod:`gaitopt.kernels.checks`, one call per arc, kept for the arc while the certificate
    runs) where it has them, else each function by itself (:func:`_values`)."""

    def __init__(self, model: HybridModel, p: np.ndarray):
        from ..kernels.checks import check_kernels

        self.model, self.p = model, p
        self.kernels = check_kernels(type(model))
        self._tables: dict[int, tuple[DenseArc, np.ndarray]] = {}

    def _table(self, arc: DenseArc) -> np.ndarray:
        entry = self._tables.get(id(arc))
        if entry is None or entry[0] is not arc:
            f = _mapped(self.kernels[arc.phase], arc.x.shape[1])
            entry = self._tables[id(arc)] = (arc, call1(f, arc.x, arc.u, self.p))
        return entry[1]

    def guard(self, arc: DenseArc, j: int) -> np.ndarray:
        tr = self.model.phases[arc.phase].transitions[j]
        if self.kernels is None:
            return _values(tr.guard, arc, self.p)
        return self._table(arc)[j]

    def admissible(self, arc: DenseArc, j: int) -> np.ndarray | None:
        """Transition ``j``'s admissibility at the samples (None: it has no rule)."""
        phase = self.model.phases[arc.phase]
        tr = phase.transitions[j]
        if tr.admissible is None:
            return None
        if self.kernels is None:
            return _values(tr.admissible, arc, self.p)
        return self._table(arc)[len(phase.transitions) + j]

    def constraint(self, arc: DenseArc, j: int) -> np.ndarray:
        phase = self.model.phases[arc.phase]
        if self.kernels is None:
            return _values(phase.constraints[j].function, arc, self.p)
        return self._table(arc)[2 * len(phase.transitions) + j]


def check_durations(arcs: Sequence[DenseArc]) -> str | None:
    """Every phase lasts a positive time."""
    for arc in arcs:
        if not arc.duration > 0:
            return (
                f"no gait: {arc.label} would last {arc.duration:.3g} s (durations must be "
                f"positive); the orbit through this guess runs backwards in time — the gait may "
                f"not exist at these parameters"
            )
    return None


def check_phase_ends(
    model: HybridModel, arcs: Sequence[DenseArc], p: np.ndarray, guard_tol: float,
    samples: _Samples | None = None,
) -> str | None:  # fmt: skip
    """Each phase ends on its cycle guard (``|g| ≤ guard_tol · (1 + max |g|)`` at its end state
    :attr:`DenseArc.end`: the transcription's own equation, re-read), in the stated direction,
    admissibly."""
    samples = samples or _Samples(model, p)
    for arc in arcs:
        phase = model.phases[arc.phase]
        tr = phase.transitions[0]
        x_end = arc.x[:, -1] if arc.end is None else np.asarray(arc.end, dtype=float).ravel()
        u_end = arc.u[:, -1]
        g = samples.guard(arc, 0)
        g_end = call1(tr.guard, x_end, u_end, p).item()
        if abs(g_end) > guard_tol * (1 + float(np.max(np.abs(g)))):
            return (
                f"no gait: {arc.label} ends {g_end:.3g} away from its guard '{tr.name}' "
                f"(tolerance {guard_tol:g}); the transcription's solution is inconsistent"
            )
        if tr.admissible is not None and not call1(tr.admissible, x_end, u_end, p).item() > 0:
            return (
                f"no gait: {arc.label} ends on '{tr.name}' where that crossing is excluded "
                f"(spurious crossing rule: {tr.doc})"
            )
        rate = call1(rate_along(phase.flow, tr.guard), x_end, u_end, p).item()
        if not tr.direction * rate > 0:
            return (
                f"no gait: {arc.label} reaches '{tr.name}' in the wrong direction "
                f"(grazing or from the other side)"
            )
    return None


def check_early_crossings(
    model: HybridModel, arcs: Sequence[DenseArc], p: np.ndarray, samples: _Samples | None = None
) -> str | None:
    """No guard of a phase is crossed (admissibly, in its direction) before the phase ends: a
    crossing counts once the guard has been strictly on its pre-crossing side
    (``direction · g < −GUARD_TOL · (1 + max |g|)``), as in the simulation."""
    samples = samples or _Samples(model, p)
    for arc in arcs:
        phase = model.phases[arc.phase]
        K = arc.x.shape[1]
        for j, tr in enumerate(phase.transitions):
            g = tr.direction * samples.guard(arc, j)
            a = samples.admissible(arc, j)
            a = np.ones(K) if a is None else a
            armed = np.maximum.accumulate(g < -GUARD_TOL * (1 + np.max(np.abs(g))))
            last = K - 1 if j == 0 else K  # the cycle transition fires at the last sample
            # a crossing at sample idx (1 ≤ idx < last): armed before it, from below to ≥ 0,
            # admissible at one of its ends
            before, after = slice(0, max(last - 1, 0)), slice(1, max(last, 1))
            admissible = (a[before] > 0) | (a[after] > 0)
            hits = np.flatnonzero(armed[before] & (g[before] < 0) & (g[after] >= 0) & admissible)
            if hits.size:
                idx = int(hits[0]) + 1
                return (
                    f"no gait: the orbit crosses '{tr.name}' inside {arc.label} at t = "
                    f"{arc.t[idx]:.4g} s, before the phase ends (e.g. a foot through the "
                    f"ground); not a gait with this phase sequence"
                )
    return None


def check_constraints(
    model: HybridModel, arcs: Sequence[DenseArc], p: np.ndarray, samples: _Samples | None = None
) -> str | None:
    """Every declared unilateral constraint (:attr:`Phase.constraints`) holds on the samples.

    ``c ≥ −CONSTRAINT_TOL · (1 + max |c|)`` at every sample (but the first of one declared
    ``at_start`` and the last of one declared ``at_end``, zero there by construction); one
    declared ``at_start`` must also rise where the phase begins, ``ċ = ∇c · f(x, u, p) >
    CONSTRAINT_TOL`` with the input of the first sample (the trailing foot lifts off).  Returns
    the first violation in words (naming the constraint and the rule), or None.
    """
    samples = samples or _Samples(model, p)
    for arc in arcs:
        phase = model.phases[arc.phase]
        for index, constraint in enumerate(phase.constraints):
            c = samples.constraint(arc, index)
            scale = CONSTRAINT_TOL * (1 + float(np.max(np.abs(c))))
            unit = f" {constraint.unit}" if constraint.unit else ""
            if constraint.at_start:
                rate = rate_along(phase.flow, constraint.function)
                c0_rate = call1(rate, arc.x[:, 0], arc.u[:, 0], p).item()
                if not c0_rate > CONSTRAINT_TOL:
                    return (
                        f"no gait: {constraint.outcome} at the start of {arc.label}: "
                        f"'{constraint.name}' starts at 0 and must rise, but its rate is "
                        f"{c0_rate:.3g}{unit}/s ({constraint.source})"
                    )
            inner = slice(1 if constraint.at_start else 0, -1 if constraint.at_end else None)
            bad = np.nonzero(c[inner] < -scale)[0]
            if bad.size:
                j = int(bad[0]) + (1 if constraint.at_start else 0)
                return (
                    f"no gait: {constraint.outcome} in {arc.label} at t = {arc.t[j]:.4g} s: "
                    f"'{constraint.name}' fails (value {c[j]:.3g}{unit}, lowest "
                    f"{float(np.min(c[inner])):.3g}{unit}, tolerance {scale:.2g}{unit}; "
                    f"{constraint.source})"
                )
    return None


#: What to try when a period-k orbit is a shorter one repeated (a shooting search; an
#: optimisation says what it asks for instead).
REPEATED_ADVICE = "try a guess on the period-{steps} orbit (past its period doubling)"


def check_minimal_period(
    model: HybridModel, arcs: Sequence[DenseArc], steps: int, advice: str = REPEATED_ADVICE
) -> str | None:
    """A period-``steps`` orbit is not a period-``j`` one repeated (``j`` dividing ``steps``):
    the state where step ``j + 1`` begins differs from the section state (``advice``: what to
    try, formatted with ``steps`` and ``j``)."""
    n_phases = len(model.phases)
    x0 = arcs[0].x[:, 0]
    for j in range(1, steps):
        if steps % j or j * n_phases >= len(arcs):
            continue
        xj = arcs[j * n_phases].x[:, 0]
        if np.max(np.abs(xj - x0)) < PERIOD_TOL * (1 + np.max(np.abs(x0))):
            return (
                f"no period-{steps} gait here: the orbit found is the period-{j} gait repeated; "
                + advice.format(steps=steps, j=j)
            )
    return None


def certify_orbit(
    model: HybridModel,
    arcs: Sequence[DenseArc],
    p: np.ndarray,
    *,
    steps: int = 1,
    guard_tol: float = 1e-6,
    repeated_advice: str = REPEATED_ADVICE,
) -> str | None:
    """Every check of the certificate, in order (see the module docstring): None if the sampled
    orbit is a gait, else the first failure in words.

    Parameters
    ----------
    model : HybridModel
        The model (its phases, transitions and constraints).
    arcs : sequence of DenseArc
        The orbit's phases in order (``steps`` cycles of ``model.phases``), densely sampled.
    p : numpy.ndarray
        The parameter vector.
    steps : int
        Returns to the section per orbit.
    guard_tol : float
        Relative tolerance of ``g = 0`` at each phase's end: the transcription's solve tolerance
        (the guard is one of its equations).
    repeated_advice : str
        What to try when the orbit is a shorter one repeated (``{steps}``, ``{j}`` filled in).
    """
    samples = _Samples(model, p)  # each arc's checks at its samples, evaluated once
    for check in (
        lambda: check_durations(arcs),
        lambda: check_phase_ends(model, arcs, p, guard_tol, samples),
        lambda: check_early_crossings(model, arcs, p, samples),
        lambda: check_constraints(model, arcs, p, samples),
        lambda: check_minimal_period(model, arcs, steps, repeated_advice) if steps > 1 else None,
    ):
        defect = check()
        if defect is not None:
            return defect
    return None
