"""Compiled steps of the verification simulation: for each phase of a model class, one DOP853 step
with its error estimate, dense-output coefficients and event functions
(:func:`gaitopt.dop853.step_function`), with the phase's unilateral constraints among the events
and without them (a guess's simulation), compiled into one library per model class and cached
like the shooting kernels (:mod:`gaitopt.kernels.cache`).

The verification stays independent of the shooting: a different method (Dormand–Prince 8(5,3)
with adaptive steps and located events, against fixed-step RK8 with guard constraints) on the same
model functions; compiling only removes CasADi's interpreter from each step (17 → 2 µs for the
compass gait, 100 → 8 µs for the five-link biped), with identical results.

The step is most of the scalar batch driver's time (three quarters of a basin's, with the
``sin`` and ``cos`` it calls; the driver is 5 %; the lane driver calls the same step's vector form
instead, :mod:`gaitopt.kernels.vector_step`, compiled with these flags and the host's vector
unit), so its library is compiled at ``-O2`` (:data:`STEP_FLAGS`)
where its C is under :data:`STEP_O2_BELOW` bytes: a step 15 % faster than at ``-O1`` for the
compass gait (0.90 against 1.05 µs, called in a C loop), 23 % for the five-link biped (6.1
against 7.9 µs), for 3.5 s more of gcc on the largest such library (the five-link biped's).
``-fno-semantic-interposition`` lets gcc inline CasADi's small helpers (``sq``, ``copy``:
otherwise calls through the PLT) and ``-ffp-contract=off`` forbids fused multiply-adds: the same
operations in the same order, so the same numbers to the bit (no ``-ffast-math``, no
``-march``).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from .cache import FLAGS, load, source_key

__all__ = ["CHECKS_PER_STEP", "STEP_FLAGS", "STEP_O2_BELOW", "verification_steps"]

#: Compiler flags of a step library of under :data:`STEP_O2_BELOW` bytes of C (see above).
STEP_FLAGS = ("-O2", "-fno-semantic-interposition", "-ffp-contract=off", "-shared", "-fPIC")
#: Above this much C (bytes; the Strandbeest's 2.8 MB: 22 s of gcc at -O2 against 10 s at -O1),
#: a step library is compiled with :data:`~gaitopt.kernels.cache.FLAGS` (-O1).
STEP_O2_BELOW = 1_000_000

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


def _flags(functions: list[ca.Function], source: str) -> tuple[str, ...]:
    """:data:`STEP_FLAGS` below :data:`STEP_O2_BELOW` bytes of C, else ``FLAGS`` (-O1)."""
    return STEP_FLAGS if len(source) < STEP_O2_BELOW else FLAGS


@lru_cache(maxsize=64)
def verification_steps(model_cls) -> dict[tuple[int, bool], ca.Function] | None:
    """``{(phase, constraints): step}`` compiled for a model class (interpreted where there is
    no compiler), or None where its functions cannot be built this way."""
    name = f"gaitopt_{model_cls.__name__.lower()}_dop853"
    try:
        functions, _ = load(
            name, lambda: _functions(model_cls), key=source_key(name, model_cls),
            flags=_flags,
        )  # fmt: skip
    except (RuntimeError, TypeError, NotImplementedError):
        return None
    n = len(model_cls.structure().phases)
    keys = [(i, constraints) for i in range(n) for constraints in (True, False)]
    return dict(zip(keys, functions, strict=True))
