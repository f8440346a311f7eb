"""Axis labels of gait figures: each state's unit from the model's declaration, and the labels
``"quantity (unit)"`` built from it.
"""

from __future__ import annotations

from ..hybrid import HybridModel

__all__ = ["coordinate_pairs", "state_unit", "unit_label", "time_label", "state_label"]

_RATE_SUFFIX = "_dot"


def coordinate_pairs(states: tuple[str, ...] | list[str]) -> list[str]:
    """The coordinates ``q`` of ``states`` whose rate ``q_dot`` is also a state, in state order.

    >>> coordinate_pairs(("stance", "swing", "stance_dot", "swing_dot"))
    ['stance', 'swing']
    """
    return [q for q in states if not q.endswith(_RATE_SUFFIX) and q + _RATE_SUFFIX in states]


def state_unit(model: HybridModel, name: str) -> str | None:
    """Unit of state ``name`` from the model's declared :attr:`HybridModel.state_units`; a rate
    ``q_dot`` not listed gets ``unit(q)/time unit``; None if nothing is declared."""
    units = dict(model.state_units)
    if name in units:
        return units[name]
    if name.endswith(_RATE_SUFFIX) and name[: -len(_RATE_SUFFIX)] in units:
        base, time = units[name[: -len(_RATE_SUFFIX)]], model.time_unit
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
