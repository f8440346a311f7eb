"""Grizzle's three-link walker under fixed virtual constraints (issue 20, first part).

Sources of the numbers:

* the model: Grizzle, Abba & Plestan 2001 (IEEE TAC 46(1)) as stated in issue 20 (D, C, G, B;
  the outputs h = [θ3 − π/8, θ1 + θ2]; ω_n = 5, ζ = 1.1; impact at θ1 = π/8 rising);
* the gait: **computed here** and checked against an independent NumPy/SciPy referee written in
  this file from the issue's equations (explicit D, C, G; the extended 5-DOF impact solved as its
  KKT system ``[D_e −Eᵀ; E 0]``, as in Westervelt et al. 2007's book code
  ``transition_three_link.m``), event-located DOP853 at rtol 1e-12.  Both give the step time
  2.1677530383 s and the dominant multiplier 0.6713863, **not** the issue's 2.2583406929 s and
  0.5512805: the issue's D, C, G, B, controller and impact are the same as those of Grizzle's own
  course code (``dyn_mod_3LinkWalkerWithController``, ``threeLinkImpactModel``), which the
  referee follows, and no variant tried (g = 9.81, θ3d = π/6, ζ or ω_n changed alone, the
  section at θ1 = −π/8) gives both of the issue's numbers; see the report of issue 20.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

import gaitopt
from gaitopt.errors import ParameterError
from gaitopt.hybrid import Symbols
from gaitopt.mechanics import lagrange_terms
from gaitopt.models import three_link_walker as tlw

# Computed here (see the module docstring); the referee below checks them independently.
STEP_TIME = 2.1677530383  # s
DOMINANT = 0.6713863  # the zero dynamics' multiplier
PAIR = 1.7041780e-3 + 3.775452e-4j  # the slow transverse pair (and its conjugate)
# The outputs just after impact on the gait (non-invariance): h (rad) and L_f h (rad/s).
H_PLUS = (3.4499e-4, 1.1191e-4)
DH_PLUS = (1.655974, 0.537163)


@pytest.fixture(scope="module")
def gait():
    cycle = gaitopt.find_limit_cycle(gaitopt.model("three_link_walker"))
    assert cycle.success, cycle.message
    return cycle


# -- the referee: the equations in NumPy ------------------------------------------------

R, M_LEG, M_HIP, M_TORSO, L_TORSO, G = 1.0, 5.0, 15.0, 10.0, 0.5, 9.8
B = np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, 1.0]])
H = np.array([[0.0, 0.0, 1.0], [1.0, 1.0, 0.0]])


def _dcg(q, dq):
    """Grizzle et al. 2001's D, C, G (issue 20's statement), NumPy."""
    c12, c13 = math.cos(q[0] - q[1]), math.cos(q[0] - q[2])
    s12, s13 = math.sin(q[0] - q[1]), math.sin(q[0] - q[2])
    a, b = M_LEG * R**2 / 2, M_TORSO * L_TORSO * R
    D = np.array(
        [
            [(M_HIP + M_TORSO + 5 * M_LEG / 4) * R**2, -a * c12, b * c13],
            [-a * c12, M_LEG * R**2 / 4, 0.0],
            [b * c13, 0.0, M_TORSO * L_TORSO**2],
        ]
    )
    C = np.array([[0.0, -a * s12 * dq[1], b * s13 * dq[2]], [a * s12 * dq[0], 0, 0],
                  [-b * s13 * dq[0], 0, 0]])  # fmt: skip
    Gv = np.array(
        [
            -(M_HIP + M_TORSO + 1.5 * M_LEG) * G * R * math.sin(q[0]),
            M_LEG * G * R / 2 * math.sin(q[1]),
            -M_TORSO * G * L_TORSO * math.sin(q[2]),
        ]
    )
    return D, C, Gv


def _torque(x, wn=5.0, zeta=1.1):
    q, dq = x[:3], x[3:]
    D, C, Gv = _dcg(q, dq)
    a, A = np.linalg.solve(D, -C @ dq - Gv), np.linalg.solve(D, B)
    h = np.array([q[2] - math.pi / 8, q[0] + q[1]])
    return np.linalg.solve(H @ A, -H @ a - wn**2 * h - 2 * zeta * wn * (H @ dq))


def _flow(t, x):
    del t
    q, dq = x[:3], x[3:]
    D, C, Gv = _dcg(q, dq)
    return np.r_[dq, np.linalg.solve(D, -C @ dq - Gv + B @ _torque(x))]


def _impact(x):
    """Extended model (stance foot at (x_f, y_f) free), KKT system; returns (x⁺ after the swap,
    the impulse on the swing foot (N·s), the old stance foot's velocity just after (m/s))."""
    t1, t2, t3 = x[:3]
    k = (M_HIP + M_TORSO + 1.5 * M_LEG) * R
    De = np.zeros((5, 5))
    De[:3, :3] = _dcg(x[:3], x[3:])[0]
    De[0, 3:] = De[3:, 0] = (k * math.cos(t1), -k * math.sin(t1))
    De[1, 3:] = De[3:, 1] = (-M_LEG * R / 2 * math.cos(t2), M_LEG * R / 2 * math.sin(t2))
    De[2, 3:] = De[3:, 2] = (M_TORSO * L_TORSO * math.cos(t3), -M_TORSO * L_TORSO * math.sin(t3))
    De[3, 3] = De[4, 4] = M_HIP + M_TORSO + 2 * M_LEG
    E = np.array([[R * math.cos(t1), -R * math.cos(t2), 0, 1, 0],
                  [-R * math.sin(t1), R * math.sin(t2), 0, 0, 1]])  # fmt: skip
    K = np.block([[De, -E.T], [E, np.zeros((2, 2))]])
    sol = np.linalg.solve(K, np.r_[De @ np.r_[x[3:], 0, 0], 0, 0])
    swap = [1, 0, 2]
    return np.r_[x[:3][swap], sol[:3][swap]], sol[5:], sol[3:5]


def _step(x):
    event = lambda t, x: x[0] - math.pi / 8  # noqa: E731
    event.terminal, event.direction = True, 1
    sol = solve_ivp(_flow, (0, 10), x, method="DOP853", events=event, rtol=1e-12, atol=1e-12)
    x_minus = sol.y_events[0][0]
    return _impact(x_minus)[0], sol.t_events[0][0], x_minus


# -- the model's equations ------------------------------------------------------------------------


def _numeric_terms():
    model = gaitopt.model("three_link_walker")
    return model, model._function("terms")


def test_the_matrices_are_lagrange_s_equations_of_the_point_masses():
    # D, C, G as stated (Grizzle et al. 2001) against Lagrange's equations of the point masses
    # (gaitopt.mechanics by AD): D = M and C q̇ + G = −rhs, at random states; 1e-12 relative.
    cls = tlw.ThreeLinkWalker
    sym = Symbols(cls.parameter_specs(), cls.inputs)
    q, qd = ca.SX.sym("q", 3), ca.SX.sym("qd", 3)
    M, rhs = lagrange_terms(tlw._geometry(sym, q)["masses"], q, qd, sym.gravity, 0)
    D, C, Gv = tlw._terms(sym, q, qd)
    check = ca.Function("check", [q, qd, sym.p], [M - D, rhs + C @ qd + Gv, D])
    model = cls()
    rng = np.random.default_rng(20)
    for _ in range(5):
        dM, dr, Dv = (np.asarray(v, dtype=float) for v in check(*rng.normal(size=(2, 3)), model.p))
        assert np.max(np.abs(dM)) < 1e-12 * np.max(np.abs(Dv))
        assert np.max(np.abs(dr)) < 1e-12 * 1e3


def test_the_model_and_the_referee_agree_on_the_flow_and_torques():
    # The CasADi closed loop against the NumPy referee (the equations): q̈ and u at
    # random states near the gait; 1e-10 relative.
    model = gaitopt.model("three_link_walker")
    flow = model.phases[0].flow
    rng = np.random.default_rng(1)
    for _ in range(5):
        x = np.r_[rng.uniform(-0.4, 0.4, 3), rng.normal(size=3)]
        ours = np.asarray(flow(x, [], model.p), dtype=float).ravel()
        np.testing.assert_allclose(ours, _flow(0, x), rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(model.torques(x), _torque(x), rtol=1e-10, atol=1e-9)


def test_the_controller_makes_the_outputs_a_damped_linear_system():
    # I/O linearisation: ḧ = −ω_n² h − 2ζω_n ḣ exactly along the closed loop (Isidori 1995,
    # §5.1), at random states and other gains; ḧ = H q̈ since h is linear in q.  1e-9.
    rng = np.random.default_rng(2)
    for wn, zeta in ((5.0, 1.1), (20.0, 0.7), (60.0, 2.0)):
        model = gaitopt.model("three_link_walker", omega_n=wn, zeta=zeta)
        for _ in range(3):
            x = np.r_[rng.uniform(-0.4, 0.4, 3), rng.normal(size=3)]
            qdd = np.asarray(model.phases[0].flow(x, [], model.p), dtype=float).ravel()[3:]
            h, dh = model.outputs(x)
            np.testing.assert_allclose(
                H @ qdd, -(wn**2) * h - 2 * zeta * wn * dh, atol=1e-9 * wn**2
            )


# -- the gait -------------------------------------------------------------------------------------


def test_the_gait_step_time_and_multipliers(gait):
    # Computed here (module docstring: the 2.2583406929 s / 0.5512805 are not
    # reproduced); step time 1e-8 s, dominant multiplier 1e-6, the slow transverse pair 1e-8
    # (modulus ~1.7e-3), the two fast ones below 1e-7 (~exp(λ_fast T) = 4.5e-8 and rounding).
    assert gait.period == pytest.approx(STEP_TIME, abs=1e-8)
    mu = gait.multipliers[np.argsort(-np.abs(gait.multipliers))]
    assert mu[0].real == pytest.approx(DOMINANT, abs=1e-6) and mu[0].imag == 0
    pair = sorted(mu[1:3], key=lambda z: -z.imag)
    assert pair[0] == pytest.approx(PAIR, abs=1e-8)
    assert pair[1] == pytest.approx(PAIR.conjugate(), abs=1e-8)
    assert np.all(np.abs(mu[3:]) < 1e-7)
    assert gait.stable and gait.verified


def test_the_referee_returns_to_the_fixed_point_in_the_step_time(gait):
    # Independent simulation (the NumPy referee, DOP853 at rtol 1e-12, its own event location
    # and impact): one step from the fixed point returns to it, 1e-9; same step time, 1e-9 s.
    x_plus, t, _ = _step(gait.x)
    np.testing.assert_allclose(x_plus, gait.x, atol=1e-9)
    assert t == pytest.approx(gait.period, abs=1e-9)


def test_the_referee_s_multipliers(gait):
    # The referee's own fixed point (fsolve) and central differences of its map (h = 1e-6):
    # the dominant multiplier to 1e-6, the pair to 1e-6 (FD error ~h² + 1e-12/h).
    idx = [0, 2, 3, 4, 5]

    def P(s):
        return _step(np.r_[s[0], math.pi / 8, s[1:]])[0][idx]

    s = fsolve(lambda s: P(s) - s, gait.section_point, xtol=1e-13)
    np.testing.assert_allclose(s, gait.section_point, atol=1e-9)
    J = np.column_stack([(P(s + e) - P(s - e)) / 2e-6 for e in 1e-6 * np.eye(5)])
    mu = np.linalg.eigvals(J)
    mu = mu[np.argsort(-np.abs(mu))]
    assert mu[0].real == pytest.approx(DOMINANT, abs=1e-6)
    assert abs(mu[1]) == pytest.approx(abs(PAIR), abs=1e-6)


def test_the_torques_and_the_ground_reaction_along_the_gait(gait):
    # max |u| on the gait (N·m, computed here; the shooting's samples and an independent
    # simulation with 400 samples agree to 1e-6); the stance foot pushes throughout (N ≥ 240 N,
    # the declared constraint), and the decoupling matrix stays invertible.
    model = gait.model
    peak = model.max_torque(gait)
    assert peak == pytest.approx(61.1654, abs=1e-3)
    sim = gaitopt.simulate(model, gait.x, steps=gait.steps)
    resampled = [arc.sample(400)[1] for arc in sim.arcs]
    assert model.max_torque(gait, resampled) == pytest.approx(peak, abs=1e-6)
    _, X = sim.arcs[0].sample(400)
    push = model.phases[0].constraints[0].function
    assert min(float(push(X[:, j], [], model.p)) for j in range(X.shape[1])) > 239.9
    det = model._function("decoupling")
    assert min(abs(float(det(X[:, j], model.p))) for j in range(X.shape[1])) > 0.45


# -- the impact -----------------------------------------------------------------------------------


def _momenta(x, foot):
    """Closed form (point masses of the issue's model): the whole walker's angular momentum
    about ``foot``, the stance leg's about the hip, the torso's about the hip (kg·m²/s), for
    the state ``x`` in the labels it is given in, positions relative to its stance foot."""
    t1, t2, t3, d1, d2, d3 = x
    e = lambda a: np.array([math.sin(a), math.cos(a)])  # noqa: E731
    de = lambda a, w: w * np.array([math.cos(a), -math.sin(a)])  # noqa: E731
    r_hip, v_hip = R * e(t1), R * de(t1, d1)
    bodies = {
        "stance": (M_LEG, R / 2 * e(t1), R / 2 * de(t1, d1)),
        "hip": (M_HIP, r_hip, v_hip),
        "torso": (M_TORSO, r_hip + L_TORSO * e(t3), v_hip + L_TORSO * de(t3, d3)),
        "swing": (M_LEG, r_hip - R / 2 * e(t2), v_hip - R / 2 * de(t2, d2)),
    }

    def about(point, names):
        return sum(
            m * ((r[0] - point[0]) * v[1] - (r[1] - point[1]) * v[0])
            for n, (m, r, v) in bodies.items()
            if n in names
        )

    whole = about(foot, bodies)
    return whole, about(r_hip, ["stance"]), about(r_hip, ["torso"]), about(r_hip, ["swing"])


def test_the_impact_conserves_the_three_angular_momenta(gait):
    # Closed form: the impulse acts at the swing foot and the torques are not impulsive, so the
    # angular momentum of the whole walker about the striking foot, of the old stance leg about
    # the hip and of the torso about the hip are conserved (Grizzle et al. 2001, §III); after
    # the swap the old stance leg is the new swing leg.  At the gait's impact and at random
    # pre-impact states; 1e-12 relative.
    model = gait.model
    reset = model.phases[0].transitions[0].reset
    x_minus = _step(gait.x)[2]
    rng = np.random.default_rng(3)
    states = [x_minus] + [
        np.r_[math.pi / 8, rng.uniform(-0.5, 0.0), rng.uniform(0, 0.5), rng.normal(size=3)]
        for _ in range(4)
    ]
    for x in states:
        x_plus = np.asarray(reset(x, [], model.p), dtype=float).ravel()
        foot = R * np.array([math.sin(x[0]) - math.sin(x[1]), math.cos(x[0]) - math.cos(x[1])])
        whole, stance, torso, _ = _momenta(x, foot)
        whole_a, _, torso_a, swing_a = _momenta(x_plus, np.zeros(2))
        scale = 1 + abs(whole)
        assert whole_a == pytest.approx(whole, abs=1e-12 * scale)
        assert swing_a == pytest.approx(stance, abs=1e-12 * scale)
        assert torso_a == pytest.approx(torso, abs=1e-12 * scale)
        # The referee's KKT solution of the extended model gives the same state, 1e-12.
        np.testing.assert_allclose(x_plus, _impact(x)[0], atol=1e-12 * scale)


def test_the_impact_is_valid_on_the_gait(gait):
    # Validity of the single-impact model (Grizzle et al. 2001, §III): the ground pushes on the
    # striking foot (vertical impulse > 0) and the old stance foot leaves the ground (upward
    # velocity just after); values from the referee's extended model, computed here.
    _, impulse, stance_velocity = _impact(_step(gait.x)[2])
    assert impulse[1] > 0
    assert stance_velocity[1] > 0


def test_the_virtual_constraints_are_not_hybrid_invariant(gait):
    # The impact throws the state off the constraint surface: just after it (the fixed point)
    # h = (3.4499e-4, 1.1191e-4) rad and L_f h = (1.655974, 0.537163) rad/s — the torso and the
    # legs' rates jump — while just before it L_f h is ~1e-3 rad/s.  Values computed here,
    # 1e-7 rad / 1e-6 rad/s; h is continuous (the swap leaves θ1 + θ2 and θ3 unchanged).
    model = gait.model
    h_plus, dh_plus = model.outputs(gait.x)
    np.testing.assert_allclose(h_plus, H_PLUS, atol=1e-7)
    np.testing.assert_allclose(dh_plus, DH_PLUS, atol=1e-6)
    h_minus, dh_minus = model.outputs(_step(gait.x)[2])
    np.testing.assert_allclose(h_minus, h_plus, atol=1e-9)
    assert np.max(np.abs(dh_minus)) < 2e-3 < np.min(np.abs(dh_plus))


# -- energy -------------------------------------------------------------------------------------


def test_the_work_of_the_torques_is_the_change_of_energy(gait):
    # Power balance of the closed loop: dE/dt = q̇ᵀ B u (the torques are the only
    # non-conservative forces).  E and W = ∫ q̇ᵀ B u dt along one step, integrated with the
    # model's flow (DOP853, rtol 1e-13): E(t) − E(0) = W(t) at every sample, 1e-9 J.
    model = gait.model
    flow = model.phases[0].flow

    def rhs(t, y):
        del t
        dx = np.asarray(flow(y[:6], [], model.p), dtype=float).ravel()
        return np.r_[dx, model.power(y[:6])]

    t_end = gait.period
    sol = solve_ivp(rhs, (0, t_end), np.r_[gait.x, 0.0], method="DOP853", rtol=1e-13,
                    atol=1e-13, dense_output=True)  # fmt: skip
    e0 = model.energy(gait.x)
    for t in np.linspace(0, t_end, 25):
        y = sol.sol(t)
        assert model.energy(y[:6]) - e0 == pytest.approx(y[6], abs=1e-9)
    assert abs(sol.y[6, -1]) > 1.0  # the torques do work (J): the balance is not trivial


# -- bad input ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["omega_n", "zeta"])
@pytest.mark.parametrize("value", [0.0, -1.0])
def test_non_positive_gains_are_refused_in_one_line(name, value):
    with pytest.raises(ParameterError, match=name) as info:
        gaitopt.model("three_link_walker", **{name: value})
    assert "\n" not in str(info.value)


def test_the_gait_depends_on_the_gains():
    # Stiffer output dynamics shorten the step and shrink the transverse multipliers (the
    # study problems/three_link_walker_gains.py follows ω_n to 100): at ω_n = 6 the step time is
    # 1.8776871 s and the dominant multiplier 0.5755808 (computed here, cross-checked by the
    # referee's fsolve during development), 1e-6.
    cycle = gaitopt.find_limit_cycle(gaitopt.model("three_link_walker", omega_n=6.0))
    assert cycle.success, cycle.message
    assert cycle.period == pytest.approx(1.8776871, abs=1e-6)
    mu = cycle.multipliers[np.argsort(-np.abs(cycle.multipliers))]
    assert mu[0].real == pytest.approx(0.5755808, abs=1e-6)
    assert np.max(np.abs(mu[1:])) < 2e-3
