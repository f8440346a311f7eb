"""The loop closure of Jansen's linkage: the ten equations ``|X − Y|² = L²``, Newton's method on
them with the tangent in θ by AD (CasADi), and the joints in closed form, dyad by dyad."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import casadi as ca

__all__ = ["JOINTS", "DYADS", "loop_closure", "closed_form_joints"]

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
# Newton options of the loop closure (absolute tolerance on the residual, m²).
_NEWTON = {"abstol": 1e-14, "abstolStep": 1e-15, "max_iter": 30, "error_on_fail": False}


@lru_cache(maxsize=1)
def closure_solver() -> ca.Function:
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
def dyad_heights() -> ca.Function:
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
