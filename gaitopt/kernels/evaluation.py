"""What an evaluation of the shooting equations returns (:mod:`gaitopt.kernels.assemble`,
:mod:`gaitopt.kernels.newton`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Evaluation"]


@dataclass
class Evaluation:
    """The shooting equations at one point: ``F`` and (with ``jacobian``) ``∂F/∂w``, ``∂F/∂u``,
    ``∂F/∂p``; the return state, each phase's end state, guard rate, admissibility, duration;
    and, where the compiled Newton (:mod:`gaitopt.kernels.newton`) converged here, the return
    map's Jacobians ``(A, B_u, B_p)`` from the same ``∂F/∂w`` (None otherwise)."""

    F: np.ndarray
    F_w: np.ndarray | None
    F_u: np.ndarray | None
    F_p: np.ndarray | None
    x_return: np.ndarray
    ends: list[np.ndarray]
    rates: np.ndarray
    admissible: np.ndarray
    durations: np.ndarray
    return_map: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
