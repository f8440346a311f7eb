"""The ballistic walker (Mochon & McMahon 1980): the swing's boundary-value problem, checked by an
independent hybrid simulation, energy conservation, and the conditions that end the range.

The swing is solved with SciPy's DOP853 inside a Newton iteration (BallisticWalker.swing); the
check re-simulates it with gaitopt.simulate (adaptive integration with a located heel-strike
event, a separate code path) and compares the heel-strike time and state.
"""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt


@pytest.fixture(scope="module")
def model():
    return gaitopt.model("ballistic_walker")  # 70 kg, 0.9 m legs, step 0.7 m


def test_a_ballistic_swing_reaches_heel_strike_at_the_requested_time(model):
    swing = model.swing(0.4)
    assert swing.success and swing.ballistic, swing.reason
    sim = gaitopt.simulate(model, dict(zip(model.section.coordinates, swing.rates, strict=True)))
    (event,) = sim.events
    assert event.transition.startswith("heel strike")
    # Tolerances 1e-6 s and 1e-6 rad: two adaptive integrations at rtol 1e-10 / 1e-11.
    assert event.t == pytest.approx(0.4, abs=1e-6)
    np.testing.assert_allclose(event.state_before[:3], model.alpha, atol=1e-6)
    # Heel strike: knee straight, extending; swing foot on the ground a step ahead.
    points = np.asarray(model.phases[0].points(event.state_before, model.p))
    assert points[0, 3] == pytest.approx(model.step_length, abs=1e-6)
    assert points[1, 3] == pytest.approx(0.0, abs=1e-6)


def test_energy_is_conserved_along_the_swing(model):
    swing = model.swing(0.45)
    energy = model.phases[0].conserved["energy"]
    values = np.array([float(energy(swing.x[:, k], model.p)) for k in range(swing.x.shape[1])])
    # Passive swing: no muscle moments, so energy is constant (relative 1e-8 at rtol 1e-10).
    assert np.ptp(values) < 1e-8 * np.max(np.abs(values))


def test_too_short_a_swing_needs_the_stance_leg_to_pull(model):
    # At 0.2 s the body must be swung over the stance leg so fast that the ground would have to
    # pull it down: not ballistic (the range's lower end).
    swing = model.swing(0.2)
    assert swing.success and not swing.ballistic
    assert "pulls" in swing.reason and swing.min_vertical_force < 0


def test_toe_off_configuration_puts_the_toe_on_the_ground_with_the_knee_flexed(model):
    x = model.lift(np.zeros(3))
    points = np.asarray(model.phases[0].points(x, model.p))
    assert points[1, 3] == pytest.approx(0.0, abs=1e-12)  # toe on the ground
    assert x[1] - x[2] == pytest.approx(model.toe_off_knee, abs=1e-12)  # knee flexion κ₀
    assert x[0] == pytest.approx(-model.alpha, abs=1e-15)


def test_no_passive_gait_is_searched_for(model):
    assert model.passive_gait is False
    assert "boundary-value" in model.existence_note()


def test_the_shortest_ballistic_swing_is_where_the_readme_says(model):
    # problems/ballistic_walking.py locates the range's lower end at step 0.7 m (the stance
    # leg's least vertical ground force crossing zero) by Brent's method to 1e-4 s: 0.2548 s
    # (README; 5 % below the closed form 0.2681 s of a point-mass hip on massless legs).  A
    # bracket ten times wider than that tolerance must straddle it.
    below, above = model.swing(0.2538), model.swing(0.2558)
    assert below.success and not below.ballistic and "pulls" in below.reason
    assert above.success and above.ballistic, above.reason
