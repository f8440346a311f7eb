"""The line juggler with the mirror law (Buehler, Koditschek & Kindlmann 1990)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.models.line_juggler import LineJuggler
from gaitopt.returnmap import return_map

# Shooting residual and discretisation-error estimate ≤ 1e-10: closed forms to 1e-9.
TOL = 1e-9


@pytest.fixture(scope="module")
def juggler() -> LineJuggler:
    return gaitopt.model("line_juggler")


def test_kappa0_balances_restitution_so_the_textbook_map_holds(juggler):
    # Source: module docstring; the general map is ḃ' = (e + (1 + e) κ) ḃ, the textbook's
    # ḃ' = ḃ (1 + (1 + e) κ1 (E_d − E)) exactly when κ0 = (1 − e)/(1 + e) = 1/9 at e = 0.8.
    e = juggler.restitution
    assert juggler.kappa0 == pytest.approx(1 / 9, abs=1e-15)
    assert e + (1 + e) * juggler.kappa0 == pytest.approx(1.0, abs=1e-15)


def test_simulated_map_is_the_closed_form(juggler):
    # Event-located SciPy map (rtol 1e-11) vs the textbook map; tolerance 1e-9.
    for b_dot in (-0.5, -1.5, -2.5, -3.0, -4.0, -5.5):
        expected = juggler.closed_form_map(b_dot)
        assert return_map(juggler, b_dot)[0] == pytest.approx(expected, abs=TOL)
    # Beyond the fastest impact the paddle knocks the ball down: undefined, a named fall.
    too_fast = -1.01 * juggler.fastest_impact()
    assert np.isnan(return_map(juggler, too_fast)[0])
    sim = gaitopt.simulate(juggler, {"b_dot": too_fast}, steps=1)
    # The paddle knocks it down at once: the declared constraint "ball above the paddle" fails
    # where the flight starts (before the 1 m drop-depth exit would fire).
    assert sim.status == "fell"
    assert [e.transition for e in sim.events] == ["ball below the paddle"]


@pytest.mark.parametrize("kappa1", [0.02, 0.04, 1 / 16.2, 0.1, 0.12, 0.13])
def test_fixed_point_and_multiplier_match_the_closed_form(juggler, kappa1):
    # Source: module docstring: ḃ* = −ḃ_d, P'(ḃ*) = 1 − (1 + e) κ1 ḃ_d² (0 at the deadbeat gain
    # 1/16.2); stable iff 0 < κ1 < 2/16.2 = 0.1235.  Tolerance 1e-9.
    model = juggler.replace(kappa1=kappa1)
    cycle = gaitopt.find_limit_cycle(model)
    assert cycle.success and cycle.verified, cycle.message
    assert cycle.fixed_point["b_dot"] == pytest.approx(-3.0, abs=TOL)
    assert cycle.period == pytest.approx(2 * 3.0 / 9.81, abs=TOL)
    assert cycle.multipliers[0].real == pytest.approx(model.multiplier(), abs=TOL)
    lo, hi = model.stable_gains()
    assert cycle.stable == (lo < kappa1 < hi)


def test_period_doubling_ends_the_stable_range(juggler):
    # Continuation in κ1 locates the PD at the closed form 2/((1 + e) ḃ_d²); tolerance 1e-6.
    branch = gaitopt.continuation(juggler, "kappa1", to=0.2, cascade=False)
    pds = [sp.param for sp in branch.special_points if sp.kind == "PD"]
    assert len(pds) == 1
    assert pds[0] == pytest.approx(juggler.stable_gains()[1], abs=1e-6)


def test_simulation_converges_and_deadbeat_is_quadratic(juggler):
    # Stable gain: from −2 and −4.5 m/s to −3 within 1e-8 in 30 impacts (|λ| = 0.352).
    for start in (-2.0, -4.5):
        sim = gaitopt.simulate(juggler, {"b_dot": start}, steps=30)
        assert sim.section_states[-1][2] == pytest.approx(-3.0, abs=1e-8)
    # Deadbeat gain: the error squares each impact (P'(ḃ*) = 0): e_{n+1} ≤ C e_n² with
    # C = |P''(ḃ*)|/2 = 3 (1 + e) κ1 ḃ_d / 2 = 3/(2 ḃ_d) = 0.5, plus the cubic term → 0.6.
    deadbeat = juggler.replace(kappa1=juggler.deadbeat_gain())
    sim = gaitopt.simulate(deadbeat, {"b_dot": -3.2}, steps=4)
    err = np.abs(sim.section_states[:, 2] + 3.0)
    assert err[3] < 1e-6
    for a, b in zip(err[:2], err[1:3], strict=True):
        assert b <= 0.6 * a**2
    # Above the stable range a small deviation grows (λ = −1.106 at κ1 = 0.13).
    unstable = juggler.replace(kappa1=0.13)
    sim = gaitopt.simulate(unstable, {"b_dot": -3.001}, steps=20)
    assert abs(sim.section_states[-1][2] + 3.0) > 0.005


def test_impacts_obey_restitution_on_the_mirror_paddle(juggler):
    # Invariants: impact at the mirror point b = 0 (1e-12), v⁺ − ṙ = −e (v⁻ − ṙ) with the paddle
    # velocity ṙ = −κ v⁻ (1e-12), energy conserved in flight (1e-9).
    sim = gaitopt.simulate(juggler, {"b_dot": -2.0}, steps=5)
    e = juggler.restitution
    for ev in sim.events:
        b, v, _ = ev.state_before
        assert b == pytest.approx(0.0, abs=1e-12)
        paddle = -juggler.kappa(b, v) * v
        assert ev.state_after[1] - paddle == pytest.approx(-e * (v - paddle), abs=1e-12)
        assert ev.state_after[2] == v
    for arc in sim.arcs:
        _, x = arc.sample(20)
        assert np.ptp(0.5 * x[1] ** 2 + juggler.gravity * x[0]) < 1e-9


def test_cli_solves_the_juggler(capsys):
    assert main(["solve", "line_juggler", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] and data["verified"] and data["stable"]
    assert data["fixed_point"]["b_dot"] == pytest.approx(-3.0, abs=TOL)
