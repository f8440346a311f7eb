"""Least effort with an active input bound, certified by arcs (issue 24, item 3).

The compass gait on level ground, 0.3 m in 0.8 s, |τ| ≤ 4 N·m: without arcs the kink where the
torque meets its bound falls inside a mesh interval and the refinement stalled at 2.5e-6
(``success: false``, cost 8.101306124 on 48 intervals).  With the arcs of the bound
(:func:`gaitopt.optimize.arcs.detect_bound_arcs`: the torque fixed at −4 on the saturated arcs,
collocated on the free one, the junction times unknowns) it is certified.
"""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
import gaitopt.optimize.solve as solve
from gaitopt.optimize import optimize_gait
from gaitopt.optimize.arcs import describe_bounds, detect_bound_arcs
from gaitopt.optimize.attempt import _collocation, attempt
from gaitopt.optimize.collocation import RadauMesh, lagrange_matrix

#: Issue 24's independent check of the bounded optimum (right to 8e-7 relative): the stalled
#: refinement's value on 48 intervals.
ISSUE_COST = 8.101306124
#: The same problem without arcs, on a uniform mesh of 192 intervals of degree 6 (the input
#: bound at the nodes only, so a little below the optimum; 96 intervals: 8.101303679318):
#: 8.10130369058398, measured with the exact differentiation matrix, warm-started from the
#: certified optimum (8.101303692109932 with the fitted one, whose bias grew with the mesh).
UNIFORM_192 = 8.10130369058398
#: README's least effort without bounds (optimal-gaits table), 10 digits.
UNBOUNDED = 6.668848534
BOUND = 4.0


@pytest.fixture(scope="module")
def compass():
    return gaitopt.model("compass_gait", slope=0)


@pytest.fixture(scope="module")
def bounded(compass):
    return optimize_gait(
        compass, "effort", period=0.8, step_length=0.3, bounds={"hip_torque": BOUND}
    )


def _junctions(gait):
    """Arc boundaries (s since the section) of the single phase and its arcs."""
    col, w = gait.transcription
    theta = col.theta_of(w, 0)
    edges = gait.period * np.concatenate([[0.0], np.cumsum(theta)])
    return col, w, edges


def test_bounded_effort_is_certified(bounded):
    gait = bounded
    assert gait.success, gait.message
    assert gait.verified
    # Issue 24's reference, to 1e-6 relative (its own stated accuracy is 8e-7).
    assert gait.cost == pytest.approx(ISSUE_COST, rel=1e-6)
    # The brute-force uniform mesh of 192 intervals, to 2e-9 relative (it sits 9.2e-9 below:
    # bounds at its nodes only, and its own discretisation error).
    assert gait.cost == pytest.approx(UNIFORM_192, rel=2e-9)
    # Certified like an unbounded optimum: below the default target 1e-8.
    assert gait.discretisation_error <= 1e-8
    # The independent simulation returns to the fixed point and costs the same (the
    # certificate's own tolerances are 1e-6; measured 4e-13 and 2e-14).
    assert gait.verification["return_error"] <= 1e-9
    assert gait.verification["cost_error"] <= 1e-9
    assert "arcs of the input bounds [lo free lo]" in gait.message


def test_saturated_arcs_are_at_the_bound(bounded):
    gait = bounded
    col, w, edges = _junctions(gait)
    structure = col.structure
    assert describe_bounds(structure, gait.model.inputs) == "[lo free lo]"
    profile = gait.profiles[0]
    for a, arc in enumerate(structure[0]):
        inside = np.linspace(edges[a], edges[a + 1], 2001)[1:-1]
        u = profile.vectorised(inside)[0]
        if arc.bounds[0]:
            # u ≡ −4 on a saturated arc, to 1e-12 (the profile is the constant polynomial).
            assert np.max(np.abs(u + BOUND)) <= 1e-12
        else:
            # Strictly inside the bound on the free arc (the profile is checked between the
            # nodes too); to 1e-12 at worst at its ends, where it meets the bound.
            assert np.max(np.abs(u)) <= BOUND + 1e-12
    # active_constraints: the bound and its arcs (no times: a library's points with the same
    # arcs share an active set); the message gives the saturated arcs' times.
    active = gait.active_constraints
    assert "|hip_torque| <= 4" in active
    assert "arcs of the input bounds [lo free lo]" in active
    assert "at the bound: hip_torque = -4 on [0, 0.40" in gait.message
    assert gait.message.count("hip_torque = -4 on [") == 2


def test_pontryagin_junctions(bounded):
    """Least effort: u = sat(−Bᵀλ/2) with λ continuous, so u is smooth on the free arc and
    meets the bound continuously at the junctions.  The transcription imposes that continuity
    (the junction time alone is pinned only to third order: a junction off by δ costs ~|u̇|²δ³
    with |u̇| ≈ 64 N·m/s here): the free arc's ends meet the bound to roundoff, tolerance
    1e-9 N·m (measured 2.7e-15); without the rows they missed by 2.2e-4 and 7.3e-4 N·m, and a
    junction misplaced into a free interval by 0.17 N·m (6 intervals)."""
    gait = bounded
    col, w, edges = _junctions(gait)
    sol = col.unpack(w, gait.model.p)
    U, d = sol["U"][0][0], col.d
    ends = lagrange_matrix(col.tau[1:], np.array([0.0, 1.0]))
    first = 0
    values = []
    for arc in col.structure[0]:
        values.append(
            [U[j * d : (j + 1) * d] @ ends.T for j in range(first, first + arc.intervals)]
        )
        first += arc.intervals
    free = values[1]
    # Smooth on the free arc: consecutive interval polynomials agree at their common point
    # (measured 9.0e-7 N·m at most; the collocated input is not continuous by construction).
    jumps = [abs(a[1] - b[0]) for a, b in zip(free[:-1], free[1:], strict=True)]
    assert max(jumps) <= 1e-5
    # At the junctions the free arc meets the bound.
    assert abs(free[0][0] + BOUND) <= 1e-9
    assert abs(free[-1][1] + BOUND) <= 1e-9
    # The junctions are where the arcs say (0.408 s and 0.774 s, inside the step).
    assert 0.0 < edges[1] < edges[2] < gait.period


def test_first_arcs_find_the_junctions(bounded):
    """The first solution with arcs (6 intervals, from the first solution's nodes at the
    bound) already has its junctions where the certified optimum has them: u is continuous
    there (imposed), so the kink where it leaves the bound cannot hide inside the free arc's
    first interval.  Tolerances 1e-4 s and 1e-6 relative (measured 2.3e-6 s, 2.1e-5 s and
    1.3e-7); without the junction continuity that solution put the first junction 4.9e-3 s
    early, 8.2e-6 below the optimum, and the refinement crept towards it at order ~3 (error
    1.2e-7 after three doublings: not certified)."""
    col, w, edges = _junctions(bounded)
    problem, p = col.problem, bounded.model.p
    first = _collocation(problem, solve.DEFAULT_MESH)
    run = attempt(first, problem, 0, 0, None)  # the default start, as optimize_gait's
    assert run["ok"], run["reason"]
    structure = detect_bound_arcs(first, run["w"], p)
    assert describe_bounds(structure, bounded.model.inputs) == "[lo free lo]"
    arcs = _collocation(problem, RadauMesh(sum(a.intervals for a in structure[0]), first.d),
                        structure)  # fmt: skip
    w6, stats = solve._run(arcs, arcs.from_solution(first, run["w"], p), p)
    assert solve._converged(stats), stats.get("return_status")
    assert arcs.N == 6
    edges6 = bounded.period * np.concatenate([[0.0], np.cumsum(arcs.theta_of(w6, 0))])
    assert np.max(np.abs(edges6[1:3] - edges[1:3])) <= 1e-4
    assert arcs.unpack(w6, p)["cost"] == pytest.approx(bounded.cost, rel=1e-6)


def test_refinement_settles(bounded):
    """One more doubling of the certified transcription (24 → 48 intervals, the arcs' too)
    changes the cost by roundoff only.  Tolerance 1e-10 relative (measured 6.5e-13); with the
    differentiation matrix fitted by least squares the cost rose with every doubling (1.6e-9
    relative from 48 to 96 intervals) and 96 intervals did not converge."""
    col, w = bounded.transcription
    p = bounded.model.p
    fine = solve._refined(col)
    w2, stats = solve._run(fine, fine.from_solution(col, w, p), p)
    assert solve._converged(stats), stats.get("return_status")
    assert fine.N == 2 * col.N
    assert fine.unpack(w2, p)["cost"] == pytest.approx(bounded.cost, rel=1e-10)


def test_inactive_bound_leaves_the_unbounded_optimum(compass):
    """|τ| ≤ 100 N·m is inactive (the unbounded optimum peaks at 5.23 N·m): no arcs, the
    unbounded optimum to 1e-9 relative (and README's 10 digits)."""
    free = optimize_gait(compass, "effort", period=0.8, step_length=0.3)
    loose = optimize_gait(
        compass, "effort", period=0.8, step_length=0.3, bounds={"hip_torque": 100.0}
    )
    assert free.success and loose.success, (free.message, loose.message)
    assert loose.cost == pytest.approx(free.cost, rel=1e-9)
    assert loose.cost == pytest.approx(UNBOUNDED, rel=1e-9)
    assert "arcs" not in loose.message
    col, _ = loose.transcription
    assert col.structure is None
    assert not any(a.startswith("arcs") for a in loose.active_constraints)
    assert "at the bound" not in loose.message


@pytest.mark.slow  # ≥ 25 s: run by `make test-slow` (CI runs both)
def test_five_link_with_an_active_torque_bound():
    """OptimTraj's five-link problem (0.4 m in 0.6 s, |q| ≤ π/2, |q̇| ≤ 10) with |u| ≤ 25 N·m
    instead of 100, warm-started from the unbounded optimum (start 4, seed 0: README's
    263.6988459642), which peaks at 28.06 N·m in the swing knee and below 20.2 N·m elsewhere,
    so only the swing knee's bound is active, on one arc after heel strike.  Certified with
    that arc: 263.8033335518 (to 1e-8 relative; measured 263.80333355161 with the exact
    differentiation matrix, 263.8033335518 with the fitted one), discretisation error 3.4e-9,
    the simulation's return 2.6e-11 and cost 5.1e-14.  Not from start 4 cold: its IPOPT path
    through 40 iterations of tiny steps reached this minimum only by the luck of roundoff (with
    the fitted matrix, Solved_To_Acceptable_Level after 116 iterations; with the exact one the
    paths agree to 7 digits for 40 iterations, part, and it stops at 1000)."""
    model = gaitopt.model("five_link_biped")
    unbounded = optimize_gait(
        model,
        period=0.6,
        step_length=0.4,
        bounds={name: high for name, (_, high) in model.input_bounds.items()},
        state_bounds=model.state_bounds,
        starts=[4],
        seed=0,
    )
    assert unbounded.success, unbounded.message
    gait = optimize_gait(
        model,
        period=0.6,
        step_length=0.4,
        bounds={name: 25.0 for name in model.inputs},
        state_bounds=model.state_bounds,
        guess=unbounded,
    )
    assert gait.success and gait.verified, gait.message
    assert gait.discretisation_error <= 1e-8
    # A bound that binds costs more than the unbounded optimum (README: 263.6988459642).
    assert gait.cost > 263.6988459642
    assert gait.cost == pytest.approx(263.8033335518, rel=1e-8)
    assert "|swing_knee_torque| <= 25" in gait.active_constraints
    assert "arcs of the input bounds [free/free/free/hi free/free/free/free]" in (
        gait.active_constraints
    )
    assert "at the bound: swing_knee_torque = 25 on [0, 0.03" in gait.message
    u = gait.profiles[0].vectorised(np.linspace(0.0, gait.period, 6001))
    assert np.max(np.abs(u)) <= 25.0 + 1e-12
