"""Boundary arcs of a guard (gaitopt/optimize/boundary_arcs.py): the kneed walker's swing knee
held straight by its torque after heel strike, on the knee-powered least cost of transport's
statement (problems/optimal_kneed_knee.py) on a small mesh."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import gaitopt
from gaitopt.hybrid import rate_along
from gaitopt.optimize import GaitProblem, solve_problem
from gaitopt.optimize.arcs import _describe
from gaitopt.optimize.attempt import _collocation, _converged, _run
from gaitopt.optimize.boundary_arcs import (
    boundary_nodes,
    boundary_spans,
    guard_rate_input,
    held_on_guard,
)
from gaitopt.optimize.collocation import Collocation, RadauMesh
from gaitopt.optimize.radau import BOUNDARY, COAST, HELD, NEGATIVE, POSITIVE, Arc

SLOPE, STEP, SPEED = 0.03, 0.47, 0.84
MESH = RadauMesh(8, 6)


def _statement(knee: float, **kw) -> GaitProblem:
    model = gaitopt.model("kneed_walker", slope=SLOPE)
    return GaitProblem(model, "cot", step_length=STEP, speed=SPEED,
                       bounds={"hip_torque": 5.0, "knee_torque": knee}, **kw)  # fmt: skip


def _structure(knee_first: int, knee_second: int | None = None) -> list[list[Arc]]:
    """The arcs of the knee-powered optimum (problems/optimal_kneed_knee.py, without its
    clearance touch and its collapsed braking sliver): the hip pushing at its bound while the
    knee is held, the knee held on, then both coasting; the two-link phase's hip arcs."""
    knee_second = knee_first if knee_second is None else knee_second
    return [
        [Arc(2, (POSITIVE, knee_first, NEGATIVE), 0.03, (-1, 0, 0)),
         Arc(2, (COAST, knee_second, NEGATIVE), 0.1),
         Arc(4, (COAST, COAST, NEGATIVE), 0.87)],
        [Arc(2, (COAST, NEGATIVE, NEGATIVE), 0.46),
         Arc(2, (NEGATIVE, NEGATIVE, NEGATIVE), 0.04, (1, 0, 0)),
         Arc(2, (COAST, NEGATIVE, NEGATIVE), 0.32),
         Arc(1, (NEGATIVE, NEGATIVE, NEGATIVE), 0.05, (-1, 0, 0)),
         Arc(1, (POSITIVE, NEGATIVE, NEGATIVE), 0.13, (-1, 0, 0))],
    ]  # fmt: skip


def _group(col: Collocation, text: str) -> list:
    return [g for g in col.groups if text in g.name]


def test_boundary_rows_replace_the_guard_side_on_the_arc():
    # Counting rows (no solve): on the boundary arcs (2 + 2 intervals of degree 6 from the
    # phase start) ċ = 0 at each of their 24 Radau points; the knee strike's side c ≥ 0 keeps
    # its rows only at the other interior nodes (8·6 − 1 − 24 = 23); no entry rows at the
    # phase start, where the section (q3 = q2, q̇3 = q̇2) makes c and ċ vanish identically.
    problem = _statement(5.0, clearance=0.01, braking_effort=1e-3)
    col = Collocation(problem, MESH, _structure(BOUNDARY))
    found = guard_rate_input(col, 0)
    assert found is not None and found[1] == problem.model.inputs.index("knee_torque")
    assert guard_rate_input(col, 1) is None  # the two-link phase's guard has a test
    (rate,) = _group(col, "its rate zero")
    assert rate.size == 4 * MESH.degree
    (side,) = _group(col, "'knee strike' not before the end of three-link")
    assert side.size == MESH.intervals * MESH.degree - 1 - 4 * MESH.degree
    assert not _group(col, "entry on the guard")
    assert boundary_nodes(col, 1) is None
    assert _describe(col.structure).startswith("[+lo/boundary/- coast/boundary/- coast/coast/-]")
    # A boundary arc that begins inside the phase: c = 0 and ċ = 0 at its entry (2 rows).
    inner = Collocation(problem, MESH, _structure(COAST, BOUNDARY))
    (entry,) = _group(inner, "entry on the guard")
    assert entry.size == 2


@pytest.fixture(scope="module")
def solved():
    # The passive-knee optimum (optimal_kneed_cot's statement at 0.84 m/s), unverified: only
    # a warm start here.
    passive = solve_problem(_statement(0.0), verify=False)
    assert passive.transcription is not None, passive.message
    pc, pw = passive.transcription
    problem = _statement(5.0, clearance=0.01, braking_effort=1e-3)
    out = {}
    for kind in (HELD, BOUNDARY):
        col = _collocation(problem, MESH, _structure(kind))
        w, stats = _run(col, col.from_solution(pc, pw, problem.model.p), problem.model.p)
        assert _converged(stats), stats.get("return_status")
        out[kind] = (col, w)
    return problem, out


def test_boundary_arc_is_the_held_knee_by_other_rows(solved):
    # Source: two transcriptions of one discrete problem by independent rows — a held knee
    # (ω = q̇3 − q̇2 = 0 at the arc's start and points, and the guard side c ≥ 0 at its nodes)
    # and the boundary arc (ċ = 0 at the points, c = ċ = 0 from the section, no guard-side
    # rows): the same feasible set, so the same optimum, to IPOPT's tolerance (1e-11; 1e-9
    # relative asked, 2e-11 measured), warm started from the passive-knee optimum.
    problem, out = solved
    p = problem.model.p
    held = out[HELD][0].unpack(out[HELD][1], p)
    boundary = out[BOUNDARY][0].unpack(out[BOUNDARY][1], p)
    assert boundary["cost"] == pytest.approx(held["cost"], rel=1e-9)
    assert np.max(np.abs(boundary["s"] - held["s"])) <= 1e-8
    assert np.allclose(
        out[BOUNDARY][0].theta_of(out[BOUNDARY][1], 0), out[HELD][0].theta_of(out[HELD][1], 0),
        atol=1e-8,
    )  # fmt: skip


def test_boundary_arc_holds_the_guard_and_its_junctions(solved):
    problem, out = solved
    col, w = out[BOUNDARY]
    model, p = problem.model, problem.model.p
    sol = col.unpack(w, p)
    c, r, _ = guard_rate_input(col, 0)
    flow = model.phases[0].flow
    crate = rate_along(flow, c)
    acc = rate_along(flow, crate)  # c̈ = ∇ċ · f: the index reduction's equation
    theta = col.theta_of(w, 0)
    exit_ = theta[0] + theta[1]  # the boundary arc: [0, exit) of the phase
    X, U = sol["X"][0], sol["U"][0]
    nodes = col.node_times(sol["breaks"][0])[1:]
    on = nodes <= exit_ + 1e-12  # the last is the exit junction, the arc's last point
    assert on.sum() == 4 * MESH.degree
    # The acceleration constraint at the arc's Radau points, from the model's flow (not a row
    # of the transcription): c̈ = 0 to 1e-8 rad/s² (the collocation equations' residual,
    # ~1e-11, over the interval length ~0.005 s, times the state's scale).
    cdd = np.asarray(acc.map(int(on.sum()))(X[:, 1:][:, on], U[:, on], p), dtype=float)
    assert np.max(np.abs(cdd)) <= 1e-8
    # The knee torque that holds it is not zero (the passive knee would fold at once: c̈ > 0
    # with it off, checked at the first point).
    assert np.min(np.abs(U[r, on])) > 1e-3
    u_off = U[:, on][:, :1].copy()
    u_off[r] = 0.0
    assert float(acc(X[:, 1:][:, on][:, :1], u_off, p)) > 0
    # The polynomials on dense samples of the arc: c and ċ vanish (the section fixes them at
    # the entry, the rows keep them), to 1e-10 (IPOPT's constraint tolerance 1e-11 times the
    # arc's ~20 points).
    tn = np.linspace(0.0, exit_, 401)
    Xs, Us = col.evaluate(X, U, tn, sol["breaks"][0])
    assert np.max(np.abs(np.asarray(c.map(tn.size)(Xs, Us, p)))) <= 1e-10
    assert np.max(np.abs(np.asarray(crate.map(tn.size)(Xs, Us, p)))) <= 1e-10
    # The exit junction: the knee leaves the guard there (c > 0 just after, the knee coasting:
    # u = 0) and the time is the arc fractions' unknown, 0.0473 s (the study's optimum, to
    # 1e-3 s on this coarse mesh).
    after = np.linspace(exit_, exit_ + 0.02, 9)[1:]
    Xa, Ua = col.evaluate(X, U, after, sol["breaks"][0])
    assert np.all(np.asarray(c.map(after.size)(Xa, Ua, p)) > 0)
    assert np.max(np.abs(Ua[r])) <= 1e-12
    assert sol["T"][0] * exit_ == pytest.approx(0.0473, abs=1e-3)
    (span,) = boundary_spans(col, w, p)
    assert span.startswith("knee_torque holds the 'knee strike' guard on [0, 0.04")


def test_held_on_guard_finds_the_boundary_arc(solved):
    # The held solution read as a first solution: its held knee arcs lie on the knee strike's
    # guard (c = 0 within 1e-6), so they become boundary arcs; the hip's arcs stay as they are.
    problem, out = solved
    col, w = out[HELD]
    theta = col.theta_of(w, 0)
    structure = [
        [replace(a, fraction=float(f)) for a, f in zip(arcs, col.theta_of(w, k), strict=True)]
        for k, arcs in enumerate(col.structure)
    ]
    found = held_on_guard(col, w, problem.model.p, structure)
    assert [a.signs for a in found[0]] == [a.signs for a in _structure(BOUNDARY)[0]]
    assert [a.signs for a in found[1]] == [a.signs for a in structure[1]]
    assert theta[0] > 0
