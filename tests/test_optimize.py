"""Optimal gait synthesis (issue 11) on the compass gait: passive limit, convergence, trust.

Sources of the expected values: the passive gait from :func:`gaitopt.find_limit_cycle`
(multiple shooting, an independent transcription) — on a slope, the least-effort gait at the
passive gait's period and step length must be the passive gait itself at zero effort; exact
derivatives against central differences; the optimum against the independent event-located
simulator; the multipliers by AD through the collocation against finite differences of the
simulated map.
"""

from __future__ import annotations

import json

import casadi as ca
import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.optimize import Collocation, GaitProblem, RadauMesh, optimize_gait
from gaitopt.optimize.collocation import Arc
from gaitopt.optimize.verify import feedforward_of, simulated_cost

LEVEL = {"period": 0.8, "step_length": 0.3}


@pytest.fixture(scope="module")
def passive():
    model = gaitopt.model("compass_gait")  # Drake defaults, slope 0.0525 rad
    cycle = gaitopt.find_limit_cycle(model)
    x = model.state_vector(cycle.fixed_point)
    points = np.asarray(model.phases[0].points(x, model.p), dtype=float)
    # Distance between the feet at heel strike = at the section (the legs only swap names).
    step = float(np.linalg.norm(points[:, model.phases[0].point_names.index("swing_foot")]))
    return model, cycle, step


@pytest.fixture(scope="module")
def level():
    model = gaitopt.model("compass_gait", slope=0.0)
    return model, optimize_gait(model, **LEVEL)


def test_passive_gait_is_the_zero_effort_optimum(passive):
    model, cycle, step = passive
    gait = optimize_gait(model, period=cycle.period, step_length=step)
    assert gait.success, gait.message
    assert gait.cost <= 1e-8  # zero effort: the passive gait needs no torque
    x_opt = np.array([gait.fixed_point[n] for n in model.state_names])
    x_ref = np.array([cycle.fixed_point[n] for n in model.state_names])
    np.testing.assert_allclose(x_opt, x_ref, atol=1e-6)  # shooting's fixed point, to 1e-6
    # Same return map with u ≡ 0: the shooting's multipliers (to 1e-6).
    np.testing.assert_allclose(
        np.sort_complex(gait.multipliers), np.sort_complex(cycle.multipliers), atol=1e-6
    )


def test_free_parameter_recovers_the_passive_leg(passive):
    # `free=("a",)`: the hip-to-leg-mass distance a is a decision variable.  Started at
    # a = 0.45 m with the period and step length of the passive gait of a = 0.5 m (Drake),
    # the least effort is zero, reached only by the passive gait itself (fixed point and two
    # gait constraints fix the one free parameter): a = 0.5 to 1e-6, shooting's fixed point.
    model, cycle, step = passive
    gait = optimize_gait(model.replace(a=0.45), period=cycle.period, step_length=step, free=("a",))
    assert gait.success, gait.message
    assert gait.cost <= 1e-8
    assert gait.params["a"] == pytest.approx(0.5, abs=1e-6)
    x_opt = np.array([gait.fixed_point[n] for n in model.state_names])
    x_ref = np.array([cycle.fixed_point[n] for n in model.state_names])
    np.testing.assert_allclose(x_opt, x_ref, atol=1e-6)


def test_level_ground_optimum_is_verified_and_converged(level):
    model, gait = level
    assert gait.success, gait.message
    assert gait.verified
    assert gait.period == pytest.approx(0.8, rel=1e-12)
    assert gait.step_length == pytest.approx(0.3, rel=1e-10)
    # Discretisation error by refinement (cost and orbit), driven below 1e-8 relative.
    assert gait.discretisation_error <= 1e-8
    # The independent simulation with u(t) as feedforward returns to the fixed point (1e-8,
    # simulation rtol 1e-12) with the same cost (quadrature of the simulated orbit, 1e-8).
    assert gait.verification["return_error"] <= 1e-8
    assert gait.verification["cost_simulated"] == pytest.approx(gait.cost, rel=1e-8)
    assert gait.active_constraints == ["period (fixed)", "step length (fixed)"]


def test_simulation_with_the_profile_reproduces_the_cost(level):
    model, gait = level
    x0 = model.state_vector(gait.fixed_point)
    sim = gaitopt.simulate(
        model, x0, steps=1, feedforward=feedforward_of(gait.profiles), rtol=1e-12, atol=1e-13
    )
    assert sim.success
    # Independent simulator (DOP853 + located events) against the collocation: 1e-8.
    np.testing.assert_allclose(sim.section_states[-1], x0, atol=1e-8)
    assert sim.section_times[-1] == pytest.approx(0.8, abs=1e-8)
    problem = GaitProblem(model, **LEVEL)
    assert simulated_cost(problem, model, sim, gait.profiles) == pytest.approx(gait.cost, rel=1e-8)


def test_multipliers_two_ways(level):
    _, gait = level
    # AD through the transcription vs central differences (h = 1e-6) of the simulated map
    # (rtol 1e-12).  The held input makes the map's second derivative jump at the orbit (a
    # longer step sees the last value, a shorter one the polynomial), so the FD error is O(h)
    # plus integrator noise ~rtol/h: ~1e-6.
    ad = np.sort_complex(gait.multipliers)
    fd = np.sort_complex(gait.multipliers_fd)
    assert ad.size == 3 and fd.size == 3
    np.testing.assert_allclose(ad, fd, atol=1e-5)
    assert gait.stable is False  # |μ| = 1.34 > 1: the open-loop optimum is unstable


def test_cost_converges_fast_under_refinement():
    # Radau IIA of degree d: cost error O(h^(2d−1)); with d = 3 doubling the mesh divides
    # successive differences by ~2^5 = 32 (at least 16 asserted).
    problem = GaitProblem(gaitopt.model("compass_gait", slope=0.0), **LEVEL)
    costs = []
    for intervals in (2, 4, 8):
        col = Collocation(problem, RadauMesh(intervals, 3))
        gait = optimize_gait(problem.model, mesh=col.mesh, tol=1.0, verify=False, **LEVEL)
        costs.append(gait.cost)
    d1, d2 = abs(costs[1] - costs[0]), abs(costs[2] - costs[1])
    assert d2 < d1 / 16


@pytest.mark.parametrize("structured", [False, True])
def test_nlp_gradient_matches_finite_differences(structured):
    model = gaitopt.model("compass_gait", slope=0.0)
    problem = GaitProblem(model, cost="work", bounds={"hip_torque": 20.0}, **LEVEL)
    # Slack powers, or the switching-time transcription (arcs + − + of free durations).
    structure = [[Arc(1, (1,), 0.2), Arc(1, (-1,), 0.5), Arc(1, (1,), 0.3)]] if structured else None
    col = Collocation(problem, RadauMesh(3, 3), structure)
    rng = np.random.default_rng(1)
    w = rng.uniform(0.1, 0.9, col.nlp["x"].shape[0])
    p = problem.model.p
    f = ca.Function("f", [col.nlp["x"], col.nlp["p"]], [col.nlp["f"], col.nlp["g"]])
    jac = f.factory("derivatives", ["i0", "i1"], ["jac:o0:i0", "jac:o1:i0"])
    grad, J = (np.asarray(v, dtype=float) for v in jac(w, p))
    h = 1e-6
    for j in rng.choice(w.size, 8, replace=False):
        e = np.zeros_like(w)
        e[j] = h
        fp, gp = (np.asarray(v, dtype=float).ravel() for v in f(w + e, p))
        fm, gm = (np.asarray(v, dtype=float).ravel() for v in f(w - e, p))
        # Central differences: truncation O(h²) ~ 1e-12, rounding ~1e-10 relative.
        assert grad[0, j] == pytest.approx((fp[0] - fm[0]) / (2 * h), rel=1e-6, abs=1e-6)
        np.testing.assert_allclose(J[:, j], (gp - gm) / (2 * h), rtol=1e-6, atol=1e-6)


def test_infeasible_requests_name_the_constraint():
    model = gaitopt.model("compass_gait", slope=0.0)
    # Legs of 1 m: feet at most 2 m apart.
    # Refused before any solve by the geometry (max_step_length = 2 (a + b) = 2 m), naming the
    # step length and the limit, as a gait that does not exist (not a solver failure).
    long = optimize_gait(model, period=0.8, step_length=2.5, verify=False)
    assert not long.success and long.cost is None and long.status == "not_a_gait"
    assert "step length of 2.5 m" in long.message and "(2 m," in long.message
    weak = optimize_gait(model, bounds={"hip_torque": 0.5}, verify=False, **LEVEL)
    assert not weak.success and weak.cost is None
    assert "|hip_torque| <= 0.5" in weak.message


def test_multistart_is_seeded_and_reports_minima():
    model = gaitopt.model("compass_gait", slope=0.0)
    a = optimize_gait(model, starts=3, seed=7, verify=False, **LEVEL)
    b = optimize_gait(model, starts=3, seed=7, verify=False, **LEVEL)
    assert a.success
    assert [m.starts for m in a.minima] == [m.starts for m in b.minima]
    assert sum(len(m.starts) for m in a.minima) <= 3
    # Every minimum is refined and certified; the result is the lowest certified one.
    assert a.cost == pytest.approx(min(m.cost for m in a.minima), rel=1e-12)
    assert all(m.discretisation_error <= 1e-8 for m in a.minima)
    assert not any(m.verified for m in a.minima)  # verify=False: nothing was simulated


def test_bad_input_is_one_error():
    model = gaitopt.model("compass_gait")
    with pytest.raises(gaitopt.GaitoptInputError, match="cost"):
        optimize_gait(model, cost="efort")
    with pytest.raises(gaitopt.GaitoptInputError, match="hip_torque"):
        optimize_gait(model, bounds={"hip": 1.0})
    with pytest.raises(gaitopt.GaitoptInputError, match="period"):
        optimize_gait(model, period=-1)
    # Positive work has no minimum without input bounds (impulses approach its infimum).
    with pytest.raises(gaitopt.GaitoptInputError, match="bound on every input"):
        optimize_gait(model, cost="work", period=0.8)


OPTIMIZE_KEYS = {
    "model", "params", "success", "message", "cost_kind", "cost", "period", "step_length",
    "speed", "fixed_point", "inputs", "multipliers", "stable", "verified",
    "discretisation_error", "active_constraints",
}  # fmt: skip


def test_cli_json_and_exit_codes(capsys):
    argv = ["optimize", "compass_gait", "--set", "slope=0", "--fix", "period=0.8"]
    status = main([*argv, "--fix", "step_length=0.3", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert status == 0
    assert OPTIMIZE_KEYS <= set(report)
    assert set(report["inputs"]) == {"time", "hip_torque"}
    assert all(len(m) == 2 for m in report["multipliers"])  # [re, im]
    status = main([*argv, "--fix", "step_length=2.5", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert status == 1 and report["success"] is False and report["cost"] is None
    assert main([*argv, "--bound", "hip=1"]) == 2
    assert "hip_torque" in capsys.readouterr().err
