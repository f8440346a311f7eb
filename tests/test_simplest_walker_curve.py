"""The simplest walker with Kuo's hip spring: its first period doubling in slope × hip stiffness
(problems/simplest_walker_pd_curve.py) against one-parameter continuation and the slope study."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import slope_at

import gaitopt
from gaitopt.continuation import PseudoArclength, continuation
from gaitopt.curves import ParameterPath, curve_from
from gaitopt.returnmap import return_map

LONG_GAIT = {"theta": 0.2003, "theta_dot": -0.1998}  # Garcia et al. 1998, γ = 0.009, rounded
K_AT = 0.2  # m_f·g·l/rad: located exactly on the curve
K_TO = 0.5  # m_f·g·l/rad: the curve's end (PD slope 0.0417 rad, inside the slope range)
#: At most 10 % of the slope per step (as the study), so no special point hides in a step.
STEPS = PseudoArclength(step=0.02, max_step=0.1)
#: The first PD at k = 0 reported by problems/simplest_walker_slope.py
#: (results/simplest_walker_slope/summary.json, the README: 0.0150884 rad).
SLOPE_STUDY_PD = 0.015088437946332843


def _first_pd(hip_stiffness: float):
    model = gaitopt.model("simplest_walker", hip_stiffness=hip_stiffness)
    branch = continuation(model, "slope", to=0.05, start=LONG_GAIT, cascade=False, options=STEPS)
    return next(sp for sp in branch.special_points if sp.kind == "PD")


@pytest.fixture(scope="module")
def curve_and_checks():
    start = _first_pd(0.0)
    model = start.cycle.model
    paths = (ParameterPath.of(model, "slope"), ParameterPath.of(model, "hip_stiffness"))
    curve = curve_from(start, "PD", paths, K_TO, at=(K_AT,))
    checks = {0.0: start.param, K_AT: _first_pd(K_AT).param, K_TO: _first_pd(K_TO).param}
    return curve, checks


def test_hip_spring_adds_minus_k_phi_to_the_swing_equation_only():
    # Closed form of the model (Kuo 2002: a hip torque −k·φ between the legs, acting on the
    # infinitesimal swing foot): the flow at k differs from Garcia's (k = 0) by −k·φ in φ̈ and by
    # nothing else, exactly (to rounding, 1e-15).
    x = np.array([0.17, 0.29, -0.21, 0.05])
    flows = []
    for k in (0.0, 0.7):
        model = gaitopt.model("simplest_walker", slope=0.012, hip_stiffness=k)
        flows.append(np.asarray(model.phases[0].flow(x, model.nominal_input(), model.p)).ravel())
    np.testing.assert_allclose(flows[1] - flows[0], [0.0, 0.0, 0.0, -0.7 * x[1]], atol=1e-15)


def test_pd_curve_meets_one_parameter_period_doublings(curve_and_checks):
    # Independent method: gaitopt.continuation in the slope at fixed hip stiffness, its PD
    # located by regula falsi on det(A + I) to 1e-10.  The curve's point at that k (corrected at
    # exactly that value) solves the same condition, located to 1e-10 with discretisation error
    # ≤ 1e-10: agreement to 1e-8 rad (measured: ≤ 6e-13 rad).
    curve, checks = curve_and_checks
    assert curve.success and curve.message.startswith("reached hip_stiffness"), curve.message
    assert curve.values(1)[-1] == pytest.approx(K_TO, abs=1e-12)  # ended exactly on `to`
    for k, slope in checks.items():
        assert slope_at(curve, k) == pytest.approx(slope, abs=1e-8)
    # The spring moves the PD to steeper slopes (measured: 0.0151, 0.0256, 0.0417 rad).
    assert checks[0.0] < checks[K_AT] < checks[K_TO]


def test_pd_at_zero_stiffness_is_the_slope_studys_and_garcias(curve_and_checks):
    # At k = 0 the model is Garcia's: the curve starts at the one-parameter PD of the slope study
    # (same method, both located to 1e-10: 1e-9 rad) and at Garcia et al.'s γ ≈ 0.0151 (given to
    # three significant digits: ±5e-5 rad).
    curve, checks = curve_and_checks
    assert slope_at(curve, 0.0) == pytest.approx(SLOPE_STUDY_PD, abs=1e-9)
    assert checks[0.0] == pytest.approx(SLOPE_STUDY_PD, abs=1e-9)
    assert slope_at(curve, 0.0) == pytest.approx(0.0151, abs=5e-5)


def test_every_curve_point_is_a_certified_gait_losing_stability(curve_and_checks):
    # Each point: certified and verified by simulation, a multiplier at −1 (to 1e-8, the
    # defining condition solved to 1e-10), the other inside the unit circle (the PD is where the
    # stable long-step gait loses its stability, not a PD of an unstable gait).
    curve, _ = curve_and_checks
    for cycle in curve.cycles:
        assert cycle.success and cycle.verified
        mu = cycle.multipliers
        at = int(np.argmin(np.abs(mu + 1)))
        assert abs(mu[at] + 1) < 1e-8
        assert np.all(np.abs(np.delete(mu, at)) < 1)


def test_simulated_return_map_has_a_multiplier_minus_one_on_the_curve(curve_and_checks):
    # Independent method: central differences (h = 1e-6 relative) of the return map simulated
    # by SciPy at rtol 1e-12 (gaitopt.returnmap), at the curve's point k = K_AT.  Error budget:
    # truncation h² ~ 1e-12, rounding 1e-12/h ~ 1e-6: an eigenvalue within 1e-4 of −1.
    curve, _ = curve_and_checks
    row = int(np.flatnonzero(np.abs(curve.params[:, 1] - K_AT) < 1e-12)[0])
    cycle = curve.cycles[row]
    s = cycle.section_point
    J = np.zeros((s.size, s.size))
    for j in range(s.size):
        e = np.zeros(s.size)
        e[j] = 1e-6 * (1 + abs(s[j]))
        J[:, j] = (return_map(cycle.model, s + e) - return_map(cycle.model, s - e)) / (2 * e[j])
    assert np.min(np.abs(np.linalg.eigvals(J) + 1)) < 1e-4
