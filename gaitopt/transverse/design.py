"""The entry point :func:`transverse_lqr`: the transverse linearisation, the periodic jump
Riccati equation, the law ``u = u*(τ) − K(τ) x⊥`` and its checks — the closed-loop monodromy
against the closed-loop return map measured by central differences of the simulator, and the
simulated closed loop from perturbed states."""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..arguments import closed_loop_trials
from ..errors import GaitoptInputError
from ..orbit.sensitivity import multipliers
from .law import LawBudgetExceeded, TransverseLaw
from .linearise import TransverseLinearisation, stage_transition, transverse_linearisation
from .result import TransverseLQR, TransverseTrial
from .riccati import PeriodicRiccati, periodic_riccati

__all__ = ["transverse_lqr", "check_weights", "closed_loop_monodromy", "simulate_law"]

_FD_STEP = 1e-5  # central differences of the simulated closed-loop map (section units): the
# open-loop phase-indexed map of the level compass optimum agrees with its monodromy to 2e-5 at
# 1e-5, 5e-4 at 1e-6 (the law's phase search, to 1e-13 T, and rtol 1e-12 are the noise)
_MULTIPLIER_TOL = 1e-4  # monodromy against the measured closed-loop multipliers (absolute)


def check_weights(model: Any, Q: Any, R: Any) -> tuple[list[np.ndarray], np.ndarray]:
    """``Q`` per phase (each phase's states, by name) and ``R`` as matrices; raise
    :class:`~gaitopt.errors.GaitoptInputError` naming the argument if one is not valid.

    ``Q``: None (identity), a scalar (times the identity in every phase), the diagonal over
    phase 0's states (a sequence) or a matrix over them; a phase whose states are not all
    phase 0's (the SLIP's stance) takes only a scalar.  ``R``: a positive scalar or a symmetric
    positive definite matrix over the inputs."""
    names = model.state_names
    n, n_u = len(names), len(model.inputs)
    if n_u == 0:
        raise GaitoptInputError(
            f"{model.name} has no inputs: transverse LQR needs an input to act with; choose a "
            f"model that declares one (compass_gait, kneed_walker)"
        )
    if R is None:
        R = 1.0
    R_arr = np.asarray(R, dtype=float)
    R_mat = R_arr * np.eye(n_u) if R_arr.ndim == 0 else np.diag(R_arr) if R_arr.ndim == 1 else R_arr
    if (
        R_mat.shape != (n_u, n_u)
        or not np.all(np.isfinite(R_mat))
        or not np.allclose(R_mat, R_mat.T)
        or np.min(np.linalg.eigvalsh(0.5 * (R_mat + R_mat.T))) <= 0
    ):
        raise GaitoptInputError(
            f"`R` must be a positive number or a symmetric positive definite {n_u} × {n_u} "
            f"matrix (inputs {', '.join(model.inputs)}), got {R!r}; e.g. R=0.1"
        )
    scalar = Q is None or np.ndim(Q) == 0
    Q_arr = np.asarray(1.0 if Q is None else Q, dtype=float)
    Q0 = Q_arr * np.eye(n) if Q_arr.ndim == 0 else np.diag(Q_arr) if Q_arr.ndim == 1 else Q_arr
    if (
        Q0.shape != (n, n)
        or not np.all(np.isfinite(Q0))
        or not np.allclose(Q0, Q0.T)
        or np.min(np.linalg.eigvalsh(0.5 * (Q0 + Q0.T))) < -1e-12 * max(1.0, np.max(np.abs(Q0)))
    ):
        raise GaitoptInputError(
            f"`Q` must be a non-negative number, {n} non-negative diagonal weights or a "
            f"symmetric positive semidefinite {n} × {n} matrix over {', '.join(names)}, got "
            f"{Q!r}; e.g. Q=1"
        )
    per_phase = []
    for phase in model.phases:
        if scalar:
            per_phase.append(float(Q_arr) * np.eye(phase.n))
            continue
        missing = [s for s in phase.states if s not in names]
        if missing:
            raise GaitoptInputError(
                f"`Q` over {', '.join(names)} cannot weigh phase {phase.name!r}'s state "
                f"{missing[0]!r}; give Q as a scalar"
            )
        idx = [names.index(s) for s in phase.states]
        per_phase.append(Q0[np.ix_(idx, idx)])
    return per_phase, R_mat


def _input_bounds(gait: Any) -> tuple[np.ndarray, np.ndarray]:
    """The optimum's input bounds (its problem's, within the model's), else the model's."""
    n_u = len(gait.model.inputs)
    transcription = getattr(gait, "transcription", None)
    if transcription is not None:
        return transcription[0].problem.input_bounds()
    box = gait.model.input_box()
    if box is None:
        return np.full(n_u, -np.inf), np.full(n_u, np.inf)
    return box


def closed_loop_monodromy(lin: TransverseLinearisation, ric: PeriodicRiccati) -> np.ndarray:
    """``∏ (J_k − J_u,k K_k(T⁻)) Φ_k^cl`` with ``Φ_k^cl`` the transition of
    ``A⊥ − B⊥ K(τ)`` over stage ``k`` (the gains from the Riccati solution itself)."""
    M = None
    for k, frame in enumerate(lin.frames):

        def closed(tau: float, d: dict, k: int = k) -> np.ndarray:
            return d["A_perp"] - d["B_perp"] @ ric.gain(k, tau)

        Phi = stage_transition(frame, closed, rtol=1e-10)
        J = lin.jumps[k] - lin.jump_inputs[k] @ ric.gain(k, frame.stage.duration)
        step = J @ Phi
        M = step if M is None else step @ M
    assert M is not None
    return M


def simulate_law(gait: Any, law: TransverseLaw, x0: np.ndarray, steps: int, **options: Any):
    """Simulate ``steps`` returns from ``x0`` (phase 0) under the law."""
    from ..simulation import simulate

    law.reset_record()
    # a phase lasting three times its nominal stage has left the orbit's neighbourhood (a
    # walker falling backwards never strikes): end it there, not after the simulator's 30 s
    longest = max(t.duration for t in law.tables)
    options = {"rtol": 1e-10, "atol": 1e-11, "max_phase_time": 3.0 * longest, **options}
    return simulate(gait.model, x0, steps=steps, feedback=law, **options)


def _section_point(gait: Any) -> np.ndarray:
    model = gait.model
    return np.asarray(model.section_coordinates_of(model.state_vector(gait.fixed_point)))


def measured_closed_loop(gait: Any, law: TransverseLaw, h: float = _FD_STEP) -> np.ndarray | None:
    """``∂s'/∂s`` of the simulated closed-loop return map (all returns of the orbit), by
    central differences (rtol 1e-12); None if a run does not complete."""
    model = gait.model
    s_star = _section_point(gait)
    steps = law.steps
    A = np.zeros((s_star.size, s_star.size))
    for j in range(s_star.size):
        ends = []
        for sign in (1.0, -1.0):
            s = s_star.copy()
            s[j] += sign * h
            sim = simulate_law(gait, law, model.lift(s), steps, rtol=1e-12, atol=1e-13)
            if not sim.success:
                return None
            ends.append(model.section_coordinates_of(sim.section_states[-1]))
        A[:, j] = (ends[0] - ends[1]) / (2 * h)
    return A


def trial(gait: Any, law: TransverseLaw, s0: np.ndarray, orbits: int) -> TransverseTrial:
    """The controlled walker from section coordinates ``s0`` for ``orbits`` orbits (rtol
    1e-9)."""
    from ..errors import StateError

    model = gait.model
    s_star = _section_point(gait)
    start = dict(zip(model.section.coordinates, map(float, s0), strict=True))
    # about 1200 evaluations of the law per step near the orbit (compass gait, rtol 1e-9)
    law.budget = 10_000 * orbits * law.steps
    try:
        x0 = model.lift(s0)
        sim = simulate_law(gait, law, x0, orbits * law.steps, rtol=1e-9, atol=1e-10)
    except StateError as exc:  # the start is not a state of the model (a foot below ground)
        return TransverseTrial(start, [float(np.max(np.abs(s0 - s_star)))], "no_start", str(exc))
    except LawBudgetExceeded as exc:  # counted as not returning, with the reason
        return TransverseTrial(start, [float(np.max(np.abs(s0 - s_star)))], "budget", str(exc))
    finally:
        law.budget = None
    states = sim.section_states[:: law.steps]
    errors = [float(np.max(np.abs(model.section_coordinates_of(x) - s_star))) for x in states]
    return TransverseTrial(
        start, errors, sim.status, sim.message, law.peak_demanded.tolist(),
        law.peak_applied.tolist(), law.saturated, law.calls, law.outside,
    )  # fmt: skip


def transverse_lqr(
    gait: Any,
    Q: Any = None,
    R: Any = None,
    *,
    orbits: int = 15,
    perturbation: float = 1e-2,
    starts: Sequence[Sequence[float]] | None = None,
    extension: float = 0.15,
) -> TransverseLQR:
    """Stabilise a gait's orbit by transverse LQR, and check it.

    Parameters
    ----------
    gait : LimitCycle or OptimalGait
        A successful gait with an input (:func:`gaitopt.find_limit_cycle` at its constant
        per-step input, or :func:`gaitopt.optimize_gait` with its profile ``u*``).
    Q : scalar, sequence or matrix, optional
        Weight of the state error ``x − x*(τ)`` (state units⁻²): a scalar (× identity, every
        phase), phase 0's diagonal or a matrix over phase 0's states (other phases by state
        name); projected on each moving surface, ``Q⊥ = Π Q Πᵀ``.  Default 1.
    R : scalar or matrix, optional
        Weight of the input correction ``δu`` (input units⁻²), positive definite.  Default 1.
    orbits : int
        Orbits simulated from each perturbed start (default 15).
    perturbation : float
        Each section coordinate in turn is displaced by ``±perturbation`` (section units) to
        start the closed-loop runs (default 1e-2).
    starts : sequence of sequences, optional
        Section-coordinate displacements to start from instead.
    extension : float
        The nominal orbit is extended past each impact by this fraction of its stage.

    Returns
    -------
    TransverseLQR
        ``success`` only if the Riccati iteration converged, the closed-loop monodromy is
        stable, the measured closed-loop multipliers agree with it, and every perturbed run
        returns to the orbit.

    Raises
    ------
    GaitoptInputError
        For a gait that is not a successful one, a model without inputs, ``R`` not positive
        definite, ``Q`` not positive semidefinite or of the wrong size, or options out of
        range.
    """
    from ..optimize.result import OptimalGait
    from ..result import LimitCycle

    if not isinstance(gait, (LimitCycle, OptimalGait)) or not gait.success:
        raise GaitoptInputError(
            f"`gait` must be a successful LimitCycle or OptimalGait, got "
            f"{getattr(gait, 'message', type(gait).__name__)!r}; find the gait first"
        )
    Q_stages, R_mat = check_weights(gait.model, Q, R)
    displacements = closed_loop_trials(
        gait.model, orbits, perturbation, starts, max_perturbation=0.5, examples=("15", "1e-2")
    )
    model = gait.model
    s_star = _section_point(gait)
    timings: dict[str, float] = {}
    clock = time.perf_counter()
    lin = transverse_linearisation(gait, extension=extension)
    timings["linearise_s"] = time.perf_counter() - clock
    clock = time.perf_counter()
    n_phases = len(model.phases)
    ric = periodic_riccati(lin, [Q_stages[st.phase] for st in lin.orbit.stages], R_mat)
    timings["riccati_s"] = time.perf_counter() - clock
    del n_phases
    low, high = _input_bounds(gait)
    clock = time.perf_counter()
    law = TransverseLaw.build(lin, ric, low, high)
    timings["tabulate_s"] = time.perf_counter() - clock
    clock = time.perf_counter()
    M_cl = closed_loop_monodromy(lin, ric)
    mu_cl = np.linalg.eigvals(M_cl)
    mu_cl = mu_cl[np.argsort(-np.abs(mu_cl))]
    timings["closed_loop_monodromy_s"] = time.perf_counter() - clock
    result = TransverseLQR(False, "", gait, lin, ric, law, Q_stages, R_mat, M_cl, mu_cl)
    result.input_low, result.input_high = low, high
    problems: list[str] = []
    if not ric.converged:
        problems.append(f"the periodic Riccati iteration did not converge in {ric.orbits} orbits")
    if not np.max(np.abs(mu_cl)) < 1:
        problems.append(
            f"the closed-loop monodromy is not stable (|λ|max {np.max(np.abs(mu_cl)):.4g})"
        )
    clock = time.perf_counter()
    measured = measured_closed_loop(gait, law)
    timings["measured_s"] = time.perf_counter() - clock
    if measured is None:
        problems.append("a perturbed controlled orbit did not complete")
    else:
        result.measured_multipliers = multipliers(measured)
        gap, rest = _match(result.measured_multipliers, mu_cl)
        result.multiplier_gap = gap
        if gap > _MULTIPLIER_TOL:
            problems.append(f"the measured closed-loop multipliers differ by {gap:.2g}")
    clock = time.perf_counter()
    for disp in displacements:
        tr = trial(gait, law, s_star + disp, orbits)
        result.trials.append(tr)
        if not tr.converged:
            problems.append(
                f"the controlled walker from {_fmt(model, s_star + disp)} did not return to the "
                f"orbit ({tr.message}; error {tr.errors[-1]:.3g} after {len(tr.errors) - 1} orbits)"
            )
    timings["trials_s"] = time.perf_counter() - clock
    result.timings = timings
    sat = sum(t.saturated for t in result.trials)
    rho = float(np.max(np.abs(mu_cl)))
    saturation = (
        f"; the input saturated at {sat} of {sum(t.calls for t in result.trials)} evaluations "
        f"of the law (clipped to its bounds)"
        if sat
        else ""
    )
    if problems:
        result.message = "not stabilised: " + "; ".join(problems) + saturation
        return result
    result.success = True
    result.message = (
        f"stabilised by transverse LQR: closed-loop |λ|max {rho:.6g} (open loop "
        f"{np.max(np.abs(lin.nontrivial())) if lin.nontrivial().size else 0.0:.6g}, measured "
        f"closed loop within {result.multiplier_gap:.2g}); from {len(result.trials)} starts the "
        f"controlled walker returns to the orbit in {orbits} orbits{saturation}"
    )
    return result


def _match(a: np.ndarray, b: np.ndarray) -> tuple[float, list[complex]]:
    """Largest distance pairing each of ``a`` with the nearest unused one of ``b``; the rest."""
    rest = list(np.asarray(b, complex))
    worst = 0.0
    for z in np.asarray(a, complex):
        j = int(np.argmin([abs(z - y) for y in rest]))
        worst = max(worst, abs(z - rest.pop(j)))
    return worst, rest


def _fmt(model: Any, s: np.ndarray) -> str:
    return ", ".join(
        f"{k}={v:.6g}" for k, v in zip(model.section.coordinates, np.ravel(s), strict=True)
    )
