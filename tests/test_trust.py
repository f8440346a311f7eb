"""Never a false gait: unilateral constraints, and a solve that finds the gait the user means.

Regression tests of the cases that once went wrong (a kneed-walker gait whose trailing foot never
left the ground, reported as verified; solves that found the wrong gait or none from the default
start although the default gait continues to the requested parameters).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import gaitopt
from gaitopt.shooting import shooting_problem

# -- unilateral constraints ----------------------------------------------------------------------


def test_every_walker_declares_its_physical_conditions():
    # The model contract: a kneed walker's swing foot clears the slope in both phases and lifts
    # off after heel strike; every walker's stance contact pushes; the SLIP's leg pushes.
    kneed = gaitopt.model("kneed_walker")
    outcomes = [[c.outcome for c in ph.constraints] for ph in kneed.phases]
    assert outcomes == [["trip", "stance foot lifts off"], ["trip", "stance foot lifts off"]]
    assert kneed.phases[0].constraints[0].at_start and kneed.phases[1].constraints[0].at_end
    for name in ("compass_gait", "simplest_walker"):
        assert [c.outcome for c in gaitopt.model(name).phases[0].constraints] == [
            "stance foot lifts off"
        ]
    slip = gaitopt.model("slip")
    assert [c.name for ph in slip.phases for c in ph.constraints] == ["leg force compressive"]


def test_kneed_walker_whose_trailing_foot_does_not_lift_off_is_no_gait():
    # Once reported as success and verified: at slope 0.2 from this guess Newton converges to an
    # orbit whose trailing foot goes down into the slope after heel strike (about 25 mm deep).
    model = gaitopt.model("kneed_walker", slope=0.2)
    cycle = gaitopt.find_limit_cycle(model, {"q1": -0.19, "q1_dot": 1.11, "q2_dot": -2.41})
    assert not cycle.success
    assert "trip" in cycle.message and "swing foot above the slope" in cycle.message
    assert cycle.as_dict()["stable"] is None and cycle.as_dict()["multipliers"] == []


def test_simulation_ends_in_a_named_trip_where_the_foot_does_not_lift_off():
    # The independent simulation treats a constraint that fails as a terminal event: a trailing
    # foot that moves down into the slope from its start ends the motion at once as a "trip".
    model = gaitopt.model("kneed_walker", slope=0.2)
    sim = gaitopt.simulate(model, {"q1": -0.19, "q1_dot": 1.11, "q2_dot": -2.41}, steps=1)
    assert sim.status == "fell" and not sim.success
    assert [e.transition for e in sim.events] == ["trip"]
    assert sim.events[0].t == 0.0 and "does not rise" in sim.message


def test_constraint_checks_agree_with_the_clearance_computed_by_hand():
    # The clearance constraint of the three-link phase is the swing foot's height above the slope,
    # n · r_foot, computed here from the drawing points (an independent path through the
    # geometry): equal to 1e-12 along the default gait.
    gait = gaitopt.find_limit_cycle(gaitopt.model("kneed_walker"))
    model, p = gait.model, gait.model.p
    phase = model.phases[0]
    clearance = phase.constraints[0].function
    n = np.array([math.sin(model.slope), math.cos(model.slope)])
    arc = gait.orbit[0]
    for j in range(0, arc.x.shape[1], 7):
        pts = np.asarray(phase.points(arc.x[:, j], p))
        foot = pts[:, phase.point_names.index("swing_foot")]
        assert float(clearance(arc.x[:, j], [], p)) == pytest.approx(float(n @ foot), abs=1e-12)


def test_kneed_walker_branch_ends_where_the_trailing_foot_stops_lifting_off():
    # Continuation in the slope from the unstable period-1 gait at 0.118 (past its period
    # doubling at 0.1062): the branch must end at a boundary where the clearance constraint becomes
    # active, not run on into the ground.  Independent check at the boundary's last gait: the
    # trailing foot's lift-off speed after heel strike (the constraint's rate, computed here by
    # AD of the model's foot height along its flow) is positive but near zero, or the foot's
    # lowest interior height is near zero (the other way the foot stops clearing).
    start = gaitopt.find_limit_cycle(gaitopt.model("kneed_walker", slope=0.118))
    assert start.success
    branch = gaitopt.continuation(start.model, "slope", to=0.13, start=start, cascade=False)
    end = branch.special_points[-1]
    assert end.kind == "boundary"
    assert "trip" in end.message
    # Located to 1e-10 in the slope like the other special points; the estimate of where
    # the lift-off speed vanishes is "near 0.1197".
    assert 0.1190 < end.param < 0.1200
    gait = end.cycle
    model, p = gait.model, gait.model.p
    phase = model.phases[0]
    c = phase.constraints[0]
    rate = float(gaitopt.hybrid.rate_along(phase.flow, c.function)(gait.orbit[0].x[:, 0], [], p))
    heights = [float(c.function(x, [], p)) for x in gait.orbit[0].x[:, 1:].T]
    assert rate > 0 and min(heights) > -1e-9
    assert rate < 1e-2 or min(heights) < 1e-3


def test_dense_constraint_check_rejects_an_orbit_through_the_ground():
    # certify's dense check on its own: the kneed walker's default gait with the slope raised in
    # the parameter vector only (the orbit unchanged) puts the swing foot under the slope.
    gait = gaitopt.find_limit_cycle(gaitopt.model("kneed_walker"))
    problem = shooting_problem(type(gait.model), gait.discretisation, 1)
    steeper = gait.model.replace(slope=0.25)
    defect = gaitopt.shooting.check_constraints(
        steeper, problem, gait.orbit, np.zeros(0), steeper.p
    )
    assert defect is not None and "swing foot above the slope" in defect


# -- the gait the user means ---------------------------------------------------------------------


@pytest.mark.parametrize("mass_hip", [0.5, 20.0, 50.0])
def test_compass_gait_at_other_masses_follows_the_default_stable_gait(mass_hip):
    # Once: "may not exist" at 20 and 0.5, the unstable gait (multiplier 4.56) at 50.  The default
    # gait followed from m_h = 10 is found and stable; independent check: continuation of the
    # default gait in mass_hip (pseudo-arclength) lands on the same fixed point, 1e-8.
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait", mass_hip=mass_hip))
    assert cycle.success and cycle.stable
    assert "homotopy" in cycle.route
    branch = gaitopt.continuation(gaitopt.model("compass_gait"), "mass_hip", to=mass_hip)
    assert branch.cycles[-1].model.mass_hip == pytest.approx(mass_hip, abs=1e-12)
    np.testing.assert_allclose(branch.cycles[-1].x, cycle.x, atol=1e-8)


def test_compass_gait_at_a_small_slope_is_the_stable_long_step_gait():
    # Once the unstable short-step gait (period 0.6176 s) at slope 0.01; the default gait
    # followed from 0.0525 is the stable long-step one (period 0.6962 s, multiplier 0.553).
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait", slope=0.01))
    assert cycle.success and cycle.stable
    assert cycle.period == pytest.approx(0.69621651, abs=1e-7)


@pytest.mark.parametrize("mu", [5.0, 10.0])
def test_vanderpol_far_from_mu_1_is_found_from_the_default(mu):
    # Once a failure from the μ = 1 start (and, for μ = 10, a mesh that stopped refining along
    # the homotopy).  Independent check: the nontrivial multiplier is exp(∮ −μ (q² − 1) dt)
    # (Liouville), by Simpson quadrature of the orbit's samples, 1e-6 relative; at μ = 10 the
    # period is 19.078 s (the pseudo-arclength continuation's value, 1e-3 s).
    cycle = gaitopt.find_limit_cycle(gaitopt.model("vanderpol", mu=mu))
    assert cycle.success and "homotopy" in cycle.route
    from scipy.integrate import simpson

    integral = sum(simpson(-mu * (a.x[0] ** 2 - 1), x=a.t) for a in cycle.orbit)
    assert abs(cycle.multipliers[0]) == pytest.approx(math.exp(integral), rel=1e-6)
    if mu == 10.0:
        assert cycle.period == pytest.approx(19.078, abs=1e-3)


def test_multi_start_finds_both_of_garcias_gaits_deterministically():
    # Garcia et al. 1998, γ = 0.009: the stable long-step gait θ* = 0.20031090049483 and the
    # unstable short-step one θ* = 0.19393736960624 (1e-9); the same seed gives the same list.
    model = gaitopt.model("simplest_walker")
    first = gaitopt.find_limit_cycle(model, starts=32, seed=0)
    again = gaitopt.find_limit_cycle(model, starts=32, seed=0)
    thetas = sorted(g["fixed_point"]["theta"] for g in first.gaits)
    assert thetas == pytest.approx([0.19393736960624, 0.20031090049483], abs=1e-9)
    assert [g["fixed_point"] for g in first.gaits] == [g["fixed_point"] for g in again.gaits]
    stable = {round(g["fixed_point"]["theta"], 6): g["stable"] for g in first.gaits}
    assert stable == {0.193937: False, 0.200311: True}
    assert sum(g["starts"] for g in first.gaits) <= 32


def test_lost_gait_is_reported_with_where_and_why():
    # The rimless wheel at slope 0.03 has no rolling gait (closed form: ω* < ω₁); the failure
    # says so and says what to try next, with null numbers.
    cycle = gaitopt.find_limit_cycle(gaitopt.model("rimless_wheel", slope=0.03))
    assert not cycle.success
    assert "--starts" in cycle.message or "closed form" in cycle.message
    assert cycle.as_dict()["stable"] is None


def test_a_period_doubling_just_before_a_boundary_is_not_stepped_over():
    # Curved feet R = 0.1 m: the branch's last regular step once jumped from a multiplier of
    # −0.90 straight to the clearance boundary (−1.18) and reported no period doubling.
    # Independent value: the two-parameter PD curve through R = 0.1 m (gaitopt.curves, the
    # extended system with det(A + I) = 0) puts it at slope 0.11604564 rad; 1e-7.
    model = gaitopt.model("kneed_walker", foot_radius=0.1)
    branch = gaitopt.continuation(model, "slope", to=0.13, cascade=False)
    kinds = [sp.kind for sp in branch.special_points]
    assert kinds == ["PD", "boundary"]
    assert branch.special_points[0].param == pytest.approx(0.11604564, abs=1e-7)
    assert branch.special_points[0].param < branch.special_points[1].param
