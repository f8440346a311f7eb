"""What a gait library is made of: the quantities it can vary, its points, the events between
them, its cold-start checks, and their JSON."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...files import jsonable
from ..result import OptimalGait

__all__ = ["CONSTRAINTS", "LibraryPoint", "LibraryEvent", "ColdCheck", "GaitLibrary"]

#: Gait constraints a library can be continued in (besides any model parameter).
CONSTRAINTS = ("period", "step_length", "speed")


@dataclass
class LibraryPoint:
    """One optimum of the library.

    Attributes
    ----------
    value : float
        The continued quantity's value (its unit: s, m, m/s or the parameter's).
    gait : OptimalGait
        The optimum found there (warm started from the previous successful point).
    warm : bool
        Whether it was warm started.
    time : float
        Wall-clock seconds of its solve.
    hessian : tuple of float
        ``(λ_min, λ_max)`` of the reduced Hessian (:func:`reduced_hessian`).
    """

    value: float
    gait: OptimalGait
    warm: bool
    time: float
    hessian: tuple[float, float] = (float("nan"), float("nan"))

    @property
    def hessian_ratio(self) -> float:
        """``λ_min / λ_max`` of the reduced Hessian (1; > 0 at a strict minimum)."""
        lo, hi = self.hessian
        return lo / hi if np.isfinite(hi) and hi != 0 else float("nan")

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types (the gait's summary, not its profile)."""
        g = self.gait
        return jsonable(
            {
                "value": self.value,
                "success": g.success,
                "message": g.message,
                "cost": g.cost,
                "period": g.period,
                "step_length": g.step_length,
                "speed": g.speed,
                "fixed_point": g.fixed_point,
                "multipliers": [complex(z) for z in g.multipliers],
                "stable": g.stable,
                "verified": g.verified,
                "discretisation_error": g.discretisation_error,
                "active_constraints": g.active_constraints,
                "reduced_hessian": list(self.hessian),
                "reduced_hessian_ratio": self.hessian_ratio,
                "warm": self.warm,
                "time": self.time,
            }
        )


@dataclass
class LibraryEvent:
    """A change between two neighbouring library points, located by bisection.

    Attributes
    ----------
    kind : str
        ``"active set"``, ``"fold"`` or ``"end"`` (warm starts stop converging, not at a fold).
    value : float
        Located value (midpoint of the final bracket).
    bracket : tuple of float
        The final bracket ``(before, after)``.
    before, after : list of str
        Active constraints on each side (``after`` empty for a fold or an end).
    message : str
        What changed.
    """

    kind: str
    value: float
    bracket: tuple[float, float]
    before: list[str]
    after: list[str]
    message: str

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types."""
        return jsonable(
            {
                "kind": self.kind,
                "value": self.value,
                "bracket": list(self.bracket),
                "before": self.before,
                "after": self.after,
                "message": self.message,
            }
        )


@dataclass
class ColdCheck:
    """The library against a cold start at one of its points.

    Attributes
    ----------
    value : float
    library_cost, cold_cost : float or None
    relative_difference : float or None
    agree : bool
        Both succeeded with costs equal to ``1e-8`` relative.
    time : float
        Wall-clock seconds of the cold solve.
    message : str
    """

    value: float
    library_cost: float | None
    cold_cost: float | None
    relative_difference: float | None
    agree: bool
    time: float
    message: str

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types."""
        return jsonable(self.__dict__)


@dataclass
class GaitLibrary:
    """A library of optimal gaits along one quantity.

    Attributes
    ----------
    success : bool
        Every point was solved and certified, and every cold-start check agrees.
    message : str
    vary : str
        The quantity continued (``period``, ``step_length``, ``speed`` or a parameter).
    points : list of LibraryPoint
    events : list of LibraryEvent
    cold_checks : list of ColdCheck
    solve_time : float
        Wall-clock seconds of the whole library.
    """

    success: bool
    message: str
    vary: str
    points: list[LibraryPoint] = field(default_factory=list)
    events: list[LibraryEvent] = field(default_factory=list)
    cold_checks: list[ColdCheck] = field(default_factory=list)
    solve_time: float = 0.0

    def __bool__(self) -> bool:
        return self.success

    @property
    def values(self) -> np.ndarray:
        """The continued quantity at each point."""
        return np.array([pt.value for pt in self.points])

    @property
    def costs(self) -> np.ndarray:
        """The optimal cost at each point (NaN where none was certified)."""
        return np.array(
            [pt.gait.cost if pt.gait.success else np.nan for pt in self.points], dtype=float
        )

    def to_json(self) -> dict[str, Any]:
        """The ``library`` object of ``gaitopt optimize --library ... --json``."""
        return jsonable(
            {
                "success": self.success,
                "message": self.message,
                "vary": self.vary,
                "points": [pt.to_json() for pt in self.points],
                "events": [e.to_json() for e in self.events],
                "cold_checks": [c.to_json() for c in self.cold_checks],
                "solve_time": self.solve_time,
            }
        )
