"""The reference numbers of docs/design.md, each with its source and tolerance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

import gaitopt
from gaitopt.returnmap import fixed_points_1d, return_map

# The discretisation-error estimate is ≤ 1e-10 by default, so 1e-9 is a safe test tolerance for
# anything published with more digits than that.
TOL = 1e-9


def test_every_default_gait_is_found_and_verified(cycles):
    for name, cycle in cycles.items():
        assert cycle.success, (name, cycle.message)
        assert cycle.verified, name
        assert cycle.residual <= 1e-10, name
        assert cycle.discretisation_error <= 1e-10, name


def test_vanderpol_period_and_amplitude(cycles):
    # Source: Hairer, Nørsett & Wanner, Solving ODEs I (μ = 1): T = 6.6632868593231301897,
    # max q = 2.00861986087484.  Tolerance 1e-9 (discretisation error estimate ≤ 1e-10).
    cycle = cycles["vanderpol"]
    assert cycle.period == pytest.approx(6.6632868593231301897, abs=TOL)
    model = cycle.model
    sim = gaitopt.simulate(model, cycle.x, steps=1)
    arc = sim.arcs[0]
    t_grid, x_grid = arc.sample(400)
    j = int(np.argmax(x_grid[0]))
    peak = minimize_scalar(
        lambda t: -arc.solution(t)[0],
        bounds=(t_grid[j - 1], t_grid[j + 1]),
        method="bounded",
        options={"xatol": 1e-12},
    )
    assert -peak.fun == pytest.approx(2.00861986087484, abs=TOL)


def test_vanderpol_multiplier_is_liouville(cycles):
    # Source: Liouville's formula — the nontrivial multiplier of a planar orbit is
    # exp(∮ div f dt) = exp(∮ μ (1 − q²) dt), integrated here on the independent simulation.
    # Tolerance 1e-8 relative: quadrature of the dense output at rtol 1e-11.
    cycle = cycles["vanderpol"]
    sim = gaitopt.simulate(cycle.model, cycle.x, steps=1)
    arc = sim.arcs[0]
    mu = cycle.model.mu
    integral, _ = quad(
        lambda t: mu * (1 - arc.solution(t)[0] ** 2),
        arc.t0,
        arc.t1,
        limit=400,
        epsabs=1e-13,
        epsrel=1e-13,
    )
    assert len(cycle.multipliers) == 1
    assert cycle.multipliers[0].real == pytest.approx(math.exp(integral), rel=1e-8)
    assert abs(cycle.multipliers[0].imag) < 1e-12


def test_rimless_wheel_closed_form_fixed_point_and_slope(cycles):
    # Source: Tedrake, Underactuated Robotics, rimless wheel: ω* = cot 2α sqrt(4 g/l sin α sin γ)
    # = 1.095462839648 rad/s at the defaults; map slope cos² 2α (= 0.5 for 8 spokes).
    cycle = cycles["rimless_wheel"]
    model = cycle.model
    assert model.rolling_speed() == pytest.approx(1.095462839648, abs=1e-12)
    assert cycle.fixed_point["theta_dot"] == pytest.approx(model.rolling_speed(), abs=TOL)
    assert cycle.fixed_point["theta"] == pytest.approx(
        model.slope - math.pi / model.spokes, abs=1e-14
    )
    assert cycle.multipliers[0].real == pytest.approx(math.cos(2 * model.alpha) ** 2, abs=TOL)
    assert cycle.stable


@pytest.mark.parametrize("theta_dot", [1.0, 1.3, 2.0, 3.5])
def test_rimless_wheel_numeric_map_matches_closed_form(theta_dot):
    # Source: the closed-form map ω⁺ₙ₊₁ = cos 2α sqrt(ω⁺ₙ² + 4 g/l sin α sin γ) (energy through the
    # swing, angular momentum through the impact).  Tolerance 1e-9: simulation at rtol 1e-11.
    model = gaitopt.model("rimless_wheel")
    assert return_map(model, [theta_dot])[0] == pytest.approx(
        model.closed_form_map(theta_dot), abs=1e-9
    )


@pytest.mark.parametrize("fraction", [0.3, 0.9])
def test_rimless_wheel_rocks_back_below_the_vaulting_rate(fraction):
    # Source: below ω₁ = sqrt(2 g/l (1 − cos(γ − α))) the hub cannot vault (Tedrake); it rocks
    # back, the uphill spoke strikes (θ̇ → −cos 2α ω: one step of the chapter's map, which
    # counts every impact), and it swings back onto the downhill spoke (θ̇ → cos² 2α ω): energy
    # through the swings, angular momentum through the two impacts.
    model = gaitopt.model("rimless_wheel")
    omega = fraction * model.vaulting_speed()
    sim = gaitopt.simulate(model, {"theta_dot": omega}, steps=2)
    assert [e.transition for e in sim.events] == ["backward step", "forward step"]
    # Each impact's simulated post-impact rate against the closed-form map (1e-9: rtol 1e-11).
    rate = model.state_names.index("theta_dot")
    back, forward = (event.state_after[rate] for event in sim.events)
    assert back == pytest.approx(model.closed_form_map(omega), abs=1e-9)
    assert forward == pytest.approx(model.closed_form_map(back), abs=1e-9)
    expected = math.cos(2 * model.alpha) ** 2 * omega
    assert return_map(model, [omega], steps=2)[0] == pytest.approx(expected, abs=1e-9)


def test_rimless_wheel_one_d_fixed_points():
    # The 1-D fixed-point finder on [ω₁, 3] finds exactly the closed-form rolling point, stable.
    model = gaitopt.model("rimless_wheel")
    found = fixed_points_1d(model, (model.vaulting_speed() * 1.001, 3.0), samples=15)
    assert len(found.cycles) == 1
    assert found.points[0] == pytest.approx(model.rolling_speed(), abs=TOL)
    assert found.cycles[0].stable


@pytest.mark.parametrize("slope", [0.03, 0.05])
def test_rimless_wheel_no_rolling_below_existence(slope):
    # Source: rolling exists only where ω* > ω₁ (Tedrake); at slopes 0.03 and 0.05 it does not
    # (ω* = 0.67 and 0.87 rad/s < ω₁ = 1.13 and 1.05 rad/s).  The search must say so.
    model = gaitopt.model("rimless_wheel", slope=slope)
    assert model.rolling_speed() < model.vaulting_speed()
    cycle = gaitopt.find_limit_cycle(model)
    assert not cycle.success
    assert cycle.stable is None and cycle.multipliers.size == 0
    assert "rolling needs" in cycle.message


def test_rimless_wheel_rolls_just_above_existence():
    # Existence boundary in closed form: ω*(γ) = ω₁(γ); just above it the gait is found.
    from scipy.optimize import brentq

    def gap(slope: float) -> float:
        m = gaitopt.model("rimless_wheel", slope=slope)
        return m.rolling_speed() - m.vaulting_speed()

    boundary = brentq(gap, 0.01, 0.3, xtol=1e-14)
    model = gaitopt.model("rimless_wheel", slope=boundary + 0.005)
    cycle = gaitopt.find_limit_cycle(model)
    assert cycle.success, cycle.message
    assert cycle.fixed_point["theta_dot"] == pytest.approx(model.rolling_speed(), abs=TOL)


def test_compass_gait_matches_drake(cycles):
    # Source: docs/design.md — step period 0.7344606 s, post-impact state
    # [−0.2187746, 0.3237746, 1.0928668, 0.3761346], which agrees with Drake's CompassGait
    # simulated to convergence.  Given to 7 decimals: tolerance 5e-8.
    cycle = cycles["compass_gait"]
    assert cycle.period == pytest.approx(0.7344606, abs=5e-8)
    expected = [-0.2187746, 0.3237746, 1.0928668, 0.3761346]
    np.testing.assert_allclose(cycle.x, expected, atol=5e-8)
    assert cycle.stable and cycle.steps == 1
    assert len(cycle.multipliers) == 3  # 4 states on a 3-D post-impact section


def test_simplest_walker_long_step_gait_is_stable(cycles):
    # Source: Garcia, Chatterjee, Ruina & Coleman 1998, γ = 0.009: stable long-step gait
    # θ* = 0.20031090049483, θ̇* = −0.19983247291764.  Tolerance 1e-9.
    cycle = cycles["simplest_walker"]
    assert cycle.fixed_point["theta"] == pytest.approx(0.20031090049483, abs=TOL)
    assert cycle.fixed_point["theta_dot"] == pytest.approx(-0.19983247291764, abs=TOL)
    assert cycle.stable
    assert len(cycle.multipliers) == 2


def test_simplest_walker_short_step_gait_is_unstable():
    # Source: Garcia et al. 1998, γ = 0.009: unstable short-step gait θ* = 0.19393736960624,
    # θ̇* = −0.20386692731962.  Tolerance 1e-9.
    model = gaitopt.model("simplest_walker")
    cycle = gaitopt.find_limit_cycle(
        model, {"theta": 0.19393736960624, "theta_dot": -0.20386692731962}
    )
    assert cycle.success, cycle.message
    assert cycle.fixed_point["theta"] == pytest.approx(0.19393736960624, abs=TOL)
    assert cycle.fixed_point["theta_dot"] == pytest.approx(-0.20386692731962, abs=TOL)
    assert cycle.stable is False
    assert np.max(np.abs(cycle.multipliers)) > 1


def test_period_two_gait_past_period_doubling():
    # At slope 0.09 the compass gait's period-1 gait has a multiplier below −1 (past its period
    # doubling; Goswami et al. 1996 report the cascade); a period-2 search finds a genuine
    # period-2 orbit (its two steps differ), verified by simulation over both steps.
    model = gaitopt.model("compass_gait", slope=0.09)
    period1 = gaitopt.find_limit_cycle(model)
    assert period1.success and np.min(period1.multipliers.real) < -1
    period2 = gaitopt.find_limit_cycle(model, steps=2)
    assert period2.success and period2.verified and period2.steps == 2
    sim = gaitopt.simulate(model, period2.x, steps=2)
    first, second = sim.section_states[1], sim.section_states[2]
    assert np.max(np.abs(first - period2.x)) > 1e-3  # not the period-1 gait repeated
    np.testing.assert_allclose(second, period2.x, atol=1e-8)
    assert period2.period == pytest.approx(sim.section_times[2], abs=1e-9)


def test_period_two_search_refuses_the_period_one_gait_repeated():
    # At the default slope there is no period-2 gait; the search must not report the period-1
    # gait twice as one.
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"), steps=2)
    assert not cycle.success
    assert "period-1 gait repeated" in cycle.message


def test_ipopt_method_agrees_with_newton(cycles):
    # Two solvers on the same equations must agree to the solver tolerance.
    model = gaitopt.model("compass_gait")
    cycle = gaitopt.find_limit_cycle(model, method="ipopt")
    assert cycle.success, cycle.message
    np.testing.assert_allclose(cycle.x, cycles["compass_gait"].x, atol=1e-10)


def test_warm_start_from_a_previous_orbit_after_a_parameter_change(cycles):
    # A previous orbit seeds the nodes (no simulation); the result must equal a cold solve at
    # the new parameters to the solver tolerance.
    model = cycles["compass_gait"].model.replace(slope=0.056)
    warm = gaitopt.find_limit_cycle(model, cycles["compass_gait"])
    cold = gaitopt.find_limit_cycle(model)
    assert warm.success and cold.success
    np.testing.assert_allclose(warm.x, cold.x, atol=1e-10)
    assert warm.period == pytest.approx(cold.period, abs=1e-10)


def test_simulation_sees_an_impact_within_one_integrator_step():
    # Regression: near slope π/spokes a slow rocking start strikes the uphill spoke and swings
    # back onto the downhill one within milliseconds — inside one adaptive step.  The rocking
    # branch of the closed-form map (cos² 2α · ω, Tedrake's energy and momentum arguments) must
    # still come out.
    model = gaitopt.model("rimless_wheel", slope=0.3)
    sim = gaitopt.simulate(model, {"theta_dot": 0.029}, steps=2)
    assert [e.transition for e in sim.events] == ["backward step", "forward step"]
    # tolerance 1e-9: simulation at rtol 1e-11, as for the other simulated maps
    two_impacts = model.closed_form_map(model.closed_form_map(0.029))
    assert sim.section_states[-1][1] == pytest.approx(two_impacts, abs=1e-9)
