"""Multi-start HZD design and an HZD gait library in speed.

:func:`design_problem` states a plant's design problem (start, free coefficients, constraints):
the three-link walker's (``problems/three_link_hzd_optimal.py``: cost ``(1/L) ∫‖u‖² dt``,
slope ≤ 0.9, ``ζ ≥ 0.05 ζ⁺``, ``N ≥ 0``, swing foot on or above the ground, ``α_M`` fixed) and
the five-link biped's, FROST's RABBIT problem (:mod:`.rabbit`).  :func:`multistart_design` runs
:func:`~.design.optimise_alpha` from ``starts`` seeded perturbations of the start (start 0 is the
start itself), groups the converged optima into distinct minima (cost within ``1e-6``
relative and coefficients within ``1e-3`` rad) and certifies each on the full-order closed loop
(:func:`~.gait.hzd_gait`: multiple shooting from the zero dynamics' fixed point, dense checks
of every declared constraint, the independent simulation).  :func:`speed_library` continues an
optimum in its average speed, each point warm-started from its neighbour (natural-parameter
continuation, as ``gaitopt.optimize.library`` does for collocated gaits).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..shooting import find_limit_cycle
from .design import (
    SurfaceGait,
    coefficient_bounds,
    free_interior,
    optimise_alpha,
    surface_gait,
)
from .gait import HZDGait, fit_to_orbit, hzd_gait
from .invariance import make_invariant
from .rabbit import RABBIT, rabbit_start
from .virtual import VirtualConstraintModel, plant_of, virtual_constraint_model

__all__ = ["Minimum", "MultiStart", "design_problem", "multistart_design", "speed_library",
           "MAX_STARTS"]  # fmt: skip

#: Starts accepted (each a full SLSQP run).
MAX_STARTS = 64


@dataclass
class Minimum:
    """One distinct minimum: its design (:class:`~.design.SurfaceGait`), the starts that reached
    it, and its full-order certificate (``gait``, None if not certified)."""

    design: SurfaceGait
    starts: list[int]
    gait: HZDGait | None = None
    at_bound: list[str] = field(default_factory=list)

    @property
    def verified(self) -> bool:
        """A certified full-order gait whose dominant multiplier is the design's slope (1e-6)."""
        g = self.gait
        if g is None or not g.success or g.cycle is None or not g.cycle.verified:
            return False
        mu = g.cycle.multipliers
        return bool(np.min(np.abs(mu - self.design.slope)) < 1e-6)

    def as_dict(self, objective: str) -> dict[str, Any]:
        d, g = self.design, self.gait
        out: dict[str, Any] = {
            "cost": d.cost if objective == "per_length" else d.effort,
            "objective": objective,
            "slope": d.slope,
            "speed": d.speed,
            "step_time": d.step_time,
            "step_length": d.step_length,
            "max_torque": d.max_torque,
            "starts": self.starts,
            "verified": self.verified,
            "at_bound": self.at_bound,
            "bezier": {j: [float(v) for v in a] for j, a in d.model.alpha.items()},
            "theta_plus": d.model.theta_plus,
            "theta_minus": d.model.theta_minus,
        }
        if g is not None and g.cycle is not None:
            mu = g.cycle.multipliers[np.argsort(-np.abs(g.cycle.multipliers))]
            out["full_order"] = {
                "success": g.success,
                "message": g.message,
                "period": g.cycle.period,
                "multipliers_abs": [float(abs(m)) for m in mu],
                "invariance_residual": g.invariance_residual,
                "max_torque": g.max_torque,
            }
        return out


@dataclass
class MultiStart:
    """:func:`multistart_design`'s outcome: the distinct minima (cheapest first) and every
    start's outcome (``{"start", "converged", "cost", "minimum", "message"}``)."""

    minima: list[Minimum]
    starts: list[dict[str, Any]]
    objective: str
    seed: int
    spread: float
    free: tuple[str, ...] = field(default=())

    def as_dict(self) -> dict[str, Any]:
        return {
            "objective": self.objective,
            "seed": self.seed,
            "spread": self.spread,
            "free": list(self.free),
            "minima": [m.as_dict(self.objective) for m in self.minima],
            "starts": self.starts,
        }


def design_problem(
    plant: HybridModel, degree: int, *, speed: float | None = None, points: int = 201
) -> tuple[VirtualConstraintModel, tuple[str, ...], dict[str, Any]]:
    """``(start, free, options of optimise_alpha)`` of ``plant``'s HZD design problem (module
    docstring); :class:`GaitoptInputError` for a plant with none."""
    cls = virtual_constraint_model(plant_of(plant), degree)
    if speed is not None and not (math.isfinite(speed) and speed > 0):
        raise GaitoptInputError(f"speed: {speed!r} must be a positive number (m/s), e.g. 0.75")
    if cls.plant.name == "three_link_walker":
        own = find_limit_cycle(plant)
        if not own.success:
            raise GaitoptInputError(f"model: three_link_walker has no gait to start from "
                                    f"({own.message[:100]})")  # fmt: skip
        params = {k: getattr(plant, k) for k in cls.plant.plant_parameters}
        start = make_invariant(fit_to_orbit(cls(**params), own))
        last = {f"alpha_{j}_{degree}" for j in start.joints}
        options = {"max_slope": 0.9, "margin": 0.05, "clearance": 0.0, "objective": "per_length"}
        return start, free_interior(start, fixed=tuple(last)), {**options, "speed": speed,
                                                                 "points": points}  # fmt: skip
    if cls.plant.name == "five_link_biped":
        start = rabbit_start(plant, degree)
        options = {"speed": RABBIT["speed"] if speed is None else speed, "max_slope": 0.95,
                   "margin": 0.05, "reach": None, "objective": "effort",
                   "torque_limit": RABBIT["torque_limit"],
                   "mid_clearance": RABBIT["mid_clearance"], "declared": True,
                   "points": points, "maxiter": 200}  # fmt: skip
        return start, free_interior(start), options
    raise GaitoptInputError(
        f"model: {cls.plant.name!r} has no HZD design problem (its start, free coefficients and "
        f"constraints); use three_link_walker or five_link_biped"
    )


#: Draws of a perturbation per start before the start is given up (each one quadrature).
MAX_DRAWS = 50


def _walking_start(
    start: VirtualConstraintModel,
    free: Sequence[str],
    x0: np.ndarray,
    rng: np.random.Generator,
    spread: float,
    points: int,
) -> tuple[VirtualConstraintModel | None, int]:
    """The first of up to :data:`MAX_DRAWS` perturbations ``x0 + U(−spread, spread)`` whose zero
    dynamics walk (a start must be a gait: SLSQP cannot leave a region where the surface has no
    fixed point, its cost and constraints being flat there); ``(None, draws)`` if none does.
    ``spread`` 0: the start itself."""
    for draw in range(1, MAX_DRAWS + 1):
        shift = rng.uniform(-spread, spread, x0.size) if spread else np.zeros_like(x0)
        model = start.replace(**dict(zip(free, map(float, x0 + shift), strict=True)))
        try:
            if surface_gait(model, points).walks:
                return model, draw
        except Exception:  # noqa: BLE001 — a perturbation where the surface breaks: draw again
            pass
        if not spread:
            break
    return None, MAX_DRAWS if spread else 1


def _same(a: SurfaceGait, b: SurfaceGait, objective: str) -> bool:
    ca_, cb = (a.cost, b.cost) if objective == "per_length" else (a.effort, b.effort)
    close_cost = abs(ca_ - cb) <= 1e-6 * max(abs(ca_), abs(cb))
    da = np.concatenate([a.model.alpha[j] - b.model.alpha[j] for j in a.model.joints])
    return bool(close_cost and np.max(np.abs(da)) < 1e-3)


def multistart_design(
    plant: HybridModel,
    degree: int,
    *,
    starts: int = 8,
    seed: int = 0,
    spread: float = 0.1,
    speed: float | None = None,
    omega_n: float = 20.0,
    zeta: float | None = None,
    certify: bool = True,
    points: int = 201,
) -> MultiStart:
    """Every distinct minimum of ``plant``'s HZD design problem from ``starts`` seeded starts.

    Parameters
    ----------
    plant : HybridModel
        ``three_link_walker`` or ``five_link_biped`` (:func:`design_problem`).
    degree : int
        Bézier degree ``M`` (3 to 20: invariance fixes ``α_0``, ``α_1``).
    starts : int
        Number of starts, 1 to :data:`MAX_STARTS`; start 0 is the problem's start, start ``k``
        adds ``U(−spread, spread)`` (rad) to each free coefficient (``numpy.random.default_rng
        (seed)``), redrawn (up to :data:`MAX_DRAWS` times) until its zero dynamics walk.
    seed : int
        The perturbations' seed.
    spread : float
        Half-width of the perturbations (rad, > 0).
    speed : float, optional
        Average speed to keep (m/s; the five-link biped's default 0.75).
    omega_n, zeta : float
        Gains of the full-order certification (rad/s, 1).
    certify : bool
        Certify every distinct minimum on the full-order closed loop.
    points : int
        Phases of the design's quadrature.
    """
    if (
        isinstance(starts, bool)
        or not isinstance(starts, (int, np.integer))
        or not (1 <= starts <= MAX_STARTS)
    ):
        raise GaitoptInputError(f"starts: {starts!r} is not an integer from 1 to {MAX_STARTS}; "
                                f"each start is a full optimisation, e.g. 8")  # fmt: skip
    if not (math.isfinite(spread) and spread > 0):
        raise GaitoptInputError(f"spread: {spread!r} must be a positive angle (rad), e.g. 0.1")
    if degree is not None and isinstance(degree, (int, np.integer)) and degree < 3:
        raise GaitoptInputError(f"degree: {degree} is too low for hybrid invariance (α_0 and "
                                f"α_1 are fixed by the impact); use 3 or more, e.g. 4")  # fmt: skip
    start, free, options = design_problem(plant, degree, speed=speed, points=points)
    rng = np.random.default_rng(seed)
    x0 = np.array([getattr(start, k) for k in free])
    # One box for every start: around the problem's start (or the plant's angle bounds).
    box = coefficient_bounds(start, free, options.pop("reach", 0.3))
    options["bounds"] = box
    minima: list[Minimum] = []
    outcomes: list[dict[str, Any]] = []
    objective = options["objective"]
    for k in range(starts):
        model, draws = _walking_start(start, free, x0, rng, spread if k else 0.0, points)
        if model is None:
            why = f"no walking start in {draws} draws (no fixed point that reaches θ⁻)"
            outcomes.append({"start": k, "converged": False, "cost": None, "minimum": None,
                             "draws": draws, "message": why})  # fmt: skip
            continue
        try:
            result = optimise_alpha(model, free, **options)
        except Exception as exc:  # noqa: BLE001 — a start where the surface breaks
            why = f"{type(exc).__name__}: {exc}"[:200]
            outcomes.append({"start": k, "converged": False, "cost": None, "minimum": None,
                             "draws": draws, "message": why})  # fmt: skip
            continue
        opt = result.optimum
        value = opt.cost if objective == "per_length" else opt.effort
        entry = {"start": k, "converged": result.success, "cost": value if result.success
                 else None, "minimum": None, "draws": draws, "message": result.message}  # fmt: skip
        if result.success:
            for i, m in enumerate(minima):
                if _same(m.design, opt, objective):
                    m.starts.append(k)
                    entry["minimum"] = i
                    break
            else:
                v = np.array([getattr(opt.model, name) for name in free])
                lo, hi = np.array(box).T
                at_bound = [name for name, a, b, c in zip(free, v, lo, hi, strict=True)
                            if min(a - b, c - a) < 1e-6]  # fmt: skip
                minima.append(Minimum(opt, [k], at_bound=at_bound))
                entry["minimum"] = len(minima) - 1
        outcomes.append(entry)
    order = sorted(
        range(len(minima)),
        key=lambda i: (
            minima[i].design.cost if objective == "per_length" else minima[i].design.effort
        ),
    )
    renumber = {old: new for new, old in enumerate(order)}
    minima = [minima[i] for i in order]
    for entry in outcomes:
        if entry["minimum"] is not None:
            entry["minimum"] = renumber[entry["minimum"]]
    if certify:
        for m in minima:
            m.gait = hzd_gait(plant, degree, alpha=m.design.model, omega_n=omega_n, zeta=zeta)
    return MultiStart(minima, outcomes, objective, seed, spread, tuple(free))


def speed_library(
    plant: HybridModel,
    degree: int,
    speeds: Sequence[float],
    *,
    points: int = 201,
    start: VirtualConstraintModel | None = None,
) -> list[tuple[float, SurfaceGait | None, str]]:
    """The design problem's optimum at each average speed of ``speeds`` (m/s, in the order
    given), each warm-started from the previous optimum (the first from ``start``, default the
    problem's start), all within the problem's box of bounds (:func:`design_problem`'s start
    ± 0.3 rad, or the plant's angle bounds); ``(speed, optimum or None, message)`` per speed.
    A failed point leaves the next one to start from the last success."""
    speeds = [float(v) for v in speeds]
    if not speeds or not all(math.isfinite(v) and v > 0 for v in speeds):
        raise GaitoptInputError(f"speeds: {speeds!r} must be positive speeds (m/s), e.g. "
                                f"0.4 0.5 0.6")  # fmt: skip
    first, free, options = design_problem(plant, degree, speed=speeds[0], points=points)
    model = first if start is None else start
    # One box for every point: the problem's (around its start, or the plant's angle bounds).
    options["bounds"] = coefficient_bounds(first, free, options.pop("reach", 0.3))
    out: list[tuple[float, SurfaceGait | None, str]] = []
    for v in speeds:
        options["speed"] = v
        result = optimise_alpha(model, free, **options)
        if result.success:
            model = result.optimum.model
            out.append((v, result.optimum, result.message))
        else:
            out.append((v, None, result.message))
    return out
