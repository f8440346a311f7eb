"""Two-parameter curves of the kneed walker: a codimension-two corner (its first PD curve meeting
the foot-clearance boundary) and a boundary curve of a lift-off rate, each against
one-parameter continuation and independent computations.

Both are the cheapest honest cases found: the corner is followed from the branch at foot radius
R = 0.12 m (not from R = 0, as problems/kneed_walker_pd_curve.py does) over R ∈ [0.12, 0.16] m;
the lift-off boundary is the kneed walker's own with a heavier hip (mass_hip = 1 kg, twice Hsu
Chen's 0.5 kg), where the trailing foot, just after heel strike, stops lifting off before it can
graze the slope later in the swing (at 0.5 kg the branch in the slope ends by that graze, with a
lift-off speed of only 5e-4 m/s; results/kneed_walker_slope).
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import slope_at

import gaitopt
from gaitopt.continuation import PseudoArclength, continuation
from gaitopt.curves import ParameterPath, curve_from
from gaitopt.hybrid import rate_along

R_FROM, R_TO = 0.12, 0.16  # m: the foot radii the corner's curves run over
MASS_FROM, MASS_AT, MASS_TO = 1.0, 1.1, 1.2  # kg: the hip masses the lift-off curve runs over
#: Branch steps of at most 5 % of the slope (as problems/kneed_walker_pd_curve.py): no special
#: point hides in a step that ends on the boundary.
STEPS = PseudoArclength(max_step=0.05)


def _branch(**params):
    model = gaitopt.model("kneed_walker", slope=0.0504, **params)
    branch = continuation(model, "slope", to=0.2, cascade=False, options=STEPS)
    return model, branch, {sp.kind: sp for sp in branch.special_points}


def _lift_off_rate(cycle) -> float:
    """The trailing foot's speed away from the slope at the start of the three-link phase (m/s):
    the rate ∇c · f of the declared clearance constraint on the orbit's first sample."""
    phase = cycle.model.phases[0]
    clearance = next(c for c in phase.constraints if c.outcome == "trip")
    rate = rate_along(phase.flow, clearance.function)
    return float(rate(cycle.orbit[0].x[:, 0], cycle.inputs, cycle.model.p))


# -- the corner: where the first PD curve meets the clearance boundary --------------------------
@pytest.fixture(scope="module")
def corner():
    model, branch, points = _branch(foot_radius=R_FROM)
    paths = (ParameterPath.of(model, "slope"), ParameterPath.of(model, "foot_radius"))
    edge = curve_from(points["boundary"], "boundary", paths, R_TO, first=branch.cycles[0])
    pd = curve_from(points["PD"], "PD", paths, R_TO)
    found = [sp for sp in edge.special_points if sp.kind == "PD"]
    at = found[0].values["foot_radius"] if found else None
    _, _, there = _branch(foot_radius=at) if at is not None else (None, None, {})
    return {"edge": edge, "pd": pd, "corners": found, "one_parameter": there}


def test_the_boundary_curve_locates_one_corner_where_the_readme_says(corner):
    # The PD test function ∏(μ + 1) changes sign once along the clearance boundary between
    # R = 0.12 and 0.16 m: one corner, located by regula falsi to 1e-10.  The study's record
    # (README, results/kneed_walker_pd_curve: γ = 0.1203906 rad, R = 0.14019 m, given to the
    # digits shown): within half a unit of the last digit.
    edge = corner["edge"]
    assert edge.success and edge.message.startswith("reached foot_radius"), edge.message
    assert len(corner["corners"]) == 1
    sp = corner["corners"][0]
    assert "corner of the stable region" in sp.message
    assert sp.values["slope"] == pytest.approx(0.1203906, abs=5e-8)
    assert sp.values["foot_radius"] == pytest.approx(0.14019, abs=5e-6)
    # The gait there is certified and verified (just inside the boundary) with a multiplier at
    # −1: the corner is located to 1e-10 in the parameters and the multiplier moves by ~40 per
    # radian of slope here (−0.90 at 0.1135 rad to −1.18 at 0.1208 rad on the branch at
    # R = 0.1 m), so |μ + 1| ≲ 1e-8; tolerance 1e-7.
    assert sp.cycle.success and sp.cycle.verified
    assert np.min(np.abs(sp.cycle.multipliers + 1)) < 1e-7
    # The stable region's corner: past the PD (|μ| > 1) on the boundary below it, stable above.
    radii = edge.params[:, 1]
    worst = np.array([np.max(np.abs(c.multipliers)) for c in edge.cycles])
    below, above = radii < sp.values["foot_radius"], radii > sp.values["foot_radius"]
    assert np.all(worst[below] > 1) and np.all(worst[above] < 1)


def test_the_corner_is_on_the_one_parameter_branch_at_its_foot_radius(corner):
    # Independent method: gaitopt.continuation in the slope at the corner's foot radius.  Its PD
    # (regula falsi on det(A + I), to 1e-10) solves the corner's multiplier condition: the same
    # slope to 1e-8 rad (each located to 1e-10, discretisation error ≤ 1e-10).  Its end, located
    # by the failure of its certification (bisection to 1e-10), can only lie beyond the true
    # boundary, by at most the dip its dense samples and simulation cannot resolve: 3e-6 rad
    # (the budget derived in tests/test_curves.py for the same clearance check).
    sp = corner["corners"][0]
    there = corner["one_parameter"]
    assert {"PD", "boundary"} <= set(there)
    assert there["PD"].param == pytest.approx(sp.values["slope"], abs=1e-8)
    gap = there["boundary"].param - sp.values["slope"]
    assert -1e-9 < gap < 3e-6


def test_the_pd_curve_ends_on_the_boundary_at_the_corner(corner):
    # The PD curve, followed from the branch's PD at R = 0.12 m, stops where its gait stops
    # existing (certification fails, located by bisection; its last point is that end): its
    # point before the end lies before the corner, its end at or beyond it, by at most what
    # certification resolves (3e-6 rad in the slope, as above).  Two independent locations of
    # one point: a test function's zero on the boundary curve, a failed check on the PD curve.
    pd, sp = corner["pd"], corner["corners"][0]
    assert pd.message.startswith("boundary at"), pd.message
    end = next(p for p in pd.special_points if p.kind == "boundary")
    assert end.values["foot_radius"] == pytest.approx(pd.params[-1, 1], abs=1e-12)
    r_corner = sp.values["foot_radius"]
    assert pd.params[-2, 1] < r_corner <= end.values["foot_radius"] + 1e-9
    assert -1e-9 < end.values["slope"] - sp.values["slope"] < 3e-6


# -- a boundary curve of a unilateral constraint: the trailing foot's lift-off rate -------------
@pytest.fixture(scope="module")
def lift_off():
    model, branch, points = _branch(mass_hip=MASS_FROM)
    paths = (ParameterPath.of(model, "slope"), ParameterPath.of(model, "mass_hip"))
    curve = curve_from(
        points["boundary"], "boundary", paths, MASS_TO, first=branch.cycles[0], at=(MASS_AT,)
    )
    ends = {MASS_FROM: points["boundary"].param}
    ends[MASS_TO] = _branch(mass_hip=MASS_TO)[2]["boundary"].param
    return curve, ends


def test_lift_off_boundary_is_followed_as_a_curve(lift_off):
    curve, _ = lift_off
    assert curve.success and curve.message.startswith("reached mass_hip"), curve.message
    assert "lift_off of 'swing foot above the slope'" in curve.condition
    assert curve.values(1)[-1] == pytest.approx(MASS_TO, abs=1e-12)
    # Each point's gait is certified (just inside: 1e-9 of the slope's scale, more only if the
    # simulation needs it) and verified; its trailing foot lifts off, ċ > 0, but barely: by
    # rate_along on the certified orbit (an independent path from the curve's condition
    # function), above certification's 1e-9 m/s threshold and below 1e-7 m/s (≤ 1e-8 of the
    # slope's scale inside, at |∂ċ/∂γ| ≈ 5 m/s per rad).
    for cycle, (slope, _) in zip(curve.cycles, curve.params, strict=True):
        assert cycle.success and cycle.verified
        assert 0 < slope - cycle.model.slope < 1e-8
        assert 1e-9 < _lift_off_rate(cycle) < 1e-7


def test_lift_off_boundary_meets_one_parameter_continuation(lift_off):
    # Independent method: gaitopt.continuation in the slope at fixed hip mass, whose branch ends
    # where certification first fails ("must rise, but its rate is ..."), bisected to 1e-10.
    # Certification needs ċ > 1e-9 m/s, so that end lies before the zero of ċ by
    # 1e-9 / |∂ċ/∂γ| (measured here from two certified gaits); with both locations to 1e-10
    # rad: −(that + 2e-10) < gap < 2e-10.
    curve, ends = lift_off
    for mass in (MASS_FROM, MASS_TO):
        slope = slope_at(curve, mass)
        model = gaitopt.model("kneed_walker", slope=slope - 1e-5, mass_hip=mass)
        guess = curve.cycles[0 if mass == MASS_FROM else -1]
        rates = [
            _lift_off_rate(gaitopt.find_limit_cycle(model.replace(slope=s), guess, verify=False))
            for s in (slope - 1e-5, slope - 2e-5)
        ]  # fmt: skip
        sensitivity = abs(rates[1] - rates[0]) / 1e-5  # m/s per rad
        gap = ends[mass] - slope
        assert -(1e-9 / sensitivity + 2e-10) < gap < 2e-10


def test_lift_off_rate_changes_sign_across_the_curve(lift_off):
    # Independent of the curve's system: the gait solved by find_limit_cycle at the curve's
    # slope ∓ 1e-7 rad (at MASS_AT, located exactly on the curve): the lift-off rate, ∇c · f at
    # the three-link phase's start, is positive inside and negative outside (|∂ċ/∂γ| ≈ 5 m/s per
    # rad makes it ±5e-7 m/s, far above the 1e-10 residual's effect).
    curve, _ = lift_off
    slope = slope_at(curve, MASS_AT)
    guess = curve.cycles[int(np.flatnonzero(np.abs(curve.params[:, 1] - MASS_AT) < 1e-12)[0])]
    rates = []
    for offset in (-1e-7, 1e-7):
        model = gaitopt.model("kneed_walker", slope=slope + offset, mass_hip=MASS_AT)
        cycle = gaitopt.find_limit_cycle(model, guess, verify=False)
        assert cycle.residual < 1e-10
        rates.append(_lift_off_rate(cycle))
    assert rates[0] > 0 > rates[1]
