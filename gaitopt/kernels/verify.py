"""Compiled steps of the verification simulation: for each phase of a model class, one DOP853 step
with its error estimate, dense-output coefficients and event functions
(:func:`gaitopt.dop853.step_function`), with the phase's unilateral constraints among the events
and without them (a guess's simulation), compiled into one library per model class and cached
like the shooting kernels (:mod:`gaitopt.kernels.cache`).

The verification stays independent of the shooting: a different method (Dormand–Prince 8(5,3)
with adaptive steps and located events, against fixed-step RK8 with guard constraints) on the same
model functions; compiling only removes CasADi's interpreter from each step (17 → 2 µs for the
compass gait, 100 → 8 µs for the five-link biped), with identical results.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from .cache import load, source_key

__all__ = ["CHECKS_PER_STEP", "verification_steps"]

#: Interior points per step where the events are also checked (on the dense output), plus the
#: step's end: a guard excursion shorter than a step (a wheel that rocks back onto a spoke within
#: milliseconds) is still seen.
CHECKS_PER_STEP = 4


def phase_events(phase, constraints: bool) -> list[ca.Function]:
    """A phase's event functions in the simulation's order: its transitions' guards, then (with
    ``constraints``) its unilateral constraints."""
    events = [t.guard for t in phase.transitions]
    return events + ([c.function for c in phase.constraints] if constraints else [])


def _functions(model_cls) -> list[ca.Function]:
    from ..dop853 import step_function

    functions = []
    for i, phase in enumerate(model_cls.structure().phases):
        for constraints in (True, False):
            f = step_function(phase.flow, phase_events(phase, constraints), CHECKS_PER_STEP)
            args = f.mx_in()
            name = f"dop853_{i}_{'c' if constraints else 'g'}"
            functions.append(ca.Function(name, args, f.call(args), f.name_in(), f.name_out()))
    return functions


@lru_cache(maxsize=64)
def verification_steps(model_cls) -> dict[tuple[int, bool], ca.Function] | None:
    """``{(phase, constraints): step}`` compiled for a model class (interpreted where there is
    no compiler), or None where its functions cannot be built this way."""
    name = f"gaitopt_{model_cls.__name__.lower()}_dop853"
    try:
        functions, _ = load(name, lambda: _functions(model_cls), key=source_key(name, model_cls))
    except (RuntimeError, TypeError, NotImplementedError):
        return None
    n = len(model_cls.structure().phases)
    keys = [(i, constraints) for i in range(n) for constraints in (True, False)]
    return dict(zip(keys, functions, strict=True))
