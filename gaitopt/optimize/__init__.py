"""Optimal gait synthesis: actuated gaits that minimise effort, positive work or cost of transport.

* :mod:`~gaitopt.optimize.problem` — the statement (cost, fixed/free period, step length, speed,
  bounds, free parameters);
* :mod:`~gaitopt.optimize.collocation` — its Legendre–Gauss–Radau transcription (with
  ``collocation_rows``, ``collocation_cost``, ``collocation_limits``, ``collocation_kernels``),
  and :mod:`~gaitopt.optimize.transcription` — the same as a
  :class:`gaitopt.orbit.Transcription` (:class:`CollocationTranscription`);
* :mod:`~gaitopt.optimize.solve` — IPOPT with exact derivatives, multi-start, mesh refinement;
* :mod:`~gaitopt.optimize.verify`, :mod:`~gaitopt.optimize.certify` and
  :mod:`~gaitopt.optimize.floquet` — trust: the common certificate and referee of
  :mod:`gaitopt.orbit` on the collocation polynomials and the input profile, multipliers two
  ways;
* :mod:`~gaitopt.optimize.result` — :class:`OptimalGait` (with every distinct minimum of a
  multi-start, :class:`Minimum`, and every start's outcome, :class:`StartRecord`);
* :mod:`~gaitopt.optimize.guess` — the starts, and :class:`WarmStartError` for a ``guess`` that
  cannot warm start;
* :mod:`~gaitopt.optimize.stabilisation` — :func:`stabilise`: a per-step input offset (LQR)
  that stabilises an unstable optimum, checked in simulation;
* :mod:`~gaitopt.optimize.library` — libraries of optima continued in a constraint (folds,
  active-set changes, cold-start checks) and multi-starts on Dask.
"""

from __future__ import annotations

from typing import Any

from .collocation import Arc, Collocation, RadauMesh
from .guess import WarmStartError
from .problem import COSTS, GaitProblem
from .profile import InputProfile
from .result import Minimum, OptimalGait, StartRecord
from .solve import optimize_gait, solve_problem
from .transcription import CollocationTranscription

#: Bound on first use (PEP 562): an optimisation needs neither subpackage.
_LAZY = {
    "GaitLibrary": ".library",
    "gait_library": ".library",
    "Stabilisation": ".stabilisation",
    "stabilise": ".stabilisation",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        from importlib import import_module

        value = getattr(import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "optimize_gait",
    "solve_problem",
    "GaitProblem",
    "Collocation",
    "CollocationTranscription",
    "RadauMesh",
    "Arc",
    "InputProfile",
    "OptimalGait",
    "Minimum",
    "StartRecord",
    "WarmStartError",
    "COSTS",
    "stabilise",
    "Stabilisation",
    "gait_library",
    "GaitLibrary",
]
