"""The public problem layer (:class:`gaitopt.ShootingProblem`): unknowns, residual, Jacobians,
bounds, the objective slot and the map back to orbits, independent of the methods that solve it."""

import numpy as np
import pytest

import gaitopt
from gaitopt.errors import GaitoptInputError


@pytest.fixture(scope="module")
def gait():
    return gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))


def test_the_result_keeps_its_problem_solution_and_jacobians(gait):
    # The solution vector solves the problem it names (residual ≤ tol = 1e-10), and the kept
    # evaluation is the Jacobian there: compared with central differences of the residual
    # (h = 1e-5: truncation ~1e-10, rounding of the ~1e-13-noisy residual ~1e-8; measured
    # 5e-8 at most).
    problem, w, u, p = gait.problem, gait.solution, gait.inputs, gait.model.p
    assert isinstance(problem, gaitopt.ShootingProblem) and w.shape == (problem.size,)
    F = problem.evaluate(w, u, p, jacobian=False).F
    assert np.max(np.abs(F)) <= 1e-10
    h = 1e-5
    fd = np.column_stack(
        [
            (problem.evaluate(w + h * e, u, p, jacobian=False).F
             - problem.evaluate(w - h * e, u, p, jacobian=False).F) / (2 * h)
            for e in np.eye(problem.size)
        ]
    )  # fmt: skip
    assert np.allclose(gait.evaluation.F_w, fd, rtol=1e-6, atol=1e-6)


def test_pack_unpack_and_the_orbit_map_back(gait):
    problem, w, p = gait.problem, gait.solution, gait.model.p
    s, nodes, durations = problem.unpack(w, p)
    assert np.array_equal(problem.pack(s, nodes, durations), w)  # exact round trip
    assert np.array_equal(s, gait.section_point)
    assert np.allclose(durations, gait.durations, rtol=0, atol=0)
    # The orbit rebuilt from w is the result's orbit (same integrator, same samples).
    arcs = problem.orbit(w, gait.inputs, p)
    assert len(arcs) == len(gait.orbit)
    for a, b in zip(arcs, gait.orbit, strict=True):
        assert np.array_equal(a.x, b.x) and np.array_equal(a.t, b.t)
    # A warm start from the result is its own solution vector, not a re-interpolation.
    assert np.array_equal(problem.unknowns_from_cycle(gait), w)


def test_bounds_keep_durations_positive(gait):
    lower, upper = gait.problem.bounds()
    index = gait.problem.duration_index()
    assert np.all(lower[index] > 0) and np.all(np.isinf(np.delete(lower, index)))
    assert np.all(np.isinf(upper))


def test_an_objective_over_free_inputs_plugs_into_ipopt(gait):
    # The objective slot: with the hip torque free, IPOPT picks the constant torque that makes
    # the period 0.7 s; an independent method (Newton at that torque, verified by simulation)
    # must give a gait of that period (1e-8 s: IPOPT's tol 1e-10 on the squared deviation).
    problem, model = gait.problem, gait.model
    target = 0.7
    solution = problem.solve(
        gait.solution,
        gait.inputs,
        model.p,
        method="ipopt",
        objective=lambda sym: (sym.period - target) ** 2,
        free_inputs=True,
    )
    assert solution.converged
    torque = float(solution.u[0])
    assert torque != 0.0
    guess = dict(zip(model.section.coordinates, gait.section_point, strict=True))
    check = gaitopt.find_limit_cycle(model, guess, inputs=[torque], follow=False)
    assert check.success and check.verified
    assert abs(check.period - target) < 1e-8


def test_newton_refuses_an_objective(gait):
    with pytest.raises(GaitoptInputError, match="method='ipopt'"):
        gait.problem.solve(
            gait.solution, gait.inputs, gait.model.p, objective=lambda sym: sym.period
        )


def test_status_codes_say_how_a_search_ended(gait):
    from gaitopt.result import STATUS

    assert gait.status == "success" and gait.as_dict()["status"] == "success"
    # The trailing foot that does not lift off (issue 9's case): solved, then refused by the
    # dense constraint check.
    walker = gaitopt.model("kneed_walker", slope=0.2)
    refused = gaitopt.find_limit_cycle(
        walker, {"q1": -0.19, "q1_dot": 1.11, "q2_dot": -2.41}, follow=False
    )
    assert not refused.success and refused.status == "not_a_gait"
    assert set(STATUS) >= {gait.status, refused.status}
