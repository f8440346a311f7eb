"""Physical parameters of a model: unit, documentation, default with its source, valid range.

A model is a frozen dataclass whose fields are declared with :func:`parameter`; the range is
checked when the model is built (``__post_init__``), so an invalid model cannot exist.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from .errors import ParameterError

__all__ = [
    "ParameterSpec",
    "parameter",
    "parameter_specs",
    "check_parameter",
    "gravity_parameter",
    "STANDARD_GRAVITY",
]

#: Standard gravity (m/s²), rounded as in the textbooks the models follow (9.80665 exactly).
STANDARD_GRAVITY = 9.81


@dataclass(frozen=True)
class ParameterSpec:
    """Metadata of one physical parameter.

    Attributes
    ----------
    name : str
        Field name; filled in from the dataclass field.
    unit : str
        SI unit (``"1"`` for dimensionless).
    default : float
        Default value.
    doc : str
        What the parameter is.
    source : str
        Where the default comes from.
    low, high : float
        Bounds of the valid range.
    low_open, high_open : bool
        Whether the bound itself is excluded.
    integer : bool
        Whether only integer values are valid (the rimless wheel's number of spokes).
    """

    name: str
    unit: str
    default: float
    doc: str
    source: str
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    integer: bool = False

    def range_text(self) -> str:
        """The valid range in interval notation, e.g. ``(0, 0.5]``."""
        left = "(" if self.low_open or math.isinf(self.low) else "["
        right = ")" if self.high_open or math.isinf(self.high) else "]"
        kind = "integer in " if self.integer else ""
        return f"{kind}{left}{_fmt(self.low)}, {_fmt(self.high)}{right}"

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies in the valid range."""
        if self.integer and value != int(value):
            return False
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready description (``gaitopt list --json``)."""
        fields = ("name", "unit", "default", "doc", "source")
        return {**{key: getattr(self, key) for key in fields}, "range": self.range_text()}


def _fmt(x: float) -> str:
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:g}"


def parameter(
    default: float,
    *,
    unit: str,
    doc: str,
    source: str,
    low: float = -math.inf,
    high: float = math.inf,
    low_open: bool = False,
    high_open: bool = False,
    integer: bool = False,
) -> Any:
    """Declare a model parameter as a dataclass field (see :class:`ParameterSpec`)."""
    spec = ParameterSpec("", unit, default, doc, source, low, high, low_open, high_open, integer)
    return dataclasses.field(default=default, metadata={"gaitopt": spec})


def gravity_parameter(source: str = "standard gravity", default: float = STANDARD_GRAVITY) -> Any:
    """The gravitational acceleration ``g`` (m/s², default :data:`STANDARD_GRAVITY`, range
    (0, 100]) as a model parameter: every model with gravity declares it with this, so that its
    name, unit and range are the same in each.  ``source``: where the model's default comes
    from, if not simply standard gravity (the five-link biped: OptimTraj's value); ``default``:
    a paper's own rounding (Grizzle's 9.8 for the three-link walker)."""
    doc = "gravitational acceleration g"
    return parameter(
        default, unit="m/s^2", doc=doc, source=source, low=0.0, high=100.0, low_open=True
    )


def parameter_specs(model_cls: type) -> tuple[ParameterSpec, ...]:
    """The parameter specifications of a model class, in declaration order."""
    return tuple(
        dataclasses.replace(f.metadata["gaitopt"], name=f.name)
        for f in dataclasses.fields(model_cls)
        if "gaitopt" in f.metadata
    )


def check_parameter(model_name: str, spec: ParameterSpec, value: Any) -> float:
    """Return ``value`` as a float, or raise :class:`ParameterError` naming what is wrong."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise ParameterError(
                f"{model_name}: parameter `{spec.name}` must be a number, got {value!r}; "
                f"e.g. {spec.name}={spec.default:g}"
            ) from None
    value = float(value)
    if not math.isfinite(value) or not spec.contains(value):
        unit = "" if spec.unit == "1" else f" {spec.unit}"
        raise ParameterError(
            f"{model_name}: parameter `{spec.name}` = {value:g} is out of range; valid: "
            f"{spec.range_text()}{unit}, default {spec.default:g}"
        )
    return value
