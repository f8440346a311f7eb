"""Bad input raises one clear error that names the argument, shows the value, suggests a fix."""

from __future__ import annotations

import dataclasses

import pytest

import gaitopt
from gaitopt import GaitoptInputError, GuessError, ParameterError, StateError, UnknownModelError


def test_unknown_model_suggests_the_close_name():
    with pytest.raises(UnknownModelError, match=r"'walkr'.*did you mean .*'simplest_walker'"):
        gaitopt.model("walkr")


def test_unknown_parameter_lists_the_parameters():
    with pytest.raises(ParameterError, match=r"unknown parameter 'slop'.*did you mean 'slope'"):
        gaitopt.model("compass_gait", slop=0.05)


@pytest.mark.parametrize(
    ("name", "params", "pattern"),
    [
        ("compass_gait", {"slope": -0.1}, r"`slope` = -0.1 is out of range; valid: \[0, 0.5\]"),
        ("compass_gait", {"mass_hip": 0}, r"`mass_hip` = 0 is out of range; valid: \(0, "),
        ("compass_gait", {"slope": "abc"}, r"`slope` must be a number, got 'abc'"),
        ("compass_gait", {"slope": float("nan")}, r"`slope` = nan is out of range"),
        ("rimless_wheel", {"spokes": 8.5}, r"`spokes` = 8.5 is out of range; valid: integer in"),
        ("rimless_wheel", {"spokes": 2}, r"`spokes` = 2 is out of range"),
        ("vanderpol", {"mu": 0}, r"`mu` = 0 is out of range"),
    ],
)
def test_parameter_out_of_range(name, params, pattern):
    with pytest.raises(ParameterError, match=pattern):
        gaitopt.model(name, **params)


def test_replace_checks_like_the_constructor():
    model = gaitopt.model("compass_gait")
    with pytest.raises(ParameterError, match="slope"):
        model.replace(slope=2.0)
    with pytest.raises(ParameterError, match="slope"):
        dataclasses.replace(model, slope=-1.0)
    assert model.replace(slope=0.06).slope == 0.06


def test_models_are_frozen():
    model = gaitopt.model("compass_gait")
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.slope = 0.1  # type: ignore[misc]


def test_guess_with_a_state_fixed_by_the_section():
    model = gaitopt.model("compass_gait")
    with pytest.raises(StateError, match=r"'swing' is fixed by the section"):
        gaitopt.find_limit_cycle(model, {"swing": 0.3})


def test_guess_with_an_unknown_state():
    model = gaitopt.model("compass_gait")
    with pytest.raises(StateError, match=r"unknown state 'knee'"):
        gaitopt.find_limit_cycle(model, {"knee": 0.3})


def test_guess_that_leads_nowhere():
    # Walking backwards from the start: the walker falls before any heel strike.
    model = gaitopt.model("compass_gait")
    with pytest.raises(
        GuessError, match=r"`guess` stance=-0.2, stance_dot=-1.*leads nowhere.*fall"
    ):
        gaitopt.find_limit_cycle(model, {"stance_dot": -1.0})


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        ({"method": "newtn"}, r"`method` must be one of newton, ipopt, got 'newtn'"),
        ({"steps": 0}, r"`steps` must be at least 1, got 0"),
        ({"inputs": [1.0, 2.0]}, r"`inputs` must be 1 finite number\(s\) \(hip_torque\)"),
    ],
)
def test_find_limit_cycle_options(kwargs, pattern):
    with pytest.raises(GaitoptInputError, match=pattern):
        gaitopt.find_limit_cycle(gaitopt.model("compass_gait"), **kwargs)


def test_discretisation_validates_itself():
    with pytest.raises(GaitoptInputError, match=r"`segments` must be a positive integer, got 0"):
        gaitopt.MultipleShooting(segments=0)


def test_simulate_options():
    model = gaitopt.model("compass_gait")
    with pytest.raises(GaitoptInputError, match=r"`method` must be one of DOP853"):
        gaitopt.simulate(model, None, method="Euler")
    with pytest.raises(StateError, match=r"unknown state"):
        gaitopt.simulate(model, {"stance": 0.1, "knee": 0.0, "stance_dot": 1, "swing_dot": 0})


def test_input_errors_are_value_errors():
    # Callers that only know ValueError keep working (python-control's exception habit).
    assert issubclass(GaitoptInputError, ValueError)
