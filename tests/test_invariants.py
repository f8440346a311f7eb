"""Physical invariants: energy along passive flows, angular momentum through impacts, resets."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt

WALKERS = ["compass_gait", "simplest_walker"]


def _angular_momentum(bodies, x, p, point) -> float:
    """Σ m_i (r_i − c) × v_i, planar (kg·m²/s)."""
    m, r, v = (np.atleast_2d(np.asarray(a, dtype=float)) for a in bodies(x, p))
    m = m.ravel()
    r = r.reshape(2, -1) - np.asarray(point, dtype=float).reshape(2, 1)
    v = v.reshape(2, -1)
    return float(np.sum(m * (r[0] * v[1] - r[1] * v[0])))


@pytest.mark.parametrize("name", ["rimless_wheel", "compass_gait", "simplest_walker"])
def test_energy_is_conserved_along_the_flow(name, cycles):
    # Invariant: the flows are conservative (Drake's compass_gait_test checks 2e-13 on one step).
    # Here: along every simulated phase (rtol 1e-11) and along the shooting orbit's samples;
    # tolerance 1e-9 relative to the energy scale.
    cycle = cycles[name]
    model = cycle.model
    phase = model.phases[0]
    energy = phase.conserved["energy"]
    sim = gaitopt.simulate(model, cycle.x, steps=3)
    for arc in sim.arcs:
        _, X = arc.sample(200)
        values = np.array([float(energy(X[:, j], model.p)) for j in range(X.shape[1])])
        scale = 1 + np.max(np.abs(values))
        assert np.ptp(values) < 1e-9 * scale, name
    for arc in cycle.orbit:
        values = np.array([float(energy(arc.x[:, j], model.p)) for j in range(arc.x.shape[1])])
        assert np.ptp(values) < 1e-9 * (1 + np.max(np.abs(values))), name


def test_energy_is_lost_at_impacts(cycles):
    # Plastic impacts dissipate: kinetic energy after heel strike is below that before.
    cycle = cycles["compass_gait"]
    model = cycle.model
    energy = model.phases[0].conserved["energy"]
    sim = gaitopt.simulate(model, cycle.x, steps=2)
    for event in sim.events:
        before = float(energy(event.state_before, model.p))
        # Potential energy is continuous through the impact (legs swap, same configuration), so
        # the change of total energy relative to the new stance foot is the kinetic loss.
        after = float(energy(event.state_after, model.p))
        assert after < before


@pytest.mark.parametrize("name", WALKERS)
def test_angular_momentum_about_the_impact_point_is_conserved(name, cycles):
    # Invariant: the impulse acts at the striking foot, so the angular momentum of the whole
    # walker about that point is the same just before and just after heel strike (Drake's
    # compass_gait_test checks 5e-15; Garcia et al. 1998 derive eq. 6 from it for the hip mass).
    # Tolerance 1e-12 relative.
    cycle = cycles[name]
    model = cycle.model
    phase = model.phases[0]
    names = phase.point_names
    sim = gaitopt.simulate(model, cycle.x, steps=2)
    heel_strikes = [e for e in sim.events if e.transition == "heel strike"]
    assert len(heel_strikes) == 2
    for event in heel_strikes:
        points = np.asarray(phase.points(event.state_before, model.p))
        swing_foot = points[:, names.index("swing_foot")]
        before = _angular_momentum(phase.bodies, event.state_before, model.p, swing_foot)
        # After the reset the new stance foot is the origin of the new state's frame.
        after = _angular_momentum(phase.bodies, event.state_after, model.p, [0.0, 0.0])
        assert after == pytest.approx(before, rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("name", WALKERS)
def test_reset_lands_on_the_next_phase_side_of_the_guard(name, cycles):
    # After heel strike the feet are again both on the slope (guard = 0) but the new swing foot
    # is behind, where the crossing rule excludes the guard; and the walker does not re-strike
    # at once: the next heel strike is a whole step later.
    cycle = cycles[name]
    model = cycle.model
    transition = model.phases[0].transitions[0]
    sim = gaitopt.simulate(model, cycle.x, steps=1)
    x_minus = sim.events[0].state_before
    x_plus = sim.events[0].state_after
    u, p = model.nominal_input(), model.p
    assert abs(float(transition.guard(x_minus, u, p))) < 1e-12
    assert abs(float(transition.guard(x_plus, u, p))) < 1e-12
    assert float(transition.admissible(x_minus, u, p)) > 0
    assert float(transition.admissible(x_plus, u, p)) < 0
    assert sim.events[0].t == pytest.approx(cycle.period, abs=1e-9)


def test_swing_foot_is_on_the_slope_at_heel_strike(cycles):
    # Geometry of the guard: stance + swing = 2·slope puts the swing foot on y = −x tan(slope).
    cycle = cycles["compass_gait"]
    model = cycle.model
    phase = model.phases[0]
    sim = gaitopt.simulate(model, cycle.x, steps=1)
    points = np.asarray(phase.points(sim.events[0].state_before, model.p))
    foot = points[:, phase.point_names.index("swing_foot")]
    assert foot[0] > 0  # ahead, downhill
    assert foot[1] == pytest.approx(-foot[0] * np.tan(model.slope), abs=1e-12)
