"""Planar mechanics of point-mass chains: Lagrange's equations and impulsive impacts, by AD.

The models describe *where their masses are* as CasADi expressions of the generalised coordinates;
everything else (mass matrix, Coriolis and gravity terms, impact maps, energy, angular momentum)
follows mechanically here, so that each model states its geometry once.

References: Lagrange's equations ``d/dt ∂L/∂q̇ − ∂L/∂q = τ`` with ``L = T − V`` (e.g. Underactuated
Robotics, Tedrake, appendix "Multi-body dynamics"); impacts by the floating-base method
(Westervelt et al. 2007, "Feedback Control of Dynamic Bipedal Robot Locomotion", §3.4.2;
Hurmuzlu & Marghitu 1994): with the stance foot added as free coordinates, the impulse ``Λ`` at the
striking foot solves ``M_e (q̇⁺ − q̇⁻) = J_cᵀ Λ``, ``J_c q̇⁺ = 0``.  An impact that locks a joint
(the kneed walker's knee strike) is the same equation without the floating base, with ``J`` the
gradient of the locked relative rate (:func:`constrained_impact_velocity`; Westervelt et al. 2007,
§3.4.2, with an internal instead of a ground constraint).
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
    "constrained_impact_velocity",
    "mass_matrix",
    "bodies_function",
    "rigid_link",
    "lagrange_terms",
    "contact_force",
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
    M, rhs = lagrange_terms(masses, q, qd, gravity, tau)
    return ca.cse(solve_small(M, rhs))


def lagrange_terms(
    masses: Sequence[PointMass], q: ca.SX, qd: ca.SX, gravity: ca.SX, tau: ca.SX | float = 0
) -> tuple[ca.SX, ca.SX]:
    """Lagrange's equations as ``M(q) q̈ = rhs(q, q̇, τ)`` (the implicit form, for collocation
    or to check ``M``); :func:`lagrange_acceleration` solves it.

    ``M = Σ m_i J_iᵀ J_i`` and ``rhs = τ − Σ m_i J_iᵀ (J̇_i q̇ + g e_y)`` with ``J_i = ∂r_i/∂q``.
    """
    M = 0
    rhs = tau
    for m, r in masses:
        J = ca.jacobian(r, q)
        v = J @ qd
        bias = ca.jtimes(v, q, qd) + ca.vertcat(0, gravity)  # J̇ q̇ + g e_y
        M = M + m * (J.T @ J)
        rhs = rhs - m * (J.T @ bias)
    return M, rhs


def rigid_link(mass: ca.SX, com: ca.SX, axis: ca.SX, inertia: ca.SX) -> list[PointMass]:
    """A planar rigid body as two point masses with the same dynamics (an equimomental system).

    Masses ``m/2`` at ``com ± √(I/m)·axis``: the same total mass, centre of mass and moment of
    inertia about it (``2·(m/2)·(I/m) = I``), so the same kinetic energy ``½ m |v_G|² + ½ I θ̇²``,
    potential energy and angular momentum about any point as the body (Routh 1905, "Elementary
    rigid dynamics", equimomental systems).  Every function of this module therefore treats
    rigid links exactly, with no change.

    Parameters
    ----------
    mass : casadi.SX
        Body mass ``m`` (kg), positive.
    com : casadi.SX
        Centre of mass (2-vector expression of ``q``, m).
    axis : casadi.SX
        A unit vector fixed in the body (expression of ``q``), e.g. along the link.
    inertia : casadi.SX
        Moment of inertia about the centre of mass ``I`` (kg·m²), non-negative.

    Returns
    -------
    list of PointMass
        The two point masses.
    """
    arm = ca.sqrt(inertia / mass) * axis
    return [(mass / 2, com + arm), (mass / 2, com - arm)]


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


def mass_matrix(masses: Sequence[PointMass], q: ca.SX) -> ca.SX:
    """``M(q) = Σ m_i J_iᵀ J_i`` with ``J_i = ∂r_i/∂q`` (kg·m², or kg·m for mixed coordinates)."""
    M = 0
    for m, r in masses:
        J = ca.jacobian(r, q)
        M = M + m * (J.T @ J)
    return M


def _plastic(M: ca.SX, J: ca.SX, qd_minus: ca.SX) -> ca.SX:
    """Solve ``M (q̇⁺ − q̇⁻) = Jᵀ Λ``, ``J q̇⁺ = 0`` for ``q̇⁺`` (KKT system)."""
    n, k = M.shape[0], J.shape[0]
    K = ca.blockcat([[M, -J.T], [J, ca.SX.zeros(k, k)]])
    rhs = ca.vertcat(M @ qd_minus, ca.SX.zeros(k, 1))
    return ca.solve(K, rhs)[:n]


def constrained_impact_velocity(
    masses: Sequence[PointMass], q: ca.SX, qd: ca.SX, constraint_rate: ca.SX
) -> ca.SX:
    """Post-impact velocities for a plastic impact that enforces ``constraint_rate = 0``.

    ``constraint_rate`` is an expression linear in ``qd`` (``J(q) q̇``), e.g. a joint's relative
    rate ``q̇₃ − q̇₂`` for a knee that locks.  Contacts already built into the coordinates (a
    pinned or rolling stance foot) persist and take whatever impulse they need; the impulse of
    the new constraint is ``Jᵀ Λ``: ``M (q̇⁺ − q̇⁻) = Jᵀ Λ``, ``J q̇⁺ = 0`` (Westervelt et al. 2007,
    §3.4.2).  Since ``Λ`` is internal to the locking joint and the contact impulses act at the
    contact point, the angular momentum of the whole system about that point is conserved, and so
    is that of the part beyond the joint about its proximal joint (the tests check both).

    Parameters
    ----------
    masses : sequence of PointMass
        Masses and positions (expressions of ``q``).
    q, qd : casadi.SX
        Generalised coordinates and velocities just before impact.
    constraint_rate : casadi.SX
        ``J(q) q̇`` (k×1), linear in ``qd``.

    Returns
    -------
    casadi.SX
        ``q̇⁺`` in the same coordinates.
    """
    J = ca.jacobian(constraint_rate, qd)
    return _plastic(mass_matrix(masses, q), J, qd)


def _floating(
    masses: Sequence[PointMass], q: ca.SX, qd: ca.SX
) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX, ca.SX]:
    """The floating-base system of ``masses`` (positions relative to the stance foot): the base's
    two free coordinates ``base`` (m) and velocities ``base_d`` (m/s) prepended to ``q`` and
    ``qd``, and its mass matrix ``M(q_e)`` (the Hessian of the kinetic energy in ``q̇_e``).

    Returns ``(base, base_d, q_e, q̇_e, M)``; ``base`` and ``base_d`` appear in neither ``M`` nor
    the contact Jacobians (translation invariance), and the callers substitute zeros to be sure.
    """
    base = ca.SX.sym("base", 2)
    base_d = ca.SX.sym("base_d", 2)
    qe = ca.vertcat(base, q)
    qde = ca.vertcat(base_d, qd)
    floating = [(m, r + base) for m, r in masses]
    return base, base_d, qe, qde, ca.hessian(kinetic_energy(floating, qe, qde), qde)[0]


def impact_velocity(
    masses: Sequence[PointMass],
    q: ca.SX,
    qd: ca.SX,
    contact: ca.SX,
    *,
    contact_slip: ca.SX | None = None,
    impulse: tuple[ca.SX, ca.SX] | None = None,
    contact_impulse: bool = False,
) -> ca.SX:
    """Post-impact generalised velocities for a plastic impact of point ``contact``.

    The stance foot is added as two free coordinates (floating base); before impact it is at rest.
    The striking point sticks (``J_c q̇_e⁺ = 0``) and the old stance foot is assumed to leave the
    ground (no impulse there).  Positions are relative to the stance foot.

    For a curved foot the material point that touches the ground is not the point whose position
    ``contact`` describes as a function of ``q`` (the touching point moves over the arc as the
    foot rotates).  ``contact_slip`` is the difference of their velocities, linear in ``qd``: for
    an arc of radius ``R`` on a line with unit tangent ``t``, on a body whose angle ``θ`` grows
    clockwise, the material point at the contact moves at ``d(contact)/dt − R θ̇ t``, so
    ``contact_slip = −R θ̇ t`` (the rolling condition).  Then ``J_c = ∂(contact)/∂q_e +
    ∂(contact_slip)/∂q̇_e``.

    Parameters
    ----------
    masses : sequence of PointMass
        Masses and positions (expressions of ``q``) relative to the stance foot.
    q, qd : casadi.SX
        Generalised coordinates and velocities just before impact.
    contact : casadi.SX
        Position of the striking point (expression of ``q``), relative to the stance foot.
    contact_slip : casadi.SX, optional
        Velocity of the striking material point minus ``d(contact)/dt`` (2×1, linear in ``qd``);
        default zero (a point foot).
    impulse : (casadi.SX, casadi.SX), optional
        ``(point, P)``: an external impulse ``P`` (N·s, 2×1, world frame) applied at ``point``
        (an expression of ``q``) together with the impact, on the floating system — Kuo's (2002)
        push-off along the trailing leg just before heel strike.  The impulse equations are
        linear, so "just before" and "together" give the same ``q̇⁺``:
        ``M (q̇_e⁺ − q̇_e⁻) = J_cᵀ Λ + J_pᵀ P``, ``J_c q̇_e⁺ = 0``.  Default: none (the
        expressions are those without it).
    contact_impulse : bool
        Also return the striking point's impulse ``Λ`` (N·s, 2×1, world frame).

    Returns
    -------
    casadi.SX
        ``q̇⁺``, the generalised velocities just after impact (same coordinates as ``q``); with
        ``contact_impulse``, ``(q̇⁺, Λ)``.
    """
    base, base_d, qe, qde, M = _floating(masses, q, qd)
    J = ca.jacobian(contact + base, qe)
    if contact_slip is not None:
        J = J + ca.jacobian(contact_slip, qde)
    n = qe.shape[0]
    K = ca.blockcat([[M, -J.T], [J, ca.SX.zeros(2, 2)]])
    qde_minus = ca.vertcat(0, 0, qd)
    momentum = M @ qde_minus
    if impulse is not None:  # Kuo's push-off: J_pᵀ P on the floating system
        point, P = impulse
        momentum = momentum + ca.jacobian(point + base, qe).T @ P
    rhs = ca.vertcat(momentum, ca.SX.zeros(2, 1))
    sol = ca.solve(K, rhs)
    post = sol[2:n]
    # base and base_d do not appear in M or J (translation invariance); substitute to be sure.
    zero = ca.DM.zeros(4, 1)
    post = ca.substitute(post, ca.vertcat(base, base_d), zero)
    if contact_impulse:
        return post, ca.substitute(sol[n:], ca.vertcat(base, base_d), zero)
    return post


def impulse_work(
    masses: Sequence[PointMass], q: ca.SX, qd: ca.SX, point: ca.SX, impulse: ca.SX
) -> ca.SX:
    """Work (J) an external impulse ``impulse`` (N·s, 2×1) at ``point`` (an expression of ``q``)
    does on the floating system of ``masses`` (its base added as two free coordinates, at rest
    before): the kinetic energy gained, ``P·v_p⁻ + ½ Pᵀ J_p M⁻¹ J_pᵀ P`` with ``v_p⁻ = J_p q̇``
    (Kuo 2002's push-off work; for a point foot pinned before, ``v_p⁻ ⟂`` a push along the leg
    and only the quadratic term remains)."""
    base, base_d, qe, qde, M = _floating(masses, q, qd)
    Jp = ca.jacobian(point + base, qe)
    v = Jp @ ca.vertcat(0, 0, qd)
    gain = ca.dot(impulse, v) + 0.5 * ca.dot(impulse, Jp @ ca.solve(M, Jp.T @ impulse))
    return ca.substitute(gain, ca.vertcat(base, base_d), ca.DM.zeros(4, 1))


def bodies_function(
    masses: Sequence[PointMass], x: ca.SX, q: ca.SX, qd: ca.SX, p: ca.SX
) -> ca.Function:
    """``bodies(x, p) -> (m, r, v)``: masses (K×1), positions and velocities (2×K)."""
    m = ca.vertcat(*[mi for mi, _ in masses])
    r = ca.horzcat(*[ri for _, ri in masses])
    v = ca.horzcat(*[_velocity(ri, q, qd) for _, ri in masses])
    return ca.Function("bodies", [x, p], [m, r, v], ["x", "p"], ["m", "r", "v"])


def contact_force(
    masses: Sequence[PointMass], q: ca.SX, qd: ca.SX, qdd: ca.SX, gravity: ca.SX
) -> ca.SX:
    """The force the ground exerts on a system with one contact (N, 2-vector, world frame).

    Newton's second law for the whole system: ``F = Σ m_i (r̈_i + g ŷ)`` with
    ``r̈_i = J_i q̈ + J̇_i q̇`` (positions in an inertial frame; gravity along −y).  Its component
    along the ground's normal must be ≥ 0: the leg pushes, it cannot pull.
    """
    total = ca.SX.zeros(2, 1)
    for m, r in masses:
        v = _velocity(r, q, qd)
        a = ca.jtimes(v, q, qd) + ca.jtimes(v, qd, qdd)
        total += m * (a + ca.vertcat(0, gravity))
    return total
