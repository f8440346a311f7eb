"""The planar quadruped's bound under Raibert's controller per virtual leg: physics of the stance
phases, the foot-placement law at touchdown, the energy balance of a stride, the stable gait and
bad input.  (AD multipliers vs finite differences of the simulated map: the model-contract suite,
tests/test_model_contract.py.)"""

from __future__ import annotations

import json
import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import simpson

import gaitopt
from gaitopt.cli import main
from gaitopt.errors import ParameterError
from gaitopt.models.planar_quadruped_raibert import PlanarQuadrupedRaibert

STANCE = {1: "back", 3: "front"}  # phase index → stance leg


@pytest.fixture(scope="module")
def model() -> PlanarQuadrupedRaibert:
    return gaitopt.model("planar_quadruped_raibert")


@pytest.fixture(scope="module")
def gait(model):
    return gaitopt.find_limit_cycle(model)


@pytest.fixture(scope="module")
def stride(model, gait):
    sim = gaitopt.simulate(model, gait.x, steps=1)
    assert sim.success, sim.message
    return sim


def _hip(m, x, which, lib=np):
    """Hip position and velocity of the back (−) or front (+) leg (closed form, module docs);
    ``lib`` numpy or casadi."""
    s = -1 if which == "back" else 1
    c, sn = lib.cos(x[2]), lib.sin(x[2])
    return (
        x[0] + s * m.half_length * c,
        x[1] + s * m.half_length * sn,
        x[3] - s * m.half_length * sn * x[5],
        x[4] + s * m.half_length * c * x[5],
    )


def _leg(m, x, which):
    hx, hz, hxd, hzd = _hip(m, x, which)
    dx, dz = hx - x[6], hz
    r = np.hypot(dx, dz)
    r_dot = (dx * hxd + dz * hzd) / r
    omega = (dx * hzd - dz * hxd) / r**2  # the leg's counter-clockwise rate, d × ḋ / r²
    return dx, dz, r, r_dot, omega


def _stance_energy(m, x, which):
    r = _leg(m, x, which)[2]
    return (
        0.5 * m.mass * (x[3] ** 2 + x[4] ** 2)
        + 0.5 * m.inertia * x[5] ** 2
        + m.mass * m.gravity * x[1]
        + 0.5 * m.stiffness * (m.rest_length + m.thrust - r) ** 2
    )


def _flight_energy(m, x):
    return (
        0.5 * m.mass * (x[3] ** 2 + x[4] ** 2)
        + 0.5 * m.inertia * x[5] ** 2
        + m.mass * m.gravity * x[1]
    )


def _random_stance_states(m, which, n, rng):
    """States with the hip 0.2–0.33 m above a foot within 0.1 m of below it."""
    out = []
    for _ in range(n):
        x = rng.uniform(-1, 1, 7)
        x[1] = rng.uniform(0.25, 0.4)
        x[2] *= 0.3
        x[5] *= 5
        hx, hz = _hip(m, x, which)[:2]
        x[6] = hx + rng.uniform(-0.1, 0.1)
        out.append(x)
    return out


def _rate(model, phase, fun, x):
    """``d/dt q(x) = ∇q · f(x)`` by AD (q built on CasADi symbols of the stance state)."""
    xs = ca.SX.sym("x", 7)
    flow = model.phases[phase].flow(xs, [], model.p)
    return float(ca.Function("r", [xs], [ca.jtimes(fun(xs), xs, flow)])(x))


def test_the_default_gait_is_found_verified_and_stable(gait):
    # Four multipliers (apex z, φ, ẋ, φ̇; nothing conserved, nothing cyclic); residual and
    # discretisation error at find_limit_cycle's tol 1e-10; verified by the SciPy simulation.
    assert gait.success and gait.verified, gait.message
    assert gait.section_coordinates == ("z", "phi", "x_dot", "phi_dot")
    assert len(gait.multipliers) == 4 and gait.stable
    assert gait.residual <= 1e-10 and gait.discretisation_error <= 1e-10
    # The values of the first solve (README), as a regression check to 1e-5: apex z = 0.381985 m,
    # ẋ = 0.823761 m/s (below ẋ_d = 1: Raibert's estimate ẋ T_s/2 overshoots the neutral
    # point), φ̇ = 4.0746 rad/s, period 0.394128 s, |λ| = 0.6992 (pair), 0.6223, 0.0352.
    fp = gait.fixed_point
    assert fp["z"] == pytest.approx(0.381985, abs=1e-5)
    assert fp["x_dot"] == pytest.approx(0.823761, abs=1e-5)
    assert fp["phi_dot"] == pytest.approx(4.074601, abs=1e-5)
    assert gait.period == pytest.approx(0.394128, abs=1e-5)
    np.testing.assert_allclose(
        np.sort(np.abs(gait.multipliers)), [0.035234, 0.622275, 0.699176, 0.699176], atol=1e-5
    )
    assert np.all(np.asarray(gait.durations) > 0)


def test_feet_land_where_raibert_s_law_places_them(model, stride):
    # At each touchdown of the simulated stride the foot is x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d) ahead
    # of its hip (Raibert 1986 eq. 2.4), T_s = π sqrt(m_h/k), m_h = m I/(I + m L²), written out
    # here from the closed form: geometry l0 sin(asin(x_f/l0)) = x_f, rounding 1e-12 m.  The leg
    # is at its rest length there: r = l0 to the event location's 1e-9 m.
    m = model
    m_h = m.mass * m.inertia / (m.inertia + m.mass * m.half_length**2)
    t_s = math.pi * math.sqrt(m_h / m.stiffness)
    landed = 0
    for arc in stride.arcs:
        if arc.phase not in STANCE:
            continue
        x = arc.solution(arc.t0)
        hx = _hip(m, x, STANCE[arc.phase])[0]
        x_f = x[3] * t_s / 2 + m.k_speed * (x[3] - m.desired_speed)
        assert x[6] - hx == pytest.approx(x_f, abs=1e-12)
        assert _leg(m, x, STANCE[arc.phase])[2] == pytest.approx(m.rest_length, abs=1e-9)
        landed += 1
    assert landed == 2


@pytest.mark.parametrize("phase", [1, 3])
def test_stance_energy_changes_by_the_loss_and_the_hip_s_work(model, phase):
    # E = ½ m |v|² + ½ I φ̇² + m g z + ½ k (l0 + δ − r)² has Ė = −c ṙ² + τ (φ̇ − ω_leg),
    # τ = −k_p φ − k_v φ̇ (the hip torque acts on the body at φ̇ and on the leg at ω_leg).  Not
    # used in the derivation (by forces).  AD at random states; tolerance 1e-9 W (round-off).
    m, which = model, STANCE[phase]
    rng = np.random.default_rng(phase)

    def energy(xs):
        hx, hz = _hip(m, [xs[i] for i in range(7)], which, lib=ca)[:2]
        r = ca.sqrt((hx - xs[6]) ** 2 + hz**2)
        return (
            0.5 * m.mass * (xs[3] ** 2 + xs[4] ** 2)
            + 0.5 * m.inertia * xs[5] ** 2
            + m.mass * m.gravity * xs[1]
            + 0.5 * m.stiffness * (m.rest_length + m.thrust - r) ** 2
        )

    for x in _random_stance_states(m, which, 20, rng):
        _, _, _, r_dot, omega = _leg(m, x, which)
        tau = -m.k_attitude * x[2] - m.d_attitude * x[5]
        expected = -m.damping * r_dot**2 + tau * (x[5] - omega)
        assert _rate(m, phase, energy, x) == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("phase", [1, 3])
def test_angular_momentum_about_the_foot_changes_only_by_gravity(model, phase):
    # The ground force acts at the foot and the hip torque is internal: about the foot,
    # H = I φ̇ + m ((x − x_f) ż − z ẋ) has Ḣ = −m g (x − x_f), whatever the leg force and the
    # servo's torque.  Checks the ground force −τ/r across the leg.  AD; tolerance 1e-10 N m.
    m = model
    rng = np.random.default_rng(10 + phase)

    def momentum(xs):
        return m.inertia * xs[5] + m.mass * ((xs[0] - xs[6]) * xs[4] - xs[1] * xs[3])

    for x in _random_stance_states(m, STANCE[phase], 20, rng):
        expected = -m.mass * m.gravity * (x[0] - x[6])
        assert _rate(m, phase, momentum, x) == pytest.approx(expected, abs=1e-10)


def test_energy_balance_of_a_stride(model, stride):
    # Each stance: the body's energy after lift-off minus before touchdown equals the thrust's
    # ½ k δ² (the spring is δ short of its stance rest length at touchdown), minus the spring
    # energy left at lift-off ½ k (l0 + δ − r)², plus ∫ (τ (φ̇ − ω_leg) − c ṙ²) dt (Simpson on
    # 4001 points of the dense output; error ≪ 1e-7 J).  Flights conserve the energy; over the
    # periodic stride the terms sum to zero.  Tolerance 1e-6 J of ~6 J per stance.
    m = model
    arcs = stride.arcs
    net = 0.0
    for i, arc in enumerate(arcs):
        if arc.phase not in STANCE:
            continue
        which = STANCE[arc.phase]
        t, X = arc.sample(4001)
        power = []
        for x in X.T:
            _, _, _, r_dot, omega = _leg(m, x, which)
            tau = -m.k_attitude * x[2] - m.d_attitude * x[5]
            power.append(tau * (x[5] - omega) - m.damping * r_dot**2)
        work = simpson(np.array(power), x=t)
        before = _flight_energy(m, arcs[i - 1].solution(arcs[i - 1].t1))
        after = _flight_energy(m, arcs[i + 1].solution(arcs[i + 1].t0))
        r_lo = _leg(m, X[:, -1], which)[2]
        left = 0.5 * m.stiffness * (m.rest_length + m.thrust - r_lo) ** 2
        assert after - before == pytest.approx(
            0.5 * m.stiffness * m.thrust**2 - left + work, abs=1e-6
        )
        net += after - before
    assert abs(net) < 1e-6


@pytest.mark.parametrize(
    ("changes", "name"),
    [
        ({"k_speed": 0.0}, "k_speed"),
        ({"k_attitude": 0.0}, "k_attitude"),
        ({"d_attitude": -1.0}, "d_attitude"),
        ({"thrust": 0.0, "damping": 0.0}, "thrust"),
    ],
)
def test_meaningless_gains_are_refused(changes, name):
    with pytest.raises(ParameterError, match=name):
        PlanarQuadrupedRaibert(**changes)


def test_a_desired_speed_no_gait_reaches_is_an_honest_failure(capsys):
    # ẋ_d = 8 m/s: followed from the default gait, the bound is lost near ẋ_d ≈ 7.15 m/s where
    # the ascent's duration reaches zero (the front leg lifts off at the apex): success false,
    # exit 1, and the reason in the message; no gait is reported.
    code = main(["solve", "planar_quadruped_raibert", "--set", "desired_speed=8", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == 1 and report["success"] is False
    assert "desired_speed" in report["message"] and "ascent" in report["message"]


def test_following_the_desired_speed_from_the_cli_ends_at_a_boundary(capsys):
    # `gaitopt continue` in ẋ_d from the default gait (1 m/s) up to 8 m/s: every gait on the way
    # is stable and there is no LP, PD or NS; the branch ends at a boundary located by
    # bisection, ẋ_d = 7.160155 m/s (the first run's value, results/planar_quadruped_raibert_study;
    # regression tolerance 1e-4 m/s), where the ascent's duration reaches zero (the front leg
    # lifts off at the apex).  The last certified gait there is still stable, |λ| < 1.
    code = main(
        [
            "continue",
            "planar_quadruped_raibert",
            "--param",
            "desired_speed",
            "--to",
            "8",
            "--no-cascade",
            "--json",
        ]
    )
    report = json.loads(capsys.readouterr().out)
    assert code == 0, report["message"]
    assert [sp["kind"] for sp in report["special_points"]] == ["boundary"]
    edge = report["special_points"][0]
    assert edge["param"] == pytest.approx(7.160155, abs=1e-4)
    assert max(abs(complex(*z)) for z in edge["multipliers"]) < 1.0
    assert all(point["stable"] for point in report["points"])


def _hopper_twin(pronk):
    """raibert_hopper with stiffness 2k, loss 2c and the pronk's mass, rest length, thrust,
    desired speed and speed gain (its inertia and servo act only off the pitch-free set)."""
    return gaitopt.model(
        "raibert_hopper",
        mass=pronk.mass,
        rest_length=pronk.rest_length,
        stiffness=2 * pronk.stiffness,
        damping=2 * pronk.damping,
        thrust=pronk.thrust,
        desired_speed=pronk.desired_speed,
        k_speed=pronk.k_speed,
        gravity=pronk.gravity,
    )


@pytest.mark.parametrize("changes", [{}, {"desired_speed": 1.5, "thrust": 0.05}])
def test_the_pitch_free_pronk_is_raibert_s_hopper_on_twice_the_spring(changes):
    # Exact reduction (gaitopt/models/planar_quadruped_raibert_pronk.py): on φ = φ̇ = 0 the two
    # legs' forces are equal, their moments cancel and the servo's torque is zero, so the COM
    # obeys the Raibert hopper's stance equations with 2k and 2c, and the foot-placement law has
    # the same T_s = π sqrt(m/(2k)).  Two independent computations (Cartesian Newton–Euler with
    # both feet here, polar coordinates about the foot in raibert_hopper), each solved to 1e-10:
    # apex z, ẋ and period agree to 1e-9, and the pronk's two multipliers (the pitch-free
    # directions) are two of the hopper's four (its others are the pitch's), to 1e-8.
    pronk = gaitopt.model("planar_quadruped_raibert_pronk", **changes)
    quad = gaitopt.find_limit_cycle(pronk)
    fp = quad.fixed_point
    twin = gaitopt.find_limit_cycle(
        _hopper_twin(pronk), {"z": fp["z"], "phi": 0.0, "x_dot": fp["x_dot"], "phi_dot": 0.0}
    )
    for cycle in (quad, twin):
        assert cycle.success and cycle.verified, cycle.message
    assert fp["z"] == pytest.approx(twin.fixed_point["z"], abs=1e-9)
    assert fp["x_dot"] == pytest.approx(twin.fixed_point["x_dot"], abs=1e-9)
    assert quad.period == pytest.approx(twin.period, abs=1e-9)
    assert len(quad.multipliers) == 2
    for lam in quad.multipliers:
        assert np.min(np.abs(twin.multipliers - lam)) < 1e-8


def test_the_default_pronk_is_stable():
    # k_ẋ = 0.03 s, below the speed loop's period doubling (problems/planar_quadruped_raibert.py);
    # both pitch-free multipliers inside the unit circle, one negative (the speed loop).
    gait = gaitopt.find_limit_cycle(gaitopt.model("planar_quadruped_raibert_pronk"))
    assert gait.success and gait.verified and gait.stable, gait.message
    assert min(z.real for z in gait.multipliers) < 0
