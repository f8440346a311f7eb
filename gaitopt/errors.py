"""Exceptions for bad input.

Bad input is an exception that names the argument, shows the value and suggests a fix; a solver
that does not converge is *data* (``success=False`` on its result), never an exception.
All input errors subclass :class:`ValueError` (as python-control's ``ControlDimension`` does), so
``except ValueError`` keeps working for callers who do not care about the distinction.
"""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Iterable

__all__ = [
    "GaitoptInputError",
    "UnknownModelError",
    "ParameterError",
    "StateError",
    "GuessError",
    "FrozenModelError",
    "did_you_mean",
    "MAX_ORBIT_STEPS",
    "MAX_SIMULATION_STEPS",
]

#: Largest number of returns to the section per periodic orbit (``steps`` of
#: :func:`gaitopt.find_limit_cycle`, ``--steps`` of ``solve`` and ``continue``, ``--max-period``).
#: The shooting system grows with the period: a period-64 kneed-walker orbit already takes about
#: 10 s and 0.5 GB to build and solve on one core, and the cost grows faster than linearly (a
#: period-1000 request ran for minutes and took 14 GB).  Period doubling cascades are resolved
#: far below this (the compass gait's chaos sets in by period 16).
MAX_ORBIT_STEPS = 64

#: Largest number of steps of one simulation (``steps`` of :func:`gaitopt.simulate`,
#: ``--steps`` of ``simulate``): about 40 s and 0.3 GB for the compass gait (4 ms and 20 kB a
#: step, every arc's dense output kept).  Simulate longer runs in pieces, each starting from the
#: last state of the one before.
MAX_SIMULATION_STEPS = 10_000


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """``"did you mean 'x'? "`` (or ``'x' or 'y'``) for the choices closest to ``word``, or ``""``.

    Whole names are compared first, then their ``_``-separated parts, so that ``walkr`` finds
    both ``simplest_walker`` and ``kneed_walker``.
    """
    word, choices = str(word), [str(c) for c in choices]
    close = difflib.get_close_matches(word, choices, n=2)
    if not close:
        matches = difflib.get_close_matches(
            word, {p for c in choices for p in c.split("_")}, n=1, cutoff=0.75
        )
        close = [c for c in choices if matches and matches[0] in c.split("_")]
    return f"did you mean {' or '.join(repr(c) for c in close)}? " if close else ""


class GaitoptInputError(ValueError):
    """Base class of every bad-input error; the CLI prints it on one line and exits with 2."""


class UnknownModelError(GaitoptInputError):
    """A model name that is not registered."""


class ParameterError(GaitoptInputError):
    """An unknown parameter, a non-number, or a value outside the parameter's range."""


class StateError(GaitoptInputError):
    """An unknown state name or a non-finite state value."""


class GuessError(GaitoptInputError):
    """An initial guess from which the model never reaches its next transition."""


class ModelDefinitionError(TypeError):
    """A model class whose hybrid structure is inconsistent (found once, when its structure is
    first built): a cycle transition that does not enter the next phase, a reset or section lift
    of the wrong dimension, a section lift that moves its own coordinates.  A defect of the
    model's code, not of a user's input."""


class FrozenModelError(dataclasses.FrozenInstanceError):
    """Assigning to a model's attribute: models are immutable (their functions are shared); the
    message says how to make a model with another parameter value."""
