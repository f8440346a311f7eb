"""Controller designs: discrete LQR and pole placement (python-control), deadbeat."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import control as ct
import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..result import LimitCycle
from .deadbeat_solver import Deadbeat
from .errors import ControlDesignError
from .linearisation import Linearisation, linearise, sorted_by_modulus
from .policy import StepController, clip_limits, square_weight


# -- designs ------------------------------------------------------------------------------------
def lqr(
    model: HybridModel | LimitCycle | Linearisation,
    Q: Any = None,
    R: Any = None,
    *,
    guess: Mapping[str, float] | None = None,
    target: Mapping[str, float] | None = None,
    input_limits: tuple[Sequence[float], Sequence[float]] | None = None,
) -> StepController:
    """Discrete LQR on the linearised return map, gain from python-control's ``dlqr``.

    Minimises ``Σ δsᵀ Q δs + δuᵀ R δu`` over steps for ``δs[n+1] = A δs[n] + B δu[n]``.

    Parameters
    ----------
    model : HybridModel, LimitCycle or Linearisation
        What to control (see :func:`linearise`).
    Q, R : scalar, diagonal (sequence) or matrix, optional
        State (m × m, section coordinates) and input (n_u × n_u) weights; default identity.
    guess, target : mapping, optional
        See :func:`linearise`.
    input_limits : (low, high), optional
        Clip every input to this box (default: the model's ``input_bounds``, if it has any;
        the SLIP's touchdown angle in [0, π/2]).
    """
    lin = _linearisation(model, guess, target)
    m, n_u = lin.B.shape
    Qm, Rm = square_weight("Q", Q, m), square_weight("R", R, n_u)
    if np.min(np.linalg.eigvalsh(Rm)) <= 0:
        raise GaitoptInputError(f"`R` must be positive definite, got {Rm.tolist()}")
    K, _, poles = ct.dlqr(lin.A, lin.B, Qm, Rm)
    K = np.atleast_2d(np.asarray(K, dtype=float))
    return StepController(
        "lqr",
        lin,
        K,
        sorted_by_modulus(np.linalg.eigvals(lin.A - lin.B @ K)),
        {"Q": Qm, "R": Rm, "dlqr_poles": np.asarray(poles)},
        clip_limits(lin.model, input_limits),
    )


def acker(
    model: HybridModel | LimitCycle | Linearisation,
    poles: Sequence[complex] | None = None,
    *,
    guess: Mapping[str, float] | None = None,
    target: Mapping[str, float] | None = None,
    input_limits: tuple[Sequence[float], Sequence[float]] | None = None,
) -> StepController:
    """Pole placement for one input with python-control's ``acker`` (Ackermann's formula).

    Parameters
    ----------
    poles : sequence of complex, optional
        Desired closed-loop multipliers (m of them); default all 0 (the linear deadbeat).
    """
    lin = _linearisation(model, guess, target)
    m, n_u = lin.B.shape
    if n_u != 1:
        raise ControlDesignError(
            f"`acker` places poles for one input; {lin.model.name} has {n_u}: use lqr"
        )
    poles = np.zeros(m) if poles is None else np.asarray(poles, dtype=complex).ravel()
    if poles.size != m or not np.all(np.isfinite(poles)):
        raise GaitoptInputError(
            f"`poles` must be {m} finite values (one per section coordinate: "
            f"{', '.join(lin.model.section.coordinates)}), got {np.asarray(poles).tolist()!r}"
        )
    if np.linalg.matrix_rank(ct.ctrb(lin.A, lin.B)) < m:
        raise ControlDesignError(
            f"{lin.model.name}: the linearised map is not controllable from "
            f"{', '.join(lin.model.inputs)}; poles cannot be placed"
        )
    K = np.atleast_2d(np.real(np.asarray(ct.acker(lin.A, lin.B, poles), dtype=complex)))
    return StepController(
        "acker",
        lin,
        K,
        sorted_by_modulus(np.linalg.eigvals(lin.A - lin.B @ K)),
        {"poles": poles.real if np.all(poles.imag == 0) else poles},
        clip_limits(lin.model, input_limits),
    )


def deadbeat(
    model: HybridModel | LimitCycle | Linearisation,
    *,
    guess: Mapping[str, float] | None = None,
    target: Mapping[str, float] | None = None,
    input_limits: tuple[Sequence[float], Sequence[float]] | None = None,
) -> StepController:
    """Deadbeat control: each step solve ``P(s, u) = s*`` for ``u`` (CasADi Newton rootfinder).

    Needs as many inputs as section coordinates (the SLIP: apex height ← touchdown angle).  Its
    linearisation is ``K = B⁻¹ A`` with every closed-loop multiplier 0.

    Raises
    ------
    ControlDesignError
        If the numbers of inputs and section coordinates differ.
    """
    lin = _linearisation(model, guess, target)
    m, n_u = lin.B.shape
    if n_u != m:
        raise ControlDesignError(
            f"deadbeat needs as many inputs as section coordinates; {lin.model.name} has "
            f"{m} ({', '.join(lin.model.section.coordinates)}) and {n_u} "
            f"({', '.join(lin.model.inputs)}): use lqr or acker"
        )
    if abs(np.linalg.det(lin.B)) < 1e-12 * max(1.0, np.max(np.abs(lin.B))):
        raise ControlDesignError(f"{lin.model.name}: ∂P/∂u is singular at the gait: no deadbeat")
    K = np.linalg.solve(lin.B, lin.A)
    return StepController(
        "deadbeat",
        lin,
        K,
        sorted_by_modulus(np.linalg.eigvals(lin.A - lin.B @ K)),
        {},
        clip_limits(lin.model, input_limits),
        Deadbeat(lin.cycle),
    )


#: Controller designs by name (``gaitopt control --kind``).
KINDS: dict[str, Callable[..., StepController]] = {"lqr": lqr, "acker": acker, "deadbeat": deadbeat}


def design_controller(
    model: HybridModel | LimitCycle | Linearisation, kind: str, **options: Any
) -> StepController:
    """Dispatch to :func:`lqr`, :func:`acker` or :func:`deadbeat` by ``kind``."""
    if kind not in KINDS:
        raise GaitoptInputError(f"`kind` must be one of {', '.join(KINDS)}, got {kind!r}")
    return KINDS[kind](model, **options)


def _linearisation(model, guess, target) -> Linearisation:
    if isinstance(model, Linearisation):
        return model
    return linearise(model, guess, target=target)
