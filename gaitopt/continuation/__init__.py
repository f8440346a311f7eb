"""Pseudo-arclength continuation of gaits in a model parameter, special points, and
period-doubling cascades.

A branch is followed in ``y = (w, ℓ)``: the shooting unknowns ``w`` of
:mod:`gaitopt.shooting` and the scaled parameter ``ℓ = λ / λ_scale``.  Each step predicts along
the tangent ``t`` (the null vector of ``[F_w, F_ℓ]``) and corrects with Newton on
``F(w, ℓ) = 0, ⟨t, y − y_pred⟩ = 0`` (Keller's pseudo-arclength method; Allgower & Georg,
"Numerical Continuation Methods", §2.1); the inner product weights the ``N`` shooting unknowns by
``1/N`` so that states and parameter count alike.  The step adapts to the corrector's work.
Every accepted point is certified like a solved gait (:func:`gaitopt.shooting.certify`: no false
gaits, multipliers, independent simulation) and its discretisation error estimated (the mesh is
refined along the branch when needed, and coarsened again where the coarser mesh meets the
tolerance).

Special points come from test functions of the return map's Jacobian ``A`` (Kuznetsov,
"Elements of Applied Bifurcation Theory", §10.2, maps): fold ``LP`` where ``det(A − I)`` changes
sign (a multiplier +1), period doubling ``PD`` where ``det(A + I)`` does (−1), Neimark–Sacker
``NS`` where the bialternate product ``∏_{i<j}(μ_i μ_j − 1)`` does with a complex pair on the unit
circle.  Each is located by regula falsi (Illinois) along the arclength to 1e-10 in the parameter.
A ``boundary`` is where the gait stops existing: a certification check fails (a guard grazes, a
duration reaches zero, a guard is crossed early, the simulation disagrees) or the corrector cannot
continue; it is located by bisection.  At a PD the period-2 orbit is found (perturbing along the
eigenvector of −1) and followed, and so on down the cascade.

Modules: :mod:`~gaitopt.continuation.branch` (the options and the results),
:mod:`~gaitopt.continuation.follower` (predictor–corrector along one direction),
:mod:`~gaitopt.continuation.special` (test functions, locating special points and boundaries),
:mod:`~gaitopt.continuation.switching` (onto the period-doubled branch at a PD).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ..errors import GaitoptInputError, ParameterError, did_you_mean
from ..hybrid import HybridModel
from ..open_loop import as_limit_cycle, is_optimal_gait
from ..result import LimitCycle
from ..shooting import find_limit_cycle
from ..threads import single_blas_thread
from .branch import Branch, PseudoArclength, SpecialPoint
from .follower import Follower
from .switching import switch_at_period_doubling

__all__ = ["PseudoArclength", "SpecialPoint", "Branch", "continuation", "DEFAULT_MAX_PERIOD"]

#: The deepest period of a cascade unless asked otherwise (the Python API and the CLI alike).
DEFAULT_MAX_PERIOD = 8

#: The default step control (frozen, so one instance serves every call).
DEFAULT_OPTIONS = PseudoArclength()


@single_blas_thread
def continuation(
    model: HybridModel | Any,
    param: str,
    *,
    to: float | None = None,
    start: LimitCycle | Any | Mapping[str, float] | None = None,
    steps: int = 1,
    options: PseudoArclength = DEFAULT_OPTIONS,
    both_directions: bool = False,
    bounds: tuple[float, float] | None = None,
    cascade: bool = True,
    max_period: int = DEFAULT_MAX_PERIOD,
    verify: bool = True,
    tol: float = 1e-10,
) -> Branch:
    """Follow a gait through a model parameter.

    Parameters
    ----------
    model : HybridModel or OptimalGait
        The model at the start; or an optimal gait (:func:`gaitopt.optimize_gait`), followed
        with its input profile held fixed: its open loop (:func:`gaitopt.open_loop.
        open_loop_cycle`, the profile on a clock since the section) is the model, its limit
        cycle the start.
    param : str
        Name of the parameter to vary (any of ``model.params``).
    to : float, optional
        Parameter value to stop at (the direction of continuation).  Default: the end of the
        parameter's valid range above the start.
    start : LimitCycle, OptimalGait or mapping, optional
        The gait to start from (a solved cycle at ``model``, or an optimal gait: as ``model``),
        or a guess for :func:`find_limit_cycle`; default: the model's default start.
    steps : int
        Period of the starting gait in steps.
    options : PseudoArclength
        Step control.
    both_directions : bool
        Also follow the branch from the start away from ``to`` (until the parameter's range ends
        or the gait stops existing).
    bounds : (float, float), optional
        Parameter interval the branch stays in (both directions, also after folds); default the
        parameter's valid range.
    cascade : bool
        At each period doubling switch to the period-2k branch and follow it too (in the
        continuation direction), down the cascade until ``max_period``.
    max_period : int
        Deepest period of the cascade (default :data:`DEFAULT_MAX_PERIOD`, 8).
    verify : bool
        Verify every point by independent simulation (as :func:`find_limit_cycle` does).
    tol : float
        Residual and discretisation-error tolerance (as :func:`find_limit_cycle`).

    Returns
    -------
    Branch
        Points in increasing arclength order (for ``both_directions`` from the far end of the
        backward part), special points, and the period-doubled branches as ``children``.

    Raises
    ------
    ParameterError
        If ``param`` is not a parameter of the model or ``to`` is outside its range.
    """
    if is_optimal_gait(model) or is_optimal_gait(start):  # its open loop's cycle
        start = as_limit_cycle(start if is_optimal_gait(start) else model, tol=tol, verify=verify)
        model = start.model
    specs = {s.name: s for s in model.parameter_specs()}
    if param not in specs:
        raise ParameterError(
            f"{model.name}: unknown parameter {param!r} to continue in; "
            f"{did_you_mean(param, specs)}parameters: {', '.join(specs)}"
        )
    spec = specs[param]
    if spec.integer:
        raise ParameterError(
            f"{model.name}: parameter `{param}` takes integer values and cannot be continued; "
            f"choose a real parameter"
        )
    lam0 = float(getattr(model, param))
    if to is not None:
        to = float(to)
        model.replace(**{param: to})  # raises ParameterError when `to` is out of range
        if to == lam0:
            raise ParameterError(
                f"`to` = {to:g} equals the start value of `{param}`; nothing to do"
            )
    if isinstance(start, LimitCycle):
        first = start
        if type(first.model) is not type(model) or first.model.params != model.params:
            raise GaitoptInputError("`start` must be a gait of the given model at its parameters")
    else:
        first = find_limit_cycle(model, start, steps=steps, verify=verify, tol=tol)
    branch = Branch(model, param, first.steps)
    if not first.success:
        branch.success, branch.status = False, first.status or "not_converged"
        branch.message = f"no gait to start from: {first.message}"
        return branch
    direction = 1.0 if to is None or to > lam0 else -1.0
    lo, hi = (-math.inf, math.inf) if bounds is None else (float(bounds[0]), float(bounds[1]))
    if not lo <= lam0 <= hi:
        raise ParameterError(
            f"`bounds` = ({lo:g}, {hi:g}) must contain the start value {param} = {lam0:g}"
        )
    return _follow_branch(
        first,
        param,
        direction,
        to,
        (lo, hi),
        options,
        both_directions,
        cascade,
        max_period,
        verify,
        tol,
    )


def _follow_branch(
    first: LimitCycle,
    param,
    direction,
    to,
    bounds,
    options,
    both_directions,
    cascade,
    max_period,
    verify,
    tol,
) -> Branch:
    """Follow a certified gait in ``direction`` (and back, if asked); switch at PDs."""
    branch = Branch(first.model, param, first.steps)
    lo, hi = bounds
    if to is not None:
        lo, hi = (lo, min(hi, to)) if direction > 0 else (max(lo, to), hi)
    forward = Follower(first, param, direction, (lo, hi), options, verify, tol).run()
    points, specials, message = forward.cycles, forward.special_points, forward.stop
    if both_directions:
        backward = Follower(first, param, -direction, bounds, options, verify, tol).run()
        n_back = len(backward.cycles) - 1  # the start is shared
        points = backward.cycles[::-1] + points[1:]
        specials = [_reindex(sp, n_back - sp.index - 1) for sp in backward.special_points[::-1]] + [
            _reindex(sp, sp.index + n_back) for sp in specials
        ]
        message = f"backward: {backward.stop}; forward: {message}"
    branch.cycles, branch.special_points, branch.message = points, specials, message
    if cascade and branch.cycles:
        span = (float(branch.params.min()), float(branch.params.max()))
        for sp in branch.special_points:
            if sp.kind == "PD" and 2 * branch.steps <= max_period:
                child, sp.switch = switch_at_period_doubling(
                    sp, param, direction, to, bounds, options, verify, tol, max_period,
                    follow=_follow_branch, span=span,
                )  # fmt: skip
                if child is not None:
                    branch.children.append(child)
    return branch


def _reindex(sp: SpecialPoint, index: int) -> SpecialPoint:
    return SpecialPoint(sp.kind, sp.param, max(index, 0), sp.cycle, sp.message)
