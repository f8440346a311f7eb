"""One solve for any transcription: :func:`solve_gait` — solve (Newton on a square
transcription, IPOPT otherwise), refine the mesh until the discretisation error is below
``tol``, certify the orbit's dense samples (:func:`gaitopt.orbit.certify_orbit`) and let the
referee simulate it (:func:`gaitopt.orbit.referee`).  Its ``status`` is a code of the one table
:data:`gaitopt.result.STATUS`.

The sequence is three stages, each a function both front doors call:

* :func:`refine` — solve (a ``solver`` the caller may supply), then refine the mesh
  (:meth:`~Transcription.error_estimate`, :meth:`~Transcription.refined`,
  :meth:`~Transcription.carry`) until the error is below ``tol``: statuses ``not_converged``,
  ``singular`` (the error estimate's linear solve is singular), ``discretisation``;
* :func:`certificate` — the one certificate on :meth:`~Transcription.dense_arcs` (with the
  transcription's own consistency checks): status ``not_a_gait``;
* :func:`judge` — a transcription's pre-checks (the shooting's standing-still test), the
  certificate, the multipliers (``singular`` where the return map cannot be linearised) and
  the referee (``not_verified``).

:func:`gaitopt.find_limit_cycle` is :func:`solve_gait` on a
:class:`~gaitopt.shooting.transcription.ShootingTranscription` with the shooting's Newton as
``solver`` (and :func:`gaitopt.shooting.certify`, continuation's check of a branch point, is
:func:`judge`); :func:`gaitopt.optimize_gait` keeps its multi-start, arcs and cost-based mesh
refinement and certifies each optimum by :func:`certificate` and the referee of a
:class:`~gaitopt.optimize.transcription.CollocationTranscription`.

Optional hooks a transcription may define (beyond rules 1–9 of
:mod:`gaitopt.orbit.transcription`): ``refinable`` (False: the finest mesh it allows is
reached), ``precheck(w)`` (``(status, message)`` or None: a solution that is no orbit to
certify, e.g. standing still), ``consistency(w)`` (a defect in words or None, checked after the
certificate), ``parameters(w)`` (the parameter vector at ``w``, where some are unknowns) and
``repeated_advice`` (what to try when a period-k orbit is a shorter one repeated)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..result import STATUS
from .certificate import REPEATED_ADVICE, certify_orbit
from .newton import solve_square
from .sensitivity import multipliers as sorted_multipliers

__all__ = ["METHODS", "OrbitSolution", "Solved", "certificate", "judge", "refine", "solve_gait"]

#: The solvers :func:`solve_gait` offers (None: Newton where the transcription is square).
METHODS = ("newton", "ipopt")


@dataclass
class Solved:
    """What a solver hands :func:`refine`: the last point ``w``, whether its stopping test
    passed, its iterations and the transcription's evaluation at ``w`` (None: evaluated by
    :func:`refine`)."""

    w: np.ndarray
    converged: bool
    iterations: int
    evaluation: Any = None
    info: Any = None  # the solver's own record (IPOPT's stats)


@dataclass
class OrbitSolution:
    """What :func:`solve_gait` found.

    Attributes
    ----------
    success : bool
        Solved to ``tol``, discretisation error below ``tol``, certified and (with ``verify``)
        confirmed by the referee.
    status : str
        A code of :data:`gaitopt.result.STATUS` (``"converged"`` after :func:`refine` alone:
        solved and refined, not yet certified).
    message : str
        What was found, or what failed.
    transcription : Transcription
        The transcription of the last mesh.
    w : numpy.ndarray
        Its solution.
    iterations : int
        Solver iterations, summed over the meshes.
    error : float
        :meth:`~Transcription.error_estimate` at ``w`` (NaN where not reached).
    refinements : int
        Meshes refined.
    multipliers : numpy.ndarray
        Eigenvalues of the return map's Jacobian, largest modulus first (empty unless
        certified).
    verdict : Verdict or None
        The referee's verdict.
    residual : float
        The largest violation of the rows' bounds at ``w`` (inf where not finite).
    evaluation : object
        The transcription's evaluation at ``w`` (rule 2).
    last_iterations : int
        The last mesh's solver iterations.
    return_map : ReturnMap or None
        The return map's linearisation (rule 5), where certified.
    defect : str
        The certificate's or a pre-check's failure in words ("" where none).
    error_parts : dict
        The named parts of :attr:`error` (an a-posteriori refinement's ``refinement_error``).
    info : object
        The last solve's own record (:attr:`Solved.info`).
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
    residual: float = float("nan")
    evaluation: Any = None
    last_iterations: int = 0
    return_map: Any = None
    defect: str = ""
    error_parts: dict[str, float] = field(default_factory=dict)
    info: Any = None

    @property
    def advice(self) -> str:
        """What :data:`~gaitopt.result.STATUS` says about :attr:`status`."""
        return STATUS[self.status]


def default_solver(method: str) -> Callable[[Any, np.ndarray], Solved]:
    """``solver(transcription, w0)``: Newton on the square system (:mod:`gaitopt.orbit.newton`)
    or IPOPT with the bounds and the objective (:mod:`gaitopt.orbit.ipopt`)."""
    if method not in METHODS:
        raise GaitoptInputError(f"`method` must be one of {', '.join(METHODS)}, got {method!r}")

    def solver(t: Any, w0: np.ndarray) -> Solved:
        if method == "newton":
            r = solve_square(t, w0)
        else:
            from .ipopt import solve_nlp  # here: Newton's solves import no IPOPT wrapper

            r = solve_nlp(t, w0)
        return Solved(r.w, r.converged, r.iterations)

    return solver


def _residual(t: Any, ev: Any) -> tuple[float, bool]:
    """``(residual, finite)``: the largest violation of the rows' bounds (inf where ``F`` is not
    finite) and whether ``F`` and ``F_w`` are finite."""
    b = t.bounds()
    F = np.asarray(ev.F, dtype=float)
    if not np.all(np.isfinite(F)):
        return float("inf"), False
    violation = np.maximum(np.asarray(b.lbg) - F, F - np.asarray(b.ubg))
    F_w = getattr(ev, "F_w", None)
    finite = F_w is None or bool(np.all(np.isfinite(np.asarray(F_w, dtype=float))))
    return float(np.max(violation, initial=0.0)), finite


def refine(
    transcription: Any,
    w0,
    *,
    solver: Callable[[Any, np.ndarray], Solved],
    tol: float,
    max_refinements: int,
    first: Solved | None = None,
) -> OrbitSolution:
    """Stages 1–2: solve from ``w0``; while the discretisation error exceeds ``tol`` (at most
    ``max_refinements`` times, and while the transcription is ``refinable``) refine the mesh and
    re-solve from :meth:`~Transcription.carry`.  A solution is accepted where ``F`` and ``F_w``
    are finite and the rows' bounds hold to ``tol``.  Returns status ``"converged"`` (solved and
    refined) or ``not_converged``, ``singular``, ``discretisation``.

    A transcription with the hook ``refinement_error(w, fine, w_fine)`` (named parts of the
    change between successive meshes' solutions, e.g. an optimum's cost and orbit) is refined a
    posteriori instead: from ``first`` (the initial mesh's solution at ``w0``, already solved),
    each refined mesh is solved and accepted where the solver converged, the error being the
    largest part of the change (inf before any refinement); a refined solve that does not
    converge ends the refinement with the mesh before it.  Status ``"converged"`` or
    ``discretisation`` (the solution and its error carried: the caller may still certify it).
    """
    if hasattr(transcription, "refinement_error"):
        return _refine_a_posteriori(transcription, w0, solver, tol, max_refinements, first)
    t, total, refinements, error = transcription, 0, 0, float("nan")
    while True:
        solved = solver(t, w0)
        w, total = solved.w, total + solved.iterations
        ev = solved.evaluation if solved.evaluation is not None else t.evaluate(w)
        residual, finite = _residual(t, ev)
        common = dict(iterations=total, refinements=refinements, residual=residual,
                      evaluation=ev, last_iterations=solved.iterations)  # fmt: skip
        if not (finite and residual <= tol):
            return OrbitSolution(
                False, "not_converged",
                f"the solver stopped after {solved.iterations} iterations with the rows "
                f"violated by {residual:.3g} (tolerance {tol:g})", t, w, **common,
            )  # fmt: skip
        try:
            error = float(t.error_estimate(w))
        except np.linalg.LinAlgError:
            return OrbitSolution(
                False, "singular", "the orbit's equations are solved but their Jacobian is "
                "singular there: the orbit is not isolated", t, w, **common,
            )  # fmt: skip
        if error <= tol or refinements == max_refinements or not getattr(t, "refinable", True):
            break
        fine = t.refined()
        w0, t = fine.carry(w, t), fine
        refinements += 1
    if not error <= tol:
        return OrbitSolution(
            False, "discretisation",
            f"the discretisation error estimate {error:.2g} stays above {tol:g} after "
            f"{refinements} refinements", t, w, error=error, **common,
        )  # fmt: skip
    return OrbitSolution(False, "converged", "solved and refined (not yet certified)", t, w,
                         error=error, **common)  # fmt: skip


def _refine_a_posteriori(
    t: Any, w0, solver: Callable[[Any, np.ndarray], Solved], tol: float, max_refinements: int,
    first: Solved | None,
) -> OrbitSolution:  # fmt: skip
    """:func:`refine` by the change between successive meshes' solutions."""
    last = first if first is not None else solver(t, w0)
    w, total, refinements = last.w, last.iterations, 0
    if first is None and not last.converged:
        return OrbitSolution(False, "not_converged", "the solver did not converge", t, w, total,
                             last_iterations=last.iterations, info=last.info)  # fmt: skip
    parts: dict[str, float] = {}
    error = float("inf")
    while refinements < max_refinements:
        fine = t.refined()
        solved = solver(fine, fine.carry(w, t))
        if not solved.converged:
            break
        parts = dict(t.refinement_error(w, fine, solved.w))
        error = max(parts.values())
        t, w, last = fine, solved.w, solved
        total += solved.iterations
        refinements += 1
        if error <= tol:
            break
    status = "converged" if error <= tol else "discretisation"
    words = ("solved and refined (not yet certified)" if error <= tol else
             f"the discretisation error {error:.2g} (the change under mesh refinement) stays "
             f"above {tol:g} after {refinements} refinements")  # fmt: skip
    return OrbitSolution(False, status, words, t, w, total, error, refinements,
                         last_iterations=last.iterations, error_parts=parts,
                         info=last.info)  # fmt: skip


def certificate(transcription: Any, w, *, guard_tol: float = 1e-6) -> str | None:
    """Stage 3: the one certificate (:func:`gaitopt.orbit.certify_orbit`) on the
    transcription's dense samples at ``w``, then its own ``consistency`` checks; None if the
    orbit is a gait, else the first failure in words."""
    t = transcription
    p = t.parameters(w) if hasattr(t, "parameters") else t.p
    defect = certify_orbit(
        t.model, t.dense_arcs(w), p, steps=t.steps, guard_tol=guard_tol,
        repeated_advice=getattr(t, "repeated_advice", REPEATED_ADVICE),
    )  # fmt: skip
    if defect is None and hasattr(t, "consistency"):
        defect = t.consistency(w)
    return defect


def judge(
    solution: OrbitSolution,
    *,
    verify: bool = True,
    guard_tol: float = 1e-6,
    referee_tol: float = 1e-6,
    precheck: bool = True,
) -> OrbitSolution:
    """Stages 3–4 on a solved (and refined) orbit: the transcription's ``precheck`` (with
    ``precheck``), the :func:`certificate`, the multipliers (rule 5; ``singular`` where the
    return map cannot be linearised) and, with ``verify``, the referee (rule 8)."""
    s = solution
    t, w = s.transcription, s.w
    keep = dict(iterations=s.iterations, error=s.error, refinements=s.refinements,
                residual=s.residual, evaluation=s.evaluation,
                last_iterations=s.last_iterations)  # fmt: skip
    if precheck and hasattr(t, "precheck"):
        found = t.precheck(w)
        if found is not None:
            status, words = found
            return OrbitSolution(False, status, words, t, w, defect=words, **keep)
    defect = certificate(t, w, guard_tol=guard_tol)
    if defect is not None:
        return OrbitSolution(False, "not_a_gait", "not a gait: " + defect.removeprefix("no gait: "),
                             t, w, defect=defect, **keep)  # fmt: skip
    try:
        return_map = t.return_map_jacobians(w)
    except np.linalg.LinAlgError:
        words = ("the orbit's equations are singular at the solution (the orbit is not "
                 "transversal to a guard, or not isolated)")  # fmt: skip
        return OrbitSolution(False, "singular", words, t, w, defect=words, **keep)
    keep.update(multipliers=sorted_multipliers(np.asarray(return_map.A, dtype=float)),
                return_map=return_map)  # fmt: skip
    if not verify:
        return OrbitSolution(True, "success", "orbit certified (not verified: verify=False)", t,
                             w, **keep)  # fmt: skip
    verdict = t.referee(w, referee_tol)
    if not verdict.ok:
        return OrbitSolution(
            False, "not_verified", "the simulation does not confirm the orbit: "
            + verdict.message, t, w, verdict=verdict, **keep,
        )  # fmt: skip
    return OrbitSolution(True, "success", "orbit certified and verified: " + verdict.message, t,
                         w, verdict=verdict, **keep)  # fmt: skip


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
    solver: Callable[[Any, np.ndarray], Solved] | None = None,
) -> OrbitSolution:
    """Solve → refine → certify → referee, on any transcription (:func:`refine`, then
    :func:`judge`).

    Parameters
    ----------
    transcription : Transcription
        The orbit's transcription (rules of :mod:`gaitopt.orbit.transcription`).
    w0 : numpy.ndarray
        A start (``transcription.columns.size`` unknowns).
    method : {"newton", "ipopt"}, optional
        Default: Newton on a square transcription, IPOPT otherwise (ignored with ``solver``).
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
    solver : callable, optional
        ``solver(transcription, w0) -> Solved``: a front door's own solver (the shooting's
        Newton with its line search); default :func:`default_solver` of ``method``.
    """
    if solver is None:
        solver = default_solver(method or ("newton" if transcription.square else "ipopt"))
    solved = refine(transcription, w0, solver=solver, tol=tol, max_refinements=max_refinements)
    if solved.status != "converged":
        return solved
    return judge(solved, verify=verify, guard_tol=guard_tol, referee_tol=referee_tol)
