"""The kneed walker's least cost of transport (issue 11 items 2 and 7): hip torque, passive knee,
exact positive work on bang, coasting and held arcs (problems/optimal_kneed_cot.py)."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.optimize import GaitProblem, solve_problem
from gaitopt.optimize.verify import check_dense, profiles, simulate_gait

# A shallow slope (0.03 rad, the passive gait's is 0.0504), a 0.47 m step at 0.84 m/s (the
# passive gait: 0.4727 m in 0.564 s, 0.838 m/s), |τ_hip| ≤ 5 N·m, the knee passive (its torque
# switched off: it locks by its own knee strike).
SLOPE, STEP, SPEED = 0.03, 0.47, 0.84
BOUNDS = {"hip_torque": 5.0, "knee_torque": 0.0}


@pytest.fixture(scope="module")
def statement():
    model = gaitopt.model("kneed_walker", slope=SLOPE)
    return GaitProblem(model, "cot", step_length=STEP, speed=SPEED, bounds=BOUNDS)


@pytest.fixture(scope="module")
def gait(statement):
    return solve_problem(statement)


def test_kneed_cot_is_certified(gait):
    # Source: the independent simulator (DOP853 with located knee and heel strikes, rtol
    # 1e-12) with the optimal torque as feedforward: the same cost of transport to 1e-8
    # relative (8e-11 measured; certify's check is 1e-6) and the same fixed point to 1e-9.
    # Refinement: cost and orbit settled below the 1e-8 target.
    assert gait.success and gait.verified, gait.message
    v = gait.verification
    assert v["cost_simulated"] == pytest.approx(gait.cost, rel=1e-8)
    assert v["return_error"] <= 1e-9
    assert gait.discretisation_error <= 1e-8
    assert gait.step_length == pytest.approx(STEP, rel=1e-9)
    assert gait.speed == pytest.approx(SPEED, rel=1e-9)
    # Dense samples: no guard crossed early, the swing foot above the slope (check_dense).
    col, w = gait.transcription
    assert check_dense(col, col.unpack(w, col.model.p)) is None


def test_kneed_cot_is_the_energy_balance(statement, gait):
    # Source: the work–energy balance of a periodic orbit, independent of the cost's
    # quadrature: along each phase dE/dt = Σ τᵢωᵢ (E the phase's conserved energy, in its own
    # stance-foot frame), so over one step the net work W⁺ − W⁻ equals Σ (E(x⁻) − E(x⁺)) over
    # the knee and heel strikes (closed form from the simulated states).  W⁻ by composite
    # Simpson on the dense simulated orbit (129 points per profile interval, split at its
    # breakpoints, where τ jumps).  Then cot = W⁺ / (M g L), M = 1.6 kg.  Tolerance 1e-8
    # relative (simulation rtol 1e-12; Simpson's error far below).
    model = gait.model
    col, w = gait.transcription
    sol = col.unpack(w, model.p)
    profs = profiles(col, sol)
    sim = simulate_gait(statement, model, model.lift(sol["s"]), profs, 1)
    assert sim.success
    jumps = 0.0
    for event in sim.events:
        if event.state_after is None:
            continue
        before = model.phases[event.phase].conserved["energy"]
        after_phase = 1 - event.phase  # three-link → two-link → three-link
        after = model.phases[after_phase].conserved["energy"]
        e_before = float(before(event.state_before, model.p))
        jumps += e_before - float(after(event.state_after, model.p))
    negative = 0.0
    breaks = profs[0].breaks
    for arc in sim.arcs:
        rates = model.input_rates(arc.phase)
        inner = breaks[(breaks > arc.t0) & (breaks < arc.t1)]
        edges = np.concatenate([[arc.t0], inner, [arc.t1]])
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            ts = np.linspace(a, b, 129)
            xs = arc.solution(ts)
            us = np.column_stack([profs[0](min(max(t, a + 1e-13), b - 1e-13)) for t in ts])
            omega = np.asarray(rates.map(ts.size)(xs, model.p))
            f = np.maximum(0.0, -np.sum(us * omega, axis=0))
            h = (b - a) / (ts.size - 1)
            negative += h / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())
    weight = statement.total_mass(model.p) * 9.81
    assert weight == pytest.approx(1.6 * 9.81, rel=1e-12)
    assert gait.cost == pytest.approx((jumps + negative) / (weight * STEP), rel=1e-8)
