"""What a controller decides at a return to the section (:class:`Decision`), and how points and
inputs are written in its messages: below the linearisation, the deadbeat solver and the policy,
which all use them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..hybrid import HybridModel

__all__ = ["Decision"]


@dataclass
class Decision:
    """One step's input, chosen at a return to the section.

    Attributes
    ----------
    success : bool
        The controller's law was applied as designed (deadbeat: the equation was solved, the
        solution is a valid step and the input within its limits; LQR/acker: not saturated).
    message : str
        What was decided, or why the law could not be applied and what was done instead.
    input : numpy.ndarray
        The input applied (after limits / fallback).
    state : numpy.ndarray
        Section coordinates the decision was made from.
    predicted : numpy.ndarray
        Predicted next section coordinates: the target (deadbeat), ``s* + (A − BK)(s − s*)``
        (linear laws).
    iterations : int
        Newton iterations (deadbeat).
    solve_time : float
        Seconds spent deciding.
    """

    success: bool
    message: str
    input: np.ndarray
    state: np.ndarray
    predicted: np.ndarray
    iterations: int = 0
    solve_time: float = float("nan")


def fmt_u(model: HybridModel, u: np.ndarray) -> str:
    return ", ".join(f"{k}={v:.6g}" for k, v in zip(model.inputs, np.ravel(u), strict=True))


def fmt_point(model: HybridModel, s: np.ndarray) -> str:
    return ", ".join(
        f"{k}={v:.6g}" for k, v in zip(model.section.coordinates, np.ravel(s), strict=True)
    )
