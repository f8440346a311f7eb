"""The least positive work of the level-ground compass gait, transcribed exactly (issue 11 item 2):
bang, coasting and held-joint arcs of free duration (gaitopt.optimize.arcs, collocation)."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.optimize import GaitProblem
from gaitopt.optimize.collocation import RadauMesh
from gaitopt.optimize.solve import _collocation, _run, attempt
from gaitopt.optimize.verify import profiles, simulate_gait

# Level ground, a 0.3 m step every 0.8 s, |τ| ≤ 20 N·m (README, "Optimal gaits").
STATEMENT = dict(period=0.8, step_length=0.3, bounds={"hip_torque": 20.0})


@pytest.fixture(scope="module")
def model():
    return gaitopt.model("compass_gait", slope=0.0)


@pytest.fixture(scope="module")
def gait(model):
    return gaitopt.optimize_gait(model, "work", **STATEMENT)


@pytest.fixture(scope="module")
def simulation(model, gait):
    col, w = gait.transcription
    sol = col.unpack(w, model.p)
    profs = profiles(col, sol)
    problem = GaitProblem(model, "work", **STATEMENT)
    sim = simulate_gait(problem, model, model.lift(sol["s"]), profs, 1)
    assert sim.success
    return sim, profs


def test_work_optimum_is_certified(gait):
    # Source: the independent simulator (DOP853 with located events, rtol 1e-12) with the
    # optimal torque as feedforward, its cost by 8-point Gauss–Legendre panels: the same
    # positive work to 1e-8 relative (1e-11–3e-11 measured; certify's own check is 1e-6), the
    # same fixed point to 1e-9 (about 1e-11 measured).  Refinement: cost and orbit settled below the
    # 1e-8 target (3.5e-9 measured, 12 → 24 intervals).
    assert gait.success and gait.verified, gait.message
    v = gait.verification
    assert v["cost_simulated"] == pytest.approx(gait.cost, rel=1e-8)
    assert v["return_error"] <= 1e-9
    assert gait.discretisation_error <= 1e-8
    assert gait.period == pytest.approx(0.8, rel=1e-12)
    assert gait.step_length == pytest.approx(0.3, rel=1e-9)
    assert gait.cost == pytest.approx(0.66553070, rel=1e-7)  # J, this transcription's value


def test_work_optimum_has_its_arcs(gait):
    # The torque pushes at its bound after heel strike, coasts, holds the hip (ω ≡ 0, τ ≠ 0),
    # coasts, brakes at its bound and pushes again until heel strike: six arcs, each transcribed
    # exactly (the bound or zero fixed, the rate zero on the held arc: 1e-9, IPOPT's tolerance).
    assert "[+lo coast held coast -lo +lo]" in gait.message
    col, w = gait.transcription
    model = col.model
    sol = col.unpack(w, model.p)
    X, U = sol["X"][0][:, 1:], sol["U"][0]
    rates = np.asarray(model.input_rates(0).map(X.shape[1])(X, model.p)).ravel()
    kinds = [a.signs[0] for a in col.structure[0] for _ in range(a.intervals * col.d)]
    kinds = np.array(kinds)
    assert np.max(np.abs(rates[kinds == 2])) <= 1e-9
    assert np.all(U[0, kinds == 0] == 0.0)
    assert np.min(np.abs(U[0, kinds == 2])) > 1.0  # the hold needs a torque (N·m)


def test_positive_work_is_the_impact_loss_plus_the_negative_work(model, gait, simulation):
    # Source: the work–energy balance of a periodic orbit on level ground, independent of the
    # cost's quadrature: along the flow dE/dt = τω, and the orbit returns to its start, so
    # W⁺ − W⁻ = E(x⁻) − E(x⁺), the energy lost in the heel strike (closed form from the
    # simulated pre- and post-impact states).  W⁻ = ∫max(0, −τω) dt by composite Simpson on the
    # dense simulated orbit (129 points per profile interval, split at its breakpoints, where
    # τ jumps).  Tolerance 1e-8 relative: the simulation's (rtol 1e-12) and Simpson's (O(h⁴),
    # below 1e-12 here) errors, far below the 3e-6 of the earlier inexact held arc.
    sim, profs = simulation
    energy = model.phases[0].conserved["energy"]
    event = next(e for e in sim.events if e.state_after is not None)
    loss = float(energy(event.state_before, model.p)) - float(energy(event.state_after, model.p))
    arc = sim.arcs[0]
    rates = model.input_rates(0)
    edges = np.unique(np.clip(profs[0].breaks, arc.t0, arc.t1))
    negative = 0.0
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        ts = np.linspace(a, b, 129)
        xs = arc.solution(ts)
        # The profile on the open interval (its value at a break is the next piece's).
        us = np.array([profs[0](min(max(t, a + 1e-13), b - 1e-13))[0] for t in ts])
        omega = np.asarray(rates.map(ts.size)(xs, model.p)).ravel()
        f = np.maximum(0.0, -us * omega)
        hh = (b - a) / (ts.size - 1)
        negative += hh / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())
    assert loss > 0 and negative > 0
    assert gait.cost == pytest.approx(loss + negative, rel=1e-8)


def test_slack_formulation_converges_to_the_exact_work(model, gait):
    # Source: the slack-power transcription (pᵢ⁺ − pᵢ⁻ = uᵢωᵢ, cost ∫Σp⁺), an independent
    # formulation whose quadrature is only first order across the switches: as its mesh is
    # doubled its least work approaches the exact optimum, the gap shrinking by 3–4 each time
    # (measured: 12 intervals 2.0e-3, 24: 5.1e-4, 48: 1.5e-4 relative).  Checked: the gap
    # shrinks at each doubling and is below 3e-4 at 48 intervals.
    problem = GaitProblem(model, "work", **STATEMENT)
    col = _collocation(problem, RadauMesh(6, 6))
    run = attempt(col, problem, 0, 0, None)
    assert run["ok"]
    w = run["w"]
    gaps = []
    for intervals in (12, 24, 48):
        fine = _collocation(problem, RadauMesh(intervals, 6))
        w, stats = _run(fine, fine.from_solution(col, w, model.p), model.p)
        assert stats["success"]
        col = fine
        gaps.append(abs(col.unpack(w, model.p)["cost"] - gait.cost) / gait.cost)
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2] < 3e-4


def test_braking_effort_is_reported_not_counted(model, gait):
    # GaitProblem.braking_effort = ε adds ε ∫u² dt over the braking arcs to the exact stage's
    # objective only.  Here the one braking arc (−lo) holds the torque at −20 N·m, so the term
    # is 400 N²·m² times that arc's duration (closed form), and ε = 1e-6 moves the optimum only
    # to second order in ε: the reported positive work is the plain optimum's to the 1e-8
    # certificate target, and the simulated work confirms it (the certificate's check).
    from gaitopt.optimize import solve_problem
    from gaitopt.optimize.radau import NEGATIVE

    braked = solve_problem(GaitProblem(model, "work", braking_effort=1e-6, **STATEMENT))
    assert braked.success, braked.message
    assert braked.cost == pytest.approx(gait.cost, rel=1e-8)
    col, w = braked.transcription
    (arcs,) = col.structure
    (j,) = [a for a, arc in enumerate(arcs) if arc.signs[0] == NEGATIVE]
    duration = col.theta_of(w, 0)[j] * braked.period
    value = col.unpack(w, model.p)["braking_effort"]
    assert value == pytest.approx(20.0**2 * duration, rel=1e-9)  # u ≡ −20 on the arc
    assert "braking arcs regularised by 1e-06" in braked.message
    assert braked.problem["braking_effort"] == 1e-6
