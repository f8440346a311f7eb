"""The gait's return map linearised in state and per-step input (by AD through the shooting
equations)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..hybrid import HybridModel
from ..open_loop import as_limit_cycle
from ..result import LimitCycle
from ..shooting import find_limit_cycle
from .deadbeat_solver import Deadbeat
from .decision import fmt_point
from .errors import ControlDesignError, NoGaitError, check_section_point


# -- the linearised map -------------------------------------------------------------------------
@dataclass(frozen=True)
class Linearisation:
    """The return map linearised at a fixed point: ``δs[n+1] = A δs[n] + B δu[n]``.

    Attributes
    ----------
    cycle : LimitCycle
        The gait (fixed point, nominal input, Jacobians).
    A : numpy.ndarray
        ``∂P/∂s`` (m × m), section coordinates.
    B : numpy.ndarray
        ``∂P/∂u`` (m × n_u).
    """

    cycle: LimitCycle
    A: np.ndarray
    B: np.ndarray

    @property
    def model(self) -> HybridModel:
        """The model."""
        return self.cycle.model

    @property
    def fixed_point(self) -> np.ndarray:
        """``s*``: the fixed point in section coordinates."""
        return self.cycle.section_point

    @property
    def nominal_input(self) -> np.ndarray:
        """``u*``: the input the gait was computed with."""
        return np.asarray(self.cycle.inputs, dtype=float)

    @property
    def open_loop_multipliers(self) -> np.ndarray:
        """``eig(A)``: the gait's nontrivial Floquet multipliers."""
        return sorted_by_modulus(np.linalg.eigvals(self.A))


def sorted_by_modulus(z: np.ndarray) -> np.ndarray:
    z = np.asarray(z, dtype=complex)
    return z[np.argsort(-np.abs(z), kind="stable")]


def linearise(
    model: HybridModel | LimitCycle | Any,
    guess: Mapping[str, float] | None = None,
    *,
    inputs: Sequence[float] | None = None,
    target: Mapping[str, float] | None = None,
) -> Linearisation:
    """Find the gait to control and linearise its return map in state and input (AD).

    Parameters
    ----------
    model : HybridModel, LimitCycle or OptimalGait
        A model with per-step inputs (``model.inputs``), or an already solved gait, or an
        optimal gait (:func:`gaitopt.optimize_gait`): its open loop's cycle
        (:func:`gaitopt.open_loop.open_loop_cycle`), whose per-step input is an offset added to
        the optimal profile over a step (``B = ∂P/∂δ``).
    guess : mapping, optional
        Section coordinates to start the gait search from (default: the model's default start).
    inputs : array_like, optional
        The nominal per-step input ``u*`` (default ``model.nominal_input()``).
    target : mapping, optional
        Make this section point the fixed point: ``u*`` is solved from ``P(s*, u*) = s*``
        (needs as many inputs as section coordinates, e.g. the SLIP's apex height and touchdown
        angle); ``inputs`` is then only the first guess.

    Raises
    ------
    ControlDesignError
        If the model has no per-step input.
    NoGaitError
        If no gait is found, or no input makes ``target`` a fixed point (the message says why).
    """
    model = as_limit_cycle(model)  # an optimal gait: its open loop's cycle
    if isinstance(model, LimitCycle):
        cycle = model
        if not cycle.success:
            raise NoGaitError(f"the gait given was not found ({cycle.message})", cycle)
        _require_inputs(cycle.model)
    else:
        _require_inputs(model)
        if target is not None:
            check_section_point(model, target, "target")
        cycle = find_limit_cycle(model, guess, inputs=inputs)
        if target is not None:
            if not cycle.success:
                cycle = find_limit_cycle(model, target, inputs=inputs)
            if cycle.success:
                s_t = model.section_vector(target)
                decision = Deadbeat(cycle).solve(s_t, target=s_t)
                if not decision.success:
                    raise NoGaitError(
                        f"`target` {fmt_point(model, s_t)}: no input makes it a fixed point "
                        f"({decision.message})"
                    )
                cycle = find_limit_cycle(model, target, inputs=decision.input)
        if not cycle.success:
            raise NoGaitError(f"{model.name}: no gait to control: {cycle.message}", cycle)
    return Linearisation(cycle, np.asarray(cycle.jacobian), np.asarray(cycle.input_jacobian))


def _require_inputs(model: HybridModel) -> None:
    if not model.inputs:
        raise ControlDesignError(
            f"{model.name} has no per-step input (it is passive): nothing to control; models "
            f"with inputs: slip (touchdown_angle), compass_gait (hip_torque)"
        )
