"""The planar Raibert hopper: physics of the phases, the closed-loop gait, speed tracking, the
neutral point."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

import gaitopt
from gaitopt.errors import ParameterError
from gaitopt.models.raibert_hopper import RaibertHopper


@pytest.fixture(scope="module")
def hopper() -> RaibertHopper:
    return gaitopt.model("raibert_hopper")


@pytest.fixture(scope="module")
def gait(hopper):
    return gaitopt.find_limit_cycle(hopper)


def _states(n: int, rng: np.random.Generator, stance: bool) -> np.ndarray:
    """Random states in the model's range (stance: r in [0.4, 0.55] m, |θ| < 0.4 rad)."""
    x = rng.uniform(-1, 1, (n, 6))
    if stance:
        x[:, 0] = rng.uniform(0.4, 0.55, n)
        x[:, 1] *= 0.4
    else:
        x[:, 1] = rng.uniform(0.5, 1.0, n)
    return x


def _rate(quantity: ca.Function, flow: ca.Function, x: np.ndarray, p: np.ndarray) -> float:
    """``d/dt q(x) = ∇q · f(x)`` by AD."""
    xs = ca.SX.sym("x", 6)
    rate = ca.Function("rate", [xs], [ca.jtimes(quantity(xs, p), xs, flow(xs, [], p))])
    return float(rate(x))


def test_the_default_gait_is_found_verified_and_stable(gait):
    # Four multipliers (section z, φ, ẋ, φ̇ at the apex; nothing conserved, nothing cyclic),
    # residual and discretisation error at find_limit_cycle's tol 1e-10.
    assert gait.success and gait.verified, gait.message
    assert gait.section_coordinates == ("z", "phi", "x_dot", "phi_dot")
    assert len(gait.multipliers) == 4 and gait.stable
    assert gait.residual <= 1e-10 and gait.discretisation_error <= 1e-10
    # Upright: the attitude servo holds φ = 0 on the orbit (no pitch is ever excited); tol 1e-12.
    assert abs(gait.fixed_point["phi"]) < 1e-12 and abs(gait.fixed_point["phi_dot"]) < 1e-12


def test_energy_is_conserved_in_passive_flight(hopper, gait):
    # E = ½ M (ẋ² + ż²) + ½ J φ̇² + M g z: dE/dt = 0 by AD at random states (round-off, 1e-10);
    # and along the solved orbit's flight arcs (RK8 shooting, discretisation error ≤ 1e-10):
    # relative spread ≤ 1e-9.
    rng = np.random.default_rng(0)
    p = hopper.p
    for phase in (hopper.phases[0], hopper.phases[2]):
        energy = phase.conserved["energy"]
        for x in _states(20, rng, stance=False):
            assert abs(_rate(energy, phase.flow, x, p)) < 1e-10
    for arc in gait.orbit:
        if arc.name in ("descent", "ascent"):
            e = np.array(
                [float(hopper.phases[0].conserved["energy"](xi, hopper.p)) for xi in arc.x.T]
            )
            assert np.ptp(e) / abs(e.mean()) < 1e-9


def test_stance_energy_bookkeeping(hopper):
    # In stance, E = ½ M (ṙ² + r² θ̇²) + ½ J φ̇² + M g r cos θ + ½ k (l0 + δ − r)² changes only by
    # the leg's loss and the hip's work: dE/dt = −c ṙ² + τ (φ̇ + θ̇), τ = −k_p φ − k_v φ̇ (the hip
    # torque acts on the body at φ̇ and on the leg, whose counter-clockwise rate is −θ̇).
    # Not used in the derivation (which is by forces).  AD at random states; tolerance 1e-9 J/s.
    h = hopper
    xs = ca.SX.sym("x", 6)
    r, th, phi, r_dot, th_dot, phi_dot = (xs[i] for i in range(6))
    M, J, g, k = h.mass, h.inertia, h.gravity, h.stiffness
    energy = ca.Function(
        "E",
        [xs, ca.SX.sym("p", len(h.p))],
        [
            0.5 * M * (r_dot**2 + r**2 * th_dot**2)
            + 0.5 * J * phi_dot**2
            + M * g * r * ca.cos(th)
            + 0.5 * k * (h.rest_length + h.thrust - r) ** 2
        ],
    )
    rng = np.random.default_rng(1)
    for x in _states(20, rng, stance=True):
        tau = -h.k_attitude * x[2] - h.d_attitude * x[5]
        expected = -h.damping * x[3] ** 2 + tau * (x[5] + x[4])
        assert _rate(energy, h.phases[1].flow, x, h.p) == pytest.approx(expected, abs=1e-9)


def test_angular_momentum_about_the_foot_changes_only_by_gravity(hopper):
    # The ground force acts at the foot and the hip torque is internal, so about the foot
    # H = J φ̇ − M r² θ̇ (counter-clockwise) has Ḣ = −M g r sin θ, whatever the hip torque and
    # the leg force.  The stance equations were derived by forces (the τ/r ground force across
    # the massless leg), so this checks them.  AD at random states; tolerance 1e-10 N m.
    h = hopper
    xs = ca.SX.sym("x", 6)
    H = ca.Function(
        "H", [xs, ca.SX.sym("p", len(h.p))], [h.inertia * xs[5] - h.mass * xs[0] ** 2 * xs[4]]
    )
    rng = np.random.default_rng(2)
    for x in _states(20, rng, stance=True):
        expected = -h.mass * h.gravity * x[0] * math.sin(x[1])
        assert _rate(H, h.phases[1].flow, x, h.p) == pytest.approx(expected, abs=1e-10)
    # In flight no torque acts on the body: the angular momentum about the hip, J φ̇, is constant.
    assert float(h.phases[0].flow(_states(1, rng, stance=False)[0], [], h.p)[5]) == 0.0


def test_speed_tracking_converges_at_the_rate_of_the_multipliers(hopper, gait):
    # A change of desired speed 1.0 → 1.1 m/s (simulate's per-step `terrain` schedule) from the
    # old gait: the apex states approach the new gait with e[n] ≈ Jⁿ e[0] (J its AD Jacobian);
    # nonlinear remainder O(|e|²)/|e| ~ 1e-2 of |e[0]| = 0.07: tolerance 1e-2.  In the modal
    # coordinates of J each mode shrinks by its multiplier a step: tolerance 0.02 (same origin).
    new = gaitopt.find_limit_cycle(hopper.replace(desired_speed=1.1), gait)
    assert new.success and new.verified, new.message
    assert new.fixed_point["x_dot"] > gait.fixed_point["x_dot"] + 0.05  # it does speed up
    sim = gaitopt.simulate(hopper, gait.x, steps=8, terrain=lambda step: {"desired_speed": 1.1})
    assert sim.success, sim.message
    e = np.array([hopper.section_coordinates_of(x) for x in sim.section_states]) - new.section_point
    J = new.jacobian
    for n in range(1, 8):
        predicted = np.linalg.matrix_power(J, n) @ e[0]
        assert np.linalg.norm(e[n] - predicted) < 1e-2 * np.linalg.norm(e[0])
    values, vectors = np.linalg.eig(J)
    modal = (np.linalg.inv(vectors) @ e.T).real
    for i in np.flatnonzero(np.abs(modal[:, 0]) > 1e-3 * np.linalg.norm(e[0])):
        ratios = modal[i, 2:6] / modal[i, 1:5]
        np.testing.assert_allclose(ratios, values[i].real, atol=0.02)


def test_recovers_from_a_push(hopper, gait):
    # A push at the apex (ẋ + 0.3 m/s, φ̇ + 2 rad/s): back to the gait within 1e-6 in 40 hops
    # (the slowest multiplier 0.72: 0.72⁴⁰ ~ 2e-6 of the push).
    pushed = gait.section_point + np.array([0.0, 0.0, 0.3, 2.0])
    sim = gaitopt.simulate(hopper, hopper.lift(pushed), steps=40)
    assert sim.success, sim.message
    last = hopper.section_coordinates_of(sim.section_states[-1])
    assert np.max(np.abs(last - gait.section_point)) < 1e-6


def test_the_neutral_point_is_a_property_of_the_speed_not_of_the_gain(hopper, gait):
    # At the gait, the foot placement x_f* gives zero net acceleration at ẋ*: the actual neutral
    # point.  Any gain k_ẋ whose law places the foot at x_f* at ẋ* has the same gait: with
    # k_ẋ = 0.1 and ẋ_d = ẋ* − (x_f* − ẋ* T_s/2)/k_ẋ, find_limit_cycle returns the same orbit
    # (tolerance 1e-8, from the solver's 1e-10 and the conditioning).
    v = gait.fixed_point["x_dot"]
    x_f = hopper.foot_placement(v)
    estimate = hopper.neutral_point_estimate(v)
    other = hopper.replace(k_speed=0.1, desired_speed=v - (x_f - estimate) / 0.1)
    same = gaitopt.find_limit_cycle(other)
    assert same.success, same.message
    np.testing.assert_allclose(same.section_point, gait.section_point, atol=1e-8)
    # Raibert's estimate ẋ T_s/2 overshoots the actual neutral point here (the thrust makes the
    # stance asymmetric), hence the steady speed below ẋ_d; measured: x_f*/estimate ≈ 0.78.
    assert 0 < x_f < estimate
    # Hopping in place (ẋ_d = 0) is symmetric: ẋ* = 0 and the foot under the hip; tol 1e-10.
    still = gaitopt.find_limit_cycle(hopper.replace(desired_speed=0.0), gait)
    assert still.success and abs(still.fixed_point["x_dot"]) < 1e-10


def test_parameters_are_checked():
    with pytest.raises(ParameterError, match="thrust"):
        RaibertHopper(thrust=0.0, damping=0.0)
