"""The verification's stepper (gaitopt.dop853): SciPy's DOP853 with each step in one CasADi call.
Against SciPy's own DOP853 on the same flow: each step from the same state with the same size
gives the same state, dense output and event values (same method, rounding apart), and whole
integrations agree to their tolerance."""

from __future__ import annotations

import numpy as np
from scipy.integrate import DOP853

import gaitopt
from gaitopt.dop853 import CompiledDOP853, step_function


def _vanderpol():
    model = gaitopt.model("vanderpol")
    phase = model.phases[0]
    u, p = model.nominal_input(), model.p
    guards = [tr.guard for tr in phase.transitions]

    def rhs(t, x):
        return np.asarray(phase.flow(x, u, p), dtype=float).ravel()

    return phase, u, p, guards, rhs


def test_each_step_matches_scipy_dop853():
    # Reference: scipy.integrate.DOP853 (Van der Pol, μ = 1, half a period); each of its steps
    # is recomputed by the compiled step from the same state and size: states, dense output and
    # the guards on it agree to 1e-12 (rounding of differently ordered sums).
    phase, u, p, guards, rhs = _vanderpol()
    step = step_function(phase.flow, guards, 4)
    x0 = np.array([2.0, 0.0])
    ours = CompiledDOP853(rhs, step, u, p, 0.0, x0, 3.3, rtol=1e-10, atol=1e-12)
    scipy_ = DOP853(rhs, 0.0, x0, 3.3, rtol=1e-10, atol=1e-12)
    steps = 0
    while scipy_.status == "running":
        f_old = scipy_.f.copy()
        scipy_.step()
        steps += 1
        h = scipy_.t - scipy_.t_old
        ours._call(scipy_.y_old, f_old, h)
        assert np.max(np.abs(ours._call.y_new - scipy_.y)) <= 1e-12
        F = ours._call.F.reshape(7, -1)
        dense = scipy_.dense_output()
        assert np.max(np.abs(F - dense.F)) <= 1e-12
        grid = scipy_.t_old + h * np.arange(1, 5) / 4
        expected = [[float(g(dense(t) if j < 3 else scipy_.y, u, p)) for j, t in enumerate(grid)]
                    for g in guards]  # fmt: skip
        values = ours._call.G.reshape(4, -1).T
        assert np.max(np.abs(values - np.array(expected))) <= 1e-12
    assert steps > 10


def test_whole_integration_agrees_with_scipy_dop853():
    # Same method and step control: the end states agree to the tolerance (rtol 1e-10 over
    # half a period: 1e-8 allows the error growth), with nearly the same number of steps.
    phase, u, p, guards, rhs = _vanderpol()
    step = step_function(phase.flow, guards, 4)
    x0 = np.array([2.0, 0.0])
    solvers = [
        CompiledDOP853(rhs, step, u, p, 0.0, x0, 3.3, rtol=1e-10, atol=1e-12),
        DOP853(rhs, 0.0, x0, 3.3, rtol=1e-10, atol=1e-12),
    ]
    counts = []
    for solver in solvers:
        n = 0
        while solver.status == "running":
            solver.step()
            n += 1
        counts.append(n)
        assert solver.status == "finished"
    assert np.max(np.abs(solvers[0].y - solvers[1].y)) <= 1e-8
    assert abs(counts[0] - counts[1]) <= 0.1 * counts[1]
