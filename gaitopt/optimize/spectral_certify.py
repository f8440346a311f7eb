"""The certificate of a bound on the multipliers (``max_multiplier``): the reported optimum's
multipliers, by AD through the final transcription (:mod:`gaitopt.optimize.floquet`, separate
from the NLP's variational rows) and by finite differences of the simulated map
(:func:`gaitopt.optimize.verify.map_jacobian_fd`), must both have modulus at most ``R``.

The finite differences of the simulated map are first order in their step ``h`` (the held input
makes the map's second derivative jump at the profile's end: an error ``c·h`` that grows with
the input's slope at heel strike, 9e-6 of ``R`` on the compass gait's bounded optimum with
``∫τ̇² dt ≤ 4 S₀`` at ``h = 1e-6``).  The check therefore uses Richardson's extrapolation
``2 A(h/2) − A(h)`` (``h = 1e-6``), which cancels that term; the plain ``A(h)`` is what
``multipliers_fd`` reports.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .verify import map_jacobian_fd

__all__ = ["certify_spectral", "AD_TOL", "FD_TOL", "FD_STEP"]

#: Relative slack of the certificate for the AD multipliers (IPOPT's tolerance on the rows).
AD_TOL = 1e-8
#: Relative slack for the extrapolated finite-difference multipliers (their noise, O(rtol/h)).
FD_TOL = 1e-5
#: The step of the finite differences (section units), halved once for the extrapolation.
FD_STEP = 1e-6


def extrapolated_fd_radius(col: Any, w: np.ndarray, result: Any) -> float | None:
    """Spectral radius of ``2 A(h/2) − A(h)``, ``A(h)`` the central differences of the
    simulated map with step ``h`` (:data:`FD_STEP`); None if a simulation does not complete."""
    sol = col.unpack(w, col.model.p)
    jacobians = [
        map_jacobian_fd(col.problem, result.model, sol["s"], result.profiles, h=h)
        for h in (FD_STEP, FD_STEP / 2)
    ]
    if any(J is None for J in jacobians):
        return None
    A = 2 * jacobians[1] - jacobians[0]
    return float(np.max(np.abs(np.linalg.eigvals(A))))


def certify_spectral(col: Any, w: np.ndarray, result: Any) -> None:
    """The certificate's part for the bound: the result records ``max_multiplier`` (``R``),
    ``max_roughness``, ``roughness`` and ``spectral_radius_fd_extrapolated``; a gait whose
    multipliers, by AD or by extrapolated finite differences of the simulated map, exceed ``R``
    (beyond :data:`AD_TOL` / :data:`FD_TOL` relative) is no certified optimum (``success``
    False, the message says by how much)."""
    rows = getattr(col, "spectral", None)
    if rows is None:
        return
    R = rows.R
    result.max_multiplier = R
    result.max_roughness = col.problem.max_roughness
    result.roughness = float(rows.roughness(w, col.model.p))
    mu = np.asarray(result.multipliers)
    if mu.size == 0 and result.cost is not None:  # verify=False: the NLP's own A
        mu = np.linalg.eigvals(np.asarray(rows.A(w, col.model.p), dtype=float))
    rho = float(np.max(np.abs(mu))) if mu.size else None
    if not result.success:
        return
    rho_fd = extrapolated_fd_radius(col, w, result) if result.verified else None
    result.spectral_radius_fd_extrapolated = rho_fd
    failure = None
    if rho is None or rho > R * (1 + AD_TOL):
        failure = f"its spectral radius by AD, {rho}, exceeds max_multiplier {R:g}"
    elif result.verified and rho_fd is None:
        failure = "its multipliers by finite differences of the simulated map are unavailable"
    elif rho_fd is not None and rho_fd > R * (1 + FD_TOL):
        failure = (
            f"its spectral radius by finite differences of the simulated map, {rho_fd:.8g}, "
            f"exceeds max_multiplier {R:g}"
        )
    if failure is not None:
        result.success, result.stable = False, None
        result.message = f"the bound on the multipliers is not confirmed: {failure}"
        return
    active = any(a.startswith("spectral radius <=") for a in result.active_constraints)
    result.message += f"; spectral radius {rho:.10g} {'at' if active else 'within'} the bound {R:g}"
