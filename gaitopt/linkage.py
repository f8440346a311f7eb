"""Theo Jansen's leg linkage (the Strandbeest): loop closure, foot path, ride height.

Geometry (Jansen, *The Great Pretender*, 2007; the lettering of Wikipedia's "Jansen's linkage"
figure, with the joints named here by what they are).  The frame carries the crank axle ``O`` at
the origin and the fixed pivot ``B = (−a, −l)``; the crank ``m`` turns the crank pin
``P = m (cos θ, sin θ)``, θ the crank angle (rad, counter-clockwise).  Five joints close the loops,
each joined to two known points by two links (a *dyad*):

===========  =======================  ======================  =================================
joint        joined to (link)         and to (link)           side in the initial assembly
===========  =======================  ======================  =================================
``upper``    crank pin ``P`` (j)      fixed pivot ``B`` (b)   above the line P→B
``lower``    crank pin ``P`` (k)      fixed pivot ``B`` (c)   below the line P→B
``back``     fixed pivot ``B`` (d)    ``upper`` (e)           away from the crank (outer)
``knee``     ``back`` (f)             ``lower`` (g)           outer
``foot``     ``knee`` (h)             ``lower`` (i)           below
===========  =======================  ======================  =================================

so that ``B, upper, back`` (sides b, e, d) and ``lower, knee, foot`` (sides g, h, i) are the two
rigid triangles.  The holy numbers (a 38, b 41.5, c 39.3, d 40.1, e 55.8, f 39.4, g 36.7,
h 65.7, i 49, j 50, k 61.9, l 7.8, m 15) are used at Robin Deits' scale, 0.01 m per unit (Drake's
``examples/multibody/strandbeest``, PVC links 0.476 kg/m).

Method.  The ten loop-closure equations ``|X − Y|² = L²`` (one per link, unknowns the five joints)
are solved by Newton's method (CasADi ``rootfinder``) and *continued* in θ: each solve starts
from the previous one, predicted along the tangent ``dz/dθ = −(∂r/∂z)⁻¹ ∂r/∂θ`` (implicit
function theorem, by CasADi's algorithmic differentiation through the rootfinder), so the branch
is chosen by continuity from the stated initial assembly.  A turn that would have to pass a dead
point (a dyad stretched straight, ``∂r/∂z`` singular) or change the side of a joint is refused:
the linkage cannot be assembled through a whole crank turn.

The foot velocity per unit crank rate ``dr_foot/dθ`` (m/rad) comes from the same AD.  By virtual
work, ``τ δθ = F · δr_foot``: a force ``F`` on the foot needs the crank torque ``τ = F · dr/dθ``,
so ``dx/dθ`` and ``dy/dθ`` are the crank torques per unit horizontal and vertical foot force
(N·m/N = m) — the mechanical advantage, in its inverse form.

The machine: leg *pairs* on one crank; a pair is a leg and its mirror image about the vertical
through the crank axle, sharing the crank pin.  The mirror of a leg at crank angle θ is the leg
at π − θ reflected (its pin reflects to the pin at θ), so its foot height is ``y(π − θ)``.  With
the frame level and the ground flat, the crank axle rides at ``−min y`` over the ground (the
lowest foot carries the machine): the *ride height*; its peak-to-peak over a turn is the ripple.
Deits' and Drake's machine has six pairs at crank phases 0, 2π/3, 4π/3, π/3, π, 5π/3.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any, ClassVar

import casadi as ca
import numpy as np
from scipy.optimize import brentq, minimize_scalar

from .errors import ParameterError, did_you_mean
from .parameters import ParameterSpec, check_parameter, parameter, parameter_specs

__all__ = [
    "JansenLinkage",
    "Turn",
    "LINKAGES",
    "linkage",
    "JOINTS",
    "DYADS",
    "SIX_PAIR_PHASES",
    "GROUND_BAND",
    "closed_form_joints",
]

#: Joint names, in the order of the unknown vector (x, y per joint).
JOINTS = ("upper", "lower", "back", "knee", "foot")
#: Each dyad: (joint, first base point, link to it, second base point, link to it, side).
#: The side is the sign of ``(Y₂ − Y₁) × (X − Y₁)`` in the initial assembly (+1: X to the left
#: of the directed line Y₁→Y₂).
DYADS = (
    ("upper", "pin", "j", "pivot", "b", -1),
    ("lower", "pin", "k", "pivot", "c", +1),
    ("back", "pivot", "d", "upper", "e", +1),
    ("knee", "back", "f", "lower", "g", -1),
    ("foot", "knee", "h", "lower", "i", -1),
)
#: Deits' and Drake's six pairs on one crank (rad).
SIX_PAIR_PHASES = (0.0, 2 * math.pi / 3, 4 * math.pi / 3, math.pi / 3, math.pi, 5 * math.pi / 3)
#: The ground band of the ground fraction: within 5 mm of the foot's lowest point (m).
GROUND_BAND = 0.005

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
# Newton options of the loop closure (absolute tolerance on the residual, m²).
_NEWTON = {"abstol": 1e-14, "abstolStep": 1e-15, "max_iter": 30, "error_on_fail": False}


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
            z, dz, res = _solver()(z0, theta, self.p)
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
            Equal crank steps per turn (the solution is exact at each; more steps only make the
            continuation's steps smaller).
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
        squares = np.asarray(_dyad_heights()(theta, self.p), dtype=float).ravel()
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


@lru_cache(maxsize=1)
def _solver() -> ca.Function:
    """``(z guess, θ, lengths) -> (z, dz/dθ, residual)``: Newton's method on the loop closure,
    and the tangent by AD through the rootfinder (implicit function theorem)."""
    z = ca.SX.sym("z", 10)
    theta = ca.SX.sym("theta")
    p = ca.SX.sym("p", 13)
    residual = loop_closure(z, theta, p)
    parameters = ca.vertcat(theta, p)
    G = ca.Function("loop_closure", [z, parameters], [residual])
    rf = ca.rootfinder("jansen", "newton", G, _NEWTON)
    z0 = ca.MX.sym("z0", 10)
    th = ca.MX.sym("theta")
    pp = ca.MX.sym("p", 13)
    zs = rf(z0, ca.vertcat(th, pp))
    dz = ca.jacobian(zs, th)
    res = G(zs, ca.vertcat(th, pp))
    return ca.Function("jansen_solve", [z0, th, pp], [zs, dz, res], ["z0", "theta", "p"],
                       ["z", "dz", "residual"])  # fmt: skip


@lru_cache(maxsize=1)
def _dyad_heights() -> ca.Function:
    """``(θ, lengths) -> h²`` of each dyad, in order: the squared height (fraction of the base)
    of the triangle its two links make over its base; ``h² ≤ 0`` (or NaN after an earlier
    failure) where the two circles do not meet."""
    theta, p = ca.SX.sym("theta"), ca.SX.sym("p", 13)
    _, squares = _dyads(theta, p)
    return ca.Function("dyad_heights", [theta, p], [ca.vertcat(*squares)])


def loop_closure(z: Any, theta: Any, p: Any) -> Any:
    """The ten loop-closure residuals ``|X − Y|² − L²`` (m²), one per link b to k.

    ``z`` holds the joints ``upper, lower, back, knee, foot`` (x, y each, m), ``p`` the lengths
    a to m (m); CasADi symbols or numbers.
    """
    a, b, c, d, e, f, g, h, i, j, k, l, m = (p[n] for n in range(13))  # noqa: E741
    pts = {
        "pin": ca.vertcat(m * ca.cos(theta), m * ca.sin(theta)),
        "pivot": ca.vertcat(-a, -l),
    }
    for n, name in enumerate(JOINTS):
        pts[name] = ca.vertcat(z[2 * n], z[2 * n + 1])
    lengths = dict(b=b, c=c, d=d, e=e, f=f, g=g, h=h, i=i, j=j, k=k)
    out = []
    for joint, y1, r1, y2, r2, _ in DYADS:
        for y, r in ((y1, r1), (y2, r2)):
            diff = pts[joint] - pts[y]
            out.append(ca.dot(diff, diff) - lengths[r] ** 2)
    return ca.vertcat(*out)


def closed_form_joints(theta: Any, p: Any) -> dict[str, Any]:
    """The joints as explicit functions of θ, dyad by dyad (circle intersections on the sides
    of the initial assembly), for CasADi symbols: used where the dynamics need the positions as
    expressions (the ``strandbeest`` model).  Valid on the branch :meth:`JansenLinkage.turn`
    follows (the same sides, no dead point), which the tests check against the rootfinder.

    Returns
    -------
    dict of str to casadi expression (2×1)
        ``axle, pin, pivot, upper, lower, back, knee, foot`` (m).
    """
    return _dyads(theta, p)[0]


def _dyads(theta: Any, p: Any) -> tuple[dict[str, Any], list[Any]]:
    """Joints by circle intersections, and each dyad's squared relative height."""
    a, l, m = p[0], p[11], p[12]  # noqa: E741
    lengths = {letter: p[n] for n, letter in enumerate("abcdefghijklm")}
    pts = {
        "axle": ca.vertcat(0, 0),
        "pin": ca.vertcat(m * ca.cos(theta), m * ca.sin(theta)),
        "pivot": ca.vertcat(-a, -l),
    }
    squares = []
    for joint, y1, r1, y2, r2, side in DYADS:
        p1, p2 = pts[y1], pts[y2]
        u = p2 - p1
        dist2 = ca.dot(u, u)
        along = (lengths[r1] ** 2 - lengths[r2] ** 2 + dist2) / (2 * dist2)  # fraction of |u|
        squares.append(lengths[r1] ** 2 / dist2 - along**2)
        height = ca.sqrt(squares[-1])  # fraction of |u|
        normal = ca.vertcat(-u[1], u[0])  # u turned left
        pts[joint] = p1 + along * u + side * height * normal
    return pts, squares


# -- a turn and its numbers ----------------------------------------------------------------------
@dataclass(frozen=True)
class Turn:
    """One crank turn of a linkage, sampled: ``thetas`` (N+1,), joints ``z`` and ``dz/dθ``
    (N+1, 5, 2; m and m/rad).  :meth:`at` solves exactly between samples."""

    linkage: JansenLinkage
    thetas: np.ndarray
    z: np.ndarray
    dz: np.ndarray

    @property
    def foot(self) -> np.ndarray:
        """Foot path (N+1, 2) (m, relative to the crank axle)."""
        return self.z[:, 4]

    @property
    def foot_velocity(self) -> np.ndarray:
        """``dr_foot/dθ`` (N+1, 2) (m/rad) = crank torque per unit foot force (x, y) (N·m/N)."""
        return self.dz[:, 4]

    def at(self, theta: float) -> tuple[np.ndarray, np.ndarray]:
        """Joints and ``dz/dθ`` at any crank angle, on this turn's branch (Newton from the
        nearest sample, predicted along its tangent)."""
        t0 = self.thetas[0]
        period = 2 * math.pi
        phase = (theta - t0) % period
        n = int(round(phase / period * (len(self.thetas) - 1)))
        n = min(n, len(self.thetas) - 1)
        guess = self.z[n] + (phase + t0 - self.thetas[n]) * self.dz[n]
        return self.linkage.solve(theta, guess.ravel())

    def foot_y(self, theta: float) -> float:
        """Foot height at crank angle θ (m)."""
        return float(self.at(theta)[0][4, 1])

    def _extremum(self, values: np.ndarray, component: int, sign: float) -> tuple[float, float]:
        """Refined ``sign · max`` of a foot coordinate: Brent's method around the best sample."""
        n = int(np.argmax(sign * values))
        step = self.thetas[1] - self.thetas[0]
        res = minimize_scalar(
            lambda t: -sign * float(self.at(t)[0][4, component]),
            bounds=(self.thetas[n] - step, self.thetas[n] + step),
            method="bounded",
            options={"xatol": 1e-10},
        )
        best = max(sign * values[n], -res.fun)
        return sign * best, float(res.x)

    @cached_property
    def extremes(self) -> dict[str, tuple[float, float]]:
        """``name -> (value (m), θ (rad))`` of the foot path's x_min, x_max, y_min, y_max."""
        out = {}
        for comp, axis in ((0, "x"), (1, "y")):
            values = self.foot[:-1, comp]
            out[f"{axis}_min"] = self._extremum(values, comp, -1.0)
            out[f"{axis}_max"] = self._extremum(values, comp, +1.0)
        return out

    def ground_fraction(self, band: float = GROUND_BAND) -> float:
        """Share of a crank turn (uniform crank rate) with the foot within ``band`` (m) of its
        lowest point: the crossings of ``y = y_min + band`` refined by Brent's method."""
        level = self.extremes["y_min"][0] + band
        y = self.foot[:, 1] - level
        inside = 0.0
        crossings = []
        for n in range(len(y) - 1):
            if y[n] == 0 or y[n] * y[n + 1] < 0:
                t = brentq(
                    lambda s: self.foot_y(s) - level,
                    self.thetas[n],
                    self.thetas[n + 1],
                    xtol=1e-13,
                )
                crossings.append((t, 1 if y[n + 1] < 0 else -1))  # +1: entering the band
        if not crossings:
            return 1.0 if y[0] < 0 else 0.0
        crossings.sort()
        # Walk round the turn: from each entry to the next exit.
        for q, (t, kind) in enumerate(crossings):
            if kind == 1:
                t_exit, _ = crossings[(q + 1) % len(crossings)]
                inside += (t_exit - t) % (2 * math.pi)
        return inside / (2 * math.pi)

    def feet_heights(self, phases: Sequence[float], thetas: np.ndarray) -> np.ndarray:
        """Foot heights (2P, len(thetas)) (m) of P pairs at crank phases ``phases``: the legs
        ``y(θ + φ)`` then their mirror images ``y(π − θ − φ)`` (by interpolating the dense,
        exact samples with the AD tangents: a cubic Hermite spline)."""
        rows = [self._hermite_y(np.asarray(thetas) + ph) for ph in phases]
        rows += [self._hermite_y(math.pi - np.asarray(thetas) - ph) for ph in phases]
        return np.array(rows)

    def _hermite_y(self, t: np.ndarray) -> np.ndarray:
        t0, h = self.thetas[0], self.thetas[1] - self.thetas[0]
        s = ((t - t0) % (2 * math.pi)) / h
        n = np.minimum(np.floor(s).astype(int), len(self.thetas) - 2)
        u = s - n
        y0, y1 = self.foot[n, 1], self.foot[n + 1, 1]
        d0, d1 = self.dz[n, 4, 1] * h, self.dz[n + 1, 4, 1] * h
        return (
            (2 * u**3 - 3 * u**2 + 1) * y0
            + (u**3 - 2 * u**2 + u) * d0
            + (-2 * u**3 + 3 * u**2) * y1
            + (u**3 - u**2) * d1
        )

    def ride_height(self, phases: Sequence[float], thetas: np.ndarray) -> np.ndarray:
        """Height of the crank axle above the machine's lowest foot (m) at crank angles θ."""
        return -np.min(self.feet_heights(phases, thetas), axis=0)

    def ripple(self, phases: Sequence[float] = SIX_PAIR_PHASES) -> float:
        """Peak-to-peak ride height over a turn (m), pairs at ``phases``.

        The highest ride is ``−y_min`` (every foot reaches the path's lowest point); the lowest
        is found on a dense grid and refined with exact solves (Brent's method on the lower
        envelope of the feet around the best grid point).
        """
        grid = np.linspace(0, 2 * math.pi, 8 * (len(self.thetas) - 1), endpoint=False)
        ride = self.ride_height(phases, grid)
        n = int(np.argmin(ride))
        step = grid[1] - grid[0]

        def exact(t: float) -> float:
            heights = [self.foot_y(t + ph) for ph in phases]
            heights += [self.foot_y(math.pi - t - ph) for ph in phases]
            return -min(heights)

        res = minimize_scalar(
            exact, bounds=(grid[n] - step, grid[n] + step), method="bounded",
            options={"xatol": 1e-11},
        )  # fmt: skip
        lowest = min(float(res.fun), exact(grid[n]))
        return -self.extremes["y_min"][0] - lowest

    def numbers(self) -> dict[str, Any]:
        """The foot path's numbers (m unless stated).

        ``width``/``height``: horizontal/vertical extents of the foot path; ``ground_fraction``:
        share of a turn within 5 mm of the lowest point; ``stride``: horizontal length of the
        path inside that band; ``ripple_six_pairs``/``ripple_one_pair``: peak-to-peak ride
        height; ``lowest_point``: (x, y) of the lowest point; ``ground_speed``: foot speed
        ``|dx/dθ|`` at the lowest point (m/rad).
        """
        ex = self.extremes
        y_min, t_low = ex["y_min"]
        z_low, dz_low = self.at(t_low)
        band = self.foot[:, 1] <= y_min + GROUND_BAND
        stride = float(np.ptp(self.foot[band, 0])) if np.any(band) else 0.0
        return {
            "linkage": self.linkage.name,
            "width": ex["x_max"][0] - ex["x_min"][0],
            "height": ex["y_max"][0] - ex["y_min"][0],
            "ground_fraction": self.ground_fraction(),
            "ripple_six_pairs": self.ripple(SIX_PAIR_PHASES),
            "ripple_one_pair": self.ripple((0.0,)),
            "stride": stride,
            "lowest_point": [float(z_low[4, 0]), float(y_min)],
            "lowest_point_theta": t_low % (2 * math.pi),
            "ground_speed": float(abs(dz_low[4, 0])),
            "ground_band": GROUND_BAND,
            "six_pair_phases": list(SIX_PAIR_PHASES),
            "units": {
                "width": "m", "height": "m", "ground_fraction": "1", "ripple_six_pairs": "m",
                "ripple_one_pair": "m", "stride": "m", "lowest_point": "m",
                "lowest_point_theta": "rad", "ground_speed": "m/rad", "ground_band": "m",
                "six_pair_phases": "rad",
            },
            "params": self.linkage.params,
        }  # fmt: skip


#: The linkages ``gaitopt linkage`` knows.
LINKAGES: dict[str, type[JansenLinkage]] = {"jansen": JansenLinkage}


def linkage(name: str, **lengths: float) -> JansenLinkage:
    """A linkage by name with some lengths changed (m).

    Raises
    ------
    ParameterError
        For an unknown linkage or length, or a length out of range.
    """
    if name not in LINKAGES:
        raise ParameterError(
            f"unknown linkage {name!r}; {did_you_mean(name, LINKAGES)}available: "
            f"{', '.join(LINKAGES)}"
        )
    cls = LINKAGES[name]
    known = [s.name for s in cls.parameter_specs()]
    for key in lengths:
        if key not in known:
            raise ParameterError(
                f"{name}: unknown parameter {key!r}; {did_you_mean(key, known)}"
                f"parameters: {', '.join(known)}"
            )
    return cls(**lengths)
