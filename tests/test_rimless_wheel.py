"""The rimless wheel complete: the chapter's three-branch return map, the γ > α form, rolling at
steep slopes, and standing still as the limit of infinitely many impacts (Zeno).

Source of every closed form: Tedrake, *Underactuated Robotics*, ch. "Simple models of walking and
running", §rimless wheel (energy through the swing, angular momentum about the new contact through
each impact).  Simulated maps run at rtol 1e-11, so 1e-9 is the tolerance on a simulated map.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import load_study
from scipy.integrate import quad

import gaitopt
from gaitopt.cli import main as cli_main
from gaitopt.returnmap import return_map
from gaitopt.simulation.zeno import accumulation as _accumulation

MAP_TOL = 1e-9  # simulated map (rtol 1e-11) vs closed form


def _g(model) -> float:
    return model.gravity / model.length


# -- the thresholds ω₁ and ω₂ -------------------------------------------------------------------
def test_thresholds_closed_forms_below_and_above_alpha():
    # Tedrake: ω₁ = sqrt(2 g/l (1 − cos(γ − α))), ω₂ = −sqrt(2 g/l (1 − cos(γ + α))) for γ < α;
    # for γ ≥ α the hub starts past the top: ω₁ = 0, ω₂ = −sqrt(4 g/l sin α sin γ).
    m = gaitopt.model("rimless_wheel")  # γ = 0.08 < α = π/8
    a, g = m.alpha, _g(m)
    assert m.vaulting_speed() == pytest.approx(math.sqrt(2 * g * (1 - math.cos(0.08 - a))), 1e-14)
    assert m.backward_vaulting_speed() == pytest.approx(
        -math.sqrt(2 * g * (1 - math.cos(0.08 + a))), rel=1e-14
    )
    steep = m.replace(slope=0.5)
    assert steep.vaulting_speed() == 0.0
    assert steep.backward_vaulting_speed() == pytest.approx(
        -math.sqrt(4 * g * math.sin(a) * math.sin(0.5)), rel=1e-14
    )


# -- each branch of the map, simulated vs closed form ---------------------------------------------
@pytest.mark.parametrize(
    ("slope", "omega", "events"),
    [
        (0.08, 2.0, ["forward step"]),  # θ̇⁺ > ω₁: vaults forward
        (0.08, 0.5, ["backward step"]),  # 0 < θ̇⁺ < ω₁: rocks back onto the uphill spoke
        (0.08, -0.5, ["forward step"]),  # ω₂ < θ̇⁺ < 0: rocks forward onto the downhill spoke
        (0.08, -2.0, ["backward step"]),  # θ̇⁺ < ω₂: vaults backward, uphill
        (0.5, 0.3, ["forward step"]),  # γ > α: every θ̇⁺ ≥ 0 vaults forward
        (0.5, -1.0, ["forward step"]),  # γ > α, ω₂ < θ̇⁺ < 0 (ω₂ = −2.68 rad/s): rocks forward
        (0.5, -3.5, ["backward step"]),  # γ > α, θ̇⁺ < ω₂: vaults backward
    ],
)
def test_every_branch_of_the_map_matches_the_closed_form(slope, omega, events):
    model = gaitopt.model("rimless_wheel", slope=slope)
    sim = gaitopt.simulate(model, {"theta_dot": omega}, steps=1)
    assert sim.success, sim.message
    assert [e.transition for e in sim.events] == events  # each step has its own impact
    expected = model.closed_form_map(omega)
    a, c = model.alpha, 4 * _g(model) * math.sin(model.alpha) * math.sin(slope)
    # The branch formulas written out again (Tedrake), to test closed_form_map itself.
    if omega > model.vaulting_speed():
        by_hand = math.cos(2 * a) * math.sqrt(omega**2 + c)
    elif omega > model.backward_vaulting_speed():
        by_hand = -math.cos(2 * a) * omega
    else:
        by_hand = -math.cos(2 * a) * math.sqrt(omega**2 - c)
    assert expected == pytest.approx(by_hand, rel=1e-15)
    assert sim.section_states[-1][1] == pytest.approx(expected, abs=MAP_TOL)
    # The section: θ = γ − α after a forward impact, γ + α after a backward one.
    theta = slope - a if events == ["forward step"] else slope + a
    assert sim.section_states[-1][0] == pytest.approx(theta, abs=1e-14)


def test_backward_vault_threshold_is_omega_2():
    # Just above ω₂ (in rate) the wheel rocks forward again; just below it vaults backward.
    model = gaitopt.model("rimless_wheel")
    w2 = model.backward_vaulting_speed()
    above = gaitopt.simulate(model, {"theta_dot": w2 * (1 - 1e-3)}, steps=1)
    below = gaitopt.simulate(model, {"theta_dot": w2 * (1 + 1e-3)}, steps=1)
    assert [e.transition for e in above.events] == ["forward step"]
    assert [e.transition for e in below.events] == ["backward step"]


# -- rolling where the wheel cannot stand (γ ≥ α) -------------------------------------------------
def test_solve_rolls_at_slope_beyond_pi_over_spokes(capsys):
    # Issue: `solve rimless_wheel --set slope=0.5` was refused ("cannot stand"); ω* = cot 2α ·
    # sqrt(4 g/l sin α sin γ) = 2.683149751122 rad/s still holds (Tedrake), multiplier cos² 2α.
    status = cli_main(["solve", "rimless_wheel", "--set", "slope=0.5", "--json"])
    result = json.loads(capsys.readouterr().out)
    assert status == 0 and result["success"] is True
    model = gaitopt.model("rimless_wheel", slope=0.5)
    a, g = model.alpha, _g(model)
    omega_star = math.sqrt(4 * g * math.sin(a) * math.sin(0.5)) / math.tan(2 * a)
    assert result["fixed_point"]["theta_dot"] == pytest.approx(omega_star, abs=MAP_TOL)
    assert model.rolling_speed() == pytest.approx(omega_star, rel=1e-15)
    real, imag = result["multipliers"][0]  # [real, imaginary]
    assert real == pytest.approx(math.cos(2 * a) ** 2, abs=1e-8) and imag == 0.0


def test_standing_is_reported_impossible_not_the_parameter_refused():
    steep = gaitopt.model("rimless_wheel", slope=0.5)  # accepted
    assert not steep.standing_exists()
    assert math.isnan(steep.standing_multiplier())
    assert "standing is impossible" in steep.standing_note()
    m = gaitopt.model("rimless_wheel")
    assert m.standing_exists()
    # Standing ω = 0 is a fixed point of the rocking branch with slope −cos 2α (Tedrake).
    assert m.closed_form_map(0.0) == 0.0
    assert m.standing_multiplier() == pytest.approx(-math.cos(2 * m.alpha), rel=1e-15)
    h = 1e-6
    slope = (m.closed_form_map(h) - m.closed_form_map(-h)) / (2 * h)
    assert slope == pytest.approx(m.standing_multiplier(), rel=1e-9)


# -- standing as the limit of infinitely frequent collisions ------------------------------------
def _rocking_time(model, omega: float) -> float:
    """Duration (s) of one rocking excursion started with post-impact rate ω, independent of the
    simulator: the quadrature of dt = dθ/θ̇ along the energy level θ̇² + 2 g/l cos θ = const out to
    the turning point and back; below |ω| = 1e-4 rad/s the constant-deceleration limit
    2|ω| / (g/l |sin θ₀|) (relative error O(ω))."""
    g, a, gamma = _g(model), model.alpha, model.slope
    theta0 = gamma - a if omega > 0 else gamma + a
    if abs(omega) < 1e-4:
        return 2 * abs(omega) / (g * abs(math.sin(theta0)))
    # θ̇ = 0 at the turning point, on θ₀'s side of the vertical (the hub does not reach the top)
    turn = math.copysign(math.acos(math.cos(theta0) + omega**2 / (2 * g)), theta0)
    span = turn - theta0

    def integrand(phi: float) -> float:
        # θ = θ₀ + span sin²φ removes the turning point's 1/sqrt singularity; θ̇² = 2 g/l (cos θ_turn
        # − cos θ) = −4 g/l sin((θ_turn + θ)/2) sin((θ_turn − θ)/2), θ_turn − θ = span cos²φ.
        th = theta0 + span * math.sin(phi) ** 2
        rate2 = -4 * g * math.sin((turn + th) / 2) * math.sin(span * math.cos(phi) ** 2 / 2)
        return 2 * span * math.sin(phi) * math.cos(phi) / math.copysign(math.sqrt(rate2), span)

    value, _ = quad(integrand, 0, math.pi / 2, epsabs=1e-13, epsrel=1e-11, limit=200)
    return 2 * value


def test_rocking_ends_standing_at_the_closed_form_accumulation_time():
    # Rocking from ω = 0.5 rad/s (< ω₁): each impact multiplies the rate by −cos 2α, each
    # excursion's duration is a closed-form quadrature; the impacts accumulate at the sum of all
    # durations (a convergent series).  The simulator must end "standing" there, not time out.
    model = gaitopt.model("rimless_wheel")
    sim = gaitopt.simulate(model, {"theta_dot": 0.5}, steps=500)
    assert sim.status == "standing" and not sim.success, sim.message
    assert "Zeno" in sim.message
    total, omega = 0.0, 0.5
    while abs(omega) > 1e-12:
        total += _rocking_time(model, omega)
        omega = model.closed_form_map(omega)
    # Tolerance 1e-3 s: the simulator extrapolates the tail from a few intervals whose ratios
    # still carry the pendulum's O(ω²) nonlinearity (about 1e-4 s here).
    assert sim.accumulation_time == pytest.approx(total, abs=1e-3)
    # The events alternate backward/forward, and every recorded impact is on the closed-form map.
    rates = [s[1] for s in sim.section_states]
    for before, after in zip(rates[:-1], rates[1:], strict=True):
        assert after == pytest.approx(model.closed_form_map(before), abs=MAP_TOL)


def test_backward_start_impacts_then_stands():
    # Issue: from θ̇ = −2 rad/s no impact was applied and the run timed out.  Now: a backward
    # vault (θ̇ < ω₂ = −1.47), then rocking, then standing.
    model = gaitopt.model("rimless_wheel")
    sim = gaitopt.simulate(model, {"theta_dot": -2.0}, steps=500)
    assert sim.events[0].transition == "backward step"
    assert sim.section_states[1][1] == pytest.approx(model.closed_form_map(-2.0), abs=MAP_TOL)
    assert sim.status == "standing", sim.message


def test_rolling_is_not_taken_for_an_accumulation():
    model = gaitopt.model("rimless_wheel")
    sim = gaitopt.simulate(model, {"theta_dot": 2.0}, steps=30)
    assert sim.status == "completed" and sim.accumulation_time is None
    assert sim.section_states[-1][1] == pytest.approx(model.rolling_speed(), abs=1e-6)


def test_accumulation_detector_on_synthetic_event_times():
    # Geometric intervals d_k = 0.3·0.6^k accumulate at t₀ + 0.3/(1 − 0.6) (geometric series).
    d = 0.3 * 0.6 ** np.arange(12)
    t = np.concatenate([[0.0], np.cumsum(d)])
    ratio, t_inf = _accumulation(list(t))
    assert ratio == pytest.approx(0.6, rel=1e-12)
    assert t_inf == pytest.approx(0.3 / 0.4, rel=1e-12)
    # Alternating contacts (two interleaved geometric sequences): detected at lag 2.
    d2 = np.array([[0.3 * 0.5**k, 0.1 * 0.5**k] for k in range(8)]).ravel()
    t2 = np.concatenate([[0.0], np.cumsum(d2)])
    ratio2, t2_inf = _accumulation(list(t2))
    assert ratio2 == pytest.approx(math.sqrt(0.5), rel=1e-12)
    assert t2_inf == pytest.approx(0.4 / 0.5, rel=1e-12)
    # Intervals converging to a period (a transient approaching a gait) are not an accumulation.
    d3 = 1.0 + 0.5 * 0.7 ** np.arange(14)
    assert _accumulation(list(np.concatenate([[0.0], np.cumsum(d3)]))) is None
    # Constant intervals are not either.
    assert _accumulation(list(np.arange(20.0))) is None


def test_return_map_is_simulated_on_every_branch():
    model = gaitopt.model("rimless_wheel")
    for omega in (-3.0, -1.0, 0.3, 1.5):
        assert return_map(model, omega)[0] == pytest.approx(
            model.closed_form_map(omega), abs=MAP_TOL
        )


def test_a_wheel_at_rest_on_two_spokes_is_standing_not_a_timeout():
    # θ̇ = 0 on the section: the hub presses onto the uphill spoke (θ̈ = g/l sin(γ − α) < 0).
    model = gaitopt.model("rimless_wheel")
    sim = gaitopt.simulate(model, {"theta_dot": 0.0}, steps=3)
    assert sim.status == "standing" and "at rest" in sim.message
    # For γ > α the same start falls forward and rolls: standing is impossible there.
    steep = gaitopt.simulate(gaitopt.model("rimless_wheel", slope=0.5), {"theta_dot": 0.0}, steps=3)
    assert steep.status == "completed"


def test_basin_study_classifications_agree_with_simulation():
    # The study's closed-form fate (energy to the first impact, Tedrake's map iterated) against
    # hybrid simulation, at starts in each kind of region of the basin figure.
    study = load_study("rimless_wheel_basin")
    model = gaitopt.model("rimless_wheel")
    # -1.42 rad/s rocks forward to above ω₁ and rolls; -2.0 vaults back and stands; 0.5 stands.
    expected = {-1.42: study.ROLLING, -2.0: study.STANDING, 0.5: study.STANDING, 2.0: study.ROLLING}
    for omega, fate in expected.items():
        assert study.fate_closed_form(model, omega) == fate
        assert study.fate_simulated(model, {"theta_dot": omega}) == fate
    # the study's batch of the same starts (simulate_batch): the same fates
    rates = np.array(list(expected))[:, None]
    assert study.fates_simulated(model, rates).tolist() == list(expected.values())
    # In the plane: first impact by energy vs simulated first impact.
    for theta, rate in ((0.1, -0.5), (-0.2, 0.8), (0.3, -2.5)):
        sim = gaitopt.simulate(model, {"theta": theta, "theta_dot": rate}, steps=1)
        assert study.first_impact(model, theta, rate) == pytest.approx(
            sim.section_states[-1][1], abs=MAP_TOL
        )
