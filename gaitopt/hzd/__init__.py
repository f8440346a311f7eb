"""Hybrid zero dynamics: Bézier virtual constraints as a controller of an actuated model, made
hybrid invariant, and the zero dynamics' one-dimensional restricted Poincaré map (Westervelt,
Grizzle & Koditschek 2003, IEEE TAC 48(1); Westervelt et al. 2007, *Feedback Control of Dynamic
Bipedal Robot Locomotion*, ch. 5–6)."""

from .bezier import bezier, bezier_derivative, fit_bezier
from .virtual import MAX_DEGREE, MIN_DEGREE, VirtualConstraintModel, virtual_constraint_model

__all__ = [
    "bezier",
    "bezier_derivative",
    "fit_bezier",
    "MAX_DEGREE",
    "MIN_DEGREE",
    "VirtualConstraintModel",
    "virtual_constraint_model",
]
