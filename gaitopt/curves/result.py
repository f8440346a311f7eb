"""The result of :func:`gaitopt.bifurcation_curve`: a curve of special points in two parameters."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..continuation import SpecialPoint
from ..hybrid import HybridModel
from ..result import STATUS, LimitCycle, status_of
from .system import ParameterPath

__all__ = ["Curve", "CurvePoint"]


def _cycle_dict(cycle: LimitCycle) -> dict[str, Any]:
    return {
        "period": float(cycle.period),
        "fixed_point": {k: float(v) for k, v in cycle.fixed_point.items()},
        "multipliers": [[float(z.real), float(z.imag)] for z in cycle.multipliers],
        "stable": bool(cycle.stable),
    }


@dataclass
class CurvePoint:
    """A located codimension-two point (or the end of the curve) on a curve.

    Attributes
    ----------
    kind : str
        ``"LPPD"``, ``"R1"``, ``"R2"``, ``"R3"``, ``"R4"``, ``"PDNS"``, ``"LPNS"``,
        ``"fold:<parameter>"`` or ``"boundary"`` (see :mod:`gaitopt.curves.codim2`).
    values : dict of str to float
        Both curve parameters there, by name.
    index : int
        Index of the curve point just before it.
    cycle : LimitCycle or None
        The certified gait there (for ``boundary``: the last certified gait before it); None
        if the point could not be certified.
    message : str
        What happens there.
    """

    kind: str
    values: dict[str, float]
    index: int
    cycle: LimitCycle | None
    message: str

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        out: dict[str, Any] = {"kind": self.kind, **self.values, "message": self.message}
        out["certified"] = bool(self.cycle is not None and self.cycle.success)
        if self.cycle is not None and self.cycle.success:
            out.update(_cycle_dict(self.cycle))
        return out


@dataclass
class Curve:
    """A curve of special points (``PD``, ``LP``, ``NS`` or ``boundary``) in two parameters.

    Attributes
    ----------
    model : HybridModel
        The model at the curve's start (the special point on the branch in ``param``).
    kind : str
        The followed condition.
    paths : (ParameterPath, ParameterPath)
        The two curve parameters (``param`` free at the start, ``param2`` continued to ``to``).
    cycles : list of LimitCycle
        The certified gait at each point, in curve order.  On a ``boundary`` curve the point
        itself is exactly on the boundary, where the gait is marginal; its certified gait is the
        one just inside (the first parameter moved by 1e-9 of its scale, more only if the
        verification simulation needs it; the gait's ``note`` says how far).
    located : list of (float, float)
        ``(λ₁, λ₂)`` of each point as located on the curve (equal to the gait's parameters except
        on a boundary curve).
    special_points : list of CurvePoint
        Codimension-two points and the boundary, in curve order.
    start : SpecialPoint or None
        The special point of the one-parameter branch the curve starts from.
    condition : str
        The defining condition (for a boundary: which quantity vanishes).
    message : str
        How the curve ended.
    success : bool
        Whether a start was found and at least one curve point certified.
    steps : int
        Returns to the section per orbit.
    status : str
        A code of the one table :data:`gaitopt.result.STATUS` (``"no_special_point"`` where the
        branch has no point to start from); empty means ``"success"`` (or ``"not_converged"``
        when ``success`` is False). :attr:`advice` reads the table.
    """

    model: HybridModel
    kind: str
    paths: tuple[ParameterPath, ParameterPath]
    cycles: list[LimitCycle] = field(default_factory=list)
    special_points: list[CurvePoint] = field(default_factory=list)
    located: list[tuple[float, float]] = field(default_factory=list)
    start: SpecialPoint | None = None
    condition: str = ""
    message: str = ""
    success: bool = True
    steps: int = 1
    status: str = ""

    @property
    def advice(self) -> str:
        """What :data:`gaitopt.result.STATUS` says about the curve's status."""
        return STATUS[status_of(self)]

    @property
    def param(self) -> str:
        """Name of the first curve parameter."""
        return self.paths[0].name

    @property
    def param2(self) -> str:
        """Name of the second curve parameter."""
        return self.paths[1].name

    def values(self, which: int) -> np.ndarray:
        """Curve parameter ``which`` (0 or 1) at each point (as located on the curve)."""
        if len(self.located) == len(self.cycles):
            return np.array([lam[which] for lam in self.located], dtype=float)
        path = self.paths[which]
        return np.array([path.value_of(c.model) for c in self.cycles])

    @property
    def params(self) -> np.ndarray:
        """``(λ₁, λ₂)`` of each point (rows)."""
        return (
            np.column_stack([self.values(0), self.values(1)]) if self.cycles else np.zeros((0, 2))
        )

    @property
    def multipliers(self) -> np.ndarray:
        """Multipliers of each point (rows)."""
        return np.array([c.multipliers for c in self.cycles])

    @property
    def periods(self) -> np.ndarray:
        """Orbit period of each point (s)."""
        return np.array([c.period for c in self.cycles])

    def as_dict(self) -> dict[str, Any]:
        """The JSON object of ``gaitopt continue --follow ... --json``."""
        points = []
        for c, lam in zip(self.cycles, self.params, strict=True):
            entry = {p.name: float(v) for p, v in zip(self.paths, lam, strict=True)}
            if self.kind == "boundary":
                entry["certified_at"] = {p.name: float(p.value_of(c.model)) for p in self.paths}
            entry.update(_cycle_dict(c))
            points.append(entry)
        return {
            "model": self.model.name,
            "params": self.model.params,
            "kind": self.kind,
            "param": self.param,
            "param2": self.param2,
            "steps": self.steps,
            "success": self.success,
            "message": self.message,
            "condition": self.condition,
            "start": self.start.as_dict() if self.start is not None else None,
            "points": points,
            "special_points": [sp.as_dict() for sp in self.special_points],
        }

    def csv_rows(self) -> tuple[list[str], list[list[Any]]]:
        """Header and rows of the curve table."""
        names = self.model.state_names
        m = max((len(c.multipliers) for c in self.cycles), default=0)
        header = [self.param, self.param2, "period", *names]
        header += [f"multiplier_{i}_{part}" for i in range(m) for part in ("re", "im")]
        rows = []
        for c, (a, b) in zip(self.cycles, self.params, strict=True):
            mult = list(c.multipliers) + [complex("nan")] * (m - len(c.multipliers))
            rows.append([a, b, c.period, *c.x] + [v for z in mult for v in (z.real, z.imag)])
        return header, rows

    def __repr__(self) -> str:
        span = ""
        if self.cycles:
            q = self.values(1)
            span = f", {self.param2} {q[0]:.6g}..{q[-1]:.6g}"
        sps = ", ".join(f"{sp.kind}" for sp in self.special_points)
        return (
            f"Curve({self.model.name}, {self.kind} in ({self.param}, {self.param2}){span}, "
            f"{len(self.cycles)} points, special points [{sps}])"
        )
