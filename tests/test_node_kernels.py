"""The collocation's node kernels (:mod:`gaitopt.optimize.nodes`, :mod:`gaitopt.kernels.nodes`).

Independent method: CasADi's own AD of the whole transcription (``nlpsol`` on
``Collocation.nlp`` with ``use_node_kernels = False``, the NLP differentiated as one graph)
against the chain-rule assembly from the compiled node kernels.  Both are exact derivatives of
the same NLP, so they agree in sparsity pattern exactly and in value to rounding: 1e-12
relative to the largest entry (measured: 1e-15 to 4e-14).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gaitopt
from gaitopt.kernels.nodes import NodeKernels
from gaitopt.optimize import attempt as _attempt
from gaitopt.optimize import floquet
from gaitopt.optimize.collocation import (
    Arc,
    Collocation,
    RadauMesh,
    _derivative_matrix,
    phase_node_kernels,
)
from gaitopt.optimize.guess import _start_guess
from gaitopt.optimize.problem import as_problem

NAMES = ("nlp_jac_g", "nlp_grad_f", "nlp_hess_l")


def _derivatives(col: Collocation, w: np.ndarray, lam: np.ndarray, solver) -> list[ca.DM]:
    p = col.model.p
    jac = solver.get_function("nlp_jac_g")(w, p)[1]
    grad = solver.get_function("nlp_grad_f")(w, p)[1]
    hess = solver.get_function("nlp_hess_l")(w, p, 0.7, lam)
    return [ca.DM(jac), ca.DM(grad), ca.DM(hess)]


def _compare(problem, mesh, structure=None, monkeypatch=None):
    """The three derivative functions both ways at the start guess (random multipliers)."""
    out = {}
    for split in (True, False):
        monkeypatch.setattr(Collocation, "use_node_kernels", split)
        col = Collocation(problem, mesh, structure)
        assert bool(col.node_blocks) == split
        if split:
            _attempt._SOLVERS.clear()
            solver = _attempt._solver(col)
            _attempt._SOLVERS.clear()
        else:
            solver = ca.nlpsol("whole", "ipopt", col.nlp, _attempt._IPOPT)
        w = _start_guess(col, problem, 0, 0, None)
        lam = np.random.default_rng(1).normal(size=col.lbg.size)
        out[split] = _derivatives(col, w, lam, solver)
    for name, a, b in zip(NAMES, out[True], out[False], strict=True):
        assert a.sparsity() == b.sparsity(), name
        scale = float(np.max(np.abs(b.nonzeros()))) if b.nnz() else 1.0
        assert np.max(np.abs(np.subtract(a.nonzeros(), b.nonzeros()))) <= 1e-12 * scale, name


def test_compass_gait_explicit_flow(monkeypatch):
    model = gaitopt.model("compass_gait", slope=0)
    problem = as_problem(model, cost="effort", period=0.8, step_length=0.3)
    _compare(problem, RadauMesh(3, 4), monkeypatch=monkeypatch)


def test_five_link_implicit_dynamics_and_interval_defects(monkeypatch):
    # The implicit equations of motion and the foot constraints at the nodes, the defects of
    # each interval (the first interval's start is the nonlinear lift of the section).
    model = gaitopt.model("five_link_biped")
    problem = as_problem(model, cost="effort", period=0.6, step_length=0.4)
    _compare(problem, RadauMesh(2, 3), monkeypatch=monkeypatch)


def test_five_link_arcs(monkeypatch):
    # Arcs of an input bound: interval lengths T·θ/intervals are products of decision
    # variables, inputs of the interval kernels (second derivatives of Z(w)).
    model = gaitopt.model("five_link_biped")
    problem = as_problem(
        model,
        cost="effort",
        period=0.6,
        step_length=0.4,
        bounds={"stance_knee_torque": 100.0},
    )
    arcs = [[Arc(1, (), 0.4, (-1, 0, 0, 0)), Arc(1, (), 0.6, (0, 0, 0, 0))]]
    _compare(problem, RadauMesh(2, 3), arcs, monkeypatch=monkeypatch)


def test_compass_gait_free_parameter(monkeypatch):
    # A free parameter (the leg's a): the node kernels are differentiated in p too.
    model = gaitopt.model("compass_gait", slope=0)
    problem = as_problem(model, cost="effort", period=0.8, step_length=0.3, free=("a",))
    _compare(problem, RadauMesh(3, 4), monkeypatch=monkeypatch)


def test_kneed_walker_two_phases(monkeypatch):
    model = gaitopt.model("kneed_walker")
    problem = as_problem(model, cost="effort", period=0.5643, step_length=0.47)
    _compare(problem, RadauMesh(2, 3), monkeypatch=monkeypatch)


def test_interpreted_kernels_match_compiled(monkeypatch):
    # Without a compiler (GAITOPT_COMPILE=0) the same functions run interpreted: the same
    # numbers to rounding (1e-13 relative to the largest entry).
    model = gaitopt.model("compass_gait", slope=0)
    node, compiled = phase_node_kernels(model, 0, None)
    monkeypatch.setenv("GAITOPT_COMPILE", "0")
    interpreted = NodeKernels(node, "compassgait_0e", compiled.nd)
    assert not interpreted.compiled
    rng = np.random.default_rng(2)
    z = np.concatenate([rng.normal(scale=0.3, size=node.size1_in(0) - model.p.size), model.p])
    mu = rng.normal(size=node.size1_out(0))
    for a, b in (
        (compiled.jac(z), interpreted.jac(z)),
        (compiled.hess(z, mu), interpreted.hess(z, mu)),
    ):
        for x, y in zip(a, b, strict=True):
            x, y = np.asarray(ca.densify(x)), np.asarray(ca.densify(y))
            assert np.max(np.abs(x - y)) <= 1e-13 * (1 + np.max(np.abs(y)))


def test_floquet_sensitivity_from_flow_kernel():
    # The phase sensitivities assembled from the compiled flow Jacobians equal the symbolic
    # Jacobians of the whole phase's defects (floquet._phase_residual), to 1e-13 relative.
    model = gaitopt.model("five_link_biped")
    problem = as_problem(model, cost="effort", period=0.6, step_length=0.4)
    col = Collocation(problem, RadauMesh(2, 3))
    w = _start_guess(col, problem, 0, 0, None)
    sol = col.unpack(w, model.p)
    N, d = col.N, col.d
    D = _derivative_matrix(col.tau[1:], col.tau[1:])
    X, U, T = sol["X"][0], sol["U"][0], sol["T"][0]
    hs = T * np.diff(sol["breaks"][0])
    Ud = np.hstack([U[:, j * d : (j + 1) * d] @ D.T / hs[j] for j in range(N)])
    flow = model.phases[0].flow
    new = floquet._sensitivity(col, 0, flow, X, U, Ud, hs, sol["p"])
    sens = floquet._phase_residual(flow, N, d, col.C.tobytes())
    old = [np.asarray(v) for v in sens(X[:, 1:], X[:, 0], 0.0, U, Ud, hs, sol["p"])]
    for a, b in zip(new, old, strict=True):
        assert a.shape == b.shape
        assert np.max(np.abs(a - b)) <= 1e-13 * np.max(np.abs(b))


def test_same_optimum_and_iterations(monkeypatch):
    # A cold solve on the starts' mesh: the same IPOPT iterations and optimum both ways (the
    # compass gait's 0.3 m / 0.8 s least effort); 1e-12 relative: rounding.
    model = gaitopt.model("compass_gait", slope=0)
    problem = as_problem(model, cost="effort", period=0.8, step_length=0.3)
    runs = []
    for split in (True, False):
        monkeypatch.setattr(Collocation, "use_node_kernels", split)
        _attempt._SOLVERS.clear()
        _attempt._COLLOCATIONS.clear()
        col = _attempt._collocation(problem, RadauMesh(6, 6))
        runs.append(_attempt.attempt(col, problem, 0, 0, None))
    _attempt._SOLVERS.clear()
    _attempt._COLLOCATIONS.clear()
    assert all(r["ok"] for r in runs)
    assert runs[0]["cost"] == pytest.approx(runs[1]["cost"], rel=1e-12)
    assert runs[0]["stats"]["iter_count"] == runs[1]["stats"]["iter_count"]
