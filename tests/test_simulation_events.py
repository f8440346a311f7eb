"""Event location at the ends of an integrator step, and integrator failures as results.

Issue 24, item 1: the README's stabilised compass gait (20 orbits) ended in a traceback.  Once
the closed loop had converged, a heel strike fell within one ulp after the end of a step (the
step stopped at the torque profile's last break, t = 0.8 s after the section, with the guard at
−3.4e-15); ``brentq``, whose tolerance is a few ulps, returned the step's start, which is the
arc's last time stamp, and ``OdeSolution`` refused the repeated time.  These tests pin
:func:`gaitopt.simulation.phase.locate_crossing`'s contract (a crossing time strictly after the
bracket's start, where the guard is non-negative) and check that an integrator that fails is
reported as ``status == "failed"``, not raised (the arc assembled before was inconsistent too).
"""

import numpy as np
import pytest
from scipy.optimize import brentq

import gaitopt
from gaitopt.simulation.phase import locate_crossing

# Recorded from the failing run (compass gait, level ground, 0.3 m in 0.8 s, LQR offset, start
# +1e-3 in stance): the step's start (s) and the signed heel-strike guard there and one ulp later
# (m).  The guard's rate, (2.94e-15 + 3.44e-15) / 1.78e-15 ≈ 3.6 m/s, is the swing foot's
# descent rate at heel strike.
_A = 14.391978312193135
_G_A = -3.4416913763379853e-15
_G_NEXT = 2.942091015256665e-15


def _recorded_guard(t: float) -> float:
    """The guard near the recorded crossing, linear through the two recorded values."""
    ulp = np.nextafter(_A, np.inf) - _A
    return (_G_NEXT - _G_A) / ulp * (t - _A) + _G_A


def test_a_crossing_one_ulp_after_the_step_start_is_located_after_it():
    b = _A + 0.007  # the step's first check point (a quarter of a 0.028 s step)
    # brentq alone returns the bracket's start, where g < 0: its tolerance (xtol 1e-15 +
    # 4 eps·14.4 ≈ 1.4e-14, about eight ulps here) admits it.  That was the bug.
    assert brentq(_recorded_guard, _A, b, xtol=1e-15, rtol=4 * np.finfo(float).eps) == _A
    t = locate_crossing(_recorded_guard, _A, b)
    # Exact: the first float after a is where the guard is first non-negative (recorded values).
    assert t == np.nextafter(_A, np.inf)
    assert _A < t <= b and _recorded_guard(t) >= 0


def test_crossings_in_the_last_or_first_bits_of_a_step():
    # The caller saw g(a) < 0 <= g(b) at check points (the compiled event values, the step's end
    # state); the dense output may disagree in the last bits.  Exact answers: the ends.
    a, b = 0.5, 0.6
    # Negative on the dense output at b too: the sign change is at b itself.
    assert locate_crossing(lambda t: -1e-16, a, b) == b
    # Non-negative on the dense output at a already: the first float after a.
    assert locate_crossing(lambda t: 1e-16, a, b) == np.nextafter(a, np.inf)
    # An ordinary crossing is brentq's root (t = 0.55 to brentq's tolerance, a few ulps).
    assert locate_crossing(lambda t: t - 0.55, a, b) == pytest.approx(0.55, abs=1e-15)


@pytest.mark.parametrize("cut", [0.2, 0.0])
def test_an_integrator_failure_is_a_result(cut):
    # A torque that becomes NaN at t > cut (s): DOP853 rejects every step that reaches it until
    # its step is below 10 ulps, and fails.  Before the fix: a ValueError from OdeSolution
    # (cut 0.2: a repeated last time stamp and one interpolant too few) or a TypeError when the
    # arc was sampled (cut 0: an arc with no interpolant).
    model = gaitopt.model("compass_gait")

    def torque(t: float, step: int) -> np.ndarray:
        return np.full(len(model.inputs), np.nan if t > cut else 0.0)

    sim = gaitopt.simulate(model, steps=2, feedforward=torque)
    assert not sim.success and sim.status == "failed"
    assert "integrator failed in phase 'single support'" in sim.message
    arc = sim.arcs[-1]
    # The arc ends where the integrator could not go on: within 1e-9 s before the cut (its
    # steps shrink towards it by factors ≥ 0.2 until they are below 10 ulps).
    assert cut - 1e-9 < arc.t1 <= cut
    t, x = arc.sample(5)
    assert x.shape == (len(model.state_names), 5) and np.all(np.isfinite(x))
    np.testing.assert_array_equal(x[:, 0], model.lift(model.default_start()))  # the start, exact
