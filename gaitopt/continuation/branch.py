"""What continuation takes and gives: :class:`PseudoArclength` (step control),
:class:`SpecialPoint` and :class:`Branch`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..result import STATUS, LimitCycle, status_of

__all__ = ["Branch", "PseudoArclength", "SpecialPoint"]


@dataclass(frozen=True)
class PseudoArclength:
    """Options of the pseudo-arclength continuation (validated on construction).

    Attributes
    ----------
    step : float
        First arclength step (scaled units: parameter relative to its start value, states in
        their units averaged over the unknowns).
    min_step, max_step : float
        Bounds of the adaptive step.
    max_points : int
        Most points per branch (each direction).
    max_corrector : int
        Newton iterations allowed per corrector.
    """

    step: float = 0.02
    min_step: float = 1e-8
    max_step: float = 0.25
    max_points: int = 400
    max_corrector: int = 8

    def __post_init__(self) -> None:
        for name in ("step", "min_step", "max_step"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise GaitoptInputError(f"PseudoArclength: `{name}` must be > 0, got {value!r}")
        if not self.min_step <= self.step <= self.max_step:
            raise GaitoptInputError(
                f"PseudoArclength: need min_step ≤ step ≤ max_step, got {self.min_step:g}, "
                f"{self.step:g}, {self.max_step:g}"
            )
        for name in ("max_points", "max_corrector"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise GaitoptInputError(
                    f"PseudoArclength: `{name}` must be a positive integer, got {value!r}"
                )


@dataclass
class SpecialPoint:
    """A located special point of a branch.

    Attributes
    ----------
    kind : str
        ``"LP"`` (fold, multiplier +1), ``"PD"`` (period doubling, −1), ``"NS"``
        (Neimark–Sacker, complex pair on the unit circle) or ``"boundary"`` (the gait stops
        existing).
    param : float
        Parameter value where it lies.
    index : int
        Index of the branch point just before it.
    cycle : LimitCycle or None
        The gait at the point (for ``boundary``: the last certified gait before it).
    message : str
        What happens there.
    switch : str
        At a ``PD`` of a continuation with ``cascade=True``: how the switch onto the
        period-doubled branch went (followed, or why no branch was found); empty otherwise.
    """

    kind: str
    param: float
    index: int
    cycle: LimitCycle | None
    message: str
    switch: str = ""

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: ``kind``, ``param`` (the contract), plus the gait there."""
        out: dict[str, Any] = {
            "kind": self.kind,
            "param": float(self.param),
            "message": self.message,
        }
        if self.switch:
            out["switch"] = self.switch
        if self.cycle is not None:
            out["period"] = float(self.cycle.period)
            out["steps"] = int(self.cycle.steps)
            out["fixed_point"] = {k: float(v) for k, v in self.cycle.fixed_point.items()}
            out["multipliers"] = [[float(z.real), float(z.imag)] for z in self.cycle.multipliers]
        return out


@dataclass
class Branch:
    """A branch of gaits, stored by column (BifurcationKit's habit).

    Attributes
    ----------
    model : HybridModel
        The model at the branch's start.
    param : str
        The continued parameter.
    steps : int
        Returns to the section per orbit on this branch (2 after a period doubling, …).
    cycles : list of LimitCycle
        The certified gait at every point, in increasing order along the branch.
    special_points : list of SpecialPoint
        Located special points, in branch order.
    children : list of Branch
        Branches born at this branch's period doublings (period 2k), each with its own children.
    message : str
        How the branch ended (each direction).
    success : bool
        Whether the start was a certified gait and at least one point was computed.
    status : str
        A code of the one table :data:`gaitopt.result.STATUS`: the start gait's where there was
        none to start from; empty means ``"success"`` (or ``"not_converged"`` when
        ``success`` is False). :attr:`advice` reads the table.
    """

    model: HybridModel
    param: str
    steps: int
    cycles: list[LimitCycle] = field(default_factory=list)
    special_points: list[SpecialPoint] = field(default_factory=list)
    children: list[Branch] = field(default_factory=list)
    message: str = ""
    success: bool = True
    status: str = ""

    @property
    def advice(self) -> str:
        """What :data:`gaitopt.result.STATUS` says about the branch's status."""
        return STATUS[status_of(self)]

    # -- columns ------------------------------------------------------------------------------
    @property
    def params(self) -> np.ndarray:
        """Parameter value of each point."""
        return np.array([getattr(c.model, self.param) for c in self.cycles])

    @property
    def periods(self) -> np.ndarray:
        """Orbit period of each point (s)."""
        return np.array([c.period for c in self.cycles])

    @property
    def fixed_points(self) -> np.ndarray:
        """Fixed point of each point (rows, in ``state_names`` order)."""
        return np.array([c.x for c in self.cycles])

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the fixed-point columns."""
        return self.model.state_names

    @property
    def multipliers(self) -> np.ndarray:
        """Multipliers of each point (rows, sorted by decreasing modulus)."""
        return np.array([c.multipliers for c in self.cycles])

    @property
    def stable(self) -> np.ndarray:
        """Stability of each point."""
        return np.array([bool(c.stable) for c in self.cycles])

    @property
    def discretisation_errors(self) -> np.ndarray:
        """Discretisation-error estimate of each point."""
        return np.array([c.discretisation_error for c in self.cycles])

    def descendants(self) -> list[Branch]:
        """This branch and every branch born from it, depth first."""
        out = [self]
        for child in self.children:
            out.extend(child.descendants())
        return out

    def cascade(self) -> list[tuple[int, SpecialPoint]]:
        """Every special point of this branch and its descendants, as ``(steps, point)`` pairs
        in depth-first branch order: the period-doubling cascade read in one list."""
        return [(b.steps, sp) for b in self.descendants() for sp in b.special_points]

    # -- output ---------------------------------------------------------------------------------
    def as_dict(self) -> dict[str, Any]:
        """The JSON object of ``gaitopt continue --json`` (docs/design.md's contract), with the
        period-doubled branches under ``branches``."""
        return {
            "model": self.model.name,
            "param": self.param,
            "params": self.model.params,
            "steps": self.steps,
            "success": self.success,
            "message": self.message,
            "points": [
                {
                    "param": float(getattr(c.model, self.param)),
                    "period": float(c.period),
                    "fixed_point": {k: float(v) for k, v in c.fixed_point.items()},
                    "multipliers": [[float(z.real), float(z.imag)] for z in c.multipliers],
                    "stable": bool(c.stable),
                }
                for c in self.cycles
            ],
            "special_points": [sp.as_dict() for sp in self.special_points],
            "branches": [child.as_dict() for child in self.children],
            # The flattened view: every special point of every branch, with its period.
            "cascade": [
                {"steps": steps, "kind": sp.kind, "param": float(sp.param)}
                for steps, sp in self.cascade()
            ],
        }

    def csv_rows(self) -> tuple[list[str], list[list[float]]]:
        """Header and rows of the branch table (this branch and its descendants)."""
        m = max((len(c.multipliers) for b in self.descendants() for c in b.cycles), default=0)
        header = ["steps", self.param, "period", *self.state_names]
        header += [f"multiplier_{i}_{part}" for i in range(m) for part in ("re", "im")]
        header += ["max_abs_multiplier", "stable"]
        rows = []
        for branch in self.descendants():
            for c in branch.cycles:
                mult = list(c.multipliers) + [complex("nan")] * (m - len(c.multipliers))
                rows.append(
                    [branch.steps, getattr(c.model, self.param), c.period, *c.x]
                    + [v for z in mult for v in (z.real, z.imag)]
                    + [float(np.max(np.abs(c.multipliers))), int(bool(c.stable))]
                )
        return header, rows

    def __repr__(self) -> str:
        kinds = ", ".join(f"{sp.kind}@{sp.param:.8g}" for sp in self.special_points)
        span = f"{self.params.min():.6g}..{self.params.max():.6g}" if self.cycles else "empty"
        return (
            f"Branch({self.model.name}, {self.param} {span}, {len(self.cycles)} points, "
            f"period-{self.steps}, special points [{kinds}], {len(self.children)} children)"
        )


# ---------------------------------------------------------------------------------------------
