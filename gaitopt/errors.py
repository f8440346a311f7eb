"""Exceptions for bad input.

Bad input is an exception that names the argument, shows the value and suggests a fix; a solver
that does not converge is *data* (``success=False`` on its result), never an exception.
All input errors subclass :class:`ValueError` (as python-control's ``ControlDimension`` does), so
``except ValueError`` keeps working for callers who do not care about the distinction.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = [
    "GaitoptInputError",
    "UnknownModelError",
    "ParameterError",
    "StateError",
    "GuessError",
    "did_you_mean",
]


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """``"did you mean 'x'? "`` (or ``'x' or 'y'``) for the choices closest to ``word``, or ``""``.

    Whole names are compared first, then their ``_``-separated parts, so that ``walkr`` finds
    both ``simplest_walker`` and ``kneed_walker``.
    """
    choices = list(choices)
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
