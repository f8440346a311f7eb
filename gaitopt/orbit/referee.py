"""The referee of a gait: an independent simulation from its fixed point.

Both front doors use it through their transcription's ``referee`` (rule 8), the last stage of
:func:`gaitopt.orbit.solve_gait` (:func:`gaitopt.find_limit_cycle` with the constant per-step
input, :func:`gaitopt.optimize_gait` with the optimal profile as a feedforward).
The simulation is :func:`gaitopt.simulate` — SciPy's adaptive
DOP853 with located, directional, admissible events and every declared unilateral constraint as a
terminal event: a different method and step control from either transcription — driven by the
gait's input, a constant per-step vector or a feedforward profile ``u(t, step)``.  It must

* complete ``steps`` returns through as many phases as the orbit has;
* return to the fixed point: ``max |x_return − x*| ≤ tol · (1 + max |x*|)``;
* pass each phase in the orbit's time: ``max |T_sim − T| ≤ TIMING_TOL · (1 + period)``;
* where the gait has a cost, cost the same: ``|J_sim − J| ≤ COST_TOL · |J| + 1e-12``.

Tolerances are tried in order (:data:`LADDER`: a loose pair, then a tight one where the loose
one fails): the first pair whose simulation passes every check decides.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..hybrid import HybridModel
from ..simulation import Simulation, simulate

__all__ = ["COST_TOL", "LADDER", "TIGHT", "TIMING_TOL", "Verdict", "referee"]

# Phase timing, relative to the period: near an existence boundary (a rimless wheel that barely
# vaults) the adaptive simulation's event times drift by far more than its states, while the
# transcriptions' durations carry their discretisation error.
TIMING_TOL = 1e-6

#: The simulated cost must agree with the transcription's to this relative tolerance.
COST_TOL = 1e-6

# The simulation's tolerances, (rtol, atol): first the loose pair, whose error at the return
# (1e-13 to 1.4e-10 over the registered models' gaits, measured against the shooting's fixed
# points) stays three orders of magnitude below the 1e-7 the shooting checks it against in
# 30-40 % fewer steps; where that check fails, the tight pair decides (near an existence
# boundary, where a rimless wheel barely vaults, the event times need it).
LOOSE = (1e-10, 1e-12)
TIGHT = (1e-12, 1e-13)
LADDER = (LOOSE, TIGHT)


@dataclass
class Verdict:
    """What the referee found.

    Attributes
    ----------
    ok : bool
        Every check passed (at the tolerances of ``tolerances``).
    return_error : float
        ``max |x_return − x*|`` (state units; inf where the simulation did not return).
    timing_error : float
        ``max |T_sim − T|`` over the phases (s; inf where it did not return).
    cost_simulated, cost_error : float
        The simulated cost and its relative error (NaN without a cost).
    period_simulated : float
        Time of the last return (s; NaN where it did not return).
    message : str
        The verdict in words.
    simulation : Simulation or None
        The deciding simulation.
    tolerances : tuple of float
        Its ``(rtol, atol)``.
    """

    ok: bool
    return_error: float
    timing_error: float
    message: str
    cost_simulated: float = float("nan")
    cost_error: float = float("nan")
    period_simulated: float = float("nan")
    simulation: Simulation | None = None
    tolerances: tuple[float, float] = TIGHT


def referee(
    model: HybridModel,
    x_star: np.ndarray,
    durations: np.ndarray,
    steps: int,
    *,
    tol: float,
    inputs: np.ndarray | None = None,
    feedforward: Callable[[float, int], np.ndarray] | None = None,
    cost: tuple[float, Callable[[Simulation], float]] | None = None,
    max_phase_time: float | None = None,
    tolerances: Sequence[tuple[float, float]] = LADDER,
) -> Verdict:
    """Simulate from the fixed point and check the return, the timing and the cost.

    Parameters
    ----------
    model : HybridModel
        The model at the gait's parameters.
    x_star : numpy.ndarray
        The fixed point (full section-phase state).
    durations : numpy.ndarray
        The orbit's phase durations (s), in orbit order (``steps`` cycles).
    steps : int
        Returns to the section per orbit.
    tol : float
        Relative tolerance of the return: ``max |x_return − x*| ≤ tol · (1 + max |x*|)``.
    inputs : numpy.ndarray, optional
        A constant per-step input (the shooting's ``u``).
    feedforward : callable, optional
        ``u(t, step)`` (s since that step's section): the optimal profile.  Not with ``inputs``.
    cost : (float, callable), optional
        ``(J, cost_of)``: the transcription's cost and the function computing it from a
        simulation; the simulated cost must agree to :data:`COST_TOL`.
    max_phase_time : float, optional
        The simulation's timeout per phase (s); default the model's.
    tolerances : sequence of (rtol, atol)
        The simulation's tolerances, tried in order until one passes.
    """
    durations = np.asarray(durations, dtype=float).ravel()
    x_star = np.asarray(x_star, dtype=float).ravel()
    limit = float(model.max_phase_time if max_phase_time is None else max_phase_time)
    verdict = None
    for rtol, atol in tolerances:
        sim = simulate(
            model, x_star, steps=steps, inputs=inputs, feedforward=feedforward,
            max_phase_time=limit, rtol=rtol, atol=atol,
        )  # fmt: skip
        verdict = _judge(sim, x_star, durations, tol, cost)
        verdict.tolerances = (rtol, atol)
        if verdict.ok:
            return verdict
    assert verdict is not None, "tolerances must not be empty"
    return verdict


def _judge(
    sim: Simulation,
    x_star: np.ndarray,
    durations: np.ndarray,
    tol: float,
    cost: tuple[float, Callable[[Simulation], float]] | None,
) -> Verdict:
    inf = float("inf")
    if not sim.success:
        return Verdict(
            False, inf, inf, f"the simulation from the fixed point fails: {sim.message}",
            simulation=sim,
        )  # fmt: skip
    if len(sim.arcs) != durations.size:
        return Verdict(
            False, inf, inf,
            f"the simulation passes {len(sim.arcs)} phases where the orbit has {durations.size}",
            simulation=sim,
        )  # fmt: skip
    error = float(np.max(np.abs(sim.section_states[-1] - x_star)))
    timing = float(np.max(np.abs(np.array([a.t1 - a.t0 for a in sim.arcs]) - durations)))
    out: dict[str, Any] = dict(
        return_error=error, timing_error=timing, simulation=sim,
        period_simulated=float(sim.section_times[-1]),
    )  # fmt: skip
    return_ok = error <= tol * (1 + float(np.max(np.abs(x_star))))
    timing_ok = timing <= TIMING_TOL * (1 + float(np.sum(durations)))
    cost_ok, cost_words = True, ""
    if cost is not None:
        expected, cost_of = cost
        simulated = float(cost_of(sim))
        out["cost_simulated"] = simulated
        out["cost_error"] = (
            abs(simulated - expected) / abs(expected) if expected != 0 else abs(simulated)
        )
        cost_ok = abs(simulated - expected) <= COST_TOL * abs(expected) + 1e-12
        cost_words = f", cost {simulated:.10g} simulated"
        if not cost_ok:
            cost_words += f" against {expected:.10g}"
    if return_ok and timing_ok and cost_ok:
        return Verdict(
            True,
            message=(
                f"verified by simulation: return error {error:.2g}, timing error {timing:.2g} s"
                f"{cost_words}"
            ),
            **out,
        )
    return Verdict(
        False,
        message=(
            f"the simulation from the fixed point returns {error:.3g} away (tolerance {tol:g}); "
            f"phase timing differs by {timing:.3g} s (tolerance {TIMING_TOL:g} of the period)"
            f"{cost_words}"
        ),
        **out,
    )
