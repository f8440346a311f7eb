"""The planar juggler: one-link paddle, mirror law (Buehler, Koditschek & Kindlmann 1990)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.models.planar_juggler import PlanarJuggler
from gaitopt.returnmap import return_map

# Shooting residual and discretisation-error estimate ≤ 1e-10: closed forms to 1e-9.
TOL = 1e-9
COORDS = ("x", "x_dot_pre", "energy_pre")


@pytest.fixture(scope="module")
def juggler() -> PlanarJuggler:
    return gaitopt.model("planar_juggler")


@pytest.fixture(scope="module")
def cycle(juggler):
    cycle = gaitopt.find_limit_cycle(juggler)
    assert cycle.success and cycle.verified, cycle.message
    return cycle


def section(model, sim) -> np.ndarray:
    return np.array([model.section_coordinates_of(x) for x in sim.section_states])


def test_fixed_point_is_the_vertical_bounce(juggler, cycle):
    # Source: module docstring: the line x = x̄ is invariant; fixed point (x̄, 0, E_d = ½ ḃ_d²),
    # period 2 ḃ_d/g (the line juggler's); tolerance 1e-9.
    assert cycle.section_coordinates == COORDS
    for name, value in juggler.closed_form_fixed_point().items():
        assert cycle.fixed_point[name] == pytest.approx(value, abs=TOL)
    assert cycle.fixed_point["y"] == pytest.approx(0.0, abs=TOL)
    assert cycle.fixed_point["y_dot"] == pytest.approx(3.0, abs=TOL)  # thrown back at ḃ_d
    assert cycle.period == pytest.approx(2 * 3.0 / 9.81, abs=TOL)


def test_multipliers_match_the_closed_form(juggler, cycle):
    # Source: module docstring: λ_E = 1 − (1 + e) κ1 ḃ_d² = 0.352 (the line juggler's) and the
    # eigenvalues of the horizontal matrix [[1 − aTκ_x, T(1 − aκ_ẋ)], [−aκ_x, 1 − aκ_ẋ]],
    # a = (1 + e) ḃ_d; tolerance 1e-9.
    expected = np.sort_complex(juggler.multipliers_closed_form())
    assert np.allclose(np.sort_complex(cycle.multipliers), expected, atol=TOL)
    line = gaitopt.model("line_juggler")
    assert expected.real.min() == pytest.approx(line.multiplier(), abs=1e-15)
    assert cycle.stable


def test_ad_jacobian_matches_finite_differences_of_the_simulated_map(juggler, cycle):
    # Central differences (h = 1e-5) of the event-located SciPy map (rtol 1e-11): truncation
    # O(h²) ~ 1e-10 and rounding ~ 1e-11/h = 1e-6 → tolerance 1e-6.
    s0, h = cycle.section_point, 1e-5
    fd = np.column_stack(
        [
            (return_map(juggler, s0 + h * d) - return_map(juggler, s0 - h * d)) / (2 * h)
            for d in np.eye(3)
        ]
    )
    assert np.allclose(cycle.jacobian, fd, atol=1e-6)
    # Block triangular (invariant vertical line): the horizontal rows ignore the energy (1e-9).
    assert np.abs(cycle.jacobian[:2, 2]).max() < TOL


def test_perturbed_throws_converge_at_the_rate_of_the_multipliers(juggler, cycle):
    s0 = cycle.section_point
    d0 = np.array([0.02, 0.05, -0.3])
    sim = gaitopt.simulate(juggler, dict(zip(COORDS, s0 + d0, strict=True)), steps=30)
    assert sim.status == "completed"
    err = section(juggler, sim) - s0
    # 30 impacts at spectral radius 0.678: ‖e_30‖ ≈ 5e-7 (measured) ≪ 1e-5.
    assert np.linalg.norm(err[-1]) < 1e-5
    # Rate over impacts 5..25 vs the spectral radius sqrt(1 − a κ_ẋ) = 0.678 (closed form):
    # the complex pair makes ‖e_n‖ wobble, measured 0.673 → tolerance 2 %.
    rho = max(abs(juggler.multipliers_closed_form()))
    rate = (np.linalg.norm(err[25]) / np.linalg.norm(err[5])) ** (1 / 20)
    assert rate == pytest.approx(rho, rel=0.02)
    # Small throws follow the linear map J^n δ: deviation O(|δ|²); |δ| = 1e-4 → 1e-6.
    d_small = 1e-4 * d0 / np.linalg.norm(d0)
    sim = gaitopt.simulate(juggler, dict(zip(COORDS, s0 + d_small, strict=True)), steps=8)
    err = section(juggler, sim) - s0
    linear = [np.linalg.matrix_power(cycle.jacobian, n) @ d_small for n in range(9)]
    assert np.abs(err - linear).max() < 1e-6


def test_reduces_to_the_line_juggler_on_the_vertical_line(juggler):
    # Source: module docstring (x = x̄, ẋ = 0 is invariant; contact velocity θ̇ x̄ = −κ ẏ) and the
    # line juggler's textbook map ḃ' = ḃ (1 + (1 + e) κ1 (E_d − ½ ḃ²)); tolerance 1e-9.
    line = gaitopt.model("line_juggler")
    b_dot = -2.0
    sim = gaitopt.simulate(
        juggler, {"x": 0.5, "x_dot_pre": 0.0, "energy_pre": 0.5 * b_dot**2}, steps=6
    )
    assert len(sim.events) == 6
    for ev in sim.events:  # the start is just after an impact at ḃ = −2: events are the next
        b_dot = line.closed_form_map(b_dot)
        x, y, x_dot, y_dot = ev.state_before[:4]
        assert (x, y, x_dot) == pytest.approx((0.5, 0.0, 0.0), abs=TOL)
        assert y_dot == pytest.approx(b_dot, abs=TOL)


def test_impact_law_reverses_the_relative_normal_velocity(juggler):
    # Invariants, off the vertical line: the ball is on the paddle at impact (1e-10); relative
    # normal velocity w_n⁺ = −e w_n⁻, tangential velocity unchanged (1e-12); held states set.
    sim = gaitopt.simulate(juggler, {"x": 0.6, "x_dot_pre": 0.2, "energy_pre": 3.0}, steps=5)
    e = juggler.restitution
    for ev in sim.events:
        x, y, vx, vy = ev.state_before[:4]
        theta, theta_dot = juggler.paddle_state(x, y, vx, vy)
        n = np.array([-math.sin(theta), math.cos(theta)])
        t = np.array([math.cos(theta), math.sin(theta)])
        r = np.array([x, y])
        assert abs(r @ n) < 1e-10
        contact = theta_dot * (r @ t) * n  # the paddle point under the ball
        before, after = np.array([vx, vy]), ev.state_after[2:4]
        assert (after - contact) @ n == pytest.approx(-e * (before - contact) @ n, abs=1e-12)
        assert after @ t == pytest.approx(before @ t, abs=1e-12)
        assert ev.state_after[4] == vx
        assert ev.state_after[5] == pytest.approx(0.5 * (vx**2 + vy**2) + 9.81 * y, abs=1e-12)
    # Energy ½|v|² + g y is conserved in flight (DOP853 at rtol 1e-11 → 1e-9).
    for arc in sim.arcs:
        _, xs = arc.sample(20)
        assert np.ptp(0.5 * (xs[2] ** 2 + xs[3] ** 2) + 9.81 * xs[1]) < 1e-9


@pytest.mark.parametrize(
    ("gains", "stable"),
    [
        ({"kappa_x": 0.87, "kappa_xdot": 0.1}, True),  # κ_x bound (4 − 2aκ_ẋ)/(aT) = 0.8841
        ({"kappa_x": 0.90, "kappa_xdot": 0.1}, False),
        ({"kappa_x": -0.05, "kappa_xdot": 0.1}, False),  # κ_x > 0 needed
        ({"kappa_x": 0.02, "kappa_xdot": 0.36}, True),  # κ_ẋ < 2/a = 0.3704, κ_x < 0.0339
        ({"kappa_x": 0.02, "kappa_xdot": 0.38}, False),
        ({"kappa_x": 0.05, "kappa_xdot": 0.36}, False),
        ({"kappa1": 0.13}, False),  # the line juggler's PD at κ1 = 0.1235
    ],
)
def test_stability_region_matches_the_jury_conditions(juggler, gains, stable):
    # Source: module docstring (Jury conditions on the horizontal matrix; λ_E of the line
    # juggler); multipliers to 1e-9.
    model = juggler.replace(**gains)
    cycle = gaitopt.find_limit_cycle(model, model.closed_form_fixed_point())
    assert cycle.success and cycle.verified, cycle.message
    expected = np.sort_complex(model.multipliers_closed_form())
    assert np.allclose(np.sort_complex(cycle.multipliers), expected, atol=TOL)
    assert cycle.stable == stable


def test_deadbeat_gains_zero_every_multiplier(juggler):
    # Source: module docstring: κ1 = 1/((1 + e) ḃ_d²), κ_ẋ = 1/a, κ_x = 1/(aT); tolerance:
    # a nilpotent 2×2 block's eigenvalues are ~ sqrt(1e-16) → 1e-7.
    model = juggler.replace(**juggler.deadbeat_gains())
    cycle = gaitopt.find_limit_cycle(model, model.closed_form_fixed_point())
    assert cycle.success and cycle.verified, cycle.message
    assert np.abs(cycle.multipliers).max() < 1e-7


def test_cli_solves_the_planar_juggler(capsys):
    assert main(["solve", "planar_juggler", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] and data["verified"] and data["stable"]
    assert data["fixed_point"]["x"] == pytest.approx(0.5, abs=TOL)
    assert data["fixed_point"]["energy_pre"] == pytest.approx(4.5, abs=TOL)
