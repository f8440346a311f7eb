"""Floquet multipliers of a periodic orbit from the shooting equations (implicit function theorem).

Split the shooting unknowns into the section coordinates ``s`` of the first node and the rest
``z`` (other nodes, phase durations).  The equations other than periodicity, ``G(s, z, u, p) = 0``,
define ``z(s)``: the orbit piece that starts at ``lift(s)`` and ends on each guard.  The return map
in section coordinates is ``P(s) = Π r(x_end(s, z(s)))``, so by the implicit function theorem

    ∂P/∂s = P_s − P_z G_z⁻¹ G_s,        ∂P/∂u = P_u − P_z G_z⁻¹ G_u

(rule 1 of :mod:`gaitopt.orbit.sensitivity`, which computes it: :func:`section_jacobians`).
Differentiating through the guard equations with free durations is what the saltation matrix does
at each impact, so it is included implicitly.  Because ``lift`` parametrises exactly the set the
map lands in (the reset's image of the guard, within any conserved level set), the eigenvalues of
``∂P/∂s`` are the nontrivial multipliers only: no trivial 0 from the section, no +1 from a
conserved quantity.
"""

from __future__ import annotations

import numpy as np

from .orbit.sensitivity import section_jacobians

__all__ = ["section_jacobians", "is_stable"]


def is_stable(multipliers: np.ndarray) -> bool:
    """Every multiplier strictly inside the unit circle."""
    return bool(np.all(np.abs(multipliers) < 1.0))
