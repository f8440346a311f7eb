"""Optimal gaits of the kneed walker (hip and knee torques as profiles, issue 11 item 7)."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.errors import GaitoptInputError
from gaitopt.optimize import GaitProblem
from gaitopt.optimize.collocation import Collocation, RadauMesh
from gaitopt.optimize.verify import check_dense

# The passive gait at the default slope 0.0504 rad has period 0.564328 s and step length
# 2 sin(0.23859) = 0.4727 m (results/kneed_walker_slope/branch.csv); a step of 0.47 m in 0.5643 s
# needs a little torque.
PERIOD, STEP = 0.5643, 0.47


@pytest.fixture(scope="module")
def gait():
    model = gaitopt.model("kneed_walker")
    return gaitopt.optimize_gait(model, "effort", period=PERIOD, step_length=STEP)


def test_kneed_optimum_is_confirmed_by_simulation(gait):
    # Source: the independent event-located simulator (DOP853, rtol 1e-12) with the optimal
    # hip and knee torques as feedforward; it must return to the fixed point and give the same
    # ∫(τ_h² + τ_k²) dt to 1e-6 relative (the verification's own tolerance, never loosened).
    assert gait.success and gait.verified, gait.message
    v = gait.verification
    assert v["cost_simulated"] == pytest.approx(gait.cost, rel=1e-6)
    assert v["return_error"] <= 1e-6 * (1 + max(abs(x) for x in gait.fixed_point.values()))
    assert v["period_simulated"] == pytest.approx(PERIOD, rel=1e-6)
    # Mesh refinement: cost and orbit settled to the 1e-8 target.
    assert gait.discretisation_error <= 1e-8
    assert gait.period == pytest.approx(PERIOD, rel=1e-12)
    assert gait.step_length == pytest.approx(STEP, rel=1e-9)
    assert gait.cost > 0  # 0.47 m is not the passive gait's 0.4727 m: some torque is needed


def test_kneed_optimum_meets_every_constraint_on_dense_samples(gait):
    # Source: the model's unilateral constraints (swing foot above the slope, stance foot
    # pushing) and its guards, sampled 24 times per mesh interval on the collocation
    # polynomials (check_dense); and on the result's own orbit samples: the knee stays flexed
    # (q2 − q3 < 0) strictly inside the three-link phase, the swing foot above the slope
    # (tolerance 1e-9 m, rounding of the kinematics).
    col, w = gait.transcription
    sol = col.unpack(w, col.model.p)
    assert check_dense(col, sol) is None
    model = gait.model
    arc = gait.orbit[0]
    inside = slice(1, arc.t.size - 1)
    assert np.all(arc.x[1, inside] - arc.x[2, inside] < 0)
    clearance = model.phases[0].constraints[0]
    assert clearance.name == "swing foot above the slope"
    h = np.asarray(clearance.function.map(arc.t.size)(arc.x, arc.u, model.p)).ravel()
    assert np.min(h[1:]) >= -1e-9


def test_kneed_multipliers_ad_are_the_limit_of_finite_differences(gait):
    # Source: the simulated return map (DOP853, rtol 1e-12, the torques as a feedforward in the
    # time since the section) differentiated by the five-point stencil at h = 1e-3 and 1e-4,
    # against the AD Jacobian through the collocation (gaitopt.optimize.floquet).  The map is C¹
    # but its second derivative jumps where the knee strikes (u is continuous there,
    # GaitProblem.continuous_inputs, but u̇ is not), so the stencil's error is O(h) rather than
    # O(h⁴): measured 9e-4 at h = 1e-3 and 9e-5 at h = 1e-4 (entries up to 5.8), with rounding
    # below 1e-6 (the simulation's return error ~4e-11 over h).  So the gap must shrink about
    # tenfold with h (between 5× and 20×) and be below 2e-4 at h = 1e-4, and the moduli of the
    # multipliers must agree to 1e-5 there (2.4e-6 and 1.5e-7 measured).
    from gaitopt.optimize.floquet import multipliers_of, return_map_jacobian
    from gaitopt.optimize.verify import profiles, simulate_gait

    col, w = gait.transcription
    model = gait.model
    sol = col.unpack(w, model.p)
    profs = profiles(col, sol)
    problem = GaitProblem(model, "effort", period=PERIOD, step_length=STEP)
    A = return_map_jacobian(col, w, model.p)
    s0 = sol["s"]

    def P(s):
        sim = simulate_gait(problem, model, model.lift(s), profs, 1)
        assert sim.success
        return model.section_coordinates_of(sim.section_states[-1])

    def stencil(h):
        cols = []
        for e in np.eye(s0.size) * h:
            cols.append((-P(s0 + 2 * e) + 8 * P(s0 + e) - 8 * P(s0 - e) + P(s0 - 2 * e)) / (12 * h))
        return np.column_stack(cols)

    coarse, fine = stencil(1e-3), stencil(1e-4)
    gap_coarse, gap_fine = np.max(np.abs(coarse - A)), np.max(np.abs(fine - A))
    assert 5 < gap_coarse / gap_fine < 20
    assert gap_fine < 2e-4
    ad = np.sort(np.abs(multipliers_of(A)))
    fd = np.sort(np.abs(multipliers_of(fine)))
    np.testing.assert_allclose(ad, fd, atol=1e-5)
    assert gait.stable == bool(np.max(ad) < 1)


def test_knee_guard_keeps_its_side_inside_the_phase():
    # Source: the simulator ends a phase where a guard without an admissibility test is first
    # crossed, so the transcription requires direction · g ≤ 0 at the interior nodes of the
    # knee strike's phase; the compass gait's heel strike has an admissibility test (no such
    # rows).  Structural check: the group and its size (N·d − 1 interior nodes).
    mesh = RadauMesh(3, 3)
    kneed = Collocation(GaitProblem(gaitopt.model("kneed_walker"), "effort"), mesh)
    groups = {g.name: g for g in kneed.groups}
    knee = groups["'knee strike' not before the end of three-link swing #1"]
    assert knee.size == 3 * 3 - 1 and not knee.equality
    compass = Collocation(GaitProblem(gaitopt.model("compass_gait"), "effort"), mesh)
    assert not any("not before the end" in g.name for g in compass.groups)


def test_clearance_margin_is_c_sin_pi_t_over_the_step():
    # Source: closed form of GaitProblem.clearance: the swing foot's height must exceed
    # c·sin(π t/T) at each node, t since the step's section, T the step's duration.  Evaluated
    # on a packed guess: the constraint rows differ from the zero-margin ones by exactly the
    # margin (tolerance 1e-12, rounding).
    model = gaitopt.model("kneed_walker")
    mesh = RadauMesh(2, 3)
    plain = Collocation(GaitProblem(model, "effort"), mesh)
    margin = Collocation(GaitProblem(model, "effort", clearance=0.01), mesh)
    rng = np.random.default_rng(3)
    w = rng.uniform(0.1, 0.3, plain.blocks.size)
    durations = [0.3, 0.2]
    for k, T in enumerate(durations):
        plain.blocks.put(w, f"T{k}", T)
    g0 = np.asarray(plain.constraints(w, model.p)).ravel()
    g1 = np.asarray(margin.constraints(w, model.p)).ravel()
    name = "'swing foot above the slope' (three-link swing #1)"
    group = next(g for g in plain.groups if g.name == name)
    sl = slice(group.start, group.start + group.size)
    t = plain.node_times()[1:] * durations[0]
    np.testing.assert_allclose(g0[sl] - g1[sl], 0.01 * np.sin(np.pi * t / sum(durations)),
                               rtol=0, atol=1e-12)  # fmt: skip


@pytest.mark.parametrize(
    ("option", "value"), [("clearance", -0.01), ("clearance", "x"), ("guard_margin", np.inf)]
)
def test_bad_margins_are_named(option, value):
    # Source: house rule — bad input names the argument and shows the value.
    with pytest.raises(GaitoptInputError, match=option):
        GaitProblem(gaitopt.model("kneed_walker"), "effort", **{option: value})


def test_inputs_are_continuous_where_the_knee_strikes(gait):
    # GaitProblem.continuous_inputs (default): the torque profile, a function of the time since
    # the section, has no jump at the phase change inside a step.  The end of the first phase's
    # profile and the start of the second's (its polynomial at τ = 0) agree to the constraint
    # tolerance (IPOPT's 1e-11).
    col, w = gait.transcription
    sol = col.unpack(w, col.model.p)
    u_end = sol["U"][0][:, -1]
    u_start = sol["U"][1][:, : col.d] @ col.u_at_start
    np.testing.assert_allclose(u_start, u_end, atol=1e-9)
    assert any(g.name.startswith("inputs continuous after") for g in col.groups)


def test_continuous_inputs_is_a_boolean():
    model = gaitopt.model("kneed_walker")
    with pytest.raises(GaitoptInputError, match="continuous_inputs"):
        GaitProblem(model, "effort", period=PERIOD, continuous_inputs="yes")
    free = GaitProblem(model, "effort", period=PERIOD, continuous_inputs=False)
    assert free.describe()["continuous_inputs"] is False
