"""The nominal hybrid orbit a transverse linearisation is taken along: each stage (one phase of
one step) re-integrated from its start state with its nominal input ``u*(τ)``, ``τ`` the time
since the stage began (s), and *extended* a little past both ends.

The extension is what lets a perturbed state be given a phase near an impact: a state that has
not reached the guard yet when the nominal has (or has already been reset when the nominal has
not) lies next to the stage's flow continued past its guard (or run backwards from its start).
The extension beyond the end holds the input at its last value, the one before the start at
its first; it is a trajectory of the phase's flow, not part of the gait.

The gait itself is either a passive or constant-input :class:`gaitopt.LimitCycle` (the input
``gait.inputs`` held over every step) or a :class:`gaitopt.OptimalGait` (the input profile
``gait.profiles[step]`` in the time since the section, each stage reading it from its start
time ``t0`` on: ``u*(τ) = profile(t0 + τ)``).  The integration is SciPy's DOP853 at rtol 1e-12,
piecewise between the profile's breakpoints (where ``u*`` may jump, so that no step crosses
one), independent of the shooting or collocation that found the orbit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError

__all__ = ["Stage", "NominalOrbit", "nominal_orbit", "integrate_pieces", "Pieces"]

_RTOL, _ATOL = 1e-12, 1e-13
#: Extension of each stage past both ends, as a fraction of its duration.
EXTENSION = 0.15


class Pieces:
    """A piecewise dense solution: SciPy ``OdeSolution`` pieces on consecutive intervals of the
    independent variable (forwards or backwards), evaluated at any point of their union."""

    def __init__(self, edges: list[float], solutions: list[Any]):
        order = np.argsort([min(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True)])
        self.lo = np.array([min(edges[i], edges[i + 1]) for i in order])
        self.hi = np.array([max(edges[i], edges[i + 1]) for i in order])
        self.solutions = [solutions[i] for i in order]

    def __call__(self, t: float) -> np.ndarray:
        i = int(np.searchsorted(self.lo, t, side="right")) - 1
        i = min(max(i, 0), len(self.solutions) - 1)
        return np.asarray(self.solutions[i](min(max(t, self.lo[i]), self.hi[i])), dtype=float)


def integrate_pieces(
    rhs: Callable[[float, np.ndarray], np.ndarray],
    y0: np.ndarray,
    edges: np.ndarray,
    *,
    rtol: float = _RTOL,
    atol: float = _ATOL,
    dense: bool = True,
) -> tuple[np.ndarray, Pieces | None]:
    """Integrate ``ẏ = rhs(t, y)`` through ``edges`` (monotone: forwards or backwards), one
    DOP853 solve per interval so that no step crosses an edge; the end value and the dense
    solution."""
    from scipy.integrate import solve_ivp

    y = np.asarray(y0, dtype=float).ravel()
    solutions = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if a == b:
            continue
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=rtol, atol=atol, dense_output=dense)
        if not sol.success:
            raise RuntimeError(f"the integration failed on [{a:.6g}, {b:.6g}]: {sol.message}")
        y = sol.y[:, -1]
        solutions.append(sol.sol)
    kept = [e for i, e in enumerate(edges) if i == 0 or e != edges[i - 1]]
    return y, (Pieces(kept, solutions) if dense else None)


@dataclass
class Stage:
    """One phase of one step of the nominal orbit.

    Attributes
    ----------
    index : int
        Position in the orbit (stages of all steps, in order).
    phase : int
        Index of the model phase.
    step : int
        Step of the orbit the stage belongs to.
    start : float
        Time of the stage's start since its step's section (s).
    duration : float
        Nominal duration ``T`` (s).
    before, after : float
        Extension before ``τ = 0`` and after ``τ = T`` (s).
    breaks : numpy.ndarray
        Stage times ``τ`` (s) where ``u*`` or its derivative may jump, from ``−before`` to
        ``T + after`` (0 and ``T`` included).
    x : Pieces
        ``x*(τ)`` on ``[−before, T + after]``.
    input : callable
        ``input(τ) -> (u*, u̇*)`` (input units, per second), held outside ``[0, T]``.
    value : callable
        ``value(τ) -> u*`` alone (cheaper: what a feedback law calls).
    """

    index: int
    phase: int
    step: int
    start: float
    duration: float
    before: float
    after: float
    breaks: np.ndarray
    x: Pieces
    input: Callable[[float], tuple[np.ndarray, np.ndarray]]
    value: Callable[[float], np.ndarray]
    x0: np.ndarray = field(default_factory=lambda: np.zeros(0))
    x_end: np.ndarray = field(default_factory=lambda: np.zeros(0))


@dataclass
class NominalOrbit:
    """The orbit's stages, with the model and its parameters.

    Attributes
    ----------
    model : HybridModel
        The model (parameters included).
    stages : list of Stage
        In orbit order.
    steps : int
        Returns to the section per orbit.
    kind : str
        ``"limit cycle"`` or ``"optimal gait"``.
    closure : float
        Largest gap between a stage's re-integrated, reset end and the next stage's start (state
        units): the re-integration's agreement with the solver's orbit.
    """

    model: Any
    stages: list[Stage]
    steps: int
    kind: str
    closure: float = 0.0

    @property
    def p(self) -> np.ndarray:
        return self.model.p

    def stage_of(self, phase: int, step: int) -> Stage:
        """The stage of ``phase`` in step ``step`` (counted from any start: modulo the orbit)."""
        n = len(self.model.phases)
        return self.stages[(step % self.steps) * n + phase]


def _constant_input(u: np.ndarray):
    zero = np.zeros_like(u)
    return (lambda tau: (u, zero)), (lambda tau: u)


def _profile_input(profile: Any, t0: float, T: float):
    """``u*(τ) = profile(t0 + τ)`` on ``[0, T]``, held outside (the left limit at ``T``)."""
    end = float(np.nextafter(t0 + T, -np.inf))
    n_u = profile.coefficients.shape[2]

    def value(tau: float) -> tuple[np.ndarray, np.ndarray]:
        if tau <= 0.0:
            return profile(t0), np.zeros(n_u)
        if tau >= T:
            return profile(end), np.zeros(n_u)
        t = t0 + tau
        return profile(t), profile.derivative(t)

    def only(tau: float) -> np.ndarray:
        return profile(t0 + min(max(tau, 0.0), T)) if tau < T else profile(end)

    return value, only


def nominal_orbit(gait: Any, extension: float = EXTENSION) -> NominalOrbit:
    """The nominal orbit of a gait (a successful :class:`gaitopt.LimitCycle` or
    :class:`gaitopt.OptimalGait`), each stage re-integrated and extended by ``extension`` × its
    duration past both ends.

    Raises
    ------
    GaitoptInputError
        If ``gait`` is neither, or not successful.
    """
    from ..optimize.result import OptimalGait
    from ..result import LimitCycle

    if not isinstance(gait, (LimitCycle, OptimalGait)) or not gait.success:
        what = type(gait).__name__
        why = f" ({gait.message})" if isinstance(gait, (LimitCycle, OptimalGait)) else ""
        raise GaitoptInputError(
            f"`gait` must be a successful LimitCycle (gaitopt.find_limit_cycle) or OptimalGait "
            f"(gaitopt.optimize_gait), got a {what}{why}; find the gait first"
        )
    if not (isinstance(extension, float | int) and 0 < extension <= 0.5):
        raise GaitoptInputError(f"`extension` must be in (0, 0.5], got {extension!r}; e.g. 0.15")
    model = gait.model
    p = model.p
    n_phases = len(model.phases)
    optimal = isinstance(gait, OptimalGait)
    steps = int(gait.problem.get("steps", 1)) if optimal else int(gait.steps)
    arcs = list(gait.orbit)
    if len(arcs) != steps * n_phases:
        raise GaitoptInputError(
            f"`gait` has {len(arcs)} orbit arcs, expected {steps} × {n_phases} phases"
        )
    stages: list[Stage] = []
    t0 = 0.0
    for k, arc in enumerate(arcs):
        step = k // n_phases
        if k % n_phases == 0:
            t0 = 0.0
        i = int(arc.phase)
        T = float(arc.t[-1] - arc.t[0])
        x0 = np.asarray(arc.x[:, 0], dtype=float)
        if optimal:
            profile = gait.profiles[step % len(gait.profiles)]
            u_of, u_only = _profile_input(profile, t0, T)
            inner = profile.breaks[(profile.breaks > t0) & (profile.breaks < t0 + T)] - t0
        else:
            u_of, u_only = _constant_input(np.asarray(gait.inputs, dtype=float).ravel())
            inner = np.zeros(0)
        ext = extension * T
        flow = model.phases[i].flow

        def rhs(tau: float, x: np.ndarray, flow: ca.Function = flow, u_of=u_of) -> np.ndarray:
            return np.asarray(flow(x, u_of(tau)[0], p), dtype=float).ravel()

        forward = np.concatenate([[0.0], inner, [T, T + ext]])
        x_end_ext, ahead = integrate_pieces(rhs, x0, forward)
        _, behind = integrate_pieces(rhs, x0, np.array([0.0, -ext]))
        edges = [-ext, *forward.tolist()]
        solutions = behind.solutions + ahead.solutions  # type: ignore[union-attr]
        pieces = Pieces(edges, solutions)
        x_end = pieces(T)
        stages.append(
            Stage(k, i, step, t0, T, ext, ext, np.asarray(edges), pieces, u_of, u_only, x0, x_end)
        )
        del x_end_ext
        t0 += T
    closure = 0.0
    for k, stage in enumerate(stages):
        nxt = stages[(k + 1) % len(stages)]
        tr = model.phases[stage.phase].transitions[0]
        x_plus = np.asarray(tr.reset(stage.x_end, stage.input(stage.duration)[0], p)).ravel()
        closure = max(closure, float(np.max(np.abs(x_plus - nxt.x0))))
    return NominalOrbit(model, stages, steps, "optimal gait" if optimal else "limit cycle", closure)
