"""The ball on a vibrating table (Holmes 1982): period-1 bouncing, its window, the cascade."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.models.bouncing_ball import BouncingBall

# Shooting residual and discretisation-error estimate are ≤ 1e-10, so 1e-9 for closed forms.
TOL = 1e-9


@pytest.fixture(scope="module")
def ball() -> BouncingBall:
    return gaitopt.model("bouncing_ball")


@pytest.fixture(scope="module")
def orbits(ball):
    return {
        kind: gaitopt.find_limit_cycle(ball, ball.period_orbit(1, stable=kind == "stable"))
        for kind in ("stable", "saddle")
    }


def test_period_one_orbits_match_the_closed_form(ball, orbits):
    # Source: the module docstring's derivation (Holmes 1982 / G&H §2.4 existence condition
    # Γ cos φ = πn(1 − e)/(1 + e), ẏ⁺ = gT/2).  Tolerance 1e-9.
    for kind, cycle in orbits.items():
        assert cycle.success and cycle.verified, cycle.message
        expected = ball.period_orbit(1, stable=kind == "stable")
        assert cycle.fixed_point["phase"] == pytest.approx(expected["phase"], abs=TOL)
        assert cycle.fixed_point["y_dot"] == pytest.approx(expected["y_dot"], abs=TOL)
        assert cycle.period == pytest.approx(1 / ball.frequency, abs=TOL)
    assert orbits["stable"].stable and not orbits["saddle"].stable


def test_multipliers_match_the_closed_form(ball, orbits):
    # Source: module docstring, det J = e², tr J = 1 + e² − (1 + e)² Γ sin φ.  Two nontrivial
    # multipliers (the section is 2-D).  Tolerance 1e-9.
    for kind, cycle in orbits.items():
        expected = ball.period_multipliers(1, stable=kind == "stable")
        got = cycle.multipliers
        assert len(got) == 2
        assert np.prod(got).real == pytest.approx(ball.restitution**2, abs=TOL)
        np.testing.assert_allclose(np.sort_complex(got), np.sort_complex(expected), atol=TOL)


def test_impacts_reverse_the_relative_velocity_and_flights_conserve_energy(ball):
    # Invariants: ẏ⁺ − ṡ = −e (ẏ⁻ − ṡ) at every impact (exact reset; 1e-12), the ball lands on
    # the table (guard 0 to 1e-12), and energy is conserved in flight (rtol 1e-11 → 1e-9).
    sim = gaitopt.simulate(ball, {"phase": 0.3, "y_dot": 1.1}, steps=6)
    assert sim.success
    A, w, e, g = ball.amplitude, ball.omega, ball.restitution, ball.gravity
    for ev in sim.events:
        phase, y, v = ev.state_before
        table_v = A * w * math.cos(phase)
        assert y == pytest.approx(A * math.sin(phase), abs=1e-12)
        assert ev.state_after[2] - table_v == pytest.approx(-e * (v - table_v), abs=1e-12)
        assert -math.pi <= ev.state_after[0] < math.pi
    for arc in sim.arcs:
        _, x = arc.sample(20)
        energy = 0.5 * x[2] ** 2 + g * x[1]
        assert np.ptp(energy) < 1e-9


def test_simulation_converges_to_the_stable_orbit(ball, orbits):
    # Inside the window the stable orbit attracts: |λ| = e = 0.5 per impact, so 60 impacts from a
    # nearby start bring the error below 0.5^60·0.1 ≈ 1e-19 → the integrator's 1e-10.
    sim = gaitopt.simulate(ball, {"phase": 0.7, "y_dot": 0.9}, steps=60)
    assert sim.success
    last = sim.section_states[-1]
    star = orbits["stable"].x
    np.testing.assert_allclose(last, star, atol=1e-8)


def test_existence_and_period_doubling_of_the_window(ball):
    # Source: closed forms Γ_SN = π(1 − e)/(1 + e) = 1.0471975511965976 at e = 0.5 and
    # Γ_PD = sqrt(Γ_SN² + (2(1 + e²)/(1 + e)²)²); the located PD must agree to 1e-6 (bisection
    # of the multiplier test function).  Holmes' high-bounce window ends lower, sqrt(Γ_SN² + 1).
    assert ball.saddle_node_acceleration() == pytest.approx(math.pi / 3, abs=1e-15)
    below = ball.replace(acceleration=0.98 * ball.saddle_node_acceleration())
    assert below.period_orbit() is None
    failed = gaitopt.find_limit_cycle(below, {"phase": 0.0, "y_dot": 0.981})
    assert not failed.success and "period-1 bouncing exists for" in failed.message
    branch = gaitopt.continuation(ball, "acceleration", to=1.72, bounds=(1.05, 1.72))
    pds = [sp for sp in branch.special_points if sp.kind == "PD"]
    assert len(pds) == 1
    assert pds[0].param == pytest.approx(ball.period_doubling_acceleration(), abs=1e-6)
    assert ball.holmes_period_doubling_acceleration() < pds[0].param
    # The cascade: period 2 doubles, then period 4, with Feigenbaum-like shrinking intervals.
    chain = [pds[0].param]
    node = branch
    while node.children:
        node = node.children[0]
        chain += [sp.param for sp in node.special_points if sp.kind == "PD"][:1]
    assert len(chain) >= 3
    gaps = np.diff(chain)
    assert np.all(gaps > 0) and gaps[0] / gaps[1] > 3


def test_cli_solves_the_ball(capsys):
    assert main(["solve", "bouncing_ball", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] and data["verified"] and data["stable"]
    assert data["state_names"] == ["phase", "y", "y_dot"]
