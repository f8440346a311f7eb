"""One start of a gait optimisation on a transcription, and the caches behind it: the
transcriptions and their compiled IPOPT solvers by statement and mesh (:func:`_collocation`,
:func:`_solver`), one IPOPT run (:func:`_run`) and :func:`attempt`.  Below
:mod:`gaitopt.optimize.solve` and :mod:`gaitopt.optimize.library`, which both use them."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields
from typing import Any

import casadi as ca
import numpy as np

from ..caching import lru_by_key
from .active import _violation
from .collocation import Arc, Collocation, RadauMesh
from .guess import NoStart, _start_guess
from .nodes import split_solver
from .problem import GaitProblem
from .result import OptimalGait
from .spectral import fill_sensitivities

__all__ = ["attempt"]

_IPOPT = {
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": False,
    "ipopt.tol": 1e-11,
    "ipopt.constr_viol_tol": 1e-11,
    "ipopt.acceptable_tol": 1e-9,
    "ipopt.max_iter": 1000,
    # Adaptive barrier parameter (Nocedal, Wächter & Waltz 2009, "Adaptive barrier update
    # strategies for nonlinear interior methods"): on the five-link biped every one of 8
    # starts converges, in 28–68 iterations, where the monotone rule needs 27–206 and loses 3.
    "ipopt.mu_strategy": "adaptive",
    "error_on_fail": False,
    "expand": True,
    # A trial point where a function is undefined (the five-link biped's section lift takes an
    # arccos) is IPOPT's to reject and back off from; CasADi need not print each one.
    "show_eval_warnings": False,
}
#: Transcriptions kept with their compiled NLPs, by statement and mesh: each holds a compiled NLP
#: of a few MB, so at most this many (gaitopt's one cache rule, :mod:`gaitopt.caching`: the least
#: recently used dropped first).
_CACHED_TRANSCRIPTIONS = 4


def _statement_key(problem: GaitProblem, values: bool = True) -> tuple:
    """Everything a transcription depends on: each field of the statement (the model by class
    and parameter values; a user's cost function by identity, so a new one never hits).  With
    ``values=False``, only whether the period, step length and speed are fixed, not their
    values: they are bounds of the NLP's rows (``max_multiplier``: of a fixed variable), so such
    statements share a compiled NLP."""
    items = []
    for f in fields(problem):
        value = getattr(problem, f.name)
        if f.name == "model":
            value = (type(value), tuple(value.params.items()))
        elif not values and f.name in ("period", "step_length", "speed", "max_multiplier",
                                       "max_roughness"):  # fmt: skip
            value = value is not None
        elif callable(value):
            value = ("callable", id(value))
        elif isinstance(value, Mapping):
            value = tuple(sorted((k, repr(v)) for k, v in value.items()))
        items.append((f.name, value))
    return tuple(items)


def _collocation_key(
    problem: GaitProblem, mesh: RadauMesh, structure: list[list[Arc]] | None = None
) -> tuple:
    return (_statement_key(problem), mesh, repr(structure))


@lru_by_key(_CACHED_TRANSCRIPTIONS, _collocation_key)
def _collocation(
    problem: GaitProblem, mesh: RadauMesh, structure: list[list[Arc]] | None = None
) -> Collocation:
    """The transcription of a statement on a mesh, from a small cache: a repeated solve of the
    same statement (a second call, the points a library revisits) reuses the transcription and
    its compiled NLP (``nlpsol`` takes about 0.25 s to build for the compass gait)."""
    return Collocation(problem, mesh, structure)


def _solver_key(col: Collocation, obj_scale: float | None = None) -> tuple:
    return (_statement_key(col.problem, values=False), col.mesh, repr(col.structure), obj_scale)


@lru_by_key(_CACHED_TRANSCRIPTIONS, _solver_key)
def _solver(col: Collocation, obj_scale: float | None = None) -> ca.Function:
    """IPOPT on the transcription's NLP, built once per NLP structure: transcriptions of
    statements that differ only in the fixed period, step length or speed share it (their values are
    the bounds ``lbg = ubg`` of their rows, passed with each solve).  ``obj_scale``: IPOPT's
    ``obj_scaling_factor`` (default: IPOPT's own, 1)."""
    options = dict(_IPOPT)
    if obj_scale is not None:
        options["ipopt.obj_scaling_factor"] = float(obj_scale)
    if col.node_blocks:  # exact derivatives assembled from the compiled node kernels
        f, g = col.outer
        return split_solver("gait", col._w, col._p, f, g, col.node_blocks, options)
    return ca.nlpsol("gait", "ipopt", col.nlp, options)


#: The caches themselves (``clear()`` empties one).
_COLLOCATIONS = _collocation.cache
_SOLVERS = _solver.cache


def _run(
    col: Collocation, w0: np.ndarray, p: np.ndarray, obj_scale: float | None = None
) -> tuple[np.ndarray, dict[str, Any]]:
    solver = _solver(col, obj_scale)
    w0 = fill_sensitivities(col, np.clip(w0, col.lbx, col.ubx), p)  # ρ(A) ≤ R's unknowns
    sol = solver(x0=w0, p=p, lbx=col.lbx, ubx=col.ubx, lbg=col.lbg, ubg=col.ubg)
    return np.asarray(sol["x"], dtype=float).ravel(), dict(solver.stats())


def _converged(stats: dict[str, Any]) -> bool:
    return bool(stats.get("success")) or stats.get("return_status") == "Solved_To_Acceptable_Level"


def attempt(
    col: Collocation, problem: GaitProblem, start: int, seed: int, guess: OptimalGait | None
) -> dict[str, Any]:
    """One start of the multi-start on the initial mesh: ``{"start", "w", "stats", "ok",
    "status", "reason"}`` and ``cost``, ``s``, ``period`` if IPOPT converged, else
    ``violation`` (worst group, size).

    A start that cannot begin (:class:`~gaitopt.optimize.guess.NoStart`: its perturbed section
    point is not a state of the model) is returned as such, ``status`` ``"no_start"``, with
    ``w`` all NaN and no violation, never raised: one start does not end a multi-start.
    """
    p = problem.model.p
    try:
        w0 = _start_guess(col, problem, start, seed, guess)
    except NoStart as exc:
        return {
            "start": start,
            "w": np.full(np.size(col.lbx), np.nan),
            "stats": {},
            "ok": False,
            "status": "no_start",
            "reason": f"start {start} could not begin: {exc}",
            "violation": ("no start", float("inf")),
        }
    w, stats = _run(col, w0, p)
    ok = bool(_converged(stats) and np.all(np.isfinite(w)))
    entry: dict[str, Any] = {"start": start, "w": w, "stats": stats, "ok": ok}
    if ok:
        sol = col.unpack(w, p)
        entry.update(cost=sol["cost"], s=sol["s"], period=sol["period"], status="converged")
        entry["reason"] = f"start {start} converged (cost {sol['cost']:.10g} on the starts' mesh)"
    else:
        name, size = entry["violation"] = _violation(col, w, p)
        entry["status"] = "not_converged"
        entry["reason"] = (
            f"start {start} did not converge: IPOPT stopped ({stats.get('return_status')}) with "
            f"the constraint '{name}' violated by {size:.3g}"
        )
    return entry
