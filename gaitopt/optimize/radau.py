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

__all__ = [
    "Arc",
    "BOUNDARY",
    "COAST",
    "Group",
    "HELD",
    "NEGATIVE",
    "POSITIVE",
    "RadauMesh",
    "lagrange_matrix",
]


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
    """``D[i, j] = ℓⱼ'(pointsᵢ)`` for the Lagrange basis of ``nodes``, in closed form:
    ``ℓⱼ'(x) = Σ_{k≠j} 1/(xⱼ − xₖ) Π_{m≠j,k} (x − xₘ)/(xⱼ − xₘ)`` (Berrut & Trefethen 2004,
    SIAM Review 46, §9), exact to a few ulps: each row sums to 0 within ~1e-14 for Radau degree 6.

    Not a least-squares fit: ``np.polyfit`` through the Vandermonde matrix left errors of
    6e-12 in the row sums (OpenBLAS's SkylakeX kernels; 3e-13 with its Haswell ones), and the
    collocation equations ``Σ_r C[r, j] X_r = h f`` then carry a bias ``ε·X`` per interval that
    does not shrink with ``h``: the cost drifted in proportion to the number of intervals (the
    compass gait's least effort by 7e-10, 1.5e-9, 3e-9, 6e-9 from 12 to 192 intervals)."""
    nodes = np.asarray(nodes, dtype=float)
    points = np.atleast_1d(np.asarray(points, dtype=float))
    n = nodes.size
    D = np.zeros((points.size, n))
    for j in range(n):
        for k in range(n):
            if k == j:
                continue
            term = np.full(points.size, 1.0 / (nodes[j] - nodes[k]))
            for m in range(n):
                if m != j and m != k:
                    term *= (points - nodes[m]) / (nodes[j] - nodes[m])
            D[:, j] += term
    return D


#: Kinds of an input on an :class:`Arc` (its ``signs``).
POSITIVE, NEGATIVE, COAST, HELD = 1, -1, 0, 2
#: The input holds its joint with the phase's guard at zero: a boundary arc of the guard's side
#: (:mod:`gaitopt.optimize.boundary_arcs`).
BOUNDARY = 3


@dataclass(frozen=True)
class Arc:
    """An arc of a phase in the switching-time transcription of a work-based cost.

    Attributes
    ----------
    intervals : int
        Mesh intervals on the arc (equal lengths).
    signs : tuple of int
        Per input, ``+1`` (:data:`POSITIVE`: power ≥ 0, counted in the cost), ``−1``
        (:data:`NEGATIVE`: power ≤ 0, not counted), ``0`` (:data:`COAST`: the input vanishes,
        ``u ≡ 0``) or ``2`` (:data:`HELD`: its joint is held, ``ω ≡ 0`` while ``u ≠ 0``).  On a
        coasting or held arc the power is exactly zero: the transcription imposes ``u = 0`` at
        the arc's collocation points (the degree-``d − 1`` input polynomial then vanishes), or
        ``ω(x) = 0`` at its start and collocation points (for a rate linear in the state, the
        degree-``d`` polynomial ``ω(x(τ))`` vanishes at ``d + 1`` points of each interval, so
        everywhere); a sign alone would leave a held joint free to creep both ways between the
        nodes, and a coasting input free wherever the cost is flat.  ``3``
        (:data:`BOUNDARY`): it holds its joint with the phase's guard at zero (the kneed
        walker's knee held straight by its torque), ``ċ = 0`` at the arc's points (so ``c̈ =
        0`` there) and ``c = ċ = 0`` at its entry (:mod:`gaitopt.optimize.boundary_arcs`); no
        power either.
    fraction : float
        Initial guess of the arc's share of the phase duration (1).
    bounds : tuple of int
        Per input on an arc of a power sign, ``+1`` or ``−1`` if it stays at its upper or lower
        bound over the arc (a bang arc: the input is fixed there, so where it leaves the bound
        is a switching time, not a jump inside a mesh interval), else 0; empty: none.
    touches : tuple of str
        Labels of the state bounds and limits (``"stance knee flexion >= 0"``) that touch their
        bound where the arc ends: the junction is a touch point, ``ċ = 0`` there
        (:mod:`gaitopt.optimize.state_arcs`); empty: none.
    """

    intervals: int
    signs: tuple[int, ...]
    fraction: float
    bounds: tuple[int, ...] = ()
    touches: tuple[str, ...] = ()


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
