"""The statement of a bound on the multipliers (``max_multiplier``): which statements it applies
to (:func:`check_max_multiplier`) and the default roughness budget
(:func:`with_roughness_budget`).  The NLP's rows are :mod:`gaitopt.optimize.spectral`'s, the
check of the reported optimum :mod:`gaitopt.optimize.spectral_certify`'s.

**Why a roughness budget.**  The return map's Jacobian depends on the input's value at the
instant of each impact: a step that ends ``δτ`` later sees the torque there for ``δτ`` longer
(the saltation term ``f(x⁻, u(T)) δτ``).  The effort ``∫u² dt`` does not charge a point value, so
``ρ(A) ≤ R`` alone is met by a torque spike at heel strike whose width shrinks with the mesh:
on the level compass gait (0.3 m in 0.8 s, ``R = 1``) the least effort fell 7.1817, 6.9618,
6.8267, 6.7510 N²·m²·s over 6, 12, 24 and 48 intervals towards the unbounded 6.6688, and the
spike's multiplier holds only for perturbations within its width (central differences of the
simulated map: 1.0011 against the transcription's 1 at 48 intervals).  No optimum exists.  A
bound on the roughness ``∫ Σᵣ u̇ᵣ² dt ≤ S`` with ``u`` continuous between mesh intervals makes it
well posed (a spike of height ``H`` and width ``ε`` costs ``H²/ε`` of it): the same statement with
``S = 120`` N²·m²/s settles at 8.136072244 (6 to 48 intervals within 1e-8).  ``S`` defaults to
:data:`ROUGHNESS_FACTOR` times the roughness of the optimum without the bound (solved first),
so an inactive bound leaves that optimum as it was; ``max_roughness`` sets it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import GaitoptInputError
from .schur import MAX_SECTION
from .spectral import profile_roughness

__all__ = ["check_max_multiplier", "with_roughness_budget", "ROUGHNESS_FACTOR"]

#: The default roughness budget, as a multiple of the roughness of the optimum without the
#: bound (``max_roughness`` unset): enough room to reshape the profile (the compass gait at
#: 0.3 m in 0.8 s needs more than 1.02 of it for ``R = 1``), no room for a spike.
ROUGHNESS_FACTOR = 2.0


def _positive(name: str, value: Any, example: str, meaning: str) -> float:
    number = math.nan
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        number = float(value)
    if not (math.isfinite(number) and number > 0):
        raise GaitoptInputError(
            f"`{name}` must be a positive finite number ({meaning}), got {value!r}; e.g. "
            f"{name}={example}"
        )
    return number


def check_max_multiplier(problem: Any) -> tuple[float | None, float | None]:
    """``(max_multiplier, max_roughness)`` of a :class:`~gaitopt.optimize.problem.GaitProblem`
    checked: None or positive finite numbers, for a statement whose return map has a Jacobian
    :mod:`gaitopt.optimize.spectral` can bound; else a one-line :class:`GaitoptInputError`
    naming the argument, the value and a fix."""
    value, budget = problem.max_multiplier, problem.max_roughness
    if value is None:
        if budget is not None:
            raise GaitoptInputError(
                f"`max_roughness` {budget!r} applies with max_multiplier (the bound it makes "
                f"well posed); add max_multiplier=1 or leave max_roughness out"
            )
        return None, None
    R = _positive("max_multiplier", value, "1",
                  "the bound R on the spectral radius of the return map's Jacobian")  # fmt: skip
    if budget is not None:
        meaning = "the bound on the input profile's roughness, (input unit)^2/s"
        budget = _positive("max_roughness", budget, "120", meaning)
    model = problem.model
    m = len(model.section.coordinates)
    if m == 0:
        raise GaitoptInputError(
            f"`max_multiplier` {R:g}: {model.name}'s section has no free coordinates, so its "
            f"return map has no multipliers to bound; leave max_multiplier out"
        )
    if m > MAX_SECTION:
        raise GaitoptInputError(
            f"`max_multiplier` {R:g}: {model.name}'s section has {m} coordinates; the bound is "
            f"formulated for at most {MAX_SECTION} (its Schur-Cohn-Jury conditions are of "
            f"degree m(m-1) in the Jacobian); leave max_multiplier out and stabilise the optimum "
            f"by feedback instead (gaitopt.optimize.stabilise)"
        )
    if len(model.phases) > 1 and not problem.continuous_inputs:
        raise GaitoptInputError(
            f"`max_multiplier` {R:g}: with continuous_inputs=False the input of {model.name} "
            f"may jump where its phases hand over, so the return map has no Jacobian to bound; "
            f"use continuous_inputs=True"
        )
    if problem.cost_kind in ("work", "cot"):
        raise GaitoptInputError(
            f"`max_multiplier` {R:g} with cost {problem.cost_kind!r}: the positive-work optimum "
            f"is found in two stages (slack powers, then arcs read off that solution) and "
            f"neither carries the bound yet; use cost='effort'"
        )
    return R, budget


def with_roughness_budget(problem: Any, solve: Callable[[Any], Any]) -> tuple[Any, Any, Any]:
    """``(problem, unbounded, failure)``: the statement with its roughness budget.  With
    ``max_multiplier`` set and ``max_roughness`` not, the optimum without the bound is solved
    first (``solve(statement)``) and the budget is :data:`ROUGHNESS_FACTOR` times its
    roughness; ``unbounded`` is that optimum (a warm start), ``failure`` it if it failed (then
    there is no budget: the caller reports it)."""
    if problem.max_multiplier is None or problem.max_roughness is not None:
        return problem, None, None
    free = solve(replace(problem, max_multiplier=None))
    if not free.success:
        free.message = (
            f"the optimum without the bound on the multipliers, whose roughness sets the "
            f"default max_roughness, was not found: {free.message}; give max_roughness"
        )
        return problem, None, free
    col, w = free.transcription
    budget = ROUGHNESS_FACTOR * profile_roughness(col, w, col.model.p)
    return replace(problem, max_roughness=budget), free, None
