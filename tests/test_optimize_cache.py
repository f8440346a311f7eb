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
