"""An optimum's mesh refinement as the one sequence's refine stage
(:func:`gaitopt.orbit.solve.refine`): :class:`OptimumTranscription` is the collocation
transcription of :func:`gaitopt.optimize_gait` — its refined meshes from the compiled-NLP cache
(:func:`gaitopt.optimize.attempt._collocation`), its error the change of the cost and the orbit
between successive meshes' optima (the a-posteriori hook ``refinement_error``) — and
:func:`ipopt_solver` its solver (IPOPT with the compiled node kernels' derivatives)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..orbit.solve import Solved
from .attempt import _collocation, _converged, _run
from .collocation import Collocation
from .transcription import CollocationTranscription

__all__ = ["OptimumTranscription", "ipopt_solver", "refined"]


def refined(col: Collocation) -> Collocation:
    """The same transcription with every mesh interval halved (each arc's too), from the
    cache."""
    if col.structure is None:
        return _collocation(col.problem, col.mesh.refined())
    structure = [[replace(a, intervals=2 * a.intervals) for a in arcs] for arcs in col.structure]
    return _collocation(col.problem, col.mesh.refined(), structure)


class OptimumTranscription(CollocationTranscription):
    """The optimiser's view of a :class:`Collocation` (``col``): refined through the cache, its
    discretisation error the change of the optimum under refinement."""

    def __init__(self, col: Collocation):
        super().__init__(col=col)

    def refined(self) -> OptimumTranscription:
        """Twice the intervals per phase (each arc's too), the compiled NLP from the cache."""
        return OptimumTranscription(refined(self.col))

    def refinement_error(self, w, fine: OptimumTranscription, w_fine) -> dict[str, float]:
        """``{"cost": …, "orbit": …}``: the relative change of the cost (relative to the fine
        cost, absolute below 1e-8) and of the orbit (the section point relative to ``1 + max
        |s|``, the period relative to itself) from this mesh's optimum ``w`` to ``fine``'s
        ``w_fine``."""
        sol = self.col.unpack(w, self.p)
        sol_fine = fine.col.unpack(w_fine, fine.p)
        scale = abs(sol_fine["cost"])
        cost_error = abs(sol_fine["cost"] - sol["cost"]) / (scale if scale > 1e-8 else 1.0)
        orbit_error = float(
            max(
                np.max(np.abs(sol_fine["s"] - sol["s"])) / (1 + np.max(np.abs(sol_fine["s"]))),
                abs(sol_fine["period"] - sol["period"]) / sol_fine["period"],
            )
        )
        return {"cost": cost_error, "orbit": orbit_error}


def ipopt_solver(t: OptimumTranscription, w0: np.ndarray, obj_scale: float | None = None) -> Solved:
    """One IPOPT run on ``t``'s NLP from ``w0`` (:func:`gaitopt.optimize.attempt._run`):
    converged where IPOPT solved to its tolerance or an acceptable level; ``info`` its stats.
    ``obj_scale``: IPOPT's ``obj_scaling_factor`` (default: its own)."""
    w, stats = _run(t.col, w0, t.p, obj_scale)
    return Solved(w, _converged(stats), int(stats.get("iter_count", 0)), info=stats)


def first_solution(w: np.ndarray, stats: dict[str, Any]) -> Solved:
    """A solution in hand (a multi-start's minimum, an arcs stage's optimum) as the
    :func:`~gaitopt.orbit.solve.refine` stage's ``first``."""
    return Solved(w, _converged(stats), int(stats.get("iter_count", 0)), info=stats)
