"""The checks of a :class:`~gaitopt.optimize.problem.GaitProblem`'s statement, each a one-line
:class:`~gaitopt.errors.GaitoptInputError` naming the argument, the value and a fix, made before
any work: the model, the cost, the lengths and margins, the input and state bounds, the named
limits and free parameters, and the level-ground refusal (:func:`check_not_standing`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ..errors import GaitoptInputError, did_you_mean
from ..hybrid import HybridModel

__all__ = [
    "COSTS",
    "MAX_STEPS",
    "WHY_STEPS",
    "all_state_names",
    "bound_pair",
    "check_bounds",
    "check_footholds",
    "check_cost",
    "check_free",
    "check_lengths",
    "check_margins",
    "check_model",
    "check_not_standing",
    "check_path_constraints",
    "check_state_bounds",
    "declared_limits",
    "names_of",
    "positive",
    "state_pair",
]

COSTS = ("effort", "work", "cot")
#: Most returns to the section per optimised orbit (``steps``, ``--steps``).  The transcription
#: and its refinements grow with every step, faster than linearly (measured, one start, loaded
#: 2-core machine): the five-link biped took 10 s and 0.6 GB at 1 step, 31 s and 1.1 GB at 2,
#: 295 s and 9.1 GB at 4; the compass gait 1.1 s and 0.16 GB at 1, 6.6 s and 0.45 GB at 8.
#: ``steps=1000`` grew past 5 GB before its first iteration.
MAX_STEPS = 4
WHY_STEPS = (
    "the transcription grows faster than the number of steps (the five-link biped: 9 GB at 4 "
    f"steps); use steps <= {MAX_STEPS} (gaitopt.optimize.problem.MAX_STEPS)"
)


def names_of(argument: str, value: Any, example: str) -> tuple[str, ...]:
    """A name or an iterable of names as a tuple of str, or a one-line input error."""
    if isinstance(value, str):
        return (value,)
    try:
        names = tuple(value)
    except TypeError:
        names = None
    if names is None or not all(isinstance(n, str) for n in names):
        raise GaitoptInputError(
            f"`{argument}` must be a name or a tuple of names, got {value!r:.80}; "
            f"e.g. {argument}={example}"
        )
    return names


def bound_pair(name: str, value: Any) -> tuple[float, float]:
    """``bounds[name]`` as ``(low, high)``: a number ``b >= 0`` means ``(−b, b)``."""
    try:
        if isinstance(value, (tuple, list)):
            low, high = (float(v) for v in value)
        else:
            high = float(value)
            low = -high
    except (TypeError, ValueError):
        low = high = math.nan
    if not (math.isfinite(low) and math.isfinite(high) and low <= high):
        raise GaitoptInputError(
            f"`bounds[{name!r}]` must be a finite number >= 0 (|u| <= it; 0 switches the input "
            f"off) or a pair (low, high) with low <= high, got {value!r}; e.g. "
            f"bounds={{{name!r}: 20}} or bounds={{{name!r}: (0, 20)}}"
        )
    return low, high


def positive(name: str, value: Any, *, allow_none: bool = True) -> float | None:
    if value is None and allow_none:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not math.isfinite(number) or number <= 0:
        raise GaitoptInputError(
            f"`{name}` must be a positive finite number, got {value!r}; e.g. {name}=0.8"
        )
    return number


def all_state_names(model: HybridModel) -> tuple[str, ...]:
    """Every phase's state names, once each, in order of first appearance."""
    return tuple(dict.fromkeys(n for phase in model.phases for n in phase.states))


def declared_limits(model: HybridModel) -> tuple[str, ...]:
    """Names of the limits the model's phases declare (:attr:`gaitopt.hybrid.Phase.limits`)."""
    return tuple(dict.fromkeys(n for phase in model.phases for n in phase.limits))


def state_pair(name: str, pair: Any) -> tuple[float, float]:
    """``state_bounds[name]`` as ``(low, high)``: two numbers, ``low < high``, not both infinite."""
    try:
        low, high = (float(v) for v in pair)
    except (TypeError, ValueError):
        low = high = math.nan
    if (
        math.isnan(low)
        or math.isnan(high)
        or not low < high
        or low == math.inf
        or (high == -math.inf)
    ):
        raise GaitoptInputError(
            f"`state_bounds[{name!r}]` must be a pair (low, high) of numbers with low < high "
            f"(one side may be infinite), got {pair!r}; e.g. state_bounds={{{name!r}: (-1.0, 1.0)}}"
        )
    if math.isinf(low) and math.isinf(high):
        raise GaitoptInputError(
            f"`state_bounds[{name!r}]` = {pair!r} bounds nothing; give a finite side, e.g. "
            f"state_bounds={{{name!r}: (0.0, math.inf)}}, or leave {name!r} out"
        )
    return low, high


def check_model(model: Any) -> None:
    """A gaitopt model with inputs to optimise."""
    if not isinstance(model, HybridModel):
        raise GaitoptInputError(
            f"`model` must be a gaitopt model, got {type(model).__name__}; "
            f"e.g. gaitopt.model('compass_gait')"
        )
    if not model.inputs:
        raise GaitoptInputError(
            f"`model` {model.name!r} has no inputs to optimise; choose an actuated model "
            f"(e.g. compass_gait)"
        )


def check_cost(model: HybridModel, cost: Any, bounds: Any) -> None:
    """A named cost (the work-based ones need every input bounded and the rates they do work on)
    or a callable."""
    if isinstance(cost, str):
        if cost not in COSTS:
            raise GaitoptInputError(
                f"`cost` must be one of {', '.join(COSTS)} or a CasADi callable, got "
                f"{cost!r}; {did_you_mean(cost, COSTS)}e.g. cost='effort'"
            )
        if cost in ("work", "cot"):
            unbounded = [
                n for n in model.inputs if n not in dict(bounds) and n not in model.impulsive_inputs
            ]
            if unbounded:
                raise GaitoptInputError(
                    f"`cost` {cost!r} needs a bound on every input (positive work has "
                    f"no minimum without one: impulsive inputs approach its infimum); "
                    f"unbounded: {', '.join(unbounded)}; e.g. bounds={{{unbounded[0]!r}: 20}}"
                )
            missing = [i for i in range(len(model.phases)) if model.input_rates(i) is None]
            if missing:
                raise GaitoptInputError(
                    f"`cost` {cost!r} needs the rates the inputs do work on, which "
                    f"{model.name} does not declare (HybridModel.input_rates); use "
                    f"cost='effort'"
                )
    elif not callable(cost):
        raise GaitoptInputError(f"`cost` must be a name or a callable cost(x, u, p), got {cost!r}")


def check_lengths(
    period: Any, step_length: Any, speed: Any, steps: int
) -> tuple[float | None, float | None, float | None]:
    """Period, step length and speed: each positive or None, and at most two of them fixed
    unless they agree."""
    period, step_length, speed = (positive("period", period), positive("step_length", step_length),
                                  positive("speed", speed))  # fmt: skip
    if period is not None and step_length is not None and speed is not None:
        if abs(step_length * steps / period - speed) > 1e-12 * speed:
            raise GaitoptInputError(
                f"`speed` {speed:g} contradicts step_length/period = "
                f"{step_length * steps / period:g}; fix at most two of them"
            )
    return period, step_length, speed


def check_margins(
    clearance_value: Any, guard_margin: Any, continuous_inputs: Any
) -> tuple[float, float]:
    """The clearance (m) and guard margin (the guard's unit), finite and >= 0, and
    ``continuous_inputs`` a bool."""
    clearance = float(clearance_value) if isinstance(clearance_value, (int, float)) else -1.0
    if not (math.isfinite(clearance) and clearance >= 0):
        raise GaitoptInputError(
            f"`clearance` must be a finite length >= 0 (m), got {clearance_value!r}; "
            f"e.g. clearance=0.01"
        )
    margin = float(guard_margin) if isinstance(guard_margin, (int, float)) else -1.0
    if not (math.isfinite(margin) and margin >= 0):
        raise GaitoptInputError(
            f"`guard_margin` must be a finite number >= 0 (the guard's unit), got "
            f"{guard_margin!r}; e.g. guard_margin=0.05"
        )
    if not isinstance(continuous_inputs, bool):
        raise GaitoptInputError(
            f"`continuous_inputs` must be True or False, got {continuous_inputs!r}"
        )
    return clearance, margin


def check_bounds(model: HybridModel, bounds: Any) -> None:
    """``bounds``: a mapping of the model's inputs (not states) to a bound or a pair."""
    states = all_state_names(model)
    if not isinstance(bounds, Mapping):
        raise GaitoptInputError(
            f"`bounds` must be a mapping {{input: max}} or {{input: (low, high)}}, got "
            f"{bounds!r:.80}; e.g. bounds={{{(model.inputs or ('u',))[0]!r}: 20}}"
        )
    for name, value in dict(bounds).items():
        if name not in model.inputs and name in states:
            raise GaitoptInputError(
                f"`bounds` names {name!r}, a state of {model.name}, not an input; bound "
                f"states with state_bounds, e.g. state_bounds={{{name!r}: (-1.0, 1.0)}}"
            )
        if name not in model.inputs:
            raise GaitoptInputError(
                f"`bounds` names unknown input {name!r}; {did_you_mean(name, model.inputs)}"
                f"{model.name}'s inputs: {', '.join(model.inputs)}"
            )
        bound_pair(name, value)


def check_state_bounds(model: HybridModel, state_bounds: Any) -> dict[str, tuple[float, float]]:
    """``state_bounds``: a mapping of the model's states to ``(low, high)``, checked."""
    states = all_state_names(model)
    if not isinstance(state_bounds, Mapping):
        raise GaitoptInputError(
            f"`state_bounds` must be a mapping {{state: (low, high)}}, got "
            f"{state_bounds!r:.80}; e.g. state_bounds={{{states[0]!r}: (-1.0, 1.0)}}"
        )
    checked = {}
    for name, pair in dict(state_bounds).items():
        if name not in states:
            also = f"; {name!r} is an input: bound it with bounds" if name in model.inputs else ""
            raise GaitoptInputError(
                f"`state_bounds` names unknown state {name!r}{also}; "
                f"{did_you_mean(name, states)}{model.name}'s states: {', '.join(states)}"
            )
        checked[name] = state_pair(name, pair)
    return checked


def check_path_constraints(model: HybridModel, path_constraints: Any) -> tuple[str, ...]:
    """Names of limits the model's phases declare, each once."""
    paths = names_of("path_constraints", path_constraints, "('knee_flexion',)")
    declared = declared_limits(model)
    for name in paths:
        if name not in declared:
            have = (
                f"{model.name}'s limits: {', '.join(declared)}"
                if declared
                else f"{model.name} declares none (Phase.limits)"
            )
            raise GaitoptInputError(
                f"`path_constraints` names unknown limit {name!r}; "
                f"{did_you_mean(name, declared) if declared else ''}{have}"
            )
    if len(set(paths)) != len(paths):
        raise GaitoptInputError(
            f"`path_constraints` names a limit twice: {', '.join(paths)}; name each once"
        )
    return paths


def check_free(model: HybridModel, free: Any) -> tuple[str, ...]:
    """Names of the model's parameters, each once."""
    params = model.params
    free = names_of("free", free, "('slope',)")
    if len(set(free)) != len(free):
        raise GaitoptInputError(
            f"`free` names a parameter twice: {', '.join(free)}; name each once"
        )
    for name in free:
        if name not in params:
            raise GaitoptInputError(
                f"`free` names unknown parameter {name!r}; {did_you_mean(name, params)}"
                f"{model.name}'s parameters: {', '.join(params)}"
            )
    return free


def check_footholds(problem: Any) -> None:
    """Step length, speed and the work-based costs need the model's footholds."""
    if problem.cost in ("work", "cot") or problem.step_length or problem.speed:
        if problem.footholds() is None:
            raise GaitoptInputError(
                f"{problem.model.name} declares no foothold, so step length, speed and cost of "
                f"transport are undefined; leave them free and use cost='effort'"
            )


def check_not_standing(problem: Any) -> None:
    """A walker on level ground with nothing fixed has no optimal gait: gravity does no work
    over a step, so every step costs effort (or positive work) to replace what the heel
    strike loses, and the shorter and slower the step the less; the infimum, 0, is standing
    still, which is no gait.  The optimiser would shrink the step towards it (at slope
    1e-12 the compass gait's ended at 4 mm after about a minute, its refinement never
    settling; the five-link biped's at a 4 cm shuffle of effort 2.4e-5 N²·m²·s, against
    263.7 for OptimTraj's 0.4 m step), so the statement is refused before any work.  Not
    for the cost of transport (per distance) or a user's cost, nor when the slope is free
    (a passive gait downhill costs nothing)."""
    model = problem.model
    if problem.cost not in ("effort", "work") or problem.footholds() is None:
        return
    if problem.period is not None or problem.step_length is not None or problem.speed is not None:
        return
    if "slope" not in model.params or "slope" in problem.free or model.params["slope"] != 0:
        return
    what = "effort" if problem.cost == "effort" else "positive work"
    low, high = problem.input_bounds()
    impulses = [model.inputs[j] for j in problem.impulsive_index if low[j] < 0 or high[j] > 0]
    also = (
        f" (and every gait {' and '.join(impulses)} alone powers: the effort leaves impulses out)"
        if impulses and problem.cost == "effort"
        else ""
    )
    default = next(sp.default for sp in model.parameter_specs() if sp.name == "slope")
    downhill = (
        f", or walk down a slope, e.g. gaitopt.model({model.name!r}, slope={default:g})"
        if model.passive_gait and default > 0
        else ""
    )
    raise GaitoptInputError(
        f"{model.name} on level ground (slope=0) with no `period`, `step_length` or `speed` "
        f"given has no optimal gait: the least {what} is 0, reached by standing still"
        f"{also}, and the optimiser would only shrink the step towards it; fix a step "
        f"length, period or speed, e.g. step_length=0.3 and period=0.8{downhill}"
    )
