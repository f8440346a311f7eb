"""Transcriptions (and their compiled NLPs) are reused only for the same statement and mesh: a
second solve of the same problem skips building IPOPT's NLP, and nothing else ever shares one."""

import gaitopt
from gaitopt.optimize.problem import GaitProblem
from gaitopt.optimize.radau import RadauMesh
from gaitopt.optimize.solve import _collocation


def test_a_transcription_is_shared_only_by_the_same_statement():
    model = gaitopt.model("compass_gait", slope=0.0)
    mesh = RadauMesh(4, 3)
    a = _collocation(GaitProblem(model, "effort", period=0.8, step_length=0.3), mesh)
    assert _collocation(GaitProblem(model, "effort", period=0.8, step_length=0.3), mesh) is a
    others = [
        GaitProblem(model, "effort", period=0.7, step_length=0.3),  # another constraint value
        GaitProblem(model, "work", period=0.8, step_length=0.3, bounds={"hip_torque": 5}),
        GaitProblem(model.replace(slope=0.01), "effort", period=0.8, step_length=0.3),
        GaitProblem(model, lambda x, u, p: u[0] ** 2, period=0.8, step_length=0.3),
    ]
    for problem in others:
        assert _collocation(problem, mesh) is not a
    assert (
        _collocation(GaitProblem(model, "effort", period=0.8, step_length=0.3), RadauMesh(5, 3))
        is not a
    )


def test_statements_differing_only_in_a_fixed_speed_share_one_nlp():
    # The speed is the bound of its row (distance / period), like the period and step length.
    from gaitopt.optimize.attempt import _solver

    model = gaitopt.model("compass_gait", slope=0.0)
    mesh = RadauMesh(4, 3)
    slow = _collocation(GaitProblem(model, "effort", speed=0.375, step_length=0.3), mesh)
    fast = _collocation(GaitProblem(model, "effort", speed=0.4, step_length=0.3), mesh)
    assert fast is not slow
    assert _solver(fast) is _solver(slow)
    assert list(fast.ubg) != list(slow.ubg)  # the speed's value is in the row bounds


def test_fixed_speed_is_the_same_optimum_as_the_period_it_implies():
    # 0.3 m at 0.375 m/s is a 0.8 s step: the optimum must be the period-fixed one,
    # 6.668848535 N²·m²·s (README, verified by simulation), to the 1e-8 refinement target.
    model = gaitopt.model("compass_gait", slope=0.0)
    gait = gaitopt.optimize_gait(model, speed=0.375, step_length=0.3)
    assert gait.success, gait.message
    assert abs(gait.period - 0.8) <= 1e-10
    assert abs(gait.speed - 0.375) <= 1e-10
    assert abs(gait.cost - 6.668848535) <= 1e-8 * 6.668848535 + 5e-10
    assert "speed (fixed)" in gait.active_constraints
