"""Gait libraries: an optimum continued in a constraint, with its folds and active-set changes.

:func:`gait_library` solves :func:`gaitopt.optimize_gait` at a sequence of values of one
quantity — the period, step length or speed a gait is held to, or a model parameter such as the
slope — each point warm started from its neighbour's optimum (natural-parameter continuation of
the optimum).  Between neighbours it compares:

* the **active sets** (:attr:`OptimalGait.active_constraints`: the input and state bounds and
  inequality constraints within 1e-6 of their limits); where they differ, the value at which the
  set changes is located by bisection (warm started from the side already known);
* the **reduced Hessian** of the Lagrangian on the active constraints' null space (second-order
  sufficient condition, Nocedal & Wright 2006, Thm 12.6): its smallest eigenvalue, relative to the
  largest, is positive at a strict local minimum and falls to zero where the KKT matrix becomes
  singular — a fold, where the minimum meets a saddle and the library cannot continue.  A
  sign change between neighbours, or a warm start that stops converging after a point whose
  reduced Hessian is near singular, is reported as a fold; a warm start that stops converging
  otherwise ends the library (``end``, with the solver's reason); either boundary is located by
  bisection.

The library is checked against cold starts (the model's default start, no warm start) at a few
points: the same optimal cost to ``1e-8`` relative, else the library has followed another local
minimum and says so.  The cold starts, and the starts of a multi-start
(:func:`~gaitopt.optimize.starts.mapped_starts`, ``optimize_gait(..., workers=...)``), can run
in other processes by any map (``workers=``: a process pool, a caller's map, or Dask through
``scheduler=``; :mod:`gaitopt.workers`): each worker rebuilds the problem from plain data
(registered model and parameters) and returns plain data.

Modules: :mod:`~gaitopt.optimize.library.records` (the quantities a library can vary, its points,
events and cold-start checks, and their JSON), :mod:`~gaitopt.optimize.library.walk` (the walk
along the values: :func:`gait_library`), :mod:`~gaitopt.optimize.library.events` (the reduced
Hessian, and active-set changes, folds and ends located by bisection),
:mod:`~gaitopt.optimize.library.cold` (the cold-start checks) and
:mod:`~gaitopt.optimize.library.workers` (problems as plain data, the tasks and multi-starts);
:mod:`~gaitopt.optimize.library.both_ends` (:func:`library_both_ends`: cold starts and chains
from both ends, the lowest certified optimum per value, different local minima flagged).
"""

from .both_ends import disagreement, library_both_ends, lowest, seed_of
from .events import reduced_hessian
from .records import CONSTRAINTS, ColdCheck, GaitLibrary, LibraryEvent, LibraryPoint
from .walk import gait_library
from .workers import cold_task, dask_starts, start_task

__all__ = [
    "gait_library",
    "library_both_ends",
    "lowest",
    "seed_of",
    "disagreement",
    "GaitLibrary",
    "LibraryPoint",
    "LibraryEvent",
    "ColdCheck",
    "reduced_hessian",
    "dask_starts",
    "CONSTRAINTS",
    "cold_task",
    "start_task",
]
