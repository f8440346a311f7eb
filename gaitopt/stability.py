"""Floquet multipliers of a periodic orbit from the shooting equations (implicit function theorem).

Split the shooting unknowns into the section coordinates ``s`` of the first node and the rest
``z`` (other nodes, phase durations).  The equations other than periodicity, ``G(s, z, u, p) = 0``,
define ``z(s)``: the orbit piece that starts at ``lift(s)`` and ends on each guard.  The return map
in section coordinates is ``P(s) = Π r(x_end(s, z(s)))``, so by the implicit function theorem

    ∂P/∂s = P_s − P_z G_z⁻¹ G_s,        ∂P/∂u = P_u − P_z G_z⁻¹ G_u.

Differentiating through the guard equations with free durations is what the saltation matrix does
at each impact, so it is included implicitly.  Because ``lift`` parametrises exactly the set the
map lands in (the reset's image of the guard, within any conserved level set), the eigenvalues of
``∂P/∂s`` are the nontrivial multipliers only: no trivial 0 from the section, no +1 from a
conserved quantity.
"""

from __future__ import annotations

import numpy as np

__all__ = ["section_jacobians", "is_stable"]


def section_jacobians(
    J_w: np.ndarray, J_u: np.ndarray, m: int, n_g: int
) -> tuple[np.ndarray, np.ndarray]:
    """Return-map Jacobians ``(∂P/∂s, ∂P/∂u)`` from the Jacobians of the stacked ``[G; P]``.

    Parameters
    ----------
    J_w : numpy.ndarray
        ``∂[G; P]/∂w`` with ``w = [s; z]``; shape ``(n_g + m) × (m + n_z)``, ``n_z = n_g``.
    J_u : numpy.ndarray
        ``∂[G; P]/∂u``; shape ``(n_g + m) × n_u``.
    m : int
        Number of section coordinates.
    n_g : int
        Number of equations in ``G``.
    """
    G_s, G_z = J_w[:n_g, :m], J_w[:n_g, m:]
    P_s, P_z = J_w[n_g:, :m], J_w[n_g:, m:]
    G_u, P_u = J_u[:n_g], J_u[n_g:]
    rhs = np.hstack([G_s, G_u])
    dz = np.linalg.solve(G_z, rhs) if n_g else np.zeros((0, rhs.shape[1]))
    total = np.hstack([P_s, P_u]) - P_z @ dz
    return total[:, :m], total[:, m:]


def is_stable(multipliers: np.ndarray) -> bool:
    """Every multiplier strictly inside the unit circle."""
    return bool(np.all(np.abs(multipliers) < 1.0))
