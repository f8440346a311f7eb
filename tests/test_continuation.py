"""Continuation: special points against closed forms and direct bisection; cascades."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import gaitopt
from gaitopt import GaitoptInputError, ParameterError
from gaitopt.continuation import PseudoArclength, continuation


def _rimless_boundary() -> float:
    """Closed form (Tedrake, Underactuated Robotics): rolling exists while ω*(γ) > ω₁(γ)."""

    def gap(slope: float) -> float:
        m = gaitopt.model("rimless_wheel", slope=slope)
        return m.rolling_speed() - m.vaulting_speed()

    return brentq(gap, 0.01, 0.3, xtol=1e-15)


@pytest.fixture(scope="module")
def compass_branch():
    return continuation(gaitopt.model("compass_gait"), "slope", to=0.0805, max_period=2)


def test_rimless_wheel_existence_boundary_matches_closed_form():
    # The rolling gait ceases to exist where ω* = ω₁ (γ_b = 0.0682294525 for 8 spokes): its
    # period grows without bound there.  Located by bisection on the certification to 1e-8
    # (issue: special points to 1e-8), on the existence side.
    branch = continuation(gaitopt.model("rimless_wheel"), "slope", to=0.01)
    boundary = [sp for sp in branch.special_points if sp.kind == "boundary"]
    assert len(boundary) == 1
    expected = _rimless_boundary()
    assert boundary[0].param == pytest.approx(expected, abs=1e-8)
    assert boundary[0].param >= expected
    assert branch.periods[-1] > 3 * branch.periods[0]  # the period diverges at the boundary


def test_rimless_wheel_branch_follows_the_closed_form():
    # Along the whole branch: ω* = cot 2α sqrt(4 g/l sin α sin γ), multiplier cos² 2α (Tedrake);
    # tolerance 1e-9 (discretisation-error estimate ≤ 1e-10).
    branch = continuation(gaitopt.model("rimless_wheel"), "slope", to=0.3)
    assert len(branch.cycles) > 5 and branch.params[-1] == pytest.approx(0.3, abs=1e-12)
    for cycle in branch.cycles:
        m = cycle.model
        assert cycle.fixed_point["theta_dot"] == pytest.approx(m.rolling_speed(), abs=1e-9)
        assert cycle.multipliers[0].real == pytest.approx(math.cos(2 * m.alpha) ** 2, abs=1e-9)
    assert branch.special_points == []


def test_period_doubling_agrees_with_bisection_on_the_multiplier(compass_branch):
    # Two independent locations of the compass gait's first period doubling: continuation's
    # regula falsi on det(A + I) vs a direct bisection in the slope on (min real multiplier + 1)
    # with separate solves.  Agreement to 1e-8 (issue: special points to 1e-8).
    pds = [sp for sp in compass_branch.special_points if sp.kind == "PD"]
    assert len(pds) == 1
    model = gaitopt.model("compass_gait")
    previous = gaitopt.find_limit_cycle(model.replace(slope=0.075), verify=False)

    def crossing(slope: float) -> float:
        nonlocal previous
        cycle = gaitopt.find_limit_cycle(model.replace(slope=slope), previous, verify=False)
        assert cycle.success
        previous = cycle
        return float(np.min(cycle.multipliers.real)) + 1.0

    direct = brentq(crossing, 0.075, 0.078, xtol=1e-12)
    assert pds[0].param == pytest.approx(direct, abs=1e-8)
    assert np.min(np.abs(pds[0].cycle.multipliers + 1)) < 1e-6


def test_period_two_branch_after_switching_is_genuine(compass_branch):
    # Branch switching at the PD: every point of the child is a verified period-2 orbit, not the
    # period-1 gait repeated (its two steps differ in simulation), and it starts at the PD.
    assert len(compass_branch.children) == 1
    child = compass_branch.children[0]
    pd = compass_branch.special_points[0].param
    assert child.steps == 2 and len(child.cycles) >= 3
    assert child.params[0] == pytest.approx(pd, abs=2e-3)
    for cycle in child.cycles:
        assert cycle.success and cycle.verified and cycle.steps == 2
    # born at the doubling: the parent's multiplier −1 squares to +1 for the period-2 map
    assert np.min(np.abs(child.cycles[0].multipliers - 1)) < 0.3
    last = child.cycles[-1]
    sim = gaitopt.simulate(last.model, last.x, steps=2)
    assert np.max(np.abs(sim.section_states[1] - last.x)) > 1e-3
    np.testing.assert_allclose(sim.section_states[2], last.x, atol=1e-8)


def test_branch_columns_and_contract(compass_branch):
    data = compass_branch.as_dict()
    assert {"model", "param", "points", "special_points"} <= set(data)
    assert data["param"] == "slope"
    for point in data["points"]:
        assert {"param", "period", "fixed_point", "multipliers", "stable"} <= set(point)
    assert all(sp["kind"] in ("LP", "PD", "NS", "boundary") for sp in data["special_points"])
    params = compass_branch.params
    assert np.all(np.diff(params) > 0)  # no fold on this branch
    assert compass_branch.fixed_points.shape == (len(params), 4)
    # stable before the PD, unstable after it
    pd = compass_branch.special_points[0].param
    assert np.all(compass_branch.stable[params < pd]) and not np.any(
        compass_branch.stable[params > pd]
    )
    header, rows = compass_branch.csv_rows()
    assert header[:3] == ["steps", "slope", "period"] and len(rows) == sum(
        len(b.cycles) for b in compass_branch.descendants()
    )


def test_both_directions_joins_at_the_start():
    model = gaitopt.model("compass_gait")
    branch = continuation(
        model,
        "slope",
        to=0.06,
        both_directions=True,
        cascade=False,
        options=PseudoArclength(max_points=6),
    )
    params = branch.params
    assert params[0] < 0.0525 < params[-1]
    assert np.all(np.diff(params) > 0)


def test_bad_input():
    model = gaitopt.model("compass_gait")
    with pytest.raises(ParameterError, match=r"unknown parameter 'slop'.*did you mean 'slope'"):
        continuation(model, "slop", to=0.06)
    with pytest.raises(ParameterError, match=r"`slope` = 2 is out of range"):
        continuation(model, "slope", to=2.0)
    with pytest.raises(ParameterError, match=r"integer values"):
        continuation(gaitopt.model("rimless_wheel"), "spokes", to=9)
    with pytest.raises(GaitoptInputError, match=r"`step` must be > 0"):
        PseudoArclength(step=0.0)


def test_slip_fold_in_touchdown_angle_is_where_two_apex_fixed_points_meet():
    # Independent check of a fold (LP): slightly below the located touchdown angle the simulated
    # apex map (Tedrake's textbook map) has two fixed points (stable and unstable); slightly
    # above it has none.  The touchdown angle is the SLIP's per-step input and a parameter:
    # continuation moves both.
    from gaitopt.returnmap import fixed_points_1d

    model = gaitopt.model("slip")
    start = gaitopt.find_limit_cycle(model, {"z": 0.87})
    branch = continuation(
        model, "touchdown_angle", start=start, to=0.54, bounds=(0.5, 0.54), cascade=False
    )
    folds = [sp for sp in branch.special_points if sp.kind == "LP"]
    assert len(folds) == 1
    lp = folds[0].param
    assert np.min(np.abs(folds[0].cycle.multipliers - 1)) < 1e-6
    for offset, expected in ((-2e-4, 2), (2e-4, 0)):
        near = model.replace(touchdown_angle=lp + offset)
        found = fixed_points_1d(near, (0.86, 0.95), samples=40)
        assert len(found.cycles) == expected, (offset, found.points)


def _switch(compass_branch, monkeypatch, *, newton_fails: bool):
    """Switch at the compass gait's first PD with the continuation's follower replaced by one
    that keeps the period-2 orbit found; counts the simulated starts (find_limit_cycle)."""
    from gaitopt.continuation import switching

    calls = {"simulated": 0}
    original = switching.find_limit_cycle

    def counted(*args, **kwargs):
        calls["simulated"] += 1
        return original(*args, **kwargs)

    def refused(*args, **kwargs):
        raise GaitoptInputError("refused on purpose: the simulated starts must find it")

    monkeypatch.setattr(switching, "find_limit_cycle", counted)
    if newton_fails:
        monkeypatch.setattr(switching, "solve_gait", refused)
    found = []

    def follow(doubled, *args):
        found.append(doubled)
        return type(compass_branch)(doubled.model, "slope", doubled.steps)

    [pd] = [sp for sp in compass_branch.special_points if sp.kind == "PD"]
    child, note = switching.switch_at_period_doubling(
        pd, "slope", 1.0, 0.0805, (-math.inf, math.inf), PseudoArclength(), False, 1e-10, 2,
        follow=follow,
    )  # fmt: skip
    return pd, child, note, found, calls


def test_switch_tries_newton_from_the_doubled_orbit_before_simulating(compass_branch, monkeypatch):
    # Source: the switch's documented order (switching module docstring): Newton from the doubled
    # orbit plus ε·null vector at every offset and amplitude before any simulated start.  At the
    # compass gait's first PD the first Newton start finds the period-2 orbit born there (the
    # born_at test: within 5 % of the parent, a multiplier within 0.25 of +1), so no simulation
    # runs (exact count).
    from gaitopt.continuation.switching import born_at

    pd, child, note, found, calls = _switch(compass_branch, monkeypatch, newton_fails=False)
    assert child is not None and note.startswith("period-2 branch followed")
    assert calls["simulated"] == 0
    assert found[0].success and found[0].steps == 2 and born_at(found[0], pd.cycle)


def test_switch_falls_back_to_simulated_starts(compass_branch, monkeypatch):
    # Source: the same switch with every Newton start refused: the simulated starts (from the
    # section point displaced along the null vector) must find an orbit born at the PD, within
    # 1e-3 relative of the PD in the slope (the largest offset, OFFSETS[0] tried first).
    from gaitopt.continuation.switching import born_at

    pd, child, note, found, calls = _switch(compass_branch, monkeypatch, newton_fails=True)
    assert child is not None and calls["simulated"] >= 1
    assert found[0].success and found[0].steps == 2 and born_at(found[0], pd.cycle)
    assert abs(found[0].model.slope - pd.param) <= 1e-3 * pd.param * (1 + 1e-12)


def test_starts_dropped_before_the_certificate_would_not_have_been_born(monkeypatch):
    # Source: the full path as the independent method: every Newton start of the compass gait's
    # cascade (to period 8, slope 0.088) that switching.clearly_unborn drops is solved and
    # certified anyway (solve_gait, with the independent simulation) and must not give an orbit
    # born at the PD (born_at false or not a gait); at least one start is dropped (the period-8
    # switch finds period-8 orbits too far past the PD at its first offset), and the cascade's
    # doublings are the compass gait's (the slope study's values, located to 1e-10; 1e-9 here).
    from gaitopt.continuation import switching
    from gaitopt.shooting import solve_gait
    from gaitopt.threads import single_blas_thread

    dropped, kept = [], []
    original = switching.clearly_unborn

    def recording(problem, w0, u, p, parent):
        unborn, restart = original(problem, w0, u, p, parent)
        start = (problem, np.array(w0), np.array(u), np.array(p), parent, np.array(restart))
        (dropped if unborn else kept).append(start)
        return unborn, restart

    monkeypatch.setattr(switching, "clearly_unborn", recording)
    model = gaitopt.model("compass_gait", slope=0.0525)
    branch = continuation(
        model, "slope", to=0.088, max_period=8, options=PseudoArclength(max_step=0.05)
    )
    pds = sorted(
        sp.param for b in branch.descendants() for sp in b.special_points if sp.kind == "PD"
    )
    expected = [0.07663563157614978, 0.08576647013295909, 0.08748354250318158, 0.08785071778447859]
    np.testing.assert_allclose(pds, expected, rtol=0, atol=1e-9)
    assert dropped
    names = [spec.name for spec in model.parameter_specs()]
    for problem, w0, u, p, parent, _ in dropped:
        at = parent.model.replace(slope=float(p[names.index("slope")]))
        certified = solve_gait(at, problem, w0, u)
        assert not (certified.success and switching.born_at(certified, parent))
    # The kept starts' orbits are certified from Newton's converged point (restart), which must
    # give the orbit of the full solve from the start itself bit for bit (Newton stops at once).
    # (One BLAS thread, as inside continuation: LAPACK's bits depend on the thread count.)
    assert kept
    solve = single_blas_thread(solve_gait)
    for problem, w0, u, p, parent, restart in kept:
        at = parent.model.replace(slope=float(p[names.index("slope")]))
        full, reused = solve(at, problem, w0, u), solve(at, problem, restart, u)
        assert full.success == reused.success
        assert np.array_equal(full.solution, reused.solution)
        assert full.discretisation == reused.discretisation
