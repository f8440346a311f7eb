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
    """Solve Lagrange's equations of a system of point masses for ``q̈``.

    For point masses ``d/dt ∂L/∂q̇ − ∂L/∂q = τ`` is ``Σ m_i J_iᵀ (J_i q̈ + J̇_i q̇ + g e_y) = τ``
    with ``J_i = ∂r_i/∂q`` (project each mass's Newton equation on the coordinates), i.e.
    ``M q̈ = τ − Σ m_i J_iᵀ (J̇_i q̇ + g e_y)`` with ``M = Σ m_i J_iᵀ J_i``.  This form gives far
    smaller expressions than differentiating ``T`` twice.
    """
    M = 0
    rhs = tau
    for m, r in masses:
        J = ca.jacobian(r, q)
        v = J @ qd
        bias = ca.jtimes(v, q, qd) + ca.vertcat(0, gravity)  # J̇ q̇ + g e_y
        M = M + m * (J.T @ J)
        rhs = rhs - m * (J.T @ bias)
    return ca.cse(solve_small(M, rhs))


def solve_small(A: ca.SX, b: ca.SX) -> ca.SX:
    """``A⁻¹ b`` for a small symbolic matrix, by Cramer's rule up to 3×3 (far fewer operations
    in the shooting integrator than a symbolic QR); ``casadi.solve`` beyond."""
    n = A.shape[0]
    if n == 1:
        return b / A
    if n == 2:
        det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
        return ca.vertcat(A[1, 1] * b[0] - A[0, 1] * b[1], A[0, 0] * b[1] - A[1, 0] * b[0]) / det
    if n == 3:
        det = ca.det(A)
        cols = []
        for k in range(3):
            Ak = ca.horzcat(*[b if j == k else A[:, j] for j in range(3)])
            cols.append(ca.det(Ak))
        return ca.vertcat(*cols) / det
    return ca.solve(A, b)


def impact_velocity(masses: Sequence[PointMass], q: ca.SX, qd: ca.SX, contact: ca.SX) -> ca.SX:
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
