"""Parameters that many models declare alike: masses, lengths, stiffnesses, energies (each
positive, in SI units), coefficients of restitution and the ground's slope; and the units of a
state (:func:`state_units`).

Each helper is :func:`gaitopt.parameters.parameter` with the unit and range fixed by the kind of
quantity, so that a mass is a positive number of kilograms in every model, as
:func:`gaitopt.parameters.gravity_parameter` does for ``g``.
"""

from __future__ import annotations

from typing import Any

from ..parameters import parameter

__all__ = [
    "positive_parameter",
    "mass_parameter",
    "length_parameter",
    "stiffness_parameter",
    "energy_parameter",
    "restitution_parameter",
    "slope_parameter",
    "state_units",
]


def positive_parameter(default: float, unit: str, doc: str, source: str, high: float) -> Any:
    """A parameter that must be positive: range ``(0, high]`` (a mass, a length, a stiffness, an
    energy)."""
    return parameter(default, unit=unit, doc=doc, source=source, low=0.0, high=high, low_open=True)


def mass_parameter(default: float, doc: str, source: str, *, high: float = 1e4) -> Any:
    """A mass (kg), range ``(0, high]`` (default up to 10 t)."""
    return positive_parameter(default, "kg", doc, source, high)


def length_parameter(default: float, doc: str, source: str, *, high: float = 10.0) -> Any:
    """A length (m), range ``(0, high]`` (default up to 10 m)."""
    return positive_parameter(default, "m", doc, source, high)


def stiffness_parameter(default: float, doc: str, source: str, *, high: float = 1e7) -> Any:
    """A spring stiffness (N/m), range ``(0, high]``."""
    return positive_parameter(default, "N/m", doc, source, high)


def energy_parameter(default: float, doc: str, source: str) -> Any:
    """An energy (J), range ``(0, 1e8]``."""
    return positive_parameter(default, "J", doc, source, 1e8)


def restitution_parameter(default: float, doc: str, source: str) -> Any:
    """A coefficient of restitution ``e`` (dimensionless), range ``(0, 1)``: 0 a plastic impact
    (excluded: no bounce), 1 an elastic one (excluded: no loss)."""
    return parameter(
        default, unit="1", doc=doc, source=source, low=0.0, high=1.0, low_open=True, high_open=True
    )


def slope_parameter(
    default: float,
    source: str,
    within: tuple[float, float],
    *,
    doc: str = "ground slope γ (downhill positive)",
    high_open: bool = False,
) -> Any:
    """The ground's slope ``γ`` (rad) in the closed range ``within`` (open at the top when
    ``high_open``)."""
    low, high = within
    return parameter(
        default, unit="rad", doc=doc, source=source, low=low, high=high, high_open=high_open
    )


def state_units(**coordinates: str) -> dict[str, str]:
    """Units of the coordinates and of their rates ``<name>_dot`` (the unit per second), for
    axis labels: ``state_units(stance="rad", swing="rad")`` is ``{"stance": "rad", "swing":
    "rad", "stance_dot": "rad/s", "swing_dot": "rad/s"}``."""
    return {**coordinates, **{f"{name}_dot": f"{unit}/s" for name, unit in coordinates.items()}}
