"""Step-to-step controllers as policies: the decision of one step and the controller object."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..result import LimitCycle
from .deadbeat_solver import Deadbeat
from .decision import Decision, fmt_point, fmt_u
from .errors import check_section_point
from .linearisation import Linearisation


# -- decisions and controllers -----------------------------------------------------------------
@dataclass
class StepController:
    """A step-to-step controller designed around a gait; also a policy for :func:`simulate`.

    Attributes
    ----------
    kind : str
        ``"lqr"``, ``"acker"`` or ``"deadbeat"``.
    linearisation : Linearisation
        The gait and ``A``, ``B``.
    gain : numpy.ndarray
        ``K`` (n_u × m) of ``u = u* − K (s − s*)``; for deadbeat, the gain of the linearised
        deadbeat law ``K = B⁻¹ A``.
    closed_loop_multipliers : numpy.ndarray
        ``eig(A − B K)``.
    weights : dict
        Design data: ``Q``, ``R`` (LQR), ``poles`` (acker).
    input_limits : tuple of numpy.ndarray or None
        ``(low, high)``: inputs are clipped to it.
    target : numpy.ndarray
        The section point the controller drives to (the fixed point).
    """

    kind: str
    linearisation: Linearisation
    gain: np.ndarray
    closed_loop_multipliers: np.ndarray
    weights: dict[str, Any] = field(default_factory=dict)
    input_limits: tuple[np.ndarray, np.ndarray] | None = None
    deadbeat_solver: Deadbeat | None = None

    @property
    def model(self) -> HybridModel:
        """The controlled model."""
        return self.linearisation.model

    @property
    def cycle(self) -> LimitCycle:
        """The gait controlled around."""
        return self.linearisation.cycle

    @property
    def target(self) -> np.ndarray:
        """``s*`` in section coordinates."""
        return self.linearisation.fixed_point

    @property
    def nominal_input(self) -> np.ndarray:
        """``u*``."""
        return self.linearisation.nominal_input

    @property
    def stable(self) -> bool:
        """Every closed-loop multiplier inside the unit circle."""
        return bool(np.all(np.abs(self.closed_loop_multipliers) < 1))

    def decide(self, state: Mapping[str, float] | Sequence[float] | np.ndarray) -> Decision:
        """The input for the next step from a state on the section.

        Parameters
        ----------
        state : mapping or array_like
            Section coordinates (mapping by name, or vector), or a full phase-0 state vector.
        """
        start = time.perf_counter()
        s = self._section(state)
        ds = s - self.target
        linear = self.nominal_input - self.gain @ ds
        if self.deadbeat_solver is not None:
            decision = self.deadbeat_solver.solve(s, target=self.target)
            if decision.success and self._within(decision.input):
                decision.solve_time = time.perf_counter() - start
                return decision
            reason = (
                decision.message
                if not decision.success
                else f"the deadbeat input {fmt_u(self.model, decision.input)} is outside the "
                f"input limits"
            )
            if len(s) == 1:
                span = self.deadbeat_solver.feasible_range()
                if span is not None:
                    name = self.model.section.coordinates[0]
                    reason += f" (deadbeat works for {span[0]:.6g} ≤ {name} ≤ {span[1]:.6g})"
            u = self._clip(linear)
            return Decision(
                False,
                f"deadbeat infeasible from {fmt_point(self.model, s)}: {reason}; applied the "
                f"linearised deadbeat law, {fmt_u(self.model, u)}",
                u,
                s,
                self.target
                + (self.linearisation.A @ ds + self.linearisation.B @ (u - self.nominal_input)),
                decision.iterations,
                time.perf_counter() - start,
            )
        u = self._clip(linear)
        saturated = not np.allclose(u, linear, rtol=0, atol=0)
        predicted = (
            self.target
            + self.linearisation.A @ ds
            + self.linearisation.B @ (u - self.nominal_input)
        )
        message = f"{self.kind}: {fmt_u(self.model, u)}" + (
            " (saturated at the input limits)" if saturated else ""
        )
        return Decision(not saturated, message, u, s, predicted, 0, time.perf_counter() - start)

    def __call__(self, step: int, x: np.ndarray) -> np.ndarray:
        """Policy for :func:`gaitopt.simulate`: ``u`` from the phase-0 state at the section."""
        return self.decide(np.asarray(x, dtype=float)).input

    def _section(self, state) -> np.ndarray:
        model = self.model
        if isinstance(state, Mapping):  # a state typed in: it must exist (simulated ones do)
            check_section_point(model, state, "state")
            return model.section_vector(state)
        v = np.asarray(state, dtype=float).ravel()
        if v.size == len(model.state_names) and v.size != len(model.section.coordinates):
            return model.section_coordinates_of(v)
        return model.section_vector(v)

    def _within(self, u: np.ndarray) -> bool:
        if self.input_limits is None:
            return True
        lo, hi = self.input_limits
        return bool(np.all(u >= lo) and np.all(u <= hi))

    def _clip(self, u: np.ndarray) -> np.ndarray:
        if self.input_limits is None:
            return u
        return np.clip(u, *self.input_limits)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready description (``gaitopt control --json``)."""
        model = self.model
        out: dict[str, Any] = {
            "model": model.name,
            "params": model.params,
            "kind": self.kind,
            "success": True,
            "message": f"{self.kind} controller around the gait at "
            f"{fmt_point(model, self.target)} ({self.cycle.message})",
            "section_coordinates": list(model.section.coordinates),
            "state_names": list(model.state_names),
            "fixed_point": dict(self.cycle.fixed_point),
            "inputs": list(model.inputs),
            "nominal_input": dict(zip(model.inputs, map(float, self.nominal_input), strict=True)),
            "A": self.linearisation.A.tolist(),
            "B": self.linearisation.B.tolist(),
            "gain": self.gain.tolist(),
            "open_loop_multipliers": _pairs(self.linearisation.open_loop_multipliers),
            "closed_loop_multipliers": _pairs(self.closed_loop_multipliers),
            "closed_loop_stable": self.stable,
            "weights": {k: np.asarray(v).tolist() for k, v in self.weights.items()},
            "input_limits": None
            if self.input_limits is None
            else [np.asarray(v).tolist() for v in self.input_limits],
        }
        if self.deadbeat_solver is not None and len(self.target) == 1:
            rng = self.deadbeat_solver.feasible_range()
            out["feasible_range"] = None if rng is None else {model.section.coordinates[0]: rng}
        return out


def _pairs(z: np.ndarray) -> list[list[float]]:
    return [[float(v.real), float(v.imag)] for v in np.asarray(z, dtype=complex)]


def clip_limits(
    model: HybridModel, input_limits: tuple[Sequence[float], Sequence[float]] | None
) -> tuple[np.ndarray, np.ndarray] | None:
    """The ``(low, high)`` input box: the one given, else the model's ``input_bounds``."""
    if input_limits is None:
        input_limits = model.input_box()
        if input_limits is None:
            return None
    try:
        lo, hi = (np.broadcast_to(np.asarray(v, dtype=float), (len(model.inputs),)).copy()
                  for v in input_limits)  # fmt: skip
    except (TypeError, ValueError):
        raise GaitoptInputError(
            f"`input_limits` must be (low, high) with {len(model.inputs)} entries each "
            f"({', '.join(model.inputs)}), got {input_limits!r}"
        ) from None
    if not np.all(lo < hi):
        raise GaitoptInputError(f"`input_limits` must have low < high, got {input_limits!r}")
    return lo, hi


def square_weight(name: str, value: Any, size: int, default: float = 1.0) -> np.ndarray:
    """A weight matrix from ``None`` (identity), a scalar, a diagonal or a full matrix."""
    if value is None:
        return default * np.eye(size)
    M = np.asarray(value, dtype=float)
    if M.ndim == 0:
        M = float(M) * np.eye(size)
    elif M.ndim == 1 and M.size == size:
        M = np.diag(M)
    if M.shape != (size, size) or not np.all(np.isfinite(M)):
        raise GaitoptInputError(
            f"`{name}` must be a scalar, {size} diagonal entries or a {size}×{size} matrix, got "
            f"{np.asarray(value).tolist()!r}"
        )
    if not np.allclose(M, M.T) or np.min(np.linalg.eigvalsh(0.5 * (M + M.T))) < 0:
        raise GaitoptInputError(
            f"`{name}` must be symmetric positive semidefinite, got {M.tolist()}"
        )
    return M
