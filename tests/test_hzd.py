"""Bézier virtual constraints, hybrid invariance and the restricted Poincaré map (issue 20).

Sources of the numbers:

* Bézier end values and derivatives: Westervelt et al. 2007, eqs (6.16)–(6.17) (closed form);
* the closed loop with the three-link walker's fixed constraints written as Bézier polynomials
  (exact: θ2 = −θ1 is linear in s) against the hand-written fixed-constraint model
  (``gaitopt.models.three_link_walker``, itself checked against a NumPy referee): step time
  2.1677530383 s, dominant multiplier 0.6713863 (independent implementations agree);
* invariance: y⁺ = ẏ⁺ = 0 (Westervelt et al. 2007, Thm 5.5, eqs (6.37));
* the restricted map against the full-order closed loop: the HZD step time ∫ I/√(2ζ) dθ against
  the shooting's period, the slope δ² against a Floquet multiplier (an invariant surface's
  restriction dynamics are the full map's, WGK 2003, Thm 4), the other multipliers → 0 as ω_n
  grows; δ_zero against the conservation of angular momentum about the striking foot (closed
  form, point masses).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import gaitopt
from gaitopt.errors import GaitoptInputError, ParameterError
from gaitopt.hzd import bezier, bezier_derivative, virtual_constraint_model
from gaitopt.hzd.gait import hzd_gait
from gaitopt.hzd.invariance import invariance_residual, make_invariant, pre_impact_state
from gaitopt.hzd.zero_dynamics import annihilator, restricted_map


@pytest.fixture(scope="module")
def plant():
    return gaitopt.model("three_link_walker")


@pytest.fixture(scope="module")
def loop(plant):
    return virtual_constraint_model(plant, 4)


@pytest.fixture(scope="module")
def invariant_gait(plant):
    gait = hzd_gait(plant, 4, omega_n=20.0)
    assert gait.success, gait.message
    return gait


def test_bezier_end_values_and_derivatives():
    # Closed form (Westervelt et al. 2007, eq. (6.17)): b(0) = α0, b(1) = αM,
    # b'(0) = M (α1 − α0), b'(1) = M (αM − αM−1); the derivative against central differences
    # (h = 1e-6, error ~1e-11), 1e-12 / 1e-8.
    rng = np.random.default_rng(0)
    alpha = rng.normal(size=6)
    M = 5
    assert bezier(alpha, 0.0) == pytest.approx(alpha[0], abs=1e-12)
    assert bezier(alpha, 1.0) == pytest.approx(alpha[-1], abs=1e-12)
    assert bezier_derivative(alpha, 0.0) == pytest.approx(M * (alpha[1] - alpha[0]), abs=1e-12)
    assert bezier_derivative(alpha, 1.0) == pytest.approx(M * (alpha[5] - alpha[4]), abs=1e-12)
    for s in (0.2, 0.55, 0.9):
        fd = (bezier(alpha, s + 1e-6) - bezier(alpha, s - 1e-6)) / 2e-6
        assert bezier_derivative(alpha, s) == pytest.approx(fd, abs=1e-8)


def test_fixed_constraints_as_bezier_reproduce_the_hand_written_closed_loop(loop):
    # The default coefficients are the fixed constraints exactly; the closed loop built by
    # gaitopt.hzd (generic Jacobians of y by AD) and the hand-written model (H = const) give the
    # same gait: 2.1677530383 s to 1e-8, 0.6713863 to 1e-6 (tests/test_three_link_walker.py).
    cycle = gaitopt.find_limit_cycle(loop())
    assert cycle.success, cycle.message
    assert cycle.period == pytest.approx(2.1677530383, abs=1e-8)
    mu = cycle.multipliers[np.argsort(-np.abs(cycle.multipliers))]
    assert mu[0].real == pytest.approx(0.6713863, abs=1e-6)


def test_io_linearisation_makes_the_outputs_linear(loop):
    # ÿ = −K_p y − K_d ẏ along the flow (Isidori 1995, §5.1): ÿ by central differences of ẏ
    # along the flow (h = 1e-5: error ~1e-9 · |y'''|), at random states and coefficients, 1e-5.
    rng = np.random.default_rng(4)
    model = loop().replace(omega_n=7.0, zeta=0.8, alpha_torso_2=0.5, alpha_swing_1=0.1)
    flow = model.phases[0].flow
    for _ in range(3):
        x = np.r_[rng.uniform(-0.3, 0.3, 3), rng.normal(size=3)]
        f = np.asarray(flow(x, [], model.p), dtype=float).ravel()
        y, dy = model.outputs(x)
        ddy = (model.outputs(x + 1e-5 * f)[1] - model.outputs(x - 1e-5 * f)[1]) / 2e-5
        np.testing.assert_allclose(ddy, -49.0 * y - 2 * 0.8 * 7.0 * dy, atol=1e-5)


def test_make_invariant_zeroes_the_outputs_after_the_impact(loop):
    # Westervelt et al. 2007, eqs (6.37): after make_invariant, y⁺ = 0 and ẏ⁺ = 0 for any
    # pre-impact rate θ̇⁻ (the construction is linear in it), 1e-10; before, they are not.
    model = loop()
    assert invariance_residual(model) > 0.1
    inv = make_invariant(model)
    for rate in (0.5, 1.0, 3.0):
        assert invariance_residual(inv, rate) < 1e-10
    # α0, θ±: the relabelled end of the step (swing α0 = θ⁻ = impact angle, θ⁺ = swing αM).
    assert inv.theta_minus == pytest.approx(math.pi / 8, abs=1e-12)
    assert inv.alpha["swing"][0] == pytest.approx(math.pi / 8, abs=1e-12)
    assert inv.theta_plus == pytest.approx(inv.alpha["swing"][-1], abs=1e-12)


def test_zero_dynamics_quantities_in_closed_form(loop):
    # B⊥ = (1, 1, 1) for B = [[−1, 0], [0, −1], [1, 1]]; σ = B⊥ D q̇ is then the angular
    # momentum about the stance foot, whose rate is gravity's torque only: κ3 ≡ 0 (E = 1).
    # δ_zero = σ⁺/σ⁻: the impact conserves the angular momentum about the striking foot, so σ⁺ =
    # the pre-impact momentum about the swing foot (point masses, closed form), 1e-10.
    model = make_invariant(loop())
    np.testing.assert_allclose(annihilator(model), [1.0, 1.0, 1.0], atol=1e-12)
    rm = restricted_map(model)
    assert rm.kappa3_max < 1e-10 and rm.gain == pytest.approx(1.0, abs=1e-10)
    _, x = pre_impact_state(model)
    t1, t2, t3, d1, d2, d3 = x

    def e(a):
        return np.array([math.sin(a), math.cos(a)])

    def de(a, w):
        return w * np.array([math.cos(a), -math.sin(a)])

    hip, vhip = e(t1), de(t1, d1)
    bodies = [(5.0, e(t1) / 2, de(t1, d1) / 2), (15.0, hip, vhip),
              (10.0, hip + 0.5 * e(t3), vhip + 0.5 * de(t3, d3)),
              (5.0, hip - e(t2) / 2, vhip - de(t2, d2) / 2)]  # fmt: skip

    def momentum(p):
        return sum(m * ((r[0] - p[0]) * v[1] - (r[1] - p[1]) * v[0]) for m, r, v in bodies)

    foot = hip - e(t2)
    assert rm.delta == pytest.approx(momentum(foot) / momentum(np.zeros(2)), abs=1e-10)


def test_restricted_map_against_the_full_order_closed_loop(invariant_gait):
    # An invariant surface carries the gait: the HZD step time ∫ I/√(2ζ) dθ (quadrature) equals
    # the shooting's period, 1e-8 s; one Floquet multiplier equals the slope δ², 1e-7; at
    # ω_n = 20 the others are below 1e-8 (|exp(λ_slow T)| = 4.7e-6 bounds the slow pair's
    # decay; computed 5.3e-10); the outputs vanish on the whole orbit, 1e-9 rad; the verification
    # simulation agrees (cycle.verified).
    g = invariant_gait
    rm, cycle = g.rmap, g.cycle
    assert g.invariance_residual < 1e-10
    assert cycle.period == pytest.approx(rm.step_time, abs=1e-8)
    mu = cycle.multipliers[np.argsort(-np.abs(cycle.multipliers))]
    assert mu[0].real == pytest.approx(rm.slope, abs=1e-7)
    assert np.max(np.abs(mu[1:])) < 1e-8
    for arc in cycle.orbit:
        for k in range(0, arc.x.shape[1], 5):
            y, _ = g.model.outputs(arc.x[:, k])
            assert np.max(np.abs(y)) < 1e-9
    assert cycle.verified and g.max_torque > 0


def test_the_torque_bound_is_enforced(plant, invariant_gait):
    # The same gait (max |u| = 112.9 N·m, computed) with a bound below it is no gait.
    low = hzd_gait(plant, 4, omega_n=20.0, torque_limit=0.5 * invariant_gait.max_torque)
    assert not low.success and "above the bound" in low.message


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"degree": 0}, "degree"),
        ({"degree": 40}, "degree"),
        ({"degree": 2}, "degree"),  # too low for invariance
        ({"omega_n": 0.0}, "omega_n"),
        ({"zeta": -1.0}, "zeta"),
        ({"phase_variable": {"foo": 1.0}}, "phase_variable"),
        ({"phase_variable": {"torso": 1.0}}, "phase_variable"),  # not monotonic
    ],
)
def test_bad_input_names_the_argument(plant, kwargs, name):
    with pytest.raises(GaitoptInputError, match=f"^{name}") as info:
        hzd_gait(plant, **{"degree": 4, **kwargs})
    assert "\n" not in str(info.value)


def test_an_unactuated_model_is_refused():
    with pytest.raises(GaitoptInputError, match="^model: 'compass_gait'"):
        virtual_constraint_model(gaitopt.model("compass_gait"), 4)
    with pytest.raises(ParameterError, match="omega_n"):
        virtual_constraint_model(gaitopt.model("three_link_walker"), 4)(omega_n=-1.0)


def _cli(*args):
    code = "import sys; from gaitopt.cli import main; sys.exit(main())"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True)


def test_cli_json_and_bad_input():
    # The JSON's new keys; a bad degree is one line naming --degree, exit 2.
    run = _cli("solve", "three_link_walker", "--controller", "hzd", "--omega-n", "20", "--json")
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out["controller"]["kind"] == "hzd" and out["controller"]["degree"] == 4
    assert out["controller"]["gains"]["Kp"] == 400.0
    assert set(out["bezier"]) == {"swing", "torso"} and len(out["bezier"]["torso"]) == 5
    assert out["restricted_map"]["slope"] == pytest.approx(out["multipliers"][0][0], abs=1e-7)
    assert out["invariance_residual"] < 1e-10 and out["max_torque"] > 0
    bad = _cli("solve", "three_link_walker", "--controller", "hzd", "--degree", "40")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--degree" in bad.stderr
    bad = _cli("solve", "compass_gait", "--controller", "hzd")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "MODEL" in bad.stderr


def test_surface_gait_by_quadrature_matches_the_full_order_gait(invariant_gait):
    # gaitopt.hzd.design.surface_gait (Simpson on 201 phases, no simulation) against the
    # certified full-order gait: step time 1e-6 s (quadrature error ~1e-7), slope = μ₁ 1e-7, max
    # |u| 1e-4 N·m (grid vs the shooting's samples), and ∫‖u‖² dt against an independent
    # DOP853 integration of the closed loop with the effort as an extra state (rtol 1e-11), to
    # the guard: 1e-6 relative.
    from scipy.integrate import solve_ivp

    from gaitopt.hzd.design import surface_gait

    g = invariant_gait
    sg = surface_gait(g.model)
    assert sg.walks
    assert sg.step_time == pytest.approx(g.cycle.period, abs=1e-6)
    assert sg.slope == pytest.approx(g.rmap.slope, abs=1e-12)
    assert sg.max_torque == pytest.approx(g.max_torque, abs=1e-4)
    m, phase = g.model, g.model.phases[0]

    def rhs(t, y):
        dx = np.asarray(phase.flow(y[:6], [], m.p), dtype=float).ravel()
        return np.r_[dx, np.sum(m.torques(y[:6]) ** 2)]

    def hit(t, y):
        return float(phase.transitions[0].guard(y[:6], [], m.p))

    hit.terminal, hit.direction = True, 1
    sol = solve_ivp(rhs, (0, 10), np.r_[g.cycle.x, 0.0], method="DOP853", rtol=1e-11,
                    atol=1e-11, events=hit)  # fmt: skip
    assert sol.t[-1] == pytest.approx(g.cycle.period, abs=1e-8)
    assert sg.cost * sg.step_length == pytest.approx(sol.y[6, -1], rel=1e-6)


def test_the_five_link_biped_closes_the_loop_too():
    # "Any actuated model": the five-link biped (an open loop in its four torques) under degree-5
    # constraints, phase variable (q1 + q2)/2.  I/O linearisation against central differences of
    # ẏ along the flow (h = 1e-5, 1e-4 at these gains); its own constraints (swing-foot
    # clearance, stance-foot push) carry over, evaluated with the feedback torques, with the
    # closed loop's friction cone (tests/test_rabbit_hzd.py); and with no
    # gait of its own to fit, hzd_gait asks for the coefficients (one line naming alpha).
    plant = gaitopt.model("five_link_biped")
    model = virtual_constraint_model(plant, 5)(omega_n=6.0, zeta=1.0)
    assert [c.name for c in model.phases[0].constraints] == [
        "swing foot above the ground",
        "stance foot pushes on the ground",
        "stance foot does not slip forward",  # the closed loop's friction cone (μ = 0.6)
        "stance foot does not slip backward",
    ]
    flow = model.phases[0].flow
    rng = np.random.default_rng(7)
    for _ in range(3):
        x = np.r_[rng.uniform(-0.3, 0.3, 5), rng.normal(size=5)]
        f = np.asarray(flow(x, [], model.p), dtype=float).ravel()
        y, dy = model.outputs(x)
        ddy = (model.outputs(x + 1e-5 * f)[1] - model.outputs(x - 1e-5 * f)[1]) / 2e-5
        np.testing.assert_allclose(ddy, -36.0 * y - 12.0 * dy, atol=1e-4)
    with pytest.raises(GaitoptInputError, match="^alpha: five_link_biped has no gait"):
        hzd_gait(plant, 5)
