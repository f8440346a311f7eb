"""Multipliers by AD through the shooting equations against finite differences of the simulated
return map; the verification and the no-false-gait checks."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import gaitopt
from gaitopt.result import OrbitArc
from gaitopt.shooting import shooting_problem, verify_by_simulation
from gaitopt.shooting.certify import _check_dense


def test_multipliers_exclude_the_trivial_ones(cycles):
    # In full coordinates the compass gait's return map has a trivial eigenvalue 0 (it lands on
    # the 3-D post-impact surface); the reported multipliers are the 3 nontrivial ones, and equal
    # the nonzero eigenvalues of the full 4×4 map (finite differences of the simulated map).
    cycle = cycles["compass_gait"]
    model = cycle.model
    x = cycle.x
    h = 1e-6
    full = np.zeros((4, 4))
    for j in range(4):
        e = np.zeros(4)
        e[j] = h
        plus = gaitopt.simulate(model, x + e, steps=1).section_states[-1]
        minus = gaitopt.simulate(model, x - e, steps=1).section_states[-1]
        full[:, j] = (plus - minus) / (2 * h)
    eig = np.linalg.eigvals(full)
    eig = eig[np.argsort(np.abs(eig))]
    assert abs(eig[0]) < 1e-4
    assert np.sort(np.abs(eig[1:])) == pytest.approx(np.sort(np.abs(cycle.multipliers)), abs=1e-4)


def test_multipliers_predict_convergence_in_simulation(cycles):
    # Stability in action: a small perturbation of the stable compass gait shrinks per step at the
    # rate of the largest |multiplier| (0.58); after 12 steps by ≈ 0.58¹² ≈ 1.5e-3.
    cycle = cycles["compass_gait"]
    model = cycle.model
    s = cycle.section_point + np.array([1e-4, 1e-4, -1e-4])
    sim = gaitopt.simulate(model, model.lift(s), steps=12)
    errors = [np.max(np.abs(x - cycle.x)) for x in sim.section_states]
    rate = (errors[-1] / errors[2]) ** (1 / 10)
    assert rate == pytest.approx(np.max(np.abs(cycle.multipliers)), abs=0.05)


def test_verification_rejects_a_point_that_is_not_on_the_orbit(cycles):
    cycle = cycles["compass_gait"]
    model = cycle.model
    ok, error, _ = verify_by_simulation(
        model, cycle.x, cycle.durations, 1, model.nominal_input(), 1e-7
    )
    assert ok and error < 1e-9
    wrong = cycle.x + np.array([1e-4, -1e-4, 0.0, 0.0])
    ok, error, message = verify_by_simulation(
        model, wrong, cycle.durations, 1, model.nominal_input(), 1e-7
    )
    assert not ok and "returns" in message


def test_dense_check_rejects_an_orbit_through_the_ground(cycles):
    # An "orbit" whose single phase runs on for 1.6 periods without the reset lets the swing foot
    # pass through the slope mid-arc (an admissible heel-strike crossing before the phase ends):
    # the no-false-gait rule must reject it, while the real orbit passes.
    cycle = cycles["compass_gait"]
    model = cycle.model
    shooting = shooting_problem(type(model), cycle.discretisation, 1)
    u, p = model.nominal_input(), model.p
    assert _check_dense(model, shooting, cycle.orbit, u, p) is None
    arc = cycle.orbit[0]
    t = np.linspace(0, 1.6 * cycle.period, arc.x.shape[1])
    flow = model.phases[0].flow
    ode = solve_ivp(
        lambda _, x: np.asarray(flow(x, u, p)).ravel(),
        (0, t[-1]),
        cycle.x,
        t_eval=t,
        rtol=1e-10,
        atol=1e-12,
    )
    through_ground = [OrbitArc(arc.phase, arc.name, arc.states, t, ode.y, arc.transition)]
    problem = _check_dense(model, shooting, through_ground, u, p)
    assert problem is not None and "crosses 'heel strike'" in problem
