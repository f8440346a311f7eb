"""One solve for any transcription: :func:`solve_gait` — solve (Newton on a square
transcription, IPOPT otherwise), refine the mesh until the discretisation error is below
``tol``, certify the orbit's dense samples (:func:`gaitopt.orbit.certify_orbit`) and let the
referee simulate it (:func:`gaitopt.orbit.referee`).  Its ``status`` is a code of the one table
:data:`gaitopt.result.STATUS`.

The front doors :func:`gaitopt.find_limit_cycle` and :func:`gaitopt.optimize_gait` do the same
four steps with what only they know (the shooting's standing-still and singular-Jacobian
tests, the optimiser's multi-start, arcs and cost refinement); this is the sequence on the
contract alone, for any :class:`~gaitopt.orbit.transcription.Transcription`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..result import STATUS
from .certificate import certify_orbit
from .ipopt import solve_nlp
from .newton import solve_square

__all__ = ["METHODS", "OrbitSolution", "solve_gait"]

#: The solvers :func:`solve_gait` offers (None: Newton where the transcription is square).
METHODS = ("newton", "ipopt")


@dataclass
class OrbitSolution:
    """What :func:`solve_gait` found.

    Attributes
    ----------
    success : bool
        Solved to ``tol``, discretisation error below ``tol``, certified and (with ``verify``)
        confirmed by the referee.
    status : str
        A code of :data:`gaitopt.result.STATUS`.
    message : str
        What was found, or what failed.
    transcription : Transcription
        The transcription of the last mesh.
    w : numpy.ndarray
        Its solution.
    iterations : int
        Solver iterations, summed over the meshes.
    error : float
        :meth:`~Transcription.error_estimate` at ``w``.
    refinements : int
        Meshes refined.
    multipliers : numpy.ndarray
        Eigenvalues of the return map's Jacobian (empty unless certified).
    verdict : Verdict or None
        The referee's verdict.
    """

    success: bool
    status: str
    message: str
    transcription: Any
    w: np.ndarray
    iterations: int = 0
    error: float = float("nan")
    refinements: int = 0
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    verdict: Any = None

    @property
    def advice(self) -> str:
        """What :data:`~gaitopt.result.STATUS` says about :attr:`status`."""
        return STATUS[self.status]


def _solve(transcription: Any, w0, method: str) -> tuple[np.ndarray, bool, int, float]:
    """``(w, converged, iterations, residual)``: the largest violation of the rows' bounds."""
    if method == "newton":
        r = solve_square(transcription, w0)
        w, converged, iterations = r.w, r.converged, r.iterations
    else:
        r = solve_nlp(transcription, w0)
        w, converged, iterations = r.w, r.converged, r.iterations
    b = transcription.bounds()
    F = transcription.evaluate(w).F
    violation = np.maximum(np.asarray(b.lbg) - F, F - np.asarray(b.ubg))
    residual = float(np.max(violation, initial=0.0)) if np.all(np.isfinite(F)) else np.inf
    return w, converged, iterations, residual


def solve_gait(
    transcription: Any,
    w0,
    *,
    method: str | None = None,
    tol: float = 1e-8,
    max_refinements: int = 3,
    verify: bool = True,
    guard_tol: float = 1e-6,
    referee_tol: float = 1e-6,
) -> OrbitSolution:
    """Solve → refine → certify → referee, on any transcription.

    Parameters
    ----------
    transcription : Transcription
        The orbit's transcription (rules of :mod:`gaitopt.orbit.transcription`).
    w0 : numpy.ndarray
        A start (``transcription.columns.size`` unknowns).
    method : {"newton", "ipopt"}, optional
        Default: Newton on a square transcription, IPOPT otherwise.
    tol : float
        The largest residual (violation of the rows' bounds) and discretisation error accepted.
    max_refinements : int
        Most meshes refined (each :meth:`~Transcription.refined`, warm started by
        :meth:`~Transcription.carry`).
    verify : bool
        Run the referee.
    guard_tol : float
        The certificate's relative tolerance of ``g = 0`` at the phase ends.
    referee_tol : float
        The referee's return tolerance (relative to ``1 + max |x*|``).
    """
    method = method or ("newton" if transcription.square else "ipopt")
    if method not in METHODS:
        raise GaitoptInputError(f"`method` must be one of {', '.join(METHODS)}, got {method!r}")
    t, total, refinements = transcription, 0, 0
    while True:
        w, converged, iterations, residual = _solve(t, w0, method)
        total += iterations
        if not residual <= tol:
            return OrbitSolution(
                False, "not_converged",
                f"{method} stopped after {iterations} iterations with the rows violated by "
                f"{residual:.3g} (tolerance {tol:g})", t, w, total, refinements=refinements,
            )  # fmt: skip
        error = t.error_estimate(w)
        if error <= tol or refinements == max_refinements:
            break
        fine = t.refined()
        w0, t = fine.carry(w, t), fine
        refinements += 1
    if not error <= tol:
        return OrbitSolution(
            False, "discretisation",
            f"the discretisation error estimate {error:.2g} stays above {tol:g} after "
            f"{refinements} refinements", t, w, total, error, refinements,
        )  # fmt: skip
    defect = certify_orbit(t.model, t.dense_arcs(w), t.p, steps=t.steps, guard_tol=guard_tol)
    if defect is not None:
        return OrbitSolution(False, "not_a_gait", "not a gait: " + defect, t, w, total, error,
                             refinements)  # fmt: skip
    multipliers = t.return_map_jacobians(w).multipliers
    if not verify:
        return OrbitSolution(True, "success", "orbit certified (not verified: verify=False)", t,
                             w, total, error, refinements, multipliers)  # fmt: skip
    verdict = t.referee(w, referee_tol)
    if not verdict.ok:
        return OrbitSolution(
            False, "not_verified", "the simulation does not confirm the orbit: "
            + verdict.message, t, w, total, error, refinements, multipliers, verdict,
        )  # fmt: skip
    return OrbitSolution(True, "success", "orbit certified and verified: " + verdict.message, t,
                         w, total, error, refinements, multipliers, verdict)  # fmt: skip
