"""Kuo's (2002) push-off impulse on the simplest walker: the reset, its work, the optimal gait."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import cross

import gaitopt
from gaitopt.errors import GaitoptInputError
from gaitopt.optimize import GaitProblem, solve_problem

RNG = np.random.default_rng(11)


def _pre_impact_states(count: int = 6) -> np.ndarray:
    """States on the heel-strike guard φ = 2θ with θ < 0, θ̇ < 0 (random, seeded)."""
    theta = -RNG.uniform(0.05, 0.35, count)
    theta_dot = -RNG.uniform(0.1, 0.5, count)
    phi_dot = RNG.uniform(-0.5, 0.5, count)
    return np.column_stack([theta, 2 * theta, theta_dot, phi_dot])


@pytest.mark.parametrize("slope", [0.0, 0.009])
def test_zero_push_off_is_garcias_map(slope):
    # Source: Garcia et al. 1998 eq. (6): θ⁺ = −θ, φ⁺ = −2θ, θ̇⁺ = cos 2θ θ̇,
    # φ̇⁺ = cos 2θ (1 − cos 2θ) θ̇; and eqs. (3)–(4) for the flow at τ = 0, k = 0.  Exact in
    # floating point (x − 0 = x): tolerance 0.
    model = gaitopt.model("simplest_walker", slope=slope)
    phase = model.phases[0]
    reset = phase.transitions[0].reset
    for x in _pre_impact_states():
        th, ph, thd, phd = x
        c = math.cos(2 * th)
        garcia = np.array([-th, -2 * th, c * thd, c * (1 - c) * thd])
        after = np.asarray(reset(x, [0.0, 0.0], model.p), dtype=float).ravel()
        np.testing.assert_allclose(after, garcia, rtol=0, atol=1e-16)
        flow = np.asarray(phase.flow(x, [0.0, 0.0], model.p), dtype=float).ravel()
        theta_dd = math.sin(th - slope)
        phi_dd = theta_dd + math.sin(ph) * (thd**2 - math.cos(th - slope))
        np.testing.assert_allclose(flow, [thd, phd, theta_dd, phi_dd], rtol=0, atol=1e-16)


def test_push_off_reset_balances_angular_momentum_about_the_new_foot():
    # Source: impulse–momentum about the new stance foot (its heel-strike impulse has no
    # moment there): H⁺ = H⁻ + r × (P ê), r the hip relative to the new foot, ê the trailing
    # leg's unit vector (foot to hip).  Hip mass M = 1; tolerance 1e-14 (rounding).
    model = gaitopt.model("simplest_walker", slope=0.0)
    phase = model.phases[0]
    reset = phase.transitions[0].reset
    names = phase.point_names
    for x in _pre_impact_states():
        for push in (0.0, 0.03, 0.1):
            _, r_hip, v_hip = (np.asarray(v, dtype=float) for v in phase.bodies(x, model.p))
            r_hip, v_hip = r_hip[:, 0], v_hip[:, 0]
            points = np.asarray(phase.points(x, model.p), dtype=float)
            new_foot = points[:, names.index("swing_foot")]
            e = r_hip / np.linalg.norm(r_hip)
            before = cross(r_hip - new_foot, v_hip + push * e)
            x_plus = np.asarray(reset(x, [0.0, push], model.p), dtype=float).ravel()
            _, r_plus, v_plus = (np.asarray(v, dtype=float) for v in phase.bodies(x_plus, model.p))
            np.testing.assert_allclose(r_plus[:, 0], r_hip - new_foot, atol=1e-15)
            assert cross(r_plus[:, 0], v_plus[:, 0]) == pytest.approx(before, abs=1e-14)
            # The hip's velocity after the heel strike is across the new leg (plastic impact).
            assert float(np.dot(v_plus[:, 0], r_plus[:, 0])) == pytest.approx(0.0, abs=1e-15)
            # The trailing foot (new swing foot) keeps zero velocity across its leg: the lift
            # of the section, φ̇⁺ = (1 − cos 2θ⁺) θ̇⁺ (Garcia eq. 6 with Kuo's push-off).
            th_p, thd_p = x_plus[0], x_plus[2]
            assert x_plus[3] == pytest.approx((1 - math.cos(2 * th_p)) * thd_p, abs=1e-15)


def test_push_off_work_is_the_kinetic_energy_it_adds():
    # Source: the push-off impulse P ê on the hip mass changes its kinetic energy by
    # ½|v⁻ + P ê|² − ½|v⁻|² = P²/2 (ê ⟂ v⁻): the model's impulse_work.  Tolerance 1e-15.
    model = gaitopt.model("simplest_walker", slope=0.0)
    phase = model.phases[0]
    work = model.impulse_work(0)
    for x in _pre_impact_states():
        _, r_hip, v_hip = (np.asarray(v, dtype=float)[:, 0] for v in phase.bodies(x, model.p))
        e = r_hip / np.linalg.norm(r_hip)
        push = 0.07
        gain = 0.5 * np.dot(v_hip + push * e, v_hip + push * e) - 0.5 * np.dot(v_hip, v_hip)
        assert float(work(x, [0.0, push], model.p)) == pytest.approx(gain, abs=1e-15)


def test_slope_zero_is_allowed_and_negative_slope_is_not():
    # Source: the range for Kuo's level-ground walking, [0, 0.05] rad.
    assert gaitopt.model("simplest_walker", slope=0.0).slope == 0.0
    with pytest.raises(GaitoptInputError, match="slope"):
        gaitopt.model("simplest_walker", slope=-0.01)


@pytest.fixture(scope="module")
def push_off():
    model = gaitopt.model("simplest_walker", slope=0.0)
    return gaitopt.optimize_gait(model, "work", step_length=0.4, bounds={"hip_torque": 0})


def test_optimal_push_off_is_kuos_steady_gait(push_off):
    # Source: Kuo 2002 — on level ground the steady push-off gait has θ* = α = asin(s/2) and
    # P = v tan α, v = |θ̇| at heel strike (θ̇⁺ = θ̇⁻ by symmetry), work P²/2.  Tolerance 1e-9
    # (discretisation error target 1e-8 on the cost; the relations hold at every mesh to ~1e-12).
    gait = push_off
    assert gait.success and gait.verified, gait.message
    alpha = math.asin(0.2)
    assert gait.fixed_point["theta"] == pytest.approx(alpha, abs=1e-9)
    v = abs(gait.fixed_point["theta_dot"])
    push = gait.inputs["push_off"][-1]
    assert push == pytest.approx(v * math.tan(alpha), rel=1e-9)
    assert gait.cost == pytest.approx(0.5 * push**2, rel=1e-12)
    # Independent simulation: the work the simulated heel strikes receive (tolerance 1e-6, the
    # verification's own).
    assert gait.verification["cost_simulated"] == pytest.approx(gait.cost, rel=1e-6)
    assert gait.discretisation_error <= 1e-8
    # The heel-strike impulse still presses the new leg into the ground (model docstring).
    x_minus = np.array([-alpha, -2 * alpha, -v, 0.0])
    assert gait.model.heel_strike_impulse(x_minus, push) > 0


def test_hip_torque_costs_more_than_push_off_at_the_same_gait(push_off):
    # Source: Kuo 2002 (pre-emptive push-off is the cheaper powering; ratio → 4 cos⁴α from above
    # as the torque bound grows, problems/optimal_kuo_pushoff.py): with 0 ≤ τ ≤ 0.02 M·g·l at the
    # push-off gait's step length and 90 % of its period (hip spring free in both), the hip
    # torque's least positive work exceeds the push-off's by more than the impulsive-torque
    # limit 4cos⁴α = 3.686.  Both verified by simulation (rel. 1e-6).
    model = gaitopt.model("simplest_walker", slope=0.0)
    push = gaitopt.optimize_gait(
        model, "work", step_length=0.4, period=0.9 * push_off.period,
        bounds={"hip_torque": 0}, free="hip_stiffness", guess=push_off,
    )  # fmt: skip
    assert push.success and push.verified, push.message
    problem = GaitProblem(
        model, "work", step_length=0.4, period=push.period,
        bounds={"hip_torque": (0.0, 0.02), "push_off": 0}, free=("hip_stiffness",),
    )  # fmt: skip
    hip = solve_problem(problem, guess=push)
    assert hip.success and hip.verified, hip.message
    alpha = math.asin(0.2)
    assert hip.cost / push.cost > 4 * math.cos(alpha) ** 4
    assert np.max(np.abs(hip.inputs["push_off"])) <= 1e-15  # switched off (profile rounding)
    assert min(hip.inputs["hip_torque"]) >= -1e-9


def test_push_off_gait_from_the_cli_is_the_python_one(push_off, capsys):
    # `--bound hip_torque=0` switches the hip torque off from the command line (the push-off's
    # declared 0 ≤ P stays): the same statement as the fixture's, so the same optimum (1e-12).
    from gaitopt.cli import main

    argv = ["optimize", "simplest_walker", "--set", "slope=0", "--cost", "work"]
    status = main([*argv, "--fix", "step_length=0.4", "--bound", "hip_torque=0", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert status == 0 and report["success"], report["message"]
    assert report["cost"] == pytest.approx(push_off.cost, rel=1e-12)
    assert max(abs(u) for u in report["inputs"]["hip_torque"]) == 0.0
    # A range LOW:HIGH is accepted; a negative bound, LOW > HIGH or text is bad input (exit 2).
    for bad in ("hip_torque=-1", "hip_torque=0.2:0.1", "hip_torque=a:1", "push=1"):
        assert main([*argv, "--fix", "step_length=0.4", "--bound", bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--bound" in err
