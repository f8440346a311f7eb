"""Newton on a square transcription: one call for the residual and its Jacobian per iteration
(rule 2 of :mod:`gaitopt.orbit.transcription`), a dense solve, and optionally a backtracking line
search.  :func:`gaitopt.shooting.newton.newton` runs this on the shooting's compiled kernels;
:func:`solve_square` runs it on any :class:`~gaitopt.orbit.transcription.Transcription`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import GaitoptInputError

__all__ = ["ABSTOL", "ABSTOL_STEP", "MAX_ITER", "NewtonResult", "newton", "solve_square"]

#: Newton's stopping tests (CasADi ``rootfinder`` "newton"'s options ``abstol``, ``abstolStep``,
#: ``max_iter`` as gaitopt sets them): the largest residual, the largest step, the iterations.
ABSTOL, ABSTOL_STEP, MAX_ITER = 1e-12, 1e-15, 30
#: Iterations with the line search.
MAX_ITER_LINE_SEARCH = 100


@dataclass(frozen=True)
class NewtonResult:
    """The last point ``w``, whether a stopping test passed, the number of Jacobians evaluated
    and the evaluation at ``w`` (reused by the caller)."""

    w: np.ndarray
    converged: bool
    iterations: int
    evaluation: Any


def newton(
    evaluate: Callable[[np.ndarray], Any],
    w0,
    *,
    line_search: bool = False,
    max_iter: int = MAX_ITER,
    abstol: float = ABSTOL,
    abstol_step: float = ABSTOL_STEP,
    residual: Callable[[np.ndarray], Any] | None = None,
    linear_solve: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
) -> tuple[np.ndarray, bool, int, Any]:
    """Newton on ``F(w) = 0``: each iteration one call ``evaluate(w)`` (with ``F`` and ``F_w``),
    a dense solve (least squares where ``F_w`` is exactly singular) and, with ``line_search``,
    halving the step until ``‖F‖₂`` decreases.  Stops where ``max |F| ≤ abstol`` or
    ``max |step| ≤ abstol_step``; ``max_iter`` iterations (100 with the line search).

    ``residual(w)``, where given, evaluates ``F`` alone (the same numbers as ``evaluate(w).F``)
    for the line search's trial points; the accepted one is then evaluated by ``evaluate``.
    Near a local minimum of ``‖F‖₂`` (no orbit) each iteration halves the step ~14 times, and
    those trials need no Jacobian.

    ``linear_solve(F_w, F)``, where given, solves for the step instead of
    :func:`numpy.linalg.solve` (the shooting's structured solve for period-k orbits,
    :mod:`gaitopt.orbit.structured`); it raises :class:`numpy.linalg.LinAlgError` likewise.

    Returns
    -------
    (w, converged, iterations, evaluation) : the last point, whether a stopping test passed,
    the number of Jacobians evaluated and the evaluation at ``w``.
    """
    max_iter = MAX_ITER_LINE_SEARCH if line_search else max_iter
    w = np.array(w0, dtype=float).ravel()
    ev = None
    for iteration in range(1, max_iter + 1):
        ev = ev if ev is not None else evaluate(w)
        F = ev.F
        if not (np.all(np.isfinite(F)) and np.all(np.isfinite(ev.F_w))):
            return w, False, iteration, ev
        if float(np.max(np.abs(F))) <= abstol:
            return w, True, iteration, ev
        try:
            step = (linear_solve or np.linalg.solve)(ev.F_w, F)
        except np.linalg.LinAlgError:  # exactly singular (a family of orbits): least squares
            step = np.linalg.lstsq(ev.F_w, F, rcond=None)[0]
        if float(np.max(np.abs(step))) <= abstol_step:
            return w, True, iteration, ev
        if not line_search:
            w, ev = w - step, None
            continue
        norm, alpha = float(F @ F), 1.0
        while True:
            trial = (residual or evaluate)(w - alpha * step)
            if (np.all(np.isfinite(trial.F)) and float(trial.F @ trial.F) < norm) or alpha < 1e-4:
                break
            alpha /= 2
        w = w - alpha * step
        ev = trial if residual is None else None  # None: evaluated with F_w at the next iteration
    return w, False, max_iter, ev if ev is not None else evaluate(w)


def solve_square(transcription: Any, w0, *, u=None, p=None) -> NewtonResult:
    """Newton (plain, then with line search) on a square
    :class:`~gaitopt.orbit.transcription.Transcription` (every row an equation, as many as
    unknowns); raises :class:`~gaitopt.errors.GaitoptInputError` for one that is not square."""
    if not transcription.square:
        raise GaitoptInputError(
            f"Newton needs a square transcription, got {transcription.rows.size} rows for "
            f"{transcription.columns.size} unknowns: use method='ipopt'"
        )

    def evaluate(w):
        return transcription.evaluate(w, u, p)

    w, converged, iterations, ev = newton(evaluate, w0)
    if not converged:
        w, converged, more, ev = newton(evaluate, w0, line_search=True)
        iterations += more
    return NewtonResult(w, converged, iterations, ev)
