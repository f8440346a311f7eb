"""Errors of controller design, and the check that a requested section point exists."""

from __future__ import annotations

from collections.abc import Mapping

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..result import LimitCycle


class ControlDesignError(GaitoptInputError):
    """A controller that cannot be designed for this model (no input, wrong sizes)."""


class NoGaitError(RuntimeError):
    """No gait to control: the search failed (``cycle`` holds the failed search and its
    message)."""

    def __init__(self, message: str, cycle: LimitCycle | None = None):
        super().__init__(message)
        self.cycle = cycle


def check_section_point(
    model: HybridModel, state: Mapping[str, float], argument: str, label: str | None = None
) -> None:
    """A section point asked for (a target, a start) must exist at the model's parameters.

    A model whose section ends at closed-form limits declares them
    (:meth:`~gaitopt.hybrid.HybridModel.section_limits`): the SLIP's apex height ``z`` cannot
    exceed the energy height ``E/(m g)``, where no forward speed is left; a state above it has
    more energy than the model and is bad input, not a gait or a decision that fails.

    Parameters
    ----------
    model : HybridModel
    state : mapping
        Section coordinates by name.
    argument : str
        The argument's name, for the message.
    label : str, optional
        What the message starts with instead of ```argument` z=VALUE`` (the CLI: ``--from z=10``).

    Raises
    ------
    ControlDesignError
        Naming ``argument``, the value and the limit.
    """
    for name, (low, high, why) in model.section_limits().items():
        if name not in state:
            continue
        value = float(state[name])
        if not low <= value <= high:
            label_ = f"`{argument}` {name}={value:g}" if label is None else label
            side = f"above {high:.6g}" if value > high else f"below {low:.6g}"
            raise ControlDesignError(
                f"{label_}: {name} = {value:g} is {side}, outside the range where the section "
                f"exists at these parameters: {why}"
            )
