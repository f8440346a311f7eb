"""Stabilising an optimal gait: a per-step input offset chosen by step-to-step LQR, checked.

An optimal gait's input ``u*(t)`` is a feedforward in the time since the section; its return
map can be unstable (the level-ground least-effort compass gait: multipliers −1.34, 0.43,
−0.003).  Add a per-step input: an offset ``δₖ`` held over step ``k`` on top of the profile,
``u(t) = u*(t) + δₖ`` (``t`` since that step's section, the profile held at its last value if the
step lasts longer, as :func:`gaitopt.optimize.verify.simulate_gait` applies it).  The map
linearised at the fixed point,

    ``sₖ₊₁ − s* = A (sₖ − s*) + B δₖ``,

has ``A`` from :func:`gaitopt.optimize.floquet.return_map_jacobian` (the implicit function theorem
on the Radau collocation equations) and ``B`` by the same construction with ``δ`` as an extra
unknown: each phase's collocation residual is differentiated in ``δ`` (the nodes see
``u + δ``), the guard's crossing time moves by ``δτ = −(g_x δx + g_u (u̇ δt₀ + δ)) / ġ`` and the
reset adds ``r_u δ`` (the saltation construction of the floquet module, Hiskens & Pai 2000).
Both are checked against central finite differences of the independent event-located simulator.

The gain is the step-to-step LQR of :func:`gaitopt.control.lqr` (python-control's ``dlqr``) on
that linearisation, ``δₖ = −K (sₖ − s*)``; its closed-loop multipliers ``eig(A − B K)`` are
checked against those *measured* from the simulated closed loop (central differences of one
controlled step of the simulator), and the closed loop is simulated from perturbed states (each
section coordinate in turn, ± a small amount): it must return to the fixed point, every step
completed by the simulator (guards located, the unilateral constraints of each phase checked),
with the constraints also sampled densely with the input actually applied, ``u*(t) + δₖ``; the
uncontrolled walker is run from the same states for comparison.

With ``steps > 1`` in the problem (an orbit of several returns) the offset is decided once per
orbit and held over its returns: the map linearised is the orbit's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..files import jsonable
from ..simulation import Simulation, simulate
from .collocation import Collocation, _derivative_matrix
from .floquet import _end_jacobians, _lift_jacobian, multipliers_of, return_map_jacobian
from .result import OptimalGait
from .verify import map_jacobian_fd

__all__ = [
    "stabilise",
    "Stabilisation",
    "ClosedLoopTrial",
    "offset_jacobian",
    "offset_jacobian_fd",
]

_FD_STEP = 1e-6  # central differences of the simulated map (section units, input units)
_JACOBIAN_TOL = 1e-5  # AD against FD: |·|∞ ≤ tol (1 + |·|∞) (FD truncation ~1e-8, noise ~1e-6)
_MULTIPLIER_TOL = 1e-4  # linearised against measured closed-loop multipliers (absolute)
_SAMPLES = 200  # per arc, for the dense check of the constraints with the applied input


# -- the linearisation ------------------------------------------------------------------------
@lru_cache(maxsize=32)
def _phase_residual(flow: ca.Function, N: int, d: int, C_key: bytes) -> ca.Function:
    """``R(Xfree, x0, dt0, delta, U, Udot, H, p)``: the collocation defects of one phase with the
    node inputs ``U + U̇ dt0 + δ``, and the Jacobians with respect to ``Xfree`` and
    ``[x0; dt0; δ]``."""
    C = np.frombuffer(C_key).reshape(d + 1, d)
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    Xf = ca.SX.sym("X", n, N * d)
    x0 = ca.SX.sym("x0", n)
    dt0 = ca.SX.sym("dt0")
    delta = ca.SX.sym("delta", n_u)
    U = ca.SX.sym("U", n_u, N * d)
    Ud = ca.SX.sym("Ud", n_u, N * d)
    H = ca.SX.sym("H", N)
    p = ca.SX.sym("p", n_p)
    X = ca.horzcat(x0, Xf)
    shift = ca.repmat(delta, 1, N * d)
    F = flow.map(N * d)(Xf, U + Ud * dt0 + shift, p)
    defects = [
        ca.mtimes(X[:, j * d : j * d + d + 1], ca.DM(C)) - H[j] * F[:, j * d : (j + 1) * d]
        for j in range(N)
    ]
    R = ca.vec(ca.horzcat(*defects))
    z = ca.vertcat(x0, dt0, delta)
    return ca.Function(
        "offset_sensitivity",
        [Xf, x0, dt0, delta, U, Ud, H, p],
        [ca.jacobian(R, ca.vec(Xf)), ca.jacobian(R, z)],
    )


def offset_jacobian(col: Collocation, w: np.ndarray, p_model: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(A, B)``: the orbit's return map differentiated in the section coordinates and in an
    input offset held over the orbit, by AD through the transcription.

    Parameters
    ----------
    col : Collocation
        The final transcription of the optimum.
    w : numpy.ndarray
        Its solution.
    p_model : numpy.ndarray
        The model's parameter vector.

    Returns
    -------
    A : numpy.ndarray
        ``∂P/∂s`` (m × m, section coordinates); the same as
        :func:`~gaitopt.optimize.floquet.return_map_jacobian`.
    B : numpy.ndarray
        ``∂P/∂δ`` (m × n_u: section units per input unit).
    """
    sol = col.unpack(w, p_model)
    p = sol["p"]
    model = col.model
    N, d = col.N, col.d
    D = _derivative_matrix(col.tau[1:], col.tau[1:])
    n_cycle = len(model.phases)
    n_u = len(model.inputs)
    L = np.asarray(_lift_jacobian(model.section.lift)(sol["s"], p), dtype=float)
    m = L.shape[1]
    n0 = L.shape[0]
    # Rows (δx, δt, δ) per unit (δs, δ); δ is carried unchanged through the orbit.
    M = np.zeros((n0 + 1 + n_u, m + n_u))
    M[:n0, :m] = L
    M[n0 + 1 :, m:] = np.eye(n_u)
    for k, i in enumerate(col.chain):
        phase = model.phases[i]
        tr = phase.transitions[0]
        n = phase.n
        X, U, T = sol["X"][k], sol["U"][k], float(sol["T"][k])
        hs = T * np.diff(sol["breaks"][k])
        Ud = np.hstack([U[:, j * d : (j + 1) * d] @ D.T / hs[j] for j in range(N)])
        sens = _phase_residual(phase.flow, N, d, col.C.tobytes())
        R_X, R_z = (
            np.asarray(v, dtype=float)
            for v in sens(X[:, 1:], X[:, 0], 0.0, np.zeros(n_u), U, Ud, hs, p)
        )
        Phi = -np.linalg.solve(R_X, R_z)[-n:, :]  # δx_end per (δx0, δt0, δ)
        f, g_x, g_u, r_x, r_u = (
            np.asarray(v, dtype=float)
            for v in _end_jacobians(phase.flow, tr.guard, tr.reset)(X[:, -1], U[:, -1], p)
        )
        f, udot = f.ravel(), Ud[:, -1]
        e_t = np.zeros((1, n + 1 + n_u))
        e_t[0, n] = 1.0
        e_d = np.zeros((n_u, n + 1 + n_u))
        e_d[:, n + 1 :] = np.eye(n_u)
        g_rate = float((g_x @ f + g_u @ udot).ravel()[0])
        # The crossing moves by δτ = −(g_x δx + g_u (u̇ δt0 + δ)) / ġ (the input at the end is
        # u + u̇ (δt0 + δτ) + δ); the reset sees that input.
        dtau = -(g_x @ Phi + g_u @ (np.outer(udot, e_t) + e_d)) / g_rate
        dx_minus = Phi + np.outer(f, dtau)
        dt_event = e_t + dtau
        dx_plus = r_x @ dx_minus + r_u @ (np.outer(udot, dt_event) + e_d)
        M = np.vstack([dx_plus, dt_event, e_d]) @ M
        if (k + 1) % n_cycle == 0:
            M[n0, :] = 0.0  # the feedforward clock restarts at the section
    rows = col.section_index
    return M[:n0, :m][rows, :], M[:n0, m:][rows, :]


def _feedforward(profiles: list[Any], offsets: dict[int, np.ndarray]):
    """``u*(t) + δₖ`` for :func:`gaitopt.simulate` (``k`` the returns so far)."""
    return lambda t, k: profiles[k % len(profiles)](t) + offsets[k]


def _simulate_orbit(gait: OptimalGait, s: np.ndarray, delta: np.ndarray, steps: int) -> Simulation:
    model = gait.model
    offsets = {k: delta for k in range(steps + 1)}
    return simulate(
        model,
        model.lift(s),
        steps=steps,
        feedforward=_feedforward(gait.profiles, offsets),
        rtol=1e-12,
        atol=1e-13,
        max_phase_time=_max_phase_time(gait),
    )


def _max_phase_time(gait: OptimalGait) -> float:
    return 10.0 * float(np.max(gait.durations)) + 1.0


def offset_jacobian_fd(gait: OptimalGait, h: float = _FD_STEP) -> np.ndarray | None:
    """``∂P/∂δ`` by central differences of the simulated orbit map (None if a perturbed
    simulation does not complete)."""
    model = gait.model
    s_star = _section_point(gait)
    steps = int(gait.problem.get("steps", 1))
    n_u = len(model.inputs)
    B = np.zeros((s_star.size, n_u))
    for j in range(n_u):
        ends = []
        for sign in (1.0, -1.0):
            delta = np.zeros(n_u)
            delta[j] = sign * h
            sim = _simulate_orbit(gait, s_star, delta, steps)
            if not sim.success:
                return None
            ends.append(model.section_coordinates_of(sim.section_states[-1]))
        B[:, j] = (ends[0] - ends[1]) / (2 * h)
    return B


def _section_point(gait: OptimalGait) -> np.ndarray:
    model = gait.model
    return np.asarray(model.section_coordinates_of(model.state_vector(gait.fixed_point)))


# -- the controller, as a gaitopt.control design ----------------------------------------------
@dataclass(frozen=True)
class _OffsetGait:
    """What :class:`gaitopt.control.Linearisation` needs of a gait, for the offset ``δ``: its
    model, its fixed point, the nominal offset 0."""

    model: Any
    section_point: np.ndarray
    fixed_point: dict[str, float]
    inputs: np.ndarray
    message: str
    success: bool = True


def _design(gait: OptimalGait, A: np.ndarray, B: np.ndarray, Q: Any, R: Any) -> Any:
    """The LQR of :func:`gaitopt.control.lqr` on ``(A, B)`` (offsets unclipped: the input bounds
    are checked on the applied ``u*(t) + δ`` in the simulations)."""
    from ..control import Linearisation, lqr

    model = gait.model
    n_u = len(model.inputs)
    base = _OffsetGait(
        model,
        _section_point(gait),
        dict(gait.fixed_point),
        np.zeros(n_u),
        f"optimal gait, {gait.cost_kind} {gait.cost:.10g}, input offset δ per step",
    )
    unbounded = (np.full(n_u, -np.inf), np.full(n_u, np.inf))
    return lqr(Linearisation(base, A, B), Q, R, input_limits=unbounded)  # type: ignore[arg-type]


# -- closed-loop runs -------------------------------------------------------------------------
@dataclass
class ClosedLoopTrial:
    """The walker from one perturbed state, with and without the offset law.

    Attributes
    ----------
    start : dict of str to float
        Section coordinates of the start.
    errors : list of float
        Controlled: max-norm distance of each return (per orbit) from the fixed point, the start
        first (section units).
    offsets : list of list of float
        The offsets ``δₖ`` applied (input units), one per orbit.
    status, message : str
        The controlled simulation's status (``"completed"``) and message.
    open_loop_errors : list of float
        Uncontrolled (``δ = 0``), from the same start.
    open_loop_status, open_loop_message : str
        The uncontrolled simulation's status (``"fell"`` where it fails) and message.
    constraint_margin : float or None
        Least value of the phases' unilateral constraints sampled densely along the controlled
        run with the applied input (constraint units; ≥ 0 required).
    input_peak : list of float
        Largest ``|u*(t) + δₖ|`` applied per input (input units).
    """

    start: dict[str, float]
    errors: list[float]
    offsets: list[list[float]]
    status: str
    message: str
    open_loop_errors: list[float]
    open_loop_status: str
    open_loop_message: str
    constraint_margin: float | None
    input_peak: list[float]

    @property
    def converged(self) -> bool:
        """The controlled run completed and ended within ``1e-3`` of its initial error."""
        return (
            self.status == "completed"
            and len(self.errors) > 1
            and self.errors[-1] <= 1e-3 * self.errors[0]
        )

    @property
    def open_loop_diverged(self) -> bool:
        """The uncontrolled run fell, or ended farther from the fixed point than it began."""
        return self.open_loop_status != "completed" or self.open_loop_errors[-1] > self.errors[0]

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types."""
        return jsonable(
            {
                "start": self.start,
                "errors": self.errors,
                "offsets": self.offsets,
                "status": self.status,
                "message": self.message,
                "converged": self.converged,
                "constraint_margin": self.constraint_margin,
                "input_peak": self.input_peak,
                "open_loop_errors": self.open_loop_errors,
                "open_loop_status": self.open_loop_status,
                "open_loop_message": self.open_loop_message,
                "open_loop_diverged": self.open_loop_diverged,
            }
        )


def _run(
    gait: OptimalGait, s0: np.ndarray, gain: np.ndarray | None, orbits: int
) -> tuple[Simulation, dict[int, np.ndarray], list[float]]:
    """Simulate ``orbits`` orbits from ``s0`` with ``δ = −K (s − s*)`` decided at each orbit's
    section (``gain`` None: δ = 0); the errors at each orbit's return."""
    model = gait.model
    s_star = _section_point(gait)
    per = int(gait.problem.get("steps", 1))
    n_u = len(model.inputs)
    offsets: dict[int, np.ndarray] = {}

    def policy(k: int, x: np.ndarray) -> np.ndarray:
        if k % per == 0:
            ds = model.section_coordinates_of(x) - s_star
            offsets[k] = -(gain @ ds) if gain is not None else np.zeros(n_u)
        else:
            offsets[k] = offsets[k - 1]
        # Guards and constraints see the step's constant input in the simulator: zero, as in
        # the optimum's own verification; the constraints are re-checked below with u*(t) + δ.
        return np.zeros(n_u)

    sim = simulate(
        model,
        model.lift(s0),
        steps=orbits * per,
        inputs=policy,
        feedforward=_feedforward(gait.profiles, offsets),
        rtol=1e-12,
        atol=1e-13,
        max_phase_time=_max_phase_time(gait),
    )
    states = sim.section_states[::per]
    errors = [float(np.max(np.abs(model.section_coordinates_of(x) - s_star))) for x in states]
    return sim, offsets, errors


def _dense_check(
    gait: OptimalGait, sim: Simulation, offsets: dict[int, np.ndarray]
) -> tuple[float | None, np.ndarray]:
    """Least constraint value along the run, sampled with the applied input, and the largest
    ``|u|`` per input."""
    model = gait.model
    p = model.p
    times = list(sim.section_times)
    margin: float | None = None
    peak = np.zeros(len(model.inputs))
    for arc in sim.arcs:
        k = max(int(np.searchsorted(times, arc.t0, side="right")) - 1, 0)
        ts = np.linspace(arc.t0, arc.t1, _SAMPLES)
        xs = np.atleast_2d(arc.solution(ts))
        us = np.array(
            [gait.profiles[k % len(gait.profiles)](t - times[k]) + offsets[k] for t in ts]
        ).T
        peak = np.maximum(peak, np.max(np.abs(us), axis=1))
        for c in model.phases[arc.phase].constraints:
            values = np.asarray(c.function.map(_SAMPLES)(xs, us, p), dtype=float).ravel()
            # At a phase's ends a constraint may vanish by design (a foot touching down).
            inner = values[1 if c.at_start else 0 : _SAMPLES - 1 if c.at_end else _SAMPLES]
            if inner.size:
                low = float(np.min(inner))
                margin = low if margin is None else min(margin, low)
    return margin, peak


def _measured_closed_loop(
    gait: OptimalGait, gain: np.ndarray, h: float = _FD_STEP
) -> np.ndarray | None:
    """``∂s'/∂s`` of one simulated controlled orbit, by central differences (the closed loop
    as the simulator runs it)."""
    s_star = _section_point(gait)
    m = s_star.size
    J = np.zeros((m, m))
    for j in range(m):
        ends = []
        for sign in (1.0, -1.0):
            s = s_star.copy()
            s[j] += sign * h
            sim, _, _ = _run(gait, s, gain, 1)
            if not sim.success:
                return None
            ends.append(gait.model.section_coordinates_of(sim.section_states[-1]))
        J[:, j] = (ends[0] - ends[1]) / (2 * h)
    return J


# -- the result -------------------------------------------------------------------------------
@dataclass
class Stabilisation:
    """An optimal gait stabilised by a per-step input offset, or why it is not.

    Attributes
    ----------
    success : bool
        True only if the AD and FD linearisations agree, the closed-loop multipliers are inside
        the unit circle and agree with those measured from the simulated closed loop, and every
        controlled run completed its steps, met the constraints with the applied input (and
        the input bounds), and returned to the fixed point.
    message : str
        What was found, or what failed.
    gait : OptimalGait
        The optimum stabilised.
    controller : gaitopt.control.StepController or None
        The LQR design (``gain``, ``closed_loop_multipliers``; a policy of the offset).
    A, B : numpy.ndarray
        ``∂P/∂s`` (floquet machinery) and ``∂P/∂δ`` (AD through the transcription).
    A_fd, B_fd : numpy.ndarray or None
        The same by central differences of the simulated map.
    gain : numpy.ndarray
        ``K`` of ``δ = −K (s − s*)`` (input units per section unit).
    open_loop_multipliers, closed_loop_multipliers : numpy.ndarray
        ``eig(A)``, ``eig(A − B K)``, largest modulus first.
    measured_closed_loop_multipliers : numpy.ndarray
        Eigenvalues of the simulated controlled orbit map (central differences).
    trials : list of ClosedLoopTrial
        Controlled and uncontrolled runs from the perturbed states.
    orbits : int
        Orbits simulated per run.
    perturbation : float
        Size of the start perturbations (section units).
    """

    success: bool
    message: str
    gait: OptimalGait
    controller: Any = None
    A: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    B: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    A_fd: np.ndarray | None = None
    B_fd: np.ndarray | None = None
    gain: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    open_loop_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    closed_loop_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    measured_closed_loop_multipliers: np.ndarray = field(
        default_factory=lambda: np.zeros(0, complex)
    )
    trials: list[ClosedLoopTrial] = field(default_factory=list)
    orbits: int = 0
    perturbation: float = 0.0

    def __bool__(self) -> bool:
        return self.success

    @property
    def jacobian_errors(self) -> dict[str, float | None]:
        """``|AD − FD|∞`` of ``A`` and ``B``."""
        return {
            "A": None if self.A_fd is None else float(np.max(np.abs(self.A - self.A_fd))),
            "B": None if self.B_fd is None else float(np.max(np.abs(self.B - self.B_fd))),
        }

    def to_json(self) -> dict[str, Any]:
        """The ``stabilisation`` object of ``gaitopt optimize --stabilise --json``."""
        model = self.gait.model
        weights = self.controller.weights if self.controller is not None else {}
        return jsonable(
            {
                "success": self.success,
                "message": self.message,
                "kind": "lqr",
                "input": "offset δ added to the optimal profile, held over each step",
                "section_coordinates": list(model.section.coordinates),
                "inputs": list(model.inputs),
                "A": self.A,
                "B": self.B,
                "A_fd": self.A_fd,
                "B_fd": self.B_fd,
                "jacobian_errors": self.jacobian_errors,
                "gain": self.gain,
                "Q": weights.get("Q"),
                "R": weights.get("R"),
                "open_loop_multipliers": [complex(z) for z in self.open_loop_multipliers],
                "closed_loop_multipliers": [complex(z) for z in self.closed_loop_multipliers],
                "measured_closed_loop_multipliers": [
                    complex(z) for z in self.measured_closed_loop_multipliers
                ],
                "closed_loop_stable": bool(
                    self.closed_loop_multipliers.size
                    and np.all(np.abs(self.closed_loop_multipliers) < 1)
                ),
                "orbits": self.orbits,
                "perturbation": self.perturbation,
                "trials": [t.to_json() for t in self.trials],
            }
        )


def _match(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance between two multiplier sets paired greedily (nearest first)."""
    a, b = list(np.asarray(a, complex)), list(np.asarray(b, complex))
    if len(a) != len(b):
        return float("inf")
    worst = 0.0
    for z in a:
        j = int(np.argmin([abs(z - y) for y in b]))
        worst = max(worst, abs(z - b.pop(j)))
    return worst


# -- the entry point --------------------------------------------------------------------------
def stabilise(
    gait: OptimalGait,
    Q: Any = None,
    R: Any = 1e-3,
    *,
    orbits: int = 20,
    perturbation: float = 1e-3,
    starts: Sequence[Sequence[float]] | None = None,
) -> Stabilisation:
    """Stabilise an optimal gait by an input offset per step (step-to-step LQR), and check it.

    Parameters
    ----------
    gait : OptimalGait
        A successful result of :func:`gaitopt.optimize_gait` (it carries its transcription).
    Q, R : scalar, diagonal (sequence) or matrix, optional
        LQR weights of the section coordinates (m × m, section units⁻²) and the offsets
        (n_u × n_u, input units⁻²) of :func:`gaitopt.control.lqr`; default ``Q = I``,
        ``R = 1e-3 I`` (an offset of 1 N·m weighs as a state error of 0.03 rad: on the
        level-ground compass gait, closed-loop |λ|max 0.24 against 0.74 with ``R = I``).
    orbits : int
        Orbits simulated from each perturbed start (default 20).
    perturbation : float
        Each section coordinate in turn is displaced by ``±perturbation`` (section units,
        default 1e-3) to start the closed-loop runs.
    starts : sequence of sequences, optional
        Section-coordinate displacements to start from instead (one row per run).

    Returns
    -------
    Stabilisation

    Raises
    ------
    GaitoptInputError
        If ``gait`` is not a successful optimum, or an option is out of range.
    """
    if not isinstance(gait, OptimalGait) or not gait.success:
        why = gait.message if isinstance(gait, OptimalGait) else type(gait).__name__
        raise GaitoptInputError(
            f"`gait` must be a successful optimum of gaitopt.optimize_gait, got one that failed "
            f"({why}); solve it first"
        )
    transcription = getattr(gait, "transcription", None)
    if transcription is None:
        raise GaitoptInputError(
            "`gait` carries no transcription (it was not made by this gaitopt's optimize_gait); "
            "re-run gaitopt.optimize_gait"
        )
    if not isinstance(orbits, int) or isinstance(orbits, bool) or not 1 <= orbits <= 1000:
        raise GaitoptInputError(f"`orbits` must be an integer in 1..1000, got {orbits!r}; e.g. 20")
    if not (isinstance(perturbation, (int, float)) and 0 < perturbation <= 0.1):
        raise GaitoptInputError(
            f"`perturbation` must be a number in (0, 0.1] (section units), got {perturbation!r}; "
            f"e.g. 1e-3"
        )
    model = gait.model
    s_star = _section_point(gait)
    m = s_star.size
    if starts is None:
        displacements = [sign * perturbation * e for e in np.eye(m) for sign in (1.0, -1.0)]
    else:
        displacements = [np.asarray(row, dtype=float).ravel() for row in starts]
        bad = [d for d in displacements if d.size != m or not np.all(np.isfinite(d))]
        if not displacements or bad:
            raise GaitoptInputError(
                f"`starts` must be rows of {m} finite displacements "
                f"({', '.join(model.section.coordinates)}), got {starts!r}"
            )

    col, w = transcription
    A_floquet = return_map_jacobian(col, w, model.p)
    A, B = offset_jacobian(col, w, model.p)
    A = A_floquet  # the floquet module's A (the offset construction reproduces it)
    A_fd = map_jacobian_fd(col.problem, model, s_star, gait.profiles)
    B_fd = offset_jacobian_fd(gait)
    controller = _design(gait, A, B, Q, R)
    K = np.asarray(controller.gain, dtype=float)
    result = Stabilisation(
        False,
        "",
        gait,
        controller,
        A,
        B,
        A_fd,
        B_fd,
        K,
        multipliers_of(A),
        np.asarray(controller.closed_loop_multipliers, dtype=complex),
        orbits=orbits,
        perturbation=perturbation,
    )
    problems: list[str] = []
    for name, ad, fd in (("A", A, A_fd), ("B", B, B_fd)):
        if fd is None:
            problems.append(f"a perturbed simulation for the finite-difference {name} failed")
        elif np.max(np.abs(ad - fd)) > _JACOBIAN_TOL * (1 + np.max(np.abs(fd))):
            problems.append(
                f"{name} by AD and by finite differences differ by {np.max(np.abs(ad - fd)):.2g}"
            )
    if not controller.stable:
        problems.append(
            "the LQR closed loop is not stable (|λ|max "
            f"{np.max(np.abs(result.closed_loop_multipliers)):.4g}): the offset cannot reach "
            "the unstable mode"
        )
    measured = _measured_closed_loop(gait, K)
    if measured is None:
        problems.append("a perturbed controlled orbit did not complete")
    else:
        result.measured_closed_loop_multipliers = multipliers_of(measured)
        gap = _match(result.closed_loop_multipliers, result.measured_closed_loop_multipliers)
        if gap > _MULTIPLIER_TOL:
            problems.append(f"the measured closed-loop multipliers differ by {gap:.2g}")
    low, high = col.problem.input_bounds()
    for disp in displacements:
        s0 = s_star + disp
        sim, offsets, errors = _run(gait, s0, K, orbits)
        margin, peak = _dense_check(gait, sim, offsets) if sim.arcs else (None, np.zeros(0))
        open_sim, _, open_errors = _run(gait, s0, None, orbits)
        trial = ClosedLoopTrial(
            dict(zip(model.section.coordinates, map(float, s0), strict=True)),
            errors,
            [offsets[k].tolist() for k in sorted(offsets) if k % col.problem.steps == 0],
            sim.status,
            sim.message,
            open_errors,
            open_sim.status,
            open_sim.message,
            margin,
            peak.tolist(),
        )
        result.trials.append(trial)
        where = f"from {_fmt(model, s0)}"
        if not trial.converged:
            problems.append(
                f"the controlled walker {where} did not return to the fixed point "
                f"({sim.message}; error {errors[-1]:.3g} after {len(errors) - 1} orbits)"
            )
        if margin is not None and margin < -1e-9:
            problems.append(f"a constraint fails {where} with the applied input ({margin:.3g})")
        if peak.size and np.any(peak > np.maximum(np.abs(low), np.abs(high)) * (1 + 1e-9)):
            problems.append(f"the applied input exceeds its bound {where}")
    rho = float(np.max(np.abs(result.closed_loop_multipliers)))
    if problems:
        result.message = "not stabilised: " + "; ".join(problems)
        return result
    diverged = sum(t.open_loop_diverged for t in result.trials)
    worst = max(t.errors[-1] for t in result.trials)
    result.success = True
    result.message = (
        f"stabilised by an input offset per step (LQR): closed-loop |λ|max {rho:.6g} "
        f"(open loop {np.max(np.abs(result.open_loop_multipliers)):.6g}); from "
        f"{len(result.trials)} starts ±{perturbation:g} the controlled walker returns to within "
        f"{worst:.2g} of the fixed point in {orbits} orbits; uncontrolled, {diverged} of "
        f"{len(result.trials)} diverge"
    )
    return result


def _fmt(model: Any, s: np.ndarray) -> str:
    return ", ".join(
        f"{k}={v:.6g}" for k, v in zip(model.section.coordinates, np.ravel(s), strict=True)
    )
