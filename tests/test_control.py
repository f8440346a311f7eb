"""Step-to-step control: gains from python-control, deadbeat in one step, closed-loop
multipliers against simulated convergence, rough terrain, blind running."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

import gaitopt
from gaitopt import control as gc
from gaitopt import terrain as gt
from gaitopt.errors import GaitoptInputError


@pytest.fixture(scope="module")
def slip():
    return gaitopt.model("slip")


@pytest.fixture(scope="module")
def slip_deadbeat(slip):
    return gc.deadbeat(slip)


@pytest.fixture(scope="module")
def steep():
    """The compass gait at slope 0.09: period-1 gait past its period doubling (unstable)."""
    return gc.linearise(gaitopt.model("compass_gait", slope=0.09))


# -- the gains come from python-control -----------------------------------------------------
def test_lqr_gain_is_python_controls_dlqr(slip):
    lin = gc.linearise(slip)
    controller = gc.lqr(lin, Q=2.0, R=0.5)
    K, _, _ = ct.dlqr(lin.A, lin.B, 2.0 * np.eye(1), 0.5 * np.eye(1))
    np.testing.assert_array_equal(controller.gain, K)  # the same call: bit for bit
    np.testing.assert_allclose(
        controller.closed_loop_multipliers, np.linalg.eigvals(lin.A - lin.B @ K), atol=1e-14
    )


def test_lqr_and_acker_call_python_control(slip, monkeypatch):
    # Not a re-implementation: replace python-control's functions and the gains follow them.
    lin = gc.linearise(slip)
    calls = []

    def fake_dlqr(A, B, Q, R):
        calls.append("dlqr")
        return np.array([[0.123]]), np.eye(1), np.array([0.0])

    def fake_acker(A, B, poles):
        calls.append("acker")
        return np.array([[0.456]])

    monkeypatch.setattr(ct, "dlqr", fake_dlqr)
    monkeypatch.setattr(ct, "acker", fake_acker)
    assert gc.lqr(lin).gain.tolist() == [[0.123]]
    assert gc.acker(lin, [0.1]).gain.tolist() == [[0.456]]
    assert calls == ["dlqr", "acker"]


def test_acker_places_the_closed_loop_multipliers(steep):
    # Ackermann's formula (python-control `acker`) on the compass gait's 3×3 map; tolerance 1e-8
    # (the map's entries are O(1)–O(10)).
    poles = [0.3, 0.2, 0.1]
    controller = gc.acker(steep, poles)
    assert np.sort(controller.closed_loop_multipliers.real) == pytest.approx([0.1, 0.2, 0.3], 1e-8)


# -- deadbeat ------------------------------------------------------------------------------
@pytest.mark.parametrize("z0", [0.87, 0.9, 1.0])
def test_deadbeat_reaches_the_target_in_one_step(slip, slip_deadbeat, z0):
    # The criterion: one step of the independent SciPy simulation with the deadbeat angle
    # lands on the target apex to 1e-9 (shooting discretisation error ≤ 1e-10, rtol 1e-11).
    decision = slip_deadbeat.decide({"z": z0})
    assert decision.success, decision.message
    sim = gaitopt.simulate(slip, {"z": z0}, steps=1, inputs=decision.input)
    assert sim.success
    assert abs(sim.section_states[-1][1] - slip_deadbeat.target[0]) < 1e-9
    # Its linearisation is K = B⁻¹A: every closed-loop multiplier 0.
    assert np.abs(slip_deadbeat.closed_loop_multipliers).max() < 1e-12


def test_deadbeat_outside_its_range_says_so(slip_deadbeat):
    lo, hi = slip_deadbeat.deadbeat_solver.feasible_range()
    # The range reaches down to the touchdown height and up to near E/(m g); bisection 1e-6.
    assert lo == pytest.approx(np.cos(np.pi / 6), abs=2e-3) and 1.4 < hi <= 1.61
    decision = slip_deadbeat.decide({"z": 0.8})
    assert not decision.success
    assert "deadbeat infeasible from z=0.8" in decision.message
    assert "deadbeat works for" in decision.message


def test_deadbeat_to_another_target(slip):
    # A target that is not a passive fixed point: the nominal angle is solved so that z = 1.0 m
    # is one; then one deadbeat step from 1.05 m lands on it (1e-9, as above).
    controller = gc.deadbeat(slip, target={"z": 1.0})
    assert controller.target[0] == pytest.approx(1.0, abs=1e-12)
    decision = controller.decide({"z": 1.05})
    sim = gaitopt.simulate(slip, {"z": 1.05}, steps=1, inputs=decision.input)
    assert abs(sim.section_states[-1][1] - 1.0) < 1e-9


def test_deadbeat_needs_as_many_inputs_as_coordinates():
    with pytest.raises(gc.ControlDesignError, match="as many inputs as section coordinates"):
        gc.deadbeat(gaitopt.model("compass_gait"))
    with pytest.raises(gc.ControlDesignError, match="no per-step input"):
        gc.lqr(gaitopt.model("rimless_wheel"))
    with pytest.raises(GaitoptInputError, match="`Q` must be"):
        gc.lqr(gaitopt.model("slip"), Q=[1.0, 2.0])


# -- closed-loop multipliers vs simulation ------------------------------------------------------
def test_slip_lqr_multiplier_is_the_simulated_contraction(slip):
    # For the 1-D apex map the closed-loop error obeys e[n+1] ≈ λ_cl e[n]; from 1e-5 off the
    # fixed point the simulated ratio matches eig(A − BK) to 5e-4 (the second-order term is
    # ~14 e here, the simulation's noise ~1e-11/e).
    controller = gc.lqr(slip, Q=1.0, R=1.0)
    run = gc.closed_loop(controller, slip, {"z": controller.target[0] + 1e-5}, steps=3)
    e = run.section[:, 0] - controller.target[0]
    ratios = e[1:] / e[:-1]
    assert ratios == pytest.approx(controller.closed_loop_multipliers[0].real, abs=5e-4)


def test_compass_gait_lqr_stabilises_the_unstable_period_one_gait(steep):
    # Slope 0.09: the passive period-1 gait has a multiplier ≈ −1.67 (past period doubling).
    # Passive, a 1e-6 perturbation grows; with LQR it decays at the rate of the largest closed-loop
    # multiplier: the fitted per-step contraction matches max |eig(A − BK)| to 2 %.
    model = steep.model
    assert steep.open_loop_multipliers[0].real == pytest.approx(-1.67, abs=0.01)
    controller = gc.lqr(steep)
    rho = np.abs(controller.closed_loop_multipliers).max()
    assert rho < 1
    x0 = steep.cycle.x + np.array([1e-6, -1e-6, 0.0, 0.0])
    passive = gc.closed_loop(None, model, x0, steps=12, target=controller.target)
    assert passive.errors[-1] > 100 * passive.errors[0]
    run = gc.closed_loop(controller, model, x0, steps=12)
    assert run.survived == 12
    tail = np.log(run.errors[4:12])
    slope = np.polyfit(np.arange(tail.size), tail, 1)[0]
    assert np.exp(slope) == pytest.approx(rho, rel=0.02)


# -- terrain and blind running ------------------------------------------------------------------
def test_terrain_changes_the_ground_per_step(slip):
    terrain = gt.random_terrain(slip, seed=7, amplitude=0.01)
    again = gt.random_terrain(slip, seed=7, amplitude=0.01)
    assert [terrain.value(k) for k in range(5)] == [again.value(k) for k in range(5)]
    controller = gc.deadbeat(slip, target={"z": 1.0})
    sim = gaitopt.simulate(slip, {"z": 1.0}, steps=3, inputs=controller, terrain=terrain)
    assert sim.success
    assert [p["ground_height"] for p in sim.step_parameters] == [terrain.value(k) for k in range(3)]
    assert all(abs(terrain.value(k)) <= 0.01 for k in range(100))
    with pytest.raises(GaitoptInputError, match="unknown parameter 'height'"):
        gaitopt.simulate(slip, {"z": 1.0}, steps=1, terrain=lambda k: {"height": 0.0})


def test_blind_swing_law_is_deadbeat_on_unknown_ground(slip):
    # Ernst/Geyer blind running: the leg angle as a function of time since apex makes every
    # touchdown deadbeat.  The Chebyshev law fits the tabulated deadbeat angles to 1e-8 rad; on
    # seeded ±5 cm terrain the runner, blind to the ground, returns to the target apex every step
    # to 1e-8 m (law fit + shooting accuracy), where plain deadbeat (assuming level ground) is off
    # by millimetres.
    controller = gc.deadbeat(slip, target={"z": 1.0})
    law = gt.blind_swing_law(controller.deadbeat_solver, 1.02, heights=(-0.06, 0.06))
    assert law.success and law.fit_error < 1e-8
    terrain = gt.random_terrain(slip, seed=1, amplitude=0.05)
    policy = gt.BlindPolicy(controller, heights=(-0.06, 0.06))
    blind = gc.closed_loop(policy, policy.model(), {"z": 1.02}, steps=4, terrain=terrain,
                           target=controller.target)  # fmt: skip
    assert blind.survived == 4 and np.max(blind.errors[1:]) < 1e-8
    plain = gc.closed_loop(controller, slip, {"z": 1.02}, steps=4, terrain=terrain)
    assert plain.survived == 4 and np.max(plain.errors[1:]) > 1e-4


def test_generated_policy_function_agrees_with_the_rootfinder(slip_deadbeat, slip):
    # The single-shooting policy that is turned into C (fast_newton) agrees with the multiple-
    # shooting deadbeat to 1e-9 rad near the gait (RK steps chosen for 1e-9 relative accuracy).
    f = slip_deadbeat.deadbeat_solver.policy_function()
    for z in (0.87, 0.9, 0.95):
        u, T, residual = f([z], slip_deadbeat.target, slip.p)
        assert float(residual) < 1e-10 and np.all(np.asarray(T) > 0)
        assert float(u) == pytest.approx(slip_deadbeat.decide({"z": z}).input[0], abs=1e-9)
