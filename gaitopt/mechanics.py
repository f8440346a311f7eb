"""Planar mechanics of point-mass chains: Lagrange's equations and impulsive impacts, by AD.

The models describe *where their masses are* as CasADi expressions of the generalised coordinates;
everything else (mass matrix, Coriolis and gravity terms, impact maps, energy, angular momentum)
follows mechanically here, so that each model states its geometry once.

References: Lagrange's equations ``d/dt ∂L/∂q̇ − ∂L/∂q = τ`` with ``L = T − V`` (e.g. Underactuated
Robotics, Tedrake, appendix "Multi-body dynamics"); impacts by the floating-base method
(Westervelt et al. 2007, "Feedback Control of Dynamic Bipedal Robot Locomotion", §3.4.2;
Hurmuzlu & Marghitu 1994): with the stance foot added as free coordinates, the impulse ``Λ`` at the
striking foot solves ``M_e (q̇⁺ − q̇⁻) = J_cᵀ Λ``, ``J_c q̇⁺ = 0``.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca

__all__ = [
    "PointMass",
    "kinetic_energy",
    "potential_energy",
    "lagrange_acceleration",
    "impact_velocity",
    "bodies_function",
]

PointMass = tuple[ca.SX, ca.SX]
"""A point mass: (mass, position as a 2-vector expression of q, world frame, y up)."""


def _velocity(position: ca.SX, q: ca.SX, qd: ca.SX) -> ca.SX:
    return ca.jtimes(position, q, qd)


def kinetic_energy(masses: Sequence[PointMass], q: ca.SX, qd: ca.SX) -> ca.SX:
    """``T = ½ Σ m_i |ṙ_i|²`` (J)."""
    total = 0
    for m, r in masses:
        v = _velocity(r, q, qd)
        total = total + 0.5 * m * ca.dot(v, v)
    return total


def potential_energy(masses: Sequence[PointMass], gravity: ca.SX) -> ca.SX:
    """``V = Σ m_i g y_i`` (J), gravity along −y."""
    total = 0
    for m, r in masses:
        total = total + m * gravity * r[1]
    return total


def lagrange_acceleration(
    masses: Sequence[PointMass], q: ca.SX, qd: ca.SX, gravity: ca.SX, tau: ca.SX | float = 0
) -> ca.SX:
    """Solve Lagrange's equations for ``q̈``.

    ``M(q) q̈ = τ − (∂(M q̇)/∂q) q̇ + ∂T/∂q − ∂V/∂q`` with ``M = ∂²T/∂q̇²``.
    """
    T = kinetic_energy(masses, q, qd)
    V = potential_energy(masses, gravity)
    M = ca.hessian(T, qd)[0]
    p = ca.gradient(T, qd)  # generalised momentum M q̇
    rhs = tau - ca.jtimes(p, q, qd) + ca.gradient(T, q) - ca.gradient(V, q)
    return ca.solve(M, rhs)


def impact_velocity(
    masses: Sequence[PointMass], q: ca.SX, qd: ca.SX, contact: ca.SX
) -> ca.SX:
    """Post-impact generalised velocities for a plastic impact of point ``contact``.

    The stance foot is added as two free coordinates (floating base); before impact it is at rest.
    The striking point sticks (``J_c q̇_e⁺ = 0``) and the old stance foot is assumed to leave the
    ground (no impulse there).  Positions are relative to the stance foot.

    Parameters
    ----------
    masses : sequence of PointMass
        Masses and positions (expressions of ``q``) relative to the stance foot.
    q, qd : casadi.SX
        Generalised coordinates and velocities just before impact.
    contact : casadi.SX
        Position of the striking point (expression of ``q``), relative to the stance foot.

    Returns
    -------
    casadi.SX
        ``q̇⁺``, the generalised velocities just after impact (same coordinates as ``q``).
    """
    base = ca.SX.sym("base", 2)
    base_d = ca.SX.sym("base_d", 2)
    qe = ca.vertcat(base, q)
    qde = ca.vertcat(base_d, qd)
    floating = [(m, r + base) for m, r in masses]
    M = ca.hessian(kinetic_energy(floating, qe, qde), qde)[0]
    J = ca.jacobian(contact + base, qe)
    n = qe.shape[0]
    K = ca.blockcat([[M, -J.T], [J, ca.SX.zeros(2, 2)]])
    qde_minus = ca.vertcat(0, 0, qd)
    rhs = ca.vertcat(M @ qde_minus, ca.SX.zeros(2, 1))
    sol = ca.solve(K, rhs)
    post = sol[2:n]
    # base and base_d do not appear in M or J (translation invariance); substitute to be sure.
    return ca.substitute(post, ca.vertcat(base, base_d), ca.DM.zeros(4, 1))


def bodies_function(
    masses: Sequence[PointMass], x: ca.SX, q: ca.SX, qd: ca.SX, p: ca.SX
) -> ca.Function:
    """``bodies(x, p) -> (m, r, v)``: masses (K×1), positions and velocities (2×K)."""
    m = ca.vertcat(*[mi for mi, _ in masses])
    r = ca.horzcat(*[ri for _, ri in masses])
    v = ca.horzcat(*[_velocity(ri, q, qd) for _, ri in masses])
    return ca.Function("bodies", [x, p], [m, r, v], ["x", "p"], ["m", "r", "v"])
