"""An HZD gait in one call: fit Bézier constraints to a plant's gait, make them hybrid invariant,
solve the restricted map, then find and verify the full-order closed loop's gait.

The route (Westervelt et al. 2007, §6.4's design recipe, without the optimisation): the plant
model's own gait (the three-link walker's fixed-constraint gait) gives the phase range and, by
least squares, the Bézier coefficients of every actuated coordinate against ``s``;
:func:`~.invariance.make_invariant` replaces ``α_0, α_1`` by the impact's; the zero dynamics'
fixed point (:func:`~.zero_dynamics.restricted_map`) is the guess of
:func:`~gaitopt.find_limit_cycle` on the closed loop, whose certificate (dense checks, the
independent simulation) decides whether the gait is reported.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..result import LimitCycle
from ..shooting import MultipleShooting, find_limit_cycle
from .bezier import fit_bezier
from .invariance import invariance_residual, make_invariant
from .virtual import VirtualConstraintModel, plant_of, virtual_constraint_model
from .zero_dynamics import RestrictedMap, fixed_point_state, restricted_map

__all__ = ["HZDGait", "hzd_gait", "fit_to_orbit", "mesh_for", "check_monotonic"]


@dataclass
class HZDGait:
    """A closed-loop gait under Bézier virtual constraints and its zero-dynamics certificate.

    Attributes
    ----------
    model : VirtualConstraintModel
        The closed loop (its ``alpha`` are the constraints).
    cycle : LimitCycle or None
        The full-order gait (``find_limit_cycle``), None if the zero dynamics have no gait.
    rmap : RestrictedMap
        The zero dynamics' restricted Poincaré map.
    invariance_residual : float
        ``max(|y⁺|, |ẏ⁺|/θ̇⁻)`` just after the impact (rad), 0 for invariant constraints.
    max_torque : float or None
        ``max |u_i|`` on the gait's dense samples (N·m).
    torque_limit : float or None
        The bound asked for (N·m).
    success : bool
        A certified gait within the torque bound.
    message : str
        What happened.
    """

    model: VirtualConstraintModel
    cycle: LimitCycle | None
    rmap: RestrictedMap
    invariance_residual: float
    max_torque: float | None
    torque_limit: float | None
    success: bool
    message: str
    extra: dict = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """The ``solve --controller hzd --json`` object: the gait's (``LimitCycle.as_dict``)
        with ``controller``, ``bezier``, ``restricted_map``, ``invariance_residual``,
        ``max_torque`` (N·m) and ``torque_limit``."""
        m = self.model
        out = dict(self.cycle.as_dict()) if self.cycle is not None else {"model": m.name}
        names = m.state_names[: len(m.phase)]
        out.update(
            {
                "success": self.success,
                "message": self.message,
                "controller": {
                    "kind": "hzd",
                    "plant": m.plant.name,
                    "phase_variable": {n: c for n, c in zip(names, m.phase, strict=True) if c},
                    "theta_plus": m.theta_plus,
                    "theta_minus": m.theta_minus,
                    "degree": m.degree,
                    "gains": {
                        "omega_n": m.omega_n,
                        "zeta": m.zeta,
                        "Kp": m.omega_n**2,
                        "Kd": 2 * m.zeta * m.omega_n,
                    },
                },
                "bezier": {j: [float(v) for v in a] for j, a in m.alpha.items()},
                "restricted_map": self.rmap.as_dict(),
                "invariance_residual": self.invariance_residual,
                "max_torque": self.max_torque,
                "torque_limit": self.torque_limit,
            }
        )
        return out


def mesh_for(omega_n: float) -> MultipleShooting:
    """Eight segments, RK steps growing with ω_n (the output dynamics' fast root −1.56 ω_n at
    ζ = 1.1 kept well inside the RK step's stability region, as in the gains study)."""
    return MultipleShooting(segments=8, rk_steps=max(2, math.ceil(omega_n / 4)))


def check_monotonic(theta: np.ndarray, what: str) -> None:
    """Refuse a phase variable that is not strictly monotonic over a step (the normalised phase
    ``s`` would not be a function of time): :class:`GaitoptInputError` naming the argument."""
    d = np.diff(np.asarray(theta, dtype=float))
    if not (np.all(d > 0) or np.all(d < 0)):
        raise GaitoptInputError(
            f"phase_variable: θ = c·q is not monotonic on {what} (it runs {theta[0]:.4g} → "
            f"{float(np.min(theta)):.4g}/{float(np.max(theta)):.4g} → {theta[-1]:.4g} rad); "
            f"choose a combination that only increases or only decreases over a step"
        )


def fit_to_orbit(model: VirtualConstraintModel, cycle: LimitCycle) -> VirtualConstraintModel:
    """``model`` with ``θ⁺, θ⁻`` and least-squares Bézier coefficients (ends pinned) of the
    plant gait ``cycle``'s actuated coordinates against ``s`` (rad)."""
    X = np.hstack([arc.x for arc in cycle.orbit])
    theta = model.phase_value(X)
    check_monotonic(theta, f"the gait of {cycle.model.name}")
    s = (theta - theta[0]) / (theta[-1] - theta[0])
    names = cycle.model.state_names
    alpha = {j: fit_bezier(s, X[names.index(j)], model.degree) for j in model.joints}
    return model.with_alpha(alpha, theta_plus=float(theta[0]), theta_minus=float(theta[-1]))


def hzd_gait(
    plant: HybridModel,
    degree: int = 4,
    *,
    phase_variable: Mapping[str, float] | None = None,
    omega_n: float | None = None,
    zeta: float | None = None,
    alpha: Mapping[str, np.ndarray] | VirtualConstraintModel | None = None,
    invariant: bool = True,
    torque_limit: float | None = None,
) -> HZDGait:
    """An HZD gait of ``plant`` (module docstring).

    Parameters
    ----------
    plant : HybridModel
        A model with the plant protocol (:mod:`.virtual`) and a gait of its own to start from
        (unless ``alpha`` is given).
    degree : int
        Bézier degree ``M`` (1 to 20; ≥ 3 for ``invariant``).
    phase_variable : mapping, optional
        ``{state: c_i}`` of ``θ = c·q``; default the plant's.
    omega_n, zeta : float, optional
        Gains ``K_p = ω_n²``, ``K_d = 2ζω_n`` (rad/s, 1; > 0); defaults the closed loop's.
    alpha : mapping or VirtualConstraintModel, optional
        Coefficients by joint (rad) instead of the fit (``theta_plus``/``theta_minus`` then
        from :func:`make_invariant`, so ``invariant`` must hold, starting from the closed
        loop's defaults), or a closed loop of the same class (a design, e.g.
        :func:`~.design.optimise_alpha`'s optimum) whose coefficients and phase range are used.
    invariant : bool
        Make the constraints hybrid invariant (default True).
    torque_limit : float, optional
        Bound on every ``|u_i|`` (N·m, > 0): a gait that needs more is ``success: False``;
        default the plant's declared ``input_bounds`` (the five-link biped's 100 N·m), if any.
    """
    cls = virtual_constraint_model(plant_of(plant), degree, phase_variable)
    for name, value in (("omega_n", omega_n), ("zeta", zeta), ("torque_limit", torque_limit)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise GaitoptInputError(f"{name}: {value!r} must be a positive number, e.g. 10")
    changes = {k: getattr(plant, k) for k in cls.plant.plant_parameters}
    changes.update({k: v for k, v in (("omega_n", omega_n), ("zeta", zeta)) if v is not None})
    model = cls(**changes)
    if torque_limit is None and plant.input_bounds:
        torque_limit = min(max(abs(lo), abs(hi)) for lo, hi in plant.input_bounds.values())
    if alpha is None:
        if not plant.passive_gait:
            raise GaitoptInputError(
                f"alpha: {plant.name} has no gait of its own to fit the constraints to; give "
                f"the Bézier coefficients (hzd_gait(..., alpha=...))"
            )
        start = find_limit_cycle(plant)
        if not start.success:
            raise GaitoptInputError(
                f"alpha: {plant.name} has no gait of its own to fit the constraints to "
                f"({start.message[:120]}); give the Bézier coefficients"
            )
        model = fit_to_orbit(model, start)
    else:
        if not invariant:
            raise GaitoptInputError("invariant: given coefficients are made invariant; "
                                    "pass invariant=True")  # fmt: skip
        if isinstance(alpha, VirtualConstraintModel):
            # A whole design (optimise_alpha's optimum): its coefficients and phase range.
            model = model.with_alpha(alpha.alpha, theta_plus=alpha.theta_plus,
                                     theta_minus=alpha.theta_minus)  # fmt: skip
        else:
            model = model.with_alpha(alpha)
    if invariant:
        model = make_invariant(model)
    residual = invariance_residual(model)
    rmap = restricted_map(model)
    if rmap.fixed_point is None or not rmap.walks:
        why = (
            f"its slope δ² = {rmap.slope:.4g} is not below 1"
            if rmap.slope >= 1
            else "the walker does not reach θ⁻ (ζ falls to 0 within the step)"
        )
        return HZDGait(model, None, rmap, residual, None, torque_limit, False,
                       f"no gait: the zero dynamics have no walking fixed point ({why}); try "
                       f"other coefficients or a higher degree")  # fmt: skip
    x = fixed_point_state(model, rmap)
    guess = dict(zip(model.section.coordinates, model.section_coordinates_of(x), strict=True))
    cycle = find_limit_cycle(model, guess, discretisation=mesh_for(model.omega_n))
    if not cycle.success:
        return HZDGait(model, cycle, rmap, residual, None, torque_limit, False, cycle.message)
    X = np.hstack([arc.x for arc in cycle.orbit])
    check_monotonic(model.phase_value(X), "the closed loop's gait")
    peak = model.max_torque(cycle)
    ok, message = True, cycle.message
    if torque_limit is not None and peak > torque_limit:
        ok = False
        message = (
            f"the gait needs max |u| = {peak:.4g} N·m, above the bound {torque_limit:g} N·m; "
            f"lower omega_n or raise the bound"
        )
    return HZDGait(model, cycle, rmap, residual, peak, torque_limit, ok, message)
