"""The last stages of one optimum (:func:`finish`): from the starts' mesh to a certified
optimal gait — the exact-work or bound-arc stage (arcs with free junction times), mesh
refinement through the one sequence's refine stage (:func:`gaitopt.orbit.solve.refine`) until
the cost and the orbit settle below ``tol``, the retries where an exact-work refinement does not
settle (guard touch points as junctions, collapsed last arcs continued, the objective scaled),
and the certificate and referee (:func:`gaitopt.optimize.certify._certify`)."""

from __future__ import annotations

import itertools
import time
from functools import partial
from typing import Any

import numpy as np

from ..orbit import solve as sequence
from .arcs import _describe, describe_bounds, detect_bound_arcs, detect_structure, structure_of
from .attempt import (
    _collocation,
    _converged,
    _run,
)
from .boundary_arcs import held_on_guard
from .certify import _certify
from .collapsed import move_collapsed_arcs, warm_start
from .collocation import Collocation, RadauMesh
from .mesh import OptimumTranscription, first_solution, ipopt_solver
from .problem import GaitProblem
from .result import OptimalGait
from .spectral_certify import certify_spectral
from .state_arcs import clearance_functions, detect_touches, guard_touch_structure

__all__ = ["finish"]

#: Mesh doublings at most before an optimum is reported with its discretisation error.
_MAX_REFINEMENTS = 3


def finish(
    problem: GaitProblem,
    col: Collocation,
    w: np.ndarray,
    stats: dict[str, Any],
    tol: float,
    verify: bool,
    guess: OptimalGait | None,
    common: dict[str, Any],
    t_start: float,
) -> OptimalGait:
    """One minimum from the starts' mesh to a certified optimum: the exact work stage (work
    costs), mesh doubling until cost and orbit settle below ``tol``, the checks."""
    p = problem.model.p
    structure_note = ""
    if problem.cost_kind in ("work", "cot"):
        # Second stage: the exact switching-time transcription with the arcs of the slack
        # solution (its quadrature of max(0, uω) is first order across the switches).
        # The arcs are read off the slack solution on a mesh twice as fine (on the coarse one
        # a short bang arc spans a node or two, caught between its bound and zero).
        slack_fine = _collocation(problem, col.mesh.refined())
        w_slack, stats_slack = _run(slack_fine, slack_fine.from_solution(col, w, p), p)
        if _converged(stats_slack):
            col, w = slack_fine, w_slack
        # Held arcs on a guard (the kneed walker's knee held straight) are boundary arcs.
        structure = held_on_guard(col, w, p, detect_structure(col, w, p))
        exact = _collocation(
            problem,
            RadauMesh(sum(a.intervals for a in structure[0]), col.d),
            structure,
        )
        w_exact, stats_exact = _run(exact, exact.from_solution(col, w, p), p)
        previous = structure_of(*(getattr(guess, "transcription", None) or (None, None)))
        if (
            not _converged(stats_exact)
            and previous
            and len(previous) == len(col.chain)
            and _describe(previous) != _describe(structure)
        ):
            # A neighbour's arcs (a library's previous optimum), from this slack solution.
            alt = _collocation(
                problem, RadauMesh(sum(a.intervals for a in previous[0]), col.d), previous
            )
            w_alt, stats_alt = _run(alt, alt.from_solution(col, w, p), p)
            if _converged(stats_alt):
                structure, exact, w_exact, stats_exact = previous, alt, w_alt, stats_alt
        if not _converged(stats_exact):
            return OptimalGait(
                False,
                f"the exact positive-work transcription (arcs {_describe(structure)}) did not "
                f"converge from the slack solution ({stats_exact.get('return_status')}); try "
                f"more starts or other bounds",
                status="not_converged",
                solve_time=time.perf_counter() - t_start,
                **common,
            )
        col, w, stats = exact, w_exact, stats_exact
        structure_note = f"; arcs of the power signs {_describe(structure)}"
        if problem.clearance:
            # A swing foot's height touching its clearance margin inside a phase is a kink no
            # mesh interval follows: made a junction before the refinement.
            col, w, stats, structure_note = _clearance_touches(
                problem, col, w, stats, structure_note
            )
    elif (structure := _arcs_without_powers(col, w, p)) is not None:
        # An active input bound: arcs with the input at its bound and free junction times
        # (the kink where it meets the bound is no longer inside a mesh interval); a touch
        # point of a state bound or limit: a junction with ċ = 0 there (state_arcs).
        arcs = _describe_arcs(structure, problem.model.inputs)
        exact = _collocation(problem, RadauMesh(sum(a.intervals for a in structure[0]), col.d),
                             structure)  # fmt: skip
        w_exact, stats_exact = _run(exact, exact.from_solution(col, w, p), p)
        if _converged(stats_exact):
            col, w, stats = exact, w_exact, stats_exact
            structure_note = f"; {arcs}"
        else:
            structure_note = (
                f"; the {arcs} did not converge "
                f"({stats_exact.get('return_status')}): refined without them"
            )
    coarse = (col, w)
    col, w, stats, cost_error, orbit_error, refinements = _refine(col, w, stats, tol)
    disc_error = max(cost_error, orbit_error)
    if problem.cost_kind in ("work", "cot") and not disc_error <= tol:
        # An exact-work optimum whose refinement did not settle: a guard touched inside its
        # phase is a kink no mesh interval follows (made a junction: guard_touch_structure); a
        # last arc collapsed against a phase change is a jump the continuous inputs forbid
        # there (continued into the next phase: collapsed.move_collapsed_arcs).  A new
        # structure is kept only if its refinement settles further.
        # First of all the same arcs with the objective scaled to about 1 (IPOPT's
        # obj_scaling_factor): a cost of transport of 0.01 leaves a direction along which the
        # cost is nearly flat pinned by IPOPT's tolerance only to ~1e-7 of the orbit.
        scale = 1.0 / max(abs(coarse[0].unpack(coarse[1], p)["cost"]), 1e-6)
        scale = scale if scale > 2.0 else None
        tries = _retry_structures(problem, coarse[0], coarse[1], col, w, p)
        if scale is not None:
            tries = itertools.chain([(coarse[0], coarse[1], structure_note)], tries)
        for cut, w_start, note in tries:
            w_cut, stats_cut = _run(cut, w_start, p, scale)
            if not _converged(stats_cut):
                continue
            again = _refine(cut, w_cut, stats_cut, tol, scale)
            if max(again[3], again[4]) < disc_error:
                col, w, stats, cost_error, orbit_error, refinements = again
                disc_error = max(cost_error, orbit_error)
                structure_note = note
            if disc_error <= tol:
                break
    result = _certify(problem, col, w, stats, verify=verify)
    col.certify_limits(w, result)  # state bounds and path constraints: dense check, where active
    # The final transcription and its solution (the stabilising design differentiates it).
    result.transcription = (col, w)
    result.discretisation_error = disc_error if np.isfinite(disc_error) else None
    result.discretisation = {
        "intervals": col.N,
        "degree": col.d,
        "cost_error": cost_error if np.isfinite(cost_error) else None,
        "orbit_error": orbit_error if np.isfinite(orbit_error) else None,
    }
    result.message += structure_note
    if result.success and not disc_error <= tol:
        # Never a gait known less well than promised: the refinement did not reach ``tol``.
        result.success, result.stable, result.status = False, None, "discretisation"
        result.message = (
            f"no certified optimum: the discretisation error {disc_error:.2g} (cost and orbit "
            f"under mesh refinement) stays above the target {tol:g} after {refinements} "
            f"refinements; the optimum is known only to about that (cost {result.cost:.10g}). "
            f"Loosen `tol` to accept it, or bound the inputs so the optimum is smoother. "
            + result.message
        )
    certify_spectral(col, w, result)  # ρ(A) ≤ R by AD and by finite differences, where asked
    return result


def _clearance_touches(
    problem: GaitProblem, col: Collocation, w: np.ndarray, stats: dict[str, Any], note: str
) -> tuple[Collocation, np.ndarray, dict[str, Any], str]:
    """The exact-work transcription ``col`` (``w``) cut at the interior touch points of its
    clearance margins (:func:`~gaitopt.optimize.state_arcs.clearance_functions`: the kneed
    walker's swing foot at mid-swing, with ``clearance=0.01``), the touches junctions with
    ``ḣ`` equal to the margin's rate there, if it has any and the cut solves; else as given."""
    p = problem.model.p
    cut = detect_touches(col, w, p, col.structure, functions=clearance_functions)
    if cut is None:
        return col, w, stats, note
    touched = _collocation(problem, RadauMesh(sum(a.intervals for a in cut[0]), col.d), cut)
    w_cut, stats_cut = _run(touched, touched.from_solution(col, w, p), p)
    if not _converged(stats_cut):
        return col, w, stats, note
    names = dict.fromkeys(n for arcs in cut for a in arcs for n in a.touches)
    return (
        touched,
        w_cut,
        stats_cut,
        (
            f"; arcs of the power signs {_describe(cut)}; touch points of {', '.join(names)} "
            f"made junctions"
        ),
    )


def _arcs_without_powers(col: Collocation, w: np.ndarray, p: np.ndarray) -> Any:
    """The arcs of a first solution of a cost without powers: those of its active input bounds
    (:func:`~gaitopt.optimize.arcs.detect_bound_arcs`), cut at the interior touch points of its
    state bounds and limits (:func:`~gaitopt.optimize.state_arcs.detect_touches`); None if it
    has neither."""
    bounds = detect_bound_arcs(col, w, p)
    limited = bool(col.limit_groups or col.problem.state_bounds)
    touched = detect_touches(col, w, p, bounds) if limited else None
    return touched if touched is not None else bounds


def _describe_arcs(structure: list, inputs: tuple[str, ...]) -> str:
    """``arcs of the input bounds [lo free lo]`` and/or ``touch points of … made junctions``."""
    words = []
    if any(any(a.bounds) for arcs in structure for a in arcs):
        words.append(f"arcs of the input bounds {describe_bounds(structure, inputs)}")
    touches = list(dict.fromkeys(n for arcs in structure for a in arcs for n in a.touches))
    if touches:
        words.append(f"touch points of {', '.join(touches)} made junctions")
    return "; ".join(words)


def _retry_structures(
    problem: GaitProblem,
    coarse: Collocation,
    w_coarse: np.ndarray,
    fine: Collocation,
    w_fine: np.ndarray,
    p: np.ndarray,
) -> Any:
    """Transcriptions to try where an exact-work refinement did not settle, with warm starts
    and the structure note: the guards' touch points made junctions (read off the coarse
    solution, else the finest), then collapsed last arcs continued into the next phase."""
    for col, w in ((coarse, w_coarse), (fine, w_fine)):
        touched = guard_touch_structure(col, w, p)
        if touched is not None:
            names = dict.fromkeys(n for arcs in touched for a in arcs for n in a.touches)
            cut = _collocation(problem, RadauMesh(sum(a.intervals for a in touched[0]), col.d),
                               touched)  # fmt: skip
            yield (
                cut,
                cut.from_solution(col, w, p),
                (
                    f"; arcs of the power signs {_describe(touched)}; touch points of "
                    f"{', '.join(names)} made junctions"
                ),
            )
            break
    moved = move_collapsed_arcs(coarse, w_coarse)
    if moved is not None:
        cut = _collocation(problem, RadauMesh(sum(a.intervals for a in moved[0]), coarse.d),
                           moved)  # fmt: skip
        yield (
            cut,
            warm_start(cut, coarse, w_coarse, p),
            (
                f"; arcs of the power signs {_describe(moved)} (a last arc collapsed against the "
                f"phase change continued into the next phase)"
            ),
        )


def _refine(
    col: Collocation,
    w: np.ndarray,
    stats: dict[str, Any],
    tol: float,
    obj_scale: float | None = None,
) -> tuple[Collocation, np.ndarray, dict[str, Any], float, float, int]:
    """The one sequence's refine stage (:func:`gaitopt.orbit.solve.refine`), a posteriori: the
    mesh doubled (warm started) from ``col``'s solution ``w`` until the cost and the orbit
    change by at most ``tol`` (relative) or :data:`_MAX_REFINEMENTS` doublings are done.
    Returns the finest converged transcription, its solution and statistics, the last cost and
    orbit changes (inf if no refinement converged) and the number of doublings (``obj_scale``:
    IPOPT's objective scaling factor, default its own)."""
    refinement = sequence.refine(
        OptimumTranscription(col), w, solver=partial(ipopt_solver, obj_scale=obj_scale), tol=tol,
        max_refinements=_MAX_REFINEMENTS, first=first_solution(w, stats),
    )  # fmt: skip
    return (
        refinement.transcription.col,
        refinement.w,
        refinement.info,
        refinement.error_parts.get("cost", float("inf")),
        refinement.error_parts.get("orbit", float("inf")),
        refinement.refinements,
    )
