"""The certificate's checks of a model class as compiled C: per phase, every guard, admissibility
rule and unilateral constraint at one state, in one function.

The certificate (:mod:`gaitopt.orbit.certificate`) evaluates these on every dense sample of an
orbit (65 per phase for the default shooting mesh).  Interpreted, a mapped SX function costs
about 1 µs per sample for a contact force of the kneed walker (529 operations), some 0.1 ms per
check; compiled and mapped over the samples it is a few µs.  The functions are compiled once per
model class into the kernel cache (:func:`gaitopt.kernels.cache.load`) and are exactly the
model's own expressions, so where there is no compiler the certificate evaluates those
directly (:func:`check_kernels` returns None).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from .cache import load, source_key

__all__ = ["check_kernels", "check_rows"]


def check_rows(phase) -> tuple[int, int, int]:
    """``(transitions, rules, constraints)``: the row counts of a phase's check function (its
    rows: each transition's guard, each transition's admissibility (1 where it has no rule),
    each unilateral constraint)."""
    n_tr = len(phase.transitions)
    return n_tr, n_tr, len(phase.constraints)


def _check_functions(model_cls) -> list[ca.Function]:
    functions = []
    for i, phase in enumerate(model_cls.structure().phases):
        flow = phase.flow
        x, u, p = (ca.SX.sym(s, flow.size1_in(j)) for j, s in enumerate("xup"))
        rows = [tr.guard(x, u, p)[0] for tr in phase.transitions]
        rows += [
            tr.admissible(x, u, p)[0] if tr.admissible is not None else ca.SX(1)
            for tr in phase.transitions
        ]
        rows += [c.function(x, u, p)[0] for c in phase.constraints]
        functions.append(ca.Function(f"checks_{i}", [x, u, p], [ca.vertcat(*rows)]))
    return functions


@lru_cache(maxsize=64)
def check_kernels(model_cls) -> list[ca.Function] | None:
    """Per phase ``checks_i(x, u, p)`` (rows as :func:`check_rows` says), compiled; None where
    there is no compiler, the model's functions cannot be evaluated on SX symbols, or the class
    is not one of gaitopt's (a user's or a derived class, e.g. an optimiser's augmented model:
    not in the kernel index, so that a certificate never waits for the compiler there)."""
    name = f"gaitopt_{model_cls.__name__.lower()}_checks"
    key = source_key(name, model_cls)
    if key is None:
        return None
    try:
        functions, compiled = load(
            name, lambda: _check_functions(model_cls), verbose=False, key=key
        )  # fmt: skip
    except (RuntimeError, TypeError, NotImplementedError, IndexError):
        return None
    return functions if compiled else None
