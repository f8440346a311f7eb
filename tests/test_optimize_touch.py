"""Touch points of state bounds and path constraints as free mesh points (issue 24, item 4).

Reference problem: the compass gait on level ground, step 0.3 m in 0.8 s, least effort (its
free optimum 6.668848534 N²·m²·s is pinned by tests/test_optimize.py).  The swing leg's angle
has an interior minimum there, −0.5005 rad at t = 0.55 s (measured on that optimum), so the bound
``swing >= -0.45`` binds at a touch point inside the step: the swing angle is of second order in
the hip torque, so the optimum meets the bound at an instant with ``c = 0`` and ``ċ = 0`` (Bryson
& Ho 1975, §3.11).  Without the touch point as a mesh point the optimum is uncertifiable: the
polynomial dips 8.5e-6 rad below the bound between the nodes at 48 intervals and the cost
changes by 5.3e-4 under mesh doubling (measured on the commit before gaitopt.optimize.
state_arcs).  The checks here are independent of the transcription's own claims: dense samples
of the polynomials, the independent simulation, and uniform meshes without a touch junction.
"""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.optimize import optimize_gait
from gaitopt.optimize.attempt import _collocation, _converged, _run
from gaitopt.optimize.collocation import LIMIT_TOL, RadauMesh
from gaitopt.optimize.state_arcs import detect_touches
from gaitopt.optimize.verify import feedforward_of

LOW = -0.45  # rad: the bound on the swing angle, inside the free optimum's minimum −0.5005
LABEL = "swing >= -0.45"


@pytest.fixture(scope="module")
def touched():
    return optimize_gait(
        gaitopt.model("compass_gait", slope=0),
        period=0.8,
        step_length=0.3,
        state_bounds={"swing": (LOW, np.inf)},
    )


def _junction(gait) -> float:
    """The time (s) of the single phase's touch junction."""
    col, w = gait.transcription
    (arcs,) = col.structure
    a = next(j for j, arc in enumerate(arcs) if LABEL in arc.touches)
    return float(gait.period * np.sum(col.theta_of(w, 0)[: a + 1]))


def test_touch_point_is_a_junction_and_certified(touched):
    gait = touched
    assert gait.success and gait.verified, gait.message
    # Certified: the refinement settles below the default target (measured 1.3e-10).
    assert gait.discretisation_error <= 1e-8
    assert f"touch points of {LABEL} (single support)" in gait.active_constraints
    assert f"{LABEL} at " in gait.message
    # The junction is where the free optimum's swing angle has its minimum, shifted a little by
    # the bound (free: 0.55 s on 8 samples per interval; measured 0.5437 s).
    t_touch = _junction(gait)
    assert 0.5 < t_touch < 0.6
    (span,) = gait.active_spans[f"{LABEL} (single support)"]
    assert span[0] == pytest.approx(t_touch, abs=1e-9)


def test_touch_point_holds_on_dense_samples_and_in_simulation(touched):
    gait = touched
    col, w = gait.transcription
    sol = col.unpack(w, col.model.p)
    (breaks,) = sol["breaks"]
    # 64 uniform samples per mesh interval, the certificate's dense check (samples of each
    # interval, so the touch junction itself is one), with its rule c ≥ −1e-9 (1 + max|c|).
    local = np.linspace(0.0, 1.0, 65)
    tn = np.unique((breaks[:-1, None] + np.diff(breaks)[:, None] * local).ravel())
    x, _ = col.evaluate(sol["X"][0], sol["U"][0], tn, breaks)
    c = x[1] - LOW
    tol = LIMIT_TOL * (1 + np.max(np.abs(c)))
    assert np.min(c) >= -tol
    # It binds (at the touch point, to the node tolerance of the active set).
    assert np.min(c) <= 1e-6
    # The independent simulation (DOP853, rtol 1e-12) with the torque as a feedforward keeps the
    # bound by the same rule (measured: its minimum 9.4e-12 below −0.45, at the junction time
    # to 1e-6 s) and touches it there with zero rate (measured 8.6e-6 rad/s; the rate at a
    # sample within 1e-5 s of the touch, where |c̈| ~ 5 rad/s², is below 1e-4 rad/s).
    x0 = np.array([gait.fixed_point[n] for n in gait.model.state_names])
    sim = gaitopt.simulate(gait.model, x0, steps=1, feedforward=feedforward_of(gait.profiles),
                           rtol=1e-12, atol=1e-13)  # fmt: skip
    assert sim.success, sim.message
    (arc,) = sim.arcs
    t = np.linspace(arc.t0, arc.t1, 80001)
    xs = arc.solution(t)
    cs = xs[1] - LOW
    j = int(np.argmin(cs))
    assert cs[j] >= -LIMIT_TOL * (1 + np.max(np.abs(cs)))
    assert cs[j] <= 1e-7
    assert t[j] == pytest.approx(_junction(gait), abs=2e-5)
    assert abs(xs[3, j]) < 1e-4


def test_uniform_meshes_approach_the_certified_cost_from_below(touched):
    # Without the junction, the bound at the nodes only is a relaxation (the polynomial dips
    # between them), so uniform meshes lie below the certified optimum and close in on it:
    # measured −6.3e-5 (48 intervals), −7.3e-6 (96), −2.3e-6 (192) relative.  An independent
    # transcription of the same optimum (no touch point, no free junction): below it, within
    # 1e-4 at 48 intervals.
    gait = touched
    col, w = gait.transcription
    p = col.model.p
    uniform = _collocation(col.problem, RadauMesh(48, 6))
    w48, stats = _run(uniform, uniform.from_solution(col, w, p), p)
    assert _converged(stats)
    cost = uniform.unpack(w48, p)["cost"]
    assert gait.cost * (1 - 1e-4) < cost < gait.cost
    # And its dense check fails (the dip the junction removes; measured 8.5e-6 rad).
    assert "fails between the nodes" in uniform.check_limits(uniform.unpack(w48, p))


def test_no_touch_without_an_interior_minimum():
    # swing_dot <= 2 binds only at heel strike, the phase's last node (tests/
    # test_optimize_constraints.py: 8.911662799, certified): already a mesh point, so no
    # junction is made and the transcription stays uniform.
    gait = optimize_gait(gaitopt.model("compass_gait", slope=0), period=0.8, step_length=0.3,
                         state_bounds={"swing_dot": (-np.inf, 2.0)})  # fmt: skip
    assert gait.success, gait.message
    col, w = gait.transcription
    assert col.structure is None
    assert detect_touches(col, w, col.model.p, None) is None
    assert gait.cost == pytest.approx(8.911662799, rel=1e-9)  # README, joint limits


@pytest.mark.slow  # 58 s wall on the loaded 2-core machine: run by `make test-slow`
def test_touch_point_with_active_input_bound(touched):
    # The touch junction and the arcs of an active input bound together: |τ| ≤ 6 N·m cuts the
    # torque of the touch-limited optimum above (its peak |τ| exceeds 6: the bound is active,
    # listed), so the least effort can only rise; certified under the same rules (measured
    # 8.909004815 N²·m²·s, discretisation error 3.3e-10, arcs [lo free free lo] with the touch
    # at the junction of the two free arcs, 0.5415 s).
    gait = optimize_gait(gaitopt.model("compass_gait", slope=0), period=0.8, step_length=0.3,
                         bounds={"hip_torque": 6.0},
                         state_bounds={"swing": (LOW, np.inf)})  # fmt: skip
    assert gait.success and gait.verified, gait.message
    assert gait.discretisation_error <= 1e-8
    assert gait.cost > touched.cost
    assert "|hip_torque| <= 6" in gait.active_constraints
    assert f"touch points of {LABEL} (single support)" in gait.active_constraints
    assert any(a.startswith("arcs of the input bounds") for a in gait.active_constraints)
    assert 0.5 < _junction(gait) < 0.6


def test_clearance_margin_rate_is_the_margin_derivative():
    # The clearance margin's rate at a junction (state_arcs.margin_rate, the term a touch of
    # the margin subtracts from ḣ) against the central difference of the margin itself
    # (state_arcs.margin_samples) on the kneed walker's two phases: h = 1e-6 s, so the gap is
    # the difference's truncation ~c (π/T)³ h² ≈ 1e-12 plus rounding ~1e-10 (1e-7 m/s asked).
    from dataclasses import replace

    import casadi as ca

    from gaitopt.optimize import GaitProblem
    from gaitopt.optimize.radau import COAST, NEGATIVE, Arc
    from gaitopt.optimize.state_arcs import clearance_functions, margin_rate, margin_samples

    model = gaitopt.model("kneed_walker", slope=0.03)
    problem = GaitProblem(model, "cot", step_length=0.47, speed=0.84,
                          bounds={"hip_torque": 5.0, "knee_torque": 0.0},
                          clearance=0.01)  # fmt: skip
    arcs = [Arc(3, (COAST, COAST, NEGATIVE), 0.5), Arc(3, (COAST, COAST, NEGATIVE), 0.5)]
    col = _collocation(problem, RadauMesh(6, 3), [arcs, arcs])
    assert [label for label, _ in clearance_functions(col, 0)] == [
        "'swing foot above the slope' >= clearance margin"
    ]
    T = np.array([0.35, 0.21])  # s: the phases' durations
    hs = [T[1] / 6] * 6
    for end in (1, 3, 5):
        rate = float(ca.evalf(margin_rate(col, [ca.DM(t) for t in T], [ca.DM(h) for h in hs],
                                          1, end)))  # fmt: skip
        t = end / 6
        dt = 1e-6 / T[1]
        fd = (margin_samples(col, T, 1, np.array([t + dt])) -
              margin_samples(col, T, 1, np.array([t - dt]))) / 2e-6  # fmt: skip
        assert rate == pytest.approx(float(fd[0]), abs=1e-7)
    none = replace(problem, clearance=0.0)
    assert clearance_functions(_collocation(none, RadauMesh(6, 3), [arcs, arcs]), 0) == []
