"""Hybrid invariance: Bézier coefficients that the impact maps back onto the constraint surface.

Westervelt et al. 2007, *Feedback Control of Dynamic Bipedal Robot Locomotion*, Thm 5.5 /
§6.3.2, eqs (6.37)–(6.38); Westervelt, Grizzle & Koditschek 2003, Thm 4.  With
``T = [H_0; c]`` (``H_0`` selects the actuated coordinates, ``c`` the phase variable), the
constraint surface is ``q = Φ(θ) = T⁻¹ [h_d(s(θ)); θ]`` with tangent ``Φ'(θ) = T⁻¹ [h_d'(θ); 1]``,
``h_d'(θ) = ∂_s h_d / (θ⁻ − θ⁺)``.  At the end of a step (``s = 1``) the state is
``q⁻ = T⁻¹ [α_M; θ⁻]``, ``q̇⁻ = Φ'(θ⁻) θ̇⁻``; the impact ``Δ`` gives ``q⁺ = Δ_q(q⁻)`` and
``q̇⁺ = Δ_q̇(q⁻) q̇⁻`` (linear in ``θ̇⁻``).  The surface is invariant (``y⁺ = 0``, ``ẏ⁺ = 0`` for
every ``θ̇⁻``) exactly when

    θ⁺ = c q⁺,   α_0 = H_0 q⁺,   α_1 = α_0 + (θ⁻ − θ⁺)/M · H_0 q̇⁺ / (c q̇⁺),

eqs (6.37): ``b(0) = α_0`` and ``b'(0) = M (α_1 − α_0)``.  ``θ⁻`` is where the guard (a function
of the configuration, e.g. the three-link walker's ``θ1 = θ_i``) meets the surface at ``s = 1``.
``α_1`` depends on ``α_{M−1}`` through ``q̇⁻``, so the construction is explicit for ``M ≥ 3``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from .bezier import bezier, bezier_derivative
from .virtual import VirtualConstraintModel

__all__ = ["surface_state", "pre_impact_state", "make_invariant", "invariance_residual"]


def _T(model: VirtualConstraintModel) -> np.ndarray:
    """``T = [H_0; c]`` (N×N): the actuated coordinates, then the phase variable."""
    names = model.state_names
    n = len(model.phase)
    T = np.zeros((n, n))
    for row, joint in enumerate(model.joints):
        T[row, names.index(joint)] = 1.0
    T[-1] = model.phase
    if abs(np.linalg.det(T)) < 1e-12:
        raise GaitoptInputError(
            f"phase_variable: c = {model.phase} together with the actuated coordinates "
            f"{', '.join(model.joints)} does not fix the configuration; choose c with a "
            f"component outside them"
        )
    return T


def surface_state(model: VirtualConstraintModel, theta: Any, theta_dot: Any) -> np.ndarray:
    """The state on the constraint surface ``(Φ(θ), Φ'(θ) θ̇)`` (rad, rad/s) at phase variable
    ``θ`` (rad) and rate ``θ̇`` (rad/s): ``(2N,)`` for scalars, ``(2N, K)`` for arrays of K."""
    T = _T(model)
    span = model.theta_minus - model.theta_plus
    th = np.atleast_1d(np.asarray(theta, dtype=float))
    rate = np.broadcast_to(np.asarray(theta_dot, dtype=float), th.shape)
    s = (th - model.theta_plus) / span
    alpha = model.alpha
    h = np.array([bezier(alpha[j], s) for j in model.joints])
    dh = np.array([bezier_derivative(alpha[j], s) for j in model.joints]) / span
    q = np.linalg.solve(T, np.vstack([h, th]))
    tangent = np.linalg.solve(T, np.vstack([dh, np.ones_like(th)]))
    out = np.vstack([q, tangent * rate])
    return out[:, 0] if np.ndim(theta) == 0 else out


def _guard_and_reset(model: VirtualConstraintModel):
    t = model.phases[0].transitions[0]
    return (
        lambda x: float(t.guard(x, [], model.p)),
        lambda x: np.asarray(t.reset(x, [], model.p), dtype=float).ravel(),
    )


def pre_impact_state(
    model: VirtualConstraintModel, theta_dot: float = 1.0
) -> tuple[float, np.ndarray]:
    """``(θ⁻, x⁻)``: where the guard meets the constraint surface's end (``s = 1`` shape, the
    phase variable free), by Newton on the guard from ``model.theta_minus``; ``x⁻`` with rate
    ``θ̇⁻ = theta_dot`` (rad/s)."""
    guard, _ = _guard_and_reset(model)
    T = _T(model)
    alpha_end = np.array([model.alpha[j][-1] for j in model.joints])

    def at(theta: float) -> np.ndarray:
        q = np.linalg.solve(T, np.r_[alpha_end, theta])
        tail = surface_state(model, model.theta_minus, theta_dot)[len(q) :]
        return np.r_[q, tail]

    theta = float(model.theta_minus)
    for _ in range(50):
        g = guard(at(theta))
        dg = (guard(at(theta + 1e-7)) - guard(at(theta - 1e-7))) / 2e-7
        if dg == 0:
            break
        step = g / dg
        theta -= step
        if abs(step) < 1e-15:
            break
    if abs(guard(at(theta))) > 1e-10:
        raise GaitoptInputError(
            f"alpha: the guard of {model.plant.name} does not meet the end of the constraint "
            f"surface near theta_minus = {model.theta_minus:g}; start from coefficients of a gait"
        )
    return theta, at(theta)


def make_invariant(model: VirtualConstraintModel) -> VirtualConstraintModel:
    """A copy of ``model`` with ``θ⁺``, ``θ⁻``, ``α_0`` and ``α_1`` set from the impact map
    (module docstring, Westervelt et al. 2007 eqs (6.37)) so that the constraint surface is
    hybrid invariant; the other coefficients are kept.  Needs degree ``M ≥ 3``."""
    if model.degree < 3:
        raise GaitoptInputError(
            f"degree: {model.degree} is too low for hybrid invariance (α_0 and α_1 are fixed by "
            f"the impact, α_(M−1) and α_M shape its pre-impact state); use a degree of 3 or more"
        )
    _, reset = _guard_and_reset(model)
    n = len(model.phase)
    c = np.asarray(model.phase)
    T = _T(model)
    H0 = T[:-1]
    # θ⁻ and q⁻ depend on α_M only; θ⁺ = c Δ_q(q⁻); then q̇⁻ (normalised by θ⁻ − θ⁺) and q̇⁺.
    theta_m, x_minus = pre_impact_state(model)
    theta_p = float(c @ reset(x_minus)[:n])
    model = model.replace(theta_plus=theta_p, theta_minus=theta_m)
    theta_m, x_minus = pre_impact_state(model)
    x_plus = reset(x_minus)
    q_plus, qd_plus = x_plus[:n], x_plus[n:]
    rate = float(c @ qd_plus)
    if abs(rate) < 1e-12:
        raise GaitoptInputError(
            "alpha: the impact stops the phase variable (c·q̇⁺ = 0); no invariant surface"
        )
    a0 = H0 @ q_plus
    a1 = a0 + (theta_m - theta_p) / model.degree * (H0 @ qd_plus) / rate
    alpha = model.alpha
    for row, joint in enumerate(model.joints):
        alpha[joint][0], alpha[joint][1] = a0[row], a1[row]
    return model.with_alpha(alpha, theta_plus=theta_p, theta_minus=theta_m)


def invariance_residual(model: VirtualConstraintModel, theta_dot: float = 1.0) -> float:
    """``max(|y⁺|, |ẏ⁺| / |θ̇⁻|)`` (rad) just after the impact from the end of the constraint
    surface with rate ``θ̇⁻`` (rad/s): 0 for hybrid-invariant constraints."""
    _, reset = _guard_and_reset(model)
    _, x_minus = pre_impact_state(model, theta_dot)
    y, dy = model.outputs(reset(x_minus))
    return float(max(np.max(np.abs(y)), np.max(np.abs(dy)) / abs(theta_dot)))
