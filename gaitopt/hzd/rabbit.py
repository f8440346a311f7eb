"""FROST's RABBIT gait-design problem on the five-link biped (OptimTraj's parameters).

The problem (Hereid & Ames 2017, FROST's ``RABBIT`` example; Westervelt et al. 2007, §6.6):
one step of the five-link biped under hybrid-invariant Bézier virtual constraints of degree 5
on the four actuated links, phase variable the stance leg's mean angle ``θ = (q1 + q2)/2``
(decreasing over a step), minimising the effort of a step ``∫‖u‖² dt`` (N²·m²·s) subject to

* an average speed of 0.75 m/s (step length / step time);
* the swing foot at least 0.1 m above the ground at mid-step (``s = 1/2``);
* ``|u_i| ≤ 100 N·m`` (the model's declared input bounds);
* the stance foot's normal force ``N ≥ 0`` and its friction cone ``|F_t| ≤ μ N``, μ = 0.6 —
  unilateral constraints the closed loop declares (:mod:`.virtual`), so the full-order gait's
  certificate and simulation check them too;
* the swing foot above the ground inside the step, θ monotonic (``ζ > 0``: the zero dynamics
  carry θ from θ⁺ to θ⁻), the restricted map's slope below ``max_slope`` (a stable fixed point),
  and hybrid invariance by construction (:func:`.invariance.make_invariant`).

OptimTraj's mass and inertia values are FROST's RABBIT's in name only
(:mod:`gaitopt.models.five_link_biped`), so no published optimum applies: the design is
verified self-consistently (grids, full-order closed loop, simulation; ``problems/rabbit_hzd.py``).
"""

from __future__ import annotations

import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from .design import DesignResult, free_interior, optimise_alpha
from .virtual import VirtualConstraintModel, virtual_constraint_model

__all__ = ["RABBIT", "rabbit_start", "design_rabbit"]

#: The problem's numbers (FROST RABBIT example; units m/s, m, N·m, 1).
RABBIT = {"speed": 0.75, "mid_clearance": 0.1, "torque_limit": 100.0, "friction": 0.6,
          "degree": 5}  # fmt: skip


def rabbit_start(
    plant: HybridModel, degree: int = 5, *, omega_n: float = 10.0, zeta: float = 1.0
) -> VirtualConstraintModel:
    """A walking (not optimal) start: θ from 0.2 to −0.2 rad, the stance knee bent 0.1 rad at
    the start and straight at the end, the torso leaning 0.05 rad forward, the swing leg the
    stance leg's mirror with its knee bent by a bump of 1.3 rad on the middle coefficients
    (swing foot ≈ 0.15 m up at mid-step); its zero dynamics walk at 0.43 m/s."""
    cls = virtual_constraint_model(plant, degree)
    M = cls.degree
    tp, tm, bend = 0.2, -0.2, 0.1

    def line(a: float, b: float) -> np.ndarray:
        return np.array([a + (b - a) * k / M for k in range(M + 1)])

    bump = np.array([1.0 if 0.25 <= k / M <= 0.75 else 0.0 for k in range(M + 1)])
    alpha = {
        "stance_thigh": line(tp + bend, tm),
        "torso": np.full(M + 1, -0.05),
        "swing_thigh": line(tm, tp + bend),
        "swing_shank": line(tm, tp - bend) - 1.3 * bump,
    }
    params = {k: getattr(plant, k) for k in cls.plant.plant_parameters}
    model = cls(**params, omega_n=omega_n, zeta=zeta, friction_coefficient=RABBIT["friction"])
    return model.with_alpha(alpha, theta_plus=tp, theta_minus=tm)


def design_rabbit(
    model: VirtualConstraintModel,
    *,
    speed: float = RABBIT["speed"],
    points: int = 201,
    maxiter: int = 200,
    max_slope: float = 0.95,
    margin: float = 0.05,
) -> DesignResult:
    """The RABBIT problem (module docstring) from ``model``'s coefficients: SLSQP over every
    ``α_k``, ``2 ≤ k ≤ M`` (:func:`.design.optimise_alpha`, objective ``"effort"``), each
    within the link's declared angle bounds."""
    if not (np.isfinite(speed) and speed > 0):
        raise GaitoptInputError(f"speed: {speed!r} must be a positive number (m/s), e.g. 0.75")
    return optimise_alpha(
        model,
        free_interior(model),
        speed=speed,
        max_slope=max_slope,
        margin=margin,
        points=points,
        maxiter=maxiter,
        reach=None,
        objective="effort",
        torque_limit=RABBIT["torque_limit"],
        mid_clearance=RABBIT["mid_clearance"],
        declared=True,
    )
