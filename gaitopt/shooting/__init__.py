"""Limit cycles of hybrid models by multiple shooting, solved with CasADi.

The problem and the methods are separate modules:

* :mod:`~gaitopt.shooting.problem` — :class:`MultipleShooting` (the discretisation) and
  :class:`ShootingProblem` (unknowns, residual, Jacobians, bounds, objective slot, and the map
  back to phases and orbits);
* :mod:`~gaitopt.shooting.newton` — Newton and IPOPT on a problem (Newton itself is
  :mod:`gaitopt.orbit.newton`'s);
* :mod:`~gaitopt.shooting.transcription` — the problem as a :class:`gaitopt.orbit.Transcription`
  (:class:`ShootingTranscription`: bound to a model's parameters and an input);
* :mod:`~gaitopt.shooting.certify` — the checks that make a solution a gait (the common
  certificate of :mod:`gaitopt.orbit` on the RK samples), and its multipliers;
* :mod:`~gaitopt.shooting.verify` — the independent simulation (the common referee);
* :mod:`~gaitopt.shooting.gait` — the direct solve from a guess (:func:`solve_gait` on the
  unknowns), below the homotopy and multi-start of :mod:`gaitopt.homotopy`.

:func:`find_limit_cycle`, which chooses among them, and :func:`solve_task`, its sweep task, live
above this package in :mod:`gaitopt.search`; they are re-exported here for the older import path,
imported on first use (PEP 562): :mod:`gaitopt.search` imports :mod:`gaitopt.shooting.gait`, so an
eager import here would make ``import gaitopt.search`` in a fresh process find this package
half-initialised.
"""

from .certify import certify, check_constraints
from .gait import solve_gait
from .newton import METHODS, Solution
from .problem import MultipleShooting, ShootingProblem, shooting_problem
from .transcription import ShootingTranscription
from .verify import verify_by_simulation

__all__ = [
    "METHODS",
    "MultipleShooting",
    "ShootingProblem",
    "ShootingTranscription",
    "Solution",
    "certify",
    "check_constraints",
    "find_limit_cycle",
    "shooting_problem",
    "solve_gait",
    "solve_task",
    "verify_by_simulation",
]


def __getattr__(name: str):
    if name in ("find_limit_cycle", "solve_task"):
        from .. import search

        value = getattr(search, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
