"""``gaitopt optimize``'s options read into :func:`gaitopt.optimize_gait`'s arguments: the fixed
quantities, bounds, path constraints and free parameters (:func:`parse_problem`) and the LQR
weights of ``--stabilise`` (:func:`lqr_weights`); each bad option a one-line input error."""

from __future__ import annotations

import argparse
import math
from typing import Any

from ..errors import did_you_mean

__all__ = ["FIXABLE", "lqr_weights", "parse_problem"]

FIXABLE = ("period", "step_length", "speed")


def parse_problem(args: argparse.Namespace, model: Any) -> dict[str, Any]:
    from .common import InputError, _assignments

    fixed = _assignments(
        "--fix", args.fix, {"period": "period=0.8", "step_length": "step_length=0.3"}
    )
    for name, (item, value) in fixed.items():
        if name not in FIXABLE:
            raise InputError(
                f"--fix {item}: {name!r} cannot be fixed; {did_you_mean(name, FIXABLE)}"
                f"choose from {', '.join(FIXABLE)}, e.g. --fix period=0.8"
            )
        if not value > 0:
            raise InputError(f"--fix {item}: must be positive, e.g. --fix {name}=0.8")
    bounds: dict[str, Any] = {  # the model's finite declared bounds (applied anyway)
        n: float(hi) if lo == -hi else (float(lo), float(hi))
        for n, (lo, hi) in model.input_bounds.items()
        if math.isfinite(lo) and math.isfinite(hi)
    }
    inputs, states = bounds_of(args.bound, model)
    bounds.update(inputs)
    state_bounds = {**dict(model.state_bounds), **states}
    paths = constrain(args.constrain, model)
    if paths and args.library is not None:
        raise InputError(
            f"--constrain {paths[0]}: a --library does not take path constraints yet; "
            f"drop --constrain or --library"
        )
    if args.max_roughness is not None and args.max_multiplier is None:
        raise InputError(
            f"--max-roughness {args.max_roughness:g} applies with --max-multiplier; add "
            f"--max-multiplier 1 or drop --max-roughness"
        )
    if args.max_multiplier is not None and args.library is not None:
        raise InputError(
            f"--max-multiplier {args.max_multiplier:g}: a --library does not take the bound "
            f"yet; drop --max-multiplier or --library"
        )
    free = tuple(args.free or ())
    for name in free:
        if name not in model.params:
            raise InputError(
                f"--free {name}: {model.name} has no parameter {name!r}; "
                f"{did_you_mean(name, model.params)}parameters: {', '.join(model.params)}"
            )
    return {
        **{name: value for name, (_, value) in fixed.items()},
        "bounds": bounds,
        "state_bounds": state_bounds,
        **({"path_constraints": paths} if paths else {}),
        "free": free,
        "tol": args.tol,
        **({"max_multiplier": args.max_multiplier} if args.max_multiplier is not None else {}),
        **({"max_roughness": args.max_roughness} if args.max_roughness is not None else {}),
    }


def constrain(items: list[str] | None, model: Any) -> tuple[str, ...]:
    """``--constrain LIMIT``: limits the model declares (``Phase.limits``), each once."""
    from ..optimize.problem import declared_limits
    from .common import InputError

    declared = declared_limits(model)
    names: list[str] = []
    for item in items or ():
        name = item.strip()
        if name not in declared:
            have = (
                f"its limits: {', '.join(declared)}"
                if declared
                else "it declares none (Phase.limits)"
            )
            raise InputError(
                f"--constrain {item}: {model.name} has no limit {name!r}; "
                f"{did_you_mean(name, declared) if declared else ''}{have}"
            )
        if name not in names:
            names.append(name)
    return tuple(names)


def bounds_of(items: list[str] | None, model: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """``--bound INPUT=MAX`` (``|u| <= MAX``; 0 switches the input off) or ``INPUT=LOW:HIGH``;
    ``--bound STATE=LOW:HIGH`` (an empty side: unbounded there) or ``STATE=MAX``: the input
    bounds and the state bounds."""
    from ..optimize.problem import all_state_names
    from .common import InputError, _number, _split

    states = all_state_names(model)
    examples = {n: f"{n}=10" for n in model.inputs} or {"INPUT": "INPUT=10"}
    examples.update({n: f"{n}=-1:1" for n in states})
    bounds: dict[str, Any] = {}
    state_bounds: dict[str, tuple[float, float]] = {}
    for item in items or ():
        name, text = _split("--bound", item, examples)
        if name not in model.inputs and name in states:
            state_bounds[name] = state_bound(item, name, text)
            continue
        if name not in model.inputs:
            raise InputError(
                f"--bound {item}: {model.name} has no input or state {name!r}; "
                f"{did_you_mean(name, (*model.inputs, *states))}inputs: "
                f"{', '.join(model.inputs) or 'none'}; states: {', '.join(states)}"
            )
        example = f"--bound {name}=10 (|u| <= 10), {name}=0 (off) or {name}=0:10"
        if ":" in text:
            low_text, _, high_text = text.partition(":")
            low = _number("--bound", item, low_text.strip(), f"{name}=0:10")
            high = _number("--bound", item, high_text.strip(), f"{name}=0:10")
            if not low <= high:
                raise InputError(f"--bound {item}: LOW must not exceed HIGH; e.g. {example}")
            bounds[name] = (low, high)
        else:
            value = _number("--bound", item, text, f"{name}=10")
            if not value >= 0:
                raise InputError(f"--bound {item}: the bound must be >= 0; e.g. {example}")
            bounds[name] = value
    return bounds, state_bounds


def state_bound(item: str, name: str, text: str) -> tuple[float, float]:
    """``--bound STATE=LOW:HIGH`` (LOW < HIGH; an empty side is unbounded) or ``STATE=MAX``
    (``|x| <= MAX``, MAX > 0)."""
    from .common import InputError, _number

    example = f"--bound {name}=-0.5:0.5 (-0.5 <= {name} <= 0.5), {name}=0: or {name}=0.5"
    if ":" not in text:
        value = _number("--bound", item, text, f"{name}=0.5")
        if not value > 0:
            raise InputError(f"--bound {item}: a state's MAX must be > 0; e.g. {example}")
        return -value, value
    low_text, _, high_text = (part.strip() for part in text.partition(":"))
    if not low_text and not high_text:
        raise InputError(f"--bound {item}: give LOW, HIGH or both; e.g. {example}")
    low = _number("--bound", item, low_text, f"{name}=-0.5:0.5") if low_text else -math.inf
    high = _number("--bound", item, high_text, f"{name}=-0.5:0.5") if high_text else math.inf
    if not low < high:
        raise InputError(
            f"--bound {item}: a state's LOW must be below its HIGH (got {low:g} >= {high:g}); "
            f"e.g. {example}"
        )
    return low, high


def lqr_weights(args: argparse.Namespace) -> dict[str, Any]:
    """``--q``/``--r`` as :func:`gaitopt.optimize.stabilise` weights (only with --stabilise)."""
    from .common import InputError, _numbers

    q, r = _numbers("--q", args.q), _numbers("--r", args.r)
    for option, value in (("--q", q), ("--r", r), ("--orbits", args.orbits != 20 or None)):
        if value is not None and not args.stabilise:
            raise InputError(f"{option} applies with --stabilise; add --stabilise")
    if args.stabilise and args.library is not None:
        raise InputError("--stabilise applies to one optimum, not a --library; drop one of them")
    weights: dict[str, Any] = {}
    for name, value in (("Q", q), ("R", r)):
        if value is not None:
            if any(v < 0 for v in value) or (name == "R" and any(v <= 0 for v in value)):
                option = f"--{name.lower()}"
                raise InputError(
                    f"{option} {getattr(args, name.lower())}: weights must be "
                    f"{'positive' if name == 'R' else 'non-negative'}, e.g. {option} 1"
                )
            weights[name] = value if len(value) > 1 else value[0]
    return weights


# -- the text output (``gaitopt optimize`` without --json) ----------------------------------
