"""Axis labels of gait figures: each state's unit from the model's declaration, and the labels
``"quantity (unit)"`` built from it.
"""

from __future__ import annotations

from ..hybrid import HybridModel

__all__ = [
    "coordinate_pairs",
    "state_unit",
    "unit_label",
    "time_label",
    "state_label",
    "time_axis_label",
    "is_rate",
    "state_quantity",
    "input_unit",
    "input_quantity",
    "speed_unit",
    "cost_unit",
]

RATE_SUFFIX = "_dot"


def coordinate_pairs(states: tuple[str, ...] | list[str]) -> list[str]:
    """The coordinates ``q`` of ``states`` whose rate ``q_dot`` is also a state, in state order.

    >>> coordinate_pairs(("stance", "swing", "stance_dot", "swing_dot"))
    ['stance', 'swing']
    """
    return [q for q in states if not q.endswith(RATE_SUFFIX) and q + RATE_SUFFIX in states]


def state_unit(model: HybridModel, name: str) -> str | None:
    """Unit of state ``name`` from the model's declared :attr:`HybridModel.state_units`; a rate
    ``q_dot`` not listed gets ``unit(q)/time unit``; None if nothing is declared."""
    units = dict(model.state_units)
    if name in units:
        return units[name]
    if name.endswith(RATE_SUFFIX) and name[: -len(RATE_SUFFIX)] in units:
        base, time = units[name[: -len(RATE_SUFFIX)]], model.time_unit
        return base if time == "1" and base == "1" else f"{base}/{time}"
    return None


def unit_label(unit: str | None) -> str:
    """``"(rad)"``; ``"(dimensionless)"`` for ``"1"``; ``"(unit not declared)"`` for None."""
    if unit is None:
        return "(unit not declared)"
    return "(dimensionless)" if unit == "1" else f"({unit})"


def time_label(model: HybridModel) -> str:
    """The model's time unit for labels: ``"s"``; ``"(dimensionless time)"`` for ``"1"``; a
    named dimensionless time (``"τ"``) with that note."""
    unit = model.time_unit
    if unit == "s":
        return "s"
    return "(dimensionless time)" if unit == "1" else f"{unit} (dimensionless time)"


def state_label(model: HybridModel, name: str, when: str = "") -> str:
    """Axis label of a state: ``"theta_dot just after return n (rad/s)"``."""
    text = f"{name} {when}".strip()
    return f"{text} {unit_label(state_unit(model, name))}"


def time_axis_label(model: HybridModel, since: str = "the section") -> str:
    """Label of a time axis: ``"time t since the section (s)"``; in dimensionless time
    ``"time t since the section (dimensionless)"``, or with its name (``"(τ, dimensionless)"``)."""
    unit = model.time_unit
    if unit in ("s", "1"):
        return f"time t since {since} {unit_label(unit)}"
    return f"time t since {since} ({unit}, dimensionless)"


def is_rate(model: HybridModel, name: str) -> bool:
    """Whether state ``name`` is a rate: ``q_dot`` of a state ``q``, or a partner the model names
    in :attr:`HybridModel.rates` (the line juggler's ``v``)."""
    return name.endswith(RATE_SUFFIX) or name in model.rates.values()


def state_quantity(model: HybridModel, name: str) -> str:
    """What kind of quantity state ``name`` is, from its declared unit: ``"angle"``,
    ``"angular rate"``, ``"position"``, ``"velocity"``; else ``"rate"`` or ``"coordinate"``."""
    unit, time, length = state_unit(model, name), model.time_unit, model.length_unit
    rate_of = {f"rad/{time}": "angular rate", f"{length}/{time}": "velocity"}
    if is_rate(model, name):
        return rate_of.get(unit or "", "rate")
    return {"rad": "angle", length: "position"}.get(unit or "", "coordinate")


def input_unit(model: HybridModel, name: str) -> str | None:
    """Unit of input ``name`` from the model's declared :attr:`HybridModel.input_units`; None if
    the model declares none."""
    units = dict(zip(model.inputs, model.input_units, strict=False))
    return units.get(name)


#: The kind of quantity an input of a unit is (others are called "input").
_INPUT_QUANTITIES = {"N*m": "torque", "N": "force", "rad": "angle", "m": "length", "s": "time"}


def input_quantity(model: HybridModel, name: str) -> str:
    """What kind of quantity input ``name`` is: an impulsive input
    (:attr:`HybridModel.impulsive_inputs`) an ``"impulse"``, ``*_torque`` or an input in N·m a
    ``"torque"``, ``*_force`` or N a ``"force"``, …; else ``"input"``."""
    if name in model.impulsive_inputs:
        return "impulse"
    for kind in ("torque", "force"):  # a torque in units of M·g·l is still a torque
        if name.endswith(f"_{kind}"):
            return kind
    return _INPUT_QUANTITIES.get(input_unit(model, name) or "", "input")


def speed_unit(model: HybridModel) -> str:
    """The unit of a speed in ``model``: ``length_unit/time_unit`` (``"m/s"``, ``"l/τ"``)."""
    time = model.time_unit
    return model.length_unit if time == "1" else f"{model.length_unit}/{time}"


def cost_unit(model: HybridModel, kind: str) -> str:
    """The unit of an optimised cost in ``model``'s declared units: ``effort`` ∫Σu² dt is
    (input unit)²·(time unit) over the inputs that act in the flow, ``work`` the model's energy
    unit, ``cot`` dimensionless (``"1"``); another kind is in the user's units.

    >>> from gaitopt import model
    >>> cost_unit(model("compass_gait"), "effort"), cost_unit(model("simplest_walker"), "work")
    ('(N*m)^2*s', 'M*g*l')
    """
    if kind == "cot":
        return "1"
    if kind == "work":
        return model.energy_unit
    if kind != "effort":
        return "user units"
    units = dict(zip(model.inputs, model.input_units, strict=False))
    flowing = {units.get(n) for n in model.inputs if n not in model.impulsive_inputs}
    time = "" if model.time_unit == "1" else f"*{model.time_unit}"
    if len(flowing) == 1 and None not in flowing:
        (unit,) = flowing
        return f"{time[1:] or '1'}" if unit == "1" else f"({unit})^2{time}"
    return f"(input unit)^2{time}"
