"""The methods that solve a :class:`~gaitopt.shooting.problem.ShootingProblem`: Newton on the
square shooting system (:mod:`gaitopt.orbit.newton` on the compiled kernels' Jacobian, or
CasADi's ``rootfinder`` where a model has none) and IPOPT (``nlpsol``) with positive durations
and an optional objective.  The methods for any transcription are :mod:`gaitopt.orbit.newton`
and :mod:`gaitopt.orbit.ipopt`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..orbit import structured
from ..orbit.newton import newton as _orbit_newton
from .pattern import pattern_of
from .symbolic import NEWTON_OPTIONS

__all__ = ["METHODS", "Solution", "compiled_or_python", "newton", "solve"]


class ShootingSystem(Protocol):
    """What the methods use of a :class:`~gaitopt.shooting.problem.ShootingProblem`: that module
    sits above this one (its :meth:`~gaitopt.shooting.problem.ShootingProblem.solve` calls
    :func:`solve`), so the methods name the problem by the members they need."""

    size: int
    model_cls: Any
    newton: ca.Function
    newton_line_search: ca.Function

    def assembly(self) -> Any: ...

    def bounds(self) -> tuple[np.ndarray, np.ndarray]: ...

    def ipopt_solver(self, objective: Any, free_inputs: bool) -> ca.Function: ...


#: The methods :meth:`ShootingProblem.solve` offers.
METHODS = ("newton", "ipopt")


@dataclass(frozen=True)
class Solution:
    """What a method returns: the last point ``w`` and inputs ``u``, whether a stopping test
    passed, the iterations (Jacobians evaluated) and the evaluation at ``w`` (None where the
    method does not have it: IPOPT, CasADi's rootfinder)."""

    w: np.ndarray
    u: np.ndarray
    converged: bool
    iterations: int
    evaluation: Any = None


def solve(problem: ShootingSystem, w0, u, p, *, method="newton", objective=None,
          free_inputs=False) -> Solution:  # fmt: skip
    """Newton (plain, then with line search), or IPOPT with the problem's bounds and an
    optional objective (see :meth:`ShootingProblem.ipopt_solver`)."""
    if method not in METHODS:
        raise GaitoptInputError(f"`method` must be one of {', '.join(METHODS)}, got {method!r}")
    u = np.asarray(u, dtype=float).ravel()
    if method == "newton":
        if objective is not None or free_inputs:
            raise GaitoptInputError(
                "`objective`/`free_inputs` need method='ipopt': Newton solves the square system"
            )
        if problem.assembly() is not None:
            w, converged, iterations, ev = compiled_or_python(problem, w0, u, p)
            if not converged:
                w, converged, more, ev = newton(problem, w0, u, p, line_search=True)
                iterations += more
            return Solution(w, u, converged, iterations, ev)
        w, converged, iterations = _newton(problem.newton, w0, u, p)
        if not converged:
            w, converged, more = _newton(problem.newton_line_search, w0, u, p)
            iterations += more
        return Solution(w, u, converged, iterations)
    lbw, ubw = problem.bounds()
    solver = problem.ipopt_solver(objective, free_inputs)
    if free_inputs:
        box = problem.model_cls.input_bounds
        names = problem.model_cls.inputs
        lbu = np.array([box.get(k, (-np.inf, np.inf))[0] for k in names])
        ubu = np.array([box.get(k, (-np.inf, np.inf))[1] for k in names])
        x0 = np.concatenate([np.asarray(w0, dtype=float).ravel(), u])
        sol = solver(x0=x0, p=p, lbg=0, ubg=0, lbx=np.concatenate([lbw, lbu]),
                     ubx=np.concatenate([ubw, ubu]))  # fmt: skip
    else:
        sol = solver(x0=w0, p=np.concatenate([u, p]), lbg=0, ubg=0, lbx=lbw, ubx=ubw)
    x = np.asarray(sol["x"], dtype=float).ravel()
    stats = solver.stats()
    w, u = (x[: problem.size], x[problem.size :]) if free_inputs else (x, u)
    return Solution(w, u, bool(stats["success"]), int(stats["iter_count"]))


def newton(problem: ShootingSystem, w0, u, p, *, line_search: bool = False):
    """Newton on the compiled shooting system (:func:`gaitopt.orbit.newton.newton`: each
    iteration one compiled call for ``F`` and ``∂F/∂w``, a solve (on the Jacobian's block pattern
    for period-k systems of :data:`gaitopt.orbit.structured.STRUCTURED_MIN_SIZE` unknowns or
    more, :mod:`gaitopt.shooting.pattern`; dense below), and with
    ``line_search`` halving the step until ``‖F‖₂`` decreases).  Stops where
    ``max |F| ≤ 1e-12`` or ``max |step| ≤ 1e-15``; 30 iterations (100 with line search).

    Returns
    -------
    (w, converged, iterations, evaluation) : the last point, whether a stopping test passed,
    the number of Jacobians evaluated and the evaluation at ``w`` (reused by the caller).
    """
    asm = problem.assembly()
    pattern = pattern_of(problem)  # None below the structured solve's size: dense steps
    return _orbit_newton(
        lambda w: asm(w, u, p), w0, line_search=line_search,
        max_iter=NEWTON_OPTIONS["max_iter"], abstol=NEWTON_OPTIONS["abstol"],
        abstol_step=NEWTON_OPTIONS["abstolStep"],
        residual=lambda w: asm(w, u, p, jacobian=False),
        linear_solve=None if pattern is None else lambda J, F: structured.solve(J, F, pattern),
    )  # fmt: skip


def compiled_or_python(problem: ShootingSystem, w0, u, p):
    """Plain Newton (:func:`newton` without line search) in one compiled call
    (:mod:`gaitopt.kernels.newton`) where the system has one and is solved densely (below
    :data:`gaitopt.orbit.structured.STRUCTURED_MIN_SIZE` unknowns), else in Python.  The same
    stopping tests; where the compiled call meets an exactly singular ``∂F/∂w`` (the Python
    Newton's least-squares step) or a kernel fails, the Python Newton runs from ``w0``.

    Returns
    -------
    (w, converged, iterations, evaluation) : as :func:`newton`; a converged compiled solve's
    evaluation carries the return map's Jacobians (``evaluation.return_map``).
    """
    compiled = None
    if problem.size < structured.STRUCTURED_MIN_SIZE:
        compiled = problem.assembly().compiled_newton()
    if compiled is not None:
        code, w, iterations, ev = compiled.solve(
            w0, u, p, max_iter=NEWTON_OPTIONS["max_iter"], abstol=NEWTON_OPTIONS["abstol"],
            abstol_step=NEWTON_OPTIONS["abstolStep"],
        )  # fmt: skip
        if ev is not None:  # converged, or stopped as the Python Newton stops
            from ..kernels.newton import CONVERGED

            return w, code in CONVERGED, iterations, ev
    return newton(problem, w0, u, p)


def _newton(solver: ca.Function, w0, u, p) -> tuple[np.ndarray, bool, int]:
    w = np.asarray(solver(w0, u, p), dtype=float).ravel()
    stats = solver.stats()
    return w, bool(stats["success"]) and bool(np.all(np.isfinite(w))), int(stats["iter_count"])
