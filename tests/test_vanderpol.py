"""Van der Pol's limit cycle as the chapter opens with it: orbital distance and its decay, and the
origin on the return map.

Sources: Liouville's formula for the nontrivial multiplier of a planar limit cycle,
λ = exp(∮ μ (1 − q²) dt) (trace of the flow's Jacobian over one period; Tedrake, Underactuated
Robotics, limit cycles); the linearisation about the origin, q̈ − μ q̇ + q = 0, for P'(0⁺).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import gaitopt
from gaitopt.orbits import OrbitSampler
from gaitopt.returnmap import return_map

MU = 0.2


@pytest.fixture(scope="module")
def cycle() -> gaitopt.LimitCycle:
    c = gaitopt.find_limit_cycle(gaitopt.model("vanderpol", mu=MU))
    assert c.success, c.message
    return c


def test_points_on_the_orbit_are_at_distance_zero(cycle):
    sim = gaitopt.simulate(cycle.model, cycle.x, steps=1, rtol=1e-12)
    arc = sim.arcs[0]
    t = np.linspace(arc.t0, arc.t1, 9)[1:-1]  # points between the coarse samples, too
    d = gaitopt.orbital_distance(cycle, arc.solution(t).T)
    # Tolerance 1e-10: the same simulation (rtol 1e-12) as the orbit's own; measured ≤ 5e-16.
    assert np.all(d < 1e-10), d


def test_orbital_distance_of_an_offset_point_is_the_offset(cycle):
    # A point displaced along the outward normal of the orbit at its section crossing is at
    # exactly that distance, for small displacements (to second order: the orbit's curvature).
    x = np.asarray(cycle.x)  # (0, q̇*): the flow there is (q̇*, −0) — horizontal, so the
    delta = 1e-3  # normal is vertical
    d = gaitopt.orbital_distance(cycle, x + np.array([0.0, delta]))
    assert d == pytest.approx(delta, rel=1e-3)


def test_orbital_distance_decays_by_the_liouville_multiplier_per_period(cycle):
    sim = gaitopt.simulate(cycle.model, cycle.x, steps=1, rtol=1e-12)
    arc = sim.arcs[0]
    t = np.linspace(arc.t0, arc.t1, 20001)
    q = arc.solution(t)[0]
    lam = math.exp(np.trapezoid(MU * (1 - q**2), t))  # Liouville
    assert complex(cycle.multipliers[0]).real == pytest.approx(lam, rel=1e-6)
    sampler = OrbitSampler(cycle)
    run = gaitopt.simulate(cycle.model, {"q_dot": 3.5}, steps=14)
    d = np.array([sampler.distance(x) for x in run.section_states])
    log_rate = np.diff(np.log(d))  # log-distance per period (section returns)
    # Once the distance is small (1e-4 here) the nonlinear terms are O(d): tolerance 1e-3 in
    # the log-rate (measured: 3e-5 at the last return).
    assert d[-1] < 1e-4
    assert log_rate[-1] == pytest.approx(math.log(abs(lam)), abs=1e-3)


def test_origin_is_the_unstable_one_sided_fixed_point_of_the_map(cycle):
    model = cycle.model
    assert return_map(model, 0.0)[0] == 0.0 or np.isnan(return_map(model, 0.0)[0])
    slope = math.exp(math.pi * MU / math.sqrt(1 - MU**2 / 4))  # linearisation: e^{πμ/ω_d}
    for s in (1e-5, 1e-4):
        # Tolerance: the map's curvature at the origin is O(s²) relative (cubic damping term).
        assert return_map(model, s)[0] / s == pytest.approx(slope, rel=1e-6)
    assert slope > 1  # unstable


def test_orbital_distance_refuses_a_failed_cycle():
    failed = gaitopt.LimitCycle(False, "did not converge", gaitopt.model("vanderpol"))
    with pytest.raises(gaitopt.GaitoptInputError, match="solved gait"):
        gaitopt.orbital_distance(failed, [0.0, 1.0])
