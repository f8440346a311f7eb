"""The model structure is validated once, when a model class is first built: a model whose
hybrid structure is inconsistent fails with ModelDefinitionError naming what is wrong, before any
solve (the shooting follows the cycle order, the simulation follows ``target``: they must agree)."""

from dataclasses import dataclass

import casadi as ca
import pytest

import gaitopt
from gaitopt.errors import ModelDefinitionError
from gaitopt.hybrid import HybridModel, Phase, Section, Symbols, Transition
from gaitopt.parameters import parameter


def _ball(target=0, reset_states=2, lift=lambda s: ca.vertcat(0, s[0])):
    """A one-phase bouncing ball with one defect switched in."""

    @dataclass(frozen=True)
    class Ball(HybridModel):
        name = "structure_test_ball"
        gravity: float = parameter(
            9.81, unit="m/s^2", doc="g", source="standard gravity", low=0.0, high=100.0,
            low_open=True,
        )  # fmt: skip

        @classmethod
        def build(cls, sym: Symbols):
            x, (y, v) = sym.states("y", "v")
            after = ca.vertcat(0, -0.5 * v, 0)[:reset_states]
            bounce = Transition(
                "bounce", sym.function("guard", x, y), -1, sym.function("reset", x, after), target
            )
            flow = sym.function("flow", x, ca.vertcat(v, -sym.gravity))
            s = ca.SX.sym("s", 1)
            return (Phase("flight", ("y", "v"), flow, (bounce,)),), Section(
                ("v",), sym.lift(s, lift(s))
            )

    return Ball


def test_a_consistent_structure_builds():
    assert _ball()().phases[0].name == "flight"


@pytest.mark.parametrize(
    "defect, match",
    [
        (dict(target=1), "target"),
        (dict(reset_states=3), "the reset gives 3 states"),
        (dict(lift=lambda s: ca.vertcat(0, 2 * s[0])), "moves its own coordinates"),
        (dict(lift=lambda s: ca.vertcat(0, s[0], 1)), "section lift must map"),
    ],
)
def test_an_inconsistent_structure_is_refused_when_built(defect, match):
    with pytest.raises(ModelDefinitionError, match=match):
        _ball(**defect).structure()


def test_every_registered_model_passes_the_structure_checks():
    for name in gaitopt.REGISTRY:
        assert gaitopt.model(name).phases  # built and validated
