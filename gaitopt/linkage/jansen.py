"""Jansen's leg linkage as an object: its thirteen lengths (checked like a model's parameters),
the assembly at one crank angle, its continuation through a whole crank turn, and the message
that names the links when the leg cannot be assembled."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..errors import ParameterError
from ..parameters import ParameterSpec, check_parameter, parameter, parameter_specs
from .closure import DYADS, JOINTS, closure_solver, dyad_heights
from .turn import Turn

#: Most crank steps per turn: each is a rootfinder solve of the loop closure (72 000 take about
#: 11 s on 2 cores; the numbers agree with 720 steps to their printed digits long before that).
MAX_SAMPLES = 100_000
SAMPLES_LIMIT = (
    "each crank step is a loop-closure solve (100 000 take about 15 s); the default 720 "
    "already resolves the foot path"
)

__all__ = ["JansenLinkage"]

_SCALE = 0.01  # m per unit of the holy numbers (Deits' scale)
_HOLY = dict(
    a=38.0, b=41.5, c=39.3, d=40.1, e=55.8, f=39.4, g=36.7, h=65.7, i=49.0, j=50.0, k=61.9,
    l=7.8, m=15.0,
)  # fmt: skip
_SOURCE = "Jansen's holy numbers (The Great Pretender, 2007) at Deits' scale, 0.01 m per unit"
_LINKS = {
    "a": "horizontal offset of the fixed pivot from the crank axle",
    "b": "link fixed pivot – upper joint",
    "c": "link fixed pivot – lower joint",
    "d": "link fixed pivot – back joint",
    "e": "link upper joint – back joint",
    "f": "link back joint – knee",
    "g": "link lower joint – knee",
    "h": "link knee – foot",
    "i": "link lower joint – foot",
    "j": "link crank pin – upper joint",
    "k": "link crank pin – lower joint",
    "l": "vertical offset of the fixed pivot below the crank axle",
    "m": "crank radius",
}
#: The initial assembly at θ = 0 (holy numbers, m): the Newton start that fixes the branch.
_ASSEMBLY = np.array(
    [
        [-0.240135, 0.312721],  # upper
        [-0.269521, -0.455152],  # lower
        [-0.747944, 0.081432],  # back
        [-0.592315, -0.280529],  # knee
        [-0.431601, -0.917569],  # foot
    ]
)
# A dyad whose |sin| of the angle at its joint falls below this is at a dead point.
_DEAD_POINT = 1e-6


def _length(letter: str) -> Any:
    return parameter(
        round(_HOLY[letter] * _SCALE, 6),
        unit="m",
        doc=f"{letter}: {_LINKS[letter]}",
        source=_SOURCE,
        low=0.0,
        high=10.0,
        low_open=True,
    )


@dataclass(frozen=True)
class JansenLinkage:
    """Theo Jansen's leg linkage: thirteen lengths (m), defaults the holy numbers × 0.01 m.

    Build it like a model (``JansenLinkage(j=0.52)``); every length is checked against its
    range, and :meth:`turn` refuses lengths for which the leg cannot be assembled through a
    whole crank turn (:class:`~gaitopt.errors.ParameterError` naming the links).
    """

    name: ClassVar[str] = "jansen"
    title: ClassVar[str] = "Jansen's linkage (Strandbeest leg)"
    reference: ClassVar[str] = (
        "Jansen 2007 (holy numbers); Wikipedia, Jansen's linkage; Deits, Drake Strandbeest"
    )

    a: float = _length("a")
    b: float = _length("b")
    c: float = _length("c")
    d: float = _length("d")
    e: float = _length("e")
    f: float = _length("f")
    g: float = _length("g")
    h: float = _length("h")
    i: float = _length("i")
    j: float = _length("j")
    k: float = _length("k")
    l: float = _length("l")  # noqa: E741 (Jansen's letter)
    m: float = _length("m")

    def __post_init__(self) -> None:
        for spec in self.parameter_specs():
            value = check_parameter(self.name, spec, getattr(self, spec.name))
            object.__setattr__(self, spec.name, value)

    @classmethod
    def parameter_specs(cls) -> tuple[ParameterSpec, ...]:
        """The thirteen lengths' specifications, a to m."""
        return parameter_specs(cls)

    @property
    def params(self) -> dict[str, float]:
        """Letter → length (m)."""
        return {s.name: getattr(self, s.name) for s in self.parameter_specs()}

    @property
    def p(self) -> np.ndarray:
        """The lengths as a vector, a to m (m)."""
        return np.array(list(self.params.values()))

    def replace(self, **changes: float) -> JansenLinkage:
        """A copy with some lengths changed (checked like the constructor)."""
        return dataclasses.replace(self, **changes)

    # -- fixed points ------------------------------------------------------------------------
    @property
    def pivot(self) -> np.ndarray:
        """The fixed pivot ``B = (−a, −l)`` (m), relative to the crank axle."""
        return np.array([-self.a, -self.l])

    def pin(self, theta: float) -> np.ndarray:
        """The crank pin ``m (cos θ, sin θ)`` (m)."""
        return self.m * np.array([math.cos(theta), math.sin(theta)])

    # -- solving -----------------------------------------------------------------------------
    def solve(self, theta: float, guess: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Joints and their derivative in θ at one crank angle, by Newton from ``guess``.

        Parameters
        ----------
        theta : float
            Crank angle (rad).
        guess : ndarray (10,), optional
            Start of Newton's method (default: the initial assembly, scaled by ``a``).

        Returns
        -------
        z : ndarray (5, 2)
            Joints ``upper, lower, back, knee, foot`` (m, relative to the crank axle).
        dz : ndarray (5, 2)
            Their derivatives ``dz/dθ`` (m/rad), by AD through the rootfinder.
        """
        z0 = self._initial_guess() if guess is None else np.asarray(guess, float).ravel()
        try:
            z, dz, res = closure_solver()(z0, theta, self.p)
        except RuntimeError:  # Newton diverged to a non-finite iterate
            raise _NoAssembly(theta, math.inf) from None
        z, dz = np.asarray(z).ravel(), np.asarray(dz).ravel()
        residual = float(np.max(np.abs(np.asarray(res))))
        if not (np.all(np.isfinite(z)) and residual < 1e-10):
            raise _NoAssembly(theta, residual)
        return z.reshape(5, 2), dz.reshape(5, 2)

    def _initial_guess(self) -> np.ndarray:
        return (_ASSEMBLY * (self.a / (_HOLY["a"] * _SCALE))).ravel()

    def sides(self, theta: float, z: np.ndarray) -> np.ndarray:
        """Each dyad's side sign and the |sine| of the angle at its joint (dead point → 0)."""
        points = self._points(theta, z)
        out = np.empty((len(DYADS), 2))
        for n, (joint, y1, r1, y2, r2, _) in enumerate(DYADS):
            u, v = points[y2] - points[y1], points[joint] - points[y1]
            w1, w2 = points[joint] - points[y1], points[joint] - points[y2]
            cross = u[0] * v[1] - u[1] * v[0]
            sine = (w1[0] * w2[1] - w1[1] * w2[0]) / (getattr(self, r1) * getattr(self, r2))
            out[n] = (np.sign(cross), abs(sine))
        return out

    def _points(self, theta: float, z: np.ndarray) -> dict[str, np.ndarray]:
        z = np.asarray(z, float).reshape(5, 2)
        points = {"axle": np.zeros(2), "pin": self.pin(theta), "pivot": self.pivot}
        points.update(zip(JOINTS, z, strict=True))
        return points

    def turn(self, samples: int = 720, start: float = 0.0) -> Turn:
        """Follow the linkage through one crank turn, θ from ``start`` to ``start + 2π``.

        Parameters
        ----------
        samples : int
            Equal crank steps per turn, 16 to :data:`MAX_SAMPLES` (the solution is exact at
            each; more steps only make the continuation's steps smaller).
        start : float
            First crank angle (rad).

        Raises
        ------
        ParameterError
            If the leg cannot be assembled at some crank angle on the branch of the initial
            assembly (a dyad reaches a dead point, or a joint changes side), or the turn does not
            close on the assembly it started from.
        """
        if samples < 16:
            raise ParameterError(f"{self.name}: a turn needs at least 16 samples, got {samples}")
        if samples > MAX_SAMPLES:
            raise ParameterError(
                f"{self.name}: `samples` = {samples} is above the limit {MAX_SAMPLES}: "
                f"{SAMPLES_LIMIT}"
            )
        thetas = start + 2 * math.pi * np.arange(samples + 1) / samples
        z = np.empty((samples + 1, 5, 2))
        dz = np.empty_like(z)
        try:
            z[0], dz[0] = self.solve(thetas[0])
        except _NoAssembly as exc:
            raise self._refusal(exc.theta, None) from None
        self._check_sides(thetas[0], z[0], None)
        for n in range(1, samples + 1):
            z[n], dz[n] = self._step(thetas[n - 1], thetas[n], z[n - 1], dz[n - 1])
        if np.max(np.abs(z[-1] - z[0])) > 1e-9:  # continuity: one turn returns to the start
            raise self._refusal(thetas[-1], z[-2], closes=False)
        return Turn(self, thetas, z, dz)

    def _step(self, t0: float, t1: float, z0, dz0, depth: int = 0):
        """One continuation step from ``t0`` to ``t1`` (tangent predictor, Newton corrector);
        halved where Newton fails or the branch changes, up to a depth."""
        try:
            z1, dz1 = self.solve(t1, (z0 + (t1 - t0) * dz0).ravel())
            self._check_sides(t1, z1, z0)
            return z1, dz1
        except (_NoAssembly, _SideChange):
            if depth >= 12:
                raise self._refusal(t1, z0) from None
        mid = 0.5 * (t0 + t1)
        zm, dzm = self._step(t0, mid, z0, dz0, depth + 1)
        return self._step(mid, t1, zm, dzm, depth + 1)

    def _check_sides(self, theta: float, z: np.ndarray, previous) -> None:
        sides = self.sides(theta, z)
        expected = np.array([d[5] for d in DYADS])
        if np.any(sides[:, 0] != expected) or np.any(sides[:, 1] < _DEAD_POINT):
            if previous is None:
                raise self._refusal(theta, None)
            raise _SideChange()

    def _refusal(self, theta: float, z_last, closes: bool = True) -> ParameterError:
        """The message naming the changed lengths and the links of the dyad that fails.

        The failing dyad is the first whose two circles do not meet at ``theta`` (explicit
        circle intersections in the order of :data:`DYADS`); failing that, the one nearest a
        dead point at the last assembled configuration ``z_last``.
        """
        squares = np.asarray(dyad_heights()(theta, self.p), dtype=float).ravel()
        bad = np.nonzero(~(squares > 0))[0]
        if bad.size:
            which = int(bad[0])
        elif z_last is not None:
            which = int(np.argmin(self.sides(theta, z_last)[:, 1]))
        else:
            which = int(np.argmin(squares))
        where = (
            "in the initial assembly (θ = 0)"
            if z_last is None
            else f"at crank angle θ = {theta % (2 * math.pi):.4g} rad"
        )
        joint, _, r1, _, r2, _ = DYADS[which]
        changed = [n for n, v in self.params.items() if not math.isclose(v, _HOLY[n] * _SCALE)]
        names = [n for n in (r1, r2) if n in changed] + [n for n in changed if n not in (r1, r2)]
        first = (names or [r1])[0]
        what = (
            f"cannot be assembled {where}"
            if closes
            else "does not return to its starting assembly after one crank turn"
        )
        return ParameterError(
            f"{self.name}: parameter `{first}` = {getattr(self, first):g} m: the leg {what}: "
            f"the {joint} joint's links {r1} = {getattr(self, r1):g} m and {r2} = "
            f"{getattr(self, r2):g} m cannot reach (a dead point); use `{first}` nearer its "
            f"holy number, e.g. {first}={_HOLY[first] * _SCALE:g}"
        )

    # -- the numbers -------------------------------------------------------------------------
    def numbers(self, samples: int = 720) -> dict[str, Any]:
        """Width, height, ground fraction, stride, ride-height ripples (see :class:`Turn`)."""
        return self.turn(samples).numbers()


class _NoAssembly(Exception):
    def __init__(self, theta: float, residual: float):
        super().__init__(theta, residual)
        self.theta = theta


class _SideChange(Exception):
    pass
