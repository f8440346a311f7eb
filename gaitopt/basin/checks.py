"""The estimates' shared settings, checked: the limits of the counts, the gait and its model as
plain data (:class:`Setup`, what every task needs), scales, windows and chosen coordinates."""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..arguments import check_count, check_positive
from ..errors import GaitoptInputError

__all__ = [
    "LIMIT",
    "MAX_CHUNK",
    "MAX_POINTS",
    "MAX_RAYS",
    "MAX_SAMPLES",
    "MAX_STEPS",
    "Setup",
    "check_setup",
    "chosen_coordinates",
    "per_coordinate",
    "unstable",
    "window_box",
]

#: Most rays, grid points per axis and samples: each is at least one simulation of
#: ``steps + hold`` periods.
MAX_RAYS = 4096
MAX_POINTS = 400
MAX_SAMPLES = 100_000
#: Most points per Dask task (the sweep's limit).
MAX_CHUNK = 10_000
MAX_STEPS = 10_000
LIMIT = "each is one simulation of up to steps + hold periods; run several smaller estimates"


@dataclass(frozen=True)
class Setup:
    """What every task needs: JSON-able, so that a chunk is a point of :func:`sweep`."""

    model: str
    params: dict[str, float]
    coordinates: list[str]  # every section coordinate, in the section's order
    centre: list[float]  # the fixed point in those
    inputs: list[float] | None
    period: int  # returns per period of the gait
    steps: int
    hold: int
    tol: float
    scale: list[float]  # per section coordinate

    def point(self, **extra: Any) -> dict[str, Any]:
        return {"setup": self.__dict__, **extra}


def check_setup(gait: Any, steps: Any, hold: Any, tol: Any, scale: Any) -> Setup:
    """Check the gait and the shared settings; one-line errors naming the argument."""
    from ..models import model as make_model

    if not all(hasattr(gait, name) for name in ("model", "section_point", "success")):
        raise GaitoptInputError(
            f"`gait` must be a gait (from gaitopt.find_limit_cycle), got {type(gait).__name__}"
        )
    if not gait.success:
        reason = " ".join(str(getattr(gait, "message", "")).split())[:160]
        raise GaitoptInputError(f"`gait` is not a gait (success is False: {reason})")
    steps = check_count("steps", steps, 1, MAX_STEPS, LIMIT)
    hold = check_count("hold", hold, 1, MAX_STEPS, LIMIT)
    tol = check_positive("tol", tol, "1e-4")
    model = gait.model
    coordinates = list(model.section.coordinates)
    centre = np.asarray(gait.section_point, dtype=float).ravel()
    if scale is None:
        scale = np.where(np.abs(centre) > 0, np.abs(centre), 1.0)
    else:
        scale = per_coordinate("scale", scale, coordinates)
    try:
        rebuilt = make_model(model.name, **model.params)
    except GaitoptInputError:
        rebuilt = None
    if rebuilt is None or rebuilt.params != model.params:
        raise GaitoptInputError(
            f"`gait`: its model {model.name!r} cannot be rebuilt by name and parameters for the "
            f"simulation tasks; register it (gaitopt.register)"
        )
    inputs = np.asarray(getattr(gait, "inputs", ()), dtype=float).ravel()
    return Setup(
        model.name,
        dict(model.params),
        coordinates,
        centre.tolist(),
        inputs.tolist() if inputs.size else None,
        int(getattr(gait, "steps", 1) or 1),
        steps,
        hold,
        tol,
        [float(s) for s in scale],
    )


def per_coordinate(name: str, value: Any, coordinates: Sequence[str]) -> np.ndarray:
    """``scale`` (or a window's half width): a positive number, one per coordinate, or a mapping
    by coordinate name (missing names: error)."""
    if isinstance(value, Mapping):
        unknown = set(value) - set(coordinates)
        if unknown:
            raise GaitoptInputError(
                f"`{name}`: {sorted(unknown)[0]!r} is not a section coordinate "
                f"({', '.join(coordinates)})"
            )
        missing = [c for c in coordinates if c not in value]
        if missing:
            raise GaitoptInputError(f"`{name}` has no entry for {missing[0]!r}")
        value = [value[c] for c in coordinates]
    if isinstance(value, numbers.Real):
        value = [value] * len(coordinates)
    values = list(np.asarray(value, dtype=object).ravel())
    if len(values) != len(coordinates):
        raise GaitoptInputError(
            f"`{name}` needs {len(coordinates)} values ({', '.join(coordinates)}), got "
            f"{len(values)}"
        )
    return np.array([check_positive(name, v, "0.1") for v in values])


def unstable(gait: Any) -> str | None:
    """Why no neighbourhood of the fixed point converges (a multiplier outside the unit circle)."""
    multipliers = np.abs(np.asarray(getattr(gait, "multipliers", ()), dtype=complex))
    if multipliers.size and multipliers.max() > 1:
        return (
            f"the gait is unstable: a multiplier has |λ| = {multipliers.max():.6g} > 1, so no "
            f"neighbourhood of the fixed point converges; the basin is empty"
        )
    return None


def chosen_coordinates(
    name: str, given: Sequence[str] | None, coordinates: Sequence[str], n: int | None
):
    """Coordinates named by ``given`` (all if None), each a section coordinate."""
    chosen = list(coordinates) if given is None else list(given)
    for c in chosen:
        if c not in coordinates:
            raise GaitoptInputError(
                f"`{name}`: {c!r} is not a section coordinate ({', '.join(coordinates)})"
            )
    if len(set(chosen)) != len(chosen) or not chosen or (n is not None and len(chosen) != n):
        count = f"{n} different" if n else "different"
        raise GaitoptInputError(f"`{name}` must name {count} section coordinates, got {chosen}")
    return chosen


def window_box(setup: Setup, window: Any) -> dict[str, tuple[float, float]]:
    """The box: ``{name: (low, high)}`` given, or ``x* ± half widths · scale`` from a number or
    one half width per coordinate (scaled)."""
    if isinstance(window, Mapping) and all(
        isinstance(v, Sequence) and not isinstance(v, str) for v in window.values()
    ):
        box = {}
        for c in setup.coordinates:
            if c not in window:
                raise GaitoptInputError(f"`window` has no range for {c!r}")
            low, high = (float(v) for v in window[c])
            if not (math.isfinite(low) and math.isfinite(high) and low < high):
                raise GaitoptInputError(
                    f"`window` range of {c!r} must be low < high, got {window[c]!r}"
                )
            box[c] = (low, high)
        return box
    half = per_coordinate("window", window, setup.coordinates) * np.asarray(setup.scale)
    return {
        c: (float(x - h), float(x + h))
        for c, x, h in zip(setup.coordinates, setup.centre, half, strict=True)
    }
