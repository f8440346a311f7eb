"""The Radau building blocks of the collocation (:mod:`gaitopt.optimize.collocation`): the mesh
(:class:`RadauMesh`: intervals per phase, Radau IIA degree), the Lagrange interpolation and
differentiation matrices on its nodes, the arcs of a work-based cost's switching-time
transcription (:class:`Arc`), constraint groups (:class:`Group`) and the named blocks of the
decision vector."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError

__all__ = ["Arc", "Group", "RadauMesh", "lagrange_matrix"]


@dataclass(frozen=True)
class RadauMesh:
    """Mesh of the transcription: ``intervals`` per phase, Radau ``degree`` per interval."""

    intervals: int = 8
    degree: int = 5

    def __post_init__(self) -> None:
        for name in ("intervals", "degree"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise GaitoptInputError(
                    f"RadauMesh: `{name}` must be a positive integer, got {value!r}"
                )

    def refined(self) -> RadauMesh:
        """Twice as many intervals."""
        return RadauMesh(2 * self.intervals, self.degree)


def lagrange_matrix(nodes: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``L[i, j] = ℓⱼ(pointsᵢ)``: Lagrange basis of ``nodes`` evaluated at ``points``."""
    nodes = np.asarray(nodes, dtype=float)
    points = np.atleast_1d(np.asarray(points, dtype=float))
    L = np.ones((points.size, nodes.size))
    for j, xj in enumerate(nodes):
        for m, xm in enumerate(nodes):
            if m != j:
                L[:, j] *= (points - xm) / (xj - xm)
    return L


def _derivative_matrix(nodes: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``D[i, j] = ℓⱼ'(pointsᵢ)`` for the Lagrange basis of ``nodes``."""
    D = np.zeros((len(points), len(nodes)))
    for j in range(len(nodes)):
        coeffs = np.polyfit(nodes, np.eye(len(nodes))[j], len(nodes) - 1)
        D[:, j] = np.polyval(np.polyder(coeffs), points)
    return D


@dataclass(frozen=True)
class Arc:
    """An arc of a phase in the switching-time transcription of a work-based cost.

    Attributes
    ----------
    intervals : int
        Mesh intervals on the arc (equal lengths).
    signs : tuple of int
        Per input, ``+1`` (positive power, counted in the cost) or ``−1`` (power ≤ 0, free).
    fraction : float
        Initial guess of the arc's share of the phase duration (1).
    """

    intervals: int
    signs: tuple[int, ...]
    fraction: float


@dataclass(frozen=True)
class Group:
    """A block of constraints, for reporting: name, slice of ``g``, and whether an equality."""

    name: str
    start: int
    size: int
    equality: bool


class _Blocks:
    """Named blocks of the decision vector with bounds."""

    def __init__(self) -> None:
        self.syms: list[ca.MX] = []
        self.names: list[str] = []
        self.shapes: list[tuple[int, int]] = []
        self.lb: list[np.ndarray] = []
        self.ub: list[np.ndarray] = []
        self.offsets: dict[str, int] = {}
        self.size = 0

    def add(self, name: str, rows: int, cols: int, low=-np.inf, high=np.inf) -> ca.MX:
        sym = ca.MX.sym(name, rows, cols)
        self.syms.append(sym)
        self.names.append(name)
        self.shapes.append((rows, cols))
        lo = np.broadcast_to(np.asarray(low, dtype=float).reshape(-1, 1), (rows, cols))
        hi = np.broadcast_to(np.asarray(high, dtype=float).reshape(-1, 1), (rows, cols))
        self.lb.append(lo.ravel(order="F"))
        self.ub.append(hi.ravel(order="F"))
        self.offsets[name] = self.size
        self.size += rows * cols
        return sym

    def vector(self) -> ca.MX:
        return ca.vertcat(*[ca.vec(s) for s in self.syms])

    def get(self, w: np.ndarray, name: str) -> np.ndarray:
        i = self.names.index(name)
        rows, cols = self.shapes[i]
        off = self.offsets[name]
        return np.asarray(w[off : off + rows * cols]).reshape((rows, cols), order="F")

    def put(self, w: np.ndarray, name: str, value: Any) -> None:
        i = self.names.index(name)
        rows, cols = self.shapes[i]
        off = self.offsets[name]
        if rows * cols == 0:
            return
        block = np.broadcast_to(np.asarray(value, dtype=float).reshape(rows, -1), (rows, cols))
        w[off : off + rows * cols] = block.ravel(order="F")
