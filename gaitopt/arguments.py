"""Checks of the library's arguments, shared by :func:`gaitopt.find_limit_cycle` and
:func:`gaitopt.simulate`: each raises a :class:`~gaitopt.errors.GaitoptInputError` that names the
argument, shows the value and suggests a fix, before any work is done.

The one physical check is :func:`check_start`: a start state whose rate of change overflows
(``--guess stance_dot=1e308``) would make the adaptive integrator shrink its step for ever.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .errors import GaitoptInputError, StateError
from .fastcall import call1
from .hybrid import HybridModel

__all__ = [
    "check_positive",
    "check_count",
    "check_start",
    "check_inputs",
    "section_guess",
    "check_scheduler",
    "closed_loop_trials",
]


def check_positive(name: str, value: Any, example: str) -> float:
    """``value`` as a positive finite float, or a :class:`GaitoptInputError`.

    Parameters
    ----------
    name : str
        The argument's name (``"tol"``).
    value : Any
        The value given.
    example : str
        A valid value for the hint (``"1e-10"``).
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise GaitoptInputError(
            f"`{name}` must be a positive number, got {value!r}; e.g. {name}={example}"
        )
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise GaitoptInputError(
            f"`{name}` must be positive and finite, got {value!r}; e.g. {name}={example}"
        )
    return value


def check_count(name: str, value: Any, low: int, high: int, why: str) -> int:
    """``value`` as an integer in ``[low, high]``, or a :class:`GaitoptInputError` that states
    the limit and ``why`` it is there."""
    hint = f"e.g. {name}={low}"
    if isinstance(value, bool):
        raise GaitoptInputError(f"`{name}` must be an integer, got {value!r}; {hint}")
    if not isinstance(value, numbers.Integral):
        if isinstance(value, numbers.Real) and math.isfinite(value) and float(value).is_integer():
            value = int(value)
        else:
            raise GaitoptInputError(f"`{name}` must be an integer, got {value!r:.80}; {hint}")
    value = int(value)
    if value < low:
        raise GaitoptInputError(f"`{name}` must be at least {low}, got {value}; {hint}")
    if value > high:
        raise GaitoptInputError(f"`{name}` = {value} is above the limit {high}: {why}")
    return value


def check_inputs(model: HybridModel, inputs: Any) -> np.ndarray:
    """The constant per-step input as a finite vector of ``len(model.inputs)`` entries."""
    if inputs is None:
        return np.asarray(model.nominal_input(), dtype=float).ravel()
    try:
        u = np.asarray(inputs, dtype=float).ravel()
    except (TypeError, ValueError):
        u = None
    if u is None or u.size != len(model.inputs) or not np.all(np.isfinite(u)):
        raise GaitoptInputError(
            f"`inputs` must be {len(model.inputs)} finite number(s) "
            f"({', '.join(model.inputs) or 'none: the model is passive'}), got {inputs!r}"
        )
    return u


def check_start(
    model: HybridModel, x: np.ndarray, u: np.ndarray, phase: int, argument: str
) -> np.ndarray:
    """A start state of ``phase`` must be finite and have a finite rate of change.

    Raises
    ------
    StateError
        If ``x`` or the flow ``f(x, u, p)`` there is not finite (values so large that the
        equations of motion overflow), naming ``argument``.
    """
    names = model.phases[phase].states
    x = np.asarray(x, dtype=float).ravel()
    shown = ", ".join(f"{n}={v:.6g}" for n, v in zip(names, x, strict=False))
    if not np.all(np.isfinite(x)):
        raise StateError(
            f"{model.name}: `{argument}` gives the state {shown}, which is not finite: it is "
            f"not a state of the model at these parameters"
        )
    with np.errstate(all="ignore"):
        rate = call1(model.phases[phase].flow, x, u, model.p).ravel()
    if not np.all(np.isfinite(rate)):
        raise StateError(
            f"{model.name}: `{argument}` gives the state {shown}, where the equations of motion "
            f"overflow (the rate of change is not finite); use values of a physical size"
        )
    return x


def section_guess(
    model: HybridModel, guess: Mapping[str, Any] | Sequence[float] | None
) -> np.ndarray:
    """Section coordinates from a guess (a mapping by name or a sequence), as a finite vector."""
    if guess is not None and not isinstance(guess, (Mapping, Sequence, np.ndarray)):
        raise GaitoptInputError(
            f"`guess` must be a mapping of section coordinates "
            f"({', '.join(model.section.coordinates)}), a LimitCycle or None, got {guess!r}"
        )
    try:
        return model.section_vector(guess if guess is not None else {})
    except (TypeError, ValueError) as exc:
        if isinstance(exc, GaitoptInputError):
            raise
        raise GaitoptInputError(
            f"`guess` must map section coordinates ({', '.join(model.section.coordinates)}) "
            f"to numbers, got {guess!r}"
        ) from None


def check_scheduler(scheduler: object, *, serial: bool = False) -> None:
    """Refuse a ``scheduler`` that is not ``None``, ``"local"`` (``"serial"`` where ``serial``,
    i.e. for :func:`gaitopt.sweep.sweep`, which also takes a connected
    ``dask.distributed.Client``) or a Dask scheduler address (``"tcp://host:8786"``,
    ``"host:8786"``) before any work, with one line naming the argument, instead of Dask's error
    when it tries to connect."""
    names = ("local", "serial") if serial else ("local",)
    if scheduler is None or (isinstance(scheduler, str) and scheduler in names):
        return
    if serial and callable(getattr(scheduler, "submit", None)):
        return  # a connected dask.distributed.Client (gaitopt.sweep uses it as it is)
    address = scheduler.split("://", 1)[-1] if isinstance(scheduler, str) else ""
    host, _, port = address.rpartition(":")
    if not (host and port.isdigit()):
        raise GaitoptInputError(
            f"`scheduler` must be None, {' or '.join(repr(n) for n in names)} or a Dask "
            f"scheduler address such as 'tcp://host:8786', got {scheduler!r:.80}"
        )


def closed_loop_trials(
    model: HybridModel,
    orbits: Any,
    perturbation: Any,
    starts: Any,
    *,
    max_perturbation: float,
    examples: tuple[str, str],
) -> list[np.ndarray]:
    """The displacements from the fixed point (section coordinates) from which a stabilised
    gait's closed loop is simulated for ``orbits`` orbits: ``±perturbation`` along each section
    coordinate, or the rows of ``starts``.  Refuses ``orbits`` outside 1..1000,
    ``perturbation`` outside ``(0, max_perturbation]`` (section units) and rows of ``starts``
    that are not finite vectors of the section's size; ``examples`` are the values suggested
    for ``orbits`` and ``perturbation``.  Shared by the step-to-step stabilisation of an optimum
    (:mod:`gaitopt.optimize.stabilisation`) and the transverse LQR (:mod:`gaitopt.transverse`)."""
    if not isinstance(orbits, int) or isinstance(orbits, bool) or not 1 <= orbits <= 1000:
        raise GaitoptInputError(
            f"`orbits` must be an integer in 1..1000, got {orbits!r}; e.g. {examples[0]}"
        )
    if not (isinstance(perturbation, (int, float)) and 0 < perturbation <= max_perturbation):
        raise GaitoptInputError(
            f"`perturbation` must be a number in (0, {max_perturbation:g}] (section units), got "
            f"{perturbation!r}; e.g. {examples[1]}"
        )
    m = len(model.section.coordinates)
    if starts is None:
        return [sign * perturbation * e for e in np.eye(m) for sign in (1.0, -1.0)]
    displacements = [np.asarray(row, dtype=float).ravel() for row in starts]
    if not displacements or any(d.size != m or not np.all(np.isfinite(d)) for d in displacements):
        raise GaitoptInputError(
            f"`starts` must be rows of {m} finite displacements "
            f"({', '.join(model.section.coordinates)}), got {starts!r}"
        )
    return displacements
