"""Exceptions for bad input.

Bad input is an exception that names the argument, shows the value and suggests a fix; a solver
that does not converge is *data* (``success=False`` on its result), never an exception.
All input errors subclass :class:`ValueError` (as python-control's ``ControlDimension`` does), so
``except ValueError`` keeps working for callers who do not care about the distinction.
"""

from __future__ import annotations

__all__ = ["GaitoptInputError", "UnknownModelError", "ParameterError", "StateError", "GuessError"]


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
