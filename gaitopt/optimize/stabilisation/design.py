"""The entry point :func:`stabilise`: linearise the optimum in a per-step input offset, design
the step-to-step LQR with :func:`gaitopt.control.lqr`, and check everything — AD against finite
differences, the linearised against the measured closed-loop multipliers, the simulated closed
loop from perturbed states."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...arguments import closed_loop_trials
from ...errors import GaitoptInputError
from ..floquet import multipliers_of, return_map_jacobian
from ..result import OptimalGait
from ..verify import map_jacobian_fd
from .closed_loop import ClosedLoopTrial, dense_check, measured_closed_loop, run
from .linearise import offset_jacobian, offset_jacobian_fd, section_point
from .result import Stabilisation

__all__ = ["stabilise"]

_JACOBIAN_TOL = 1e-5  # AD against FD: |·|∞ ≤ tol (1 + |·|∞) (FD truncation ~1e-8, noise ~1e-6)
_MULTIPLIER_TOL = 1e-4  # linearised against measured closed-loop multipliers (absolute)


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
    from ...control import Linearisation, lqr

    model = gait.model
    n_u = len(model.inputs)
    base = _OffsetGait(
        model,
        section_point(gait),
        dict(gait.fixed_point),
        np.zeros(n_u),
        f"optimal gait, {gait.cost_kind} {gait.cost:.10g}, input offset δ per step",
    )
    unbounded = (np.full(n_u, -np.inf), np.full(n_u, np.inf))
    return lqr(Linearisation(base, A, B), Q, R, input_limits=unbounded)  # type: ignore[arg-type]


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
    transcription = gait.transcription
    if transcription is None:
        raise GaitoptInputError(
            "`gait` carries no transcription (it was not made by this gaitopt's optimize_gait); "
            "re-run gaitopt.optimize_gait"
        )
    displacements = closed_loop_trials(
        gait.model, orbits, perturbation, starts, max_perturbation=0.1, examples=("20", "1e-3")
    )
    model = gait.model
    s_star = section_point(gait)

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
    measured = measured_closed_loop(gait, K)
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
        sim, offsets, errors = run(gait, s0, K, orbits)
        margin, peak = dense_check(gait, sim, offsets) if sim.arcs else (None, np.zeros(0))
        open_sim, _, open_errors = run(gait, s0, None, orbits)
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
