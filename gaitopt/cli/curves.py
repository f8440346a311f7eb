"""``gaitopt continue ... --follow PD|LP|NS|boundary --param2 Q --to2 Y``: two-parameter curves.

::

    gaitopt continue MODEL --param P --to X --follow PD|LP|NS|boundary --param2 Q --to2 Y
                           [--set ...] [--guess ...] [--steps K] [--json] [--out DIR]

starts from the first special point of that kind on the branch in ``P`` (continued towards
``X``), then follows it in ``(P, Q)`` until ``Q`` reaches ``Y`` exactly or the curve ends
(:func:`gaitopt.bifurcation_curve`).  ``--json`` prints ``model``, ``params``, ``kind``,
``param``, ``param2``, ``points`` (both parameter values by name, ``period``, ``fixed_point``,
``multipliers``) and ``special_points``; ``--out DIR`` writes curve.json, curve.csv and
curve.png.  Exit status 0 curve followed, 1 no curve (JSON still printed), 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..curves import CURVE_KINDS, Curve, bifurcation_curve
from ..curves.paths import ParameterPath
from ..errors import GuessError, ParameterError
from ..parameters import check_parameter
from .common import (
    EXIT_BAD_INPUT,
    EXIT_NOT_FOUND,
    EXIT_OK,
    InputError,
    _echo,
    _number,
    build_model,
    parse_guess,
)
from .output import (
    _print_json,
    _solver_output_to_stderr,
    print_header,
    write_outputs,
    write_result,
)

__all__ = ["add_curve_arguments", "wants_curve", "run_curve"]


def add_curve_arguments(parser: argparse.ArgumentParser) -> None:
    """``--follow``, ``--param2``, ``--to2`` of ``gaitopt continue``."""
    parser.add_argument(
        "--follow",
        choices=CURVE_KINDS,
        help="follow the first special point of this kind in two parameters (needs --param2, "
        "--to2)",
    )
    parser.add_argument("--param2", metavar="NAME", help="second parameter of --follow")
    parser.add_argument("--to2", metavar="VALUE", help="value of --param2 to follow the curve to")


def wants_curve(args: argparse.Namespace) -> bool:
    """Whether any of the curve options was given."""
    return any(getattr(args, k, None) is not None for k in ("follow", "param2", "to2"))


def run_curve(args: argparse.Namespace) -> int:
    """``gaitopt continue --follow``: validate, follow the curve, print or write it."""
    if args.follow is None:
        given = "--param2" if args.param2 is not None else "--to2"
        value = args.param2 if args.param2 is not None else args.to2
        raise InputError(
            f"{given} {value}: applies only with --follow PD|LP|NS|boundary; e.g. --follow PD "
            f"--param2 NAME --to2 VALUE"
        )
    if args.param2 is None or args.to2 is None:
        missing = "--param2 NAME" if args.param2 is None else "--to2 VALUE"
        raise InputError(
            f"--follow {args.follow}: needs {missing} (the second parameter and where to follow "
            f"the curve to), e.g. --follow {args.follow} --param2 mass_hip --to2 12"
        )
    if args.both:
        raise InputError(
            f"--both: does not apply with --follow {args.follow} (the curve runs from the first "
            f"{args.follow} point towards --to2); drop --both"
        )
    from .optimal_file import optimal_from_args

    optimal = optimal_from_args(args)  # --optimal FILE: its open loop, the profile held fixed
    model = optimal.model if optimal is not None else build_model(args.model, args.set)
    specs = {s.name: s for s in model.parameter_specs()}
    for option, name in (("--param", args.param), ("--param2", args.param2)):
        try:
            ParameterPath.of(model, name)  # a known, real-valued parameter
        except ParameterError as exc:
            raise InputError(f"{option} {name}: {exc}; choose a real parameter") from None
    if args.param2 == args.param:
        raise InputError(
            f"--param2 {args.param2}: must differ from --param {args.param}; choose another "
            f"parameter, e.g. one of {', '.join(n for n in specs if n != args.param)}"
        )
    to = _number("--to", args.to, args.to, f"{specs[args.param].default:g}")
    to2 = _number("--to2", args.to2, args.to2, f"{specs[args.param2].default:g}")
    for option, text, name, value in (
        ("--to", args.to, args.param, to),
        ("--to2", args.to2, args.param2, to2),
    ):
        try:
            check_parameter(model.name, specs[name], value)
        except ParameterError as exc:
            raise InputError(f"{option} {text}: {exc}") from None
        if value == getattr(model, name):
            raise InputError(
                f"{option} {text}: equals the start value of `{name}`; give another value"
            )
    guess = parse_guess(model, args.guess)
    try:
        with _solver_output_to_stderr():
            curve = bifurcation_curve(
                model if optimal is None else optimal,
                args.follow,
                args.param,
                args.param2,
                to=to2,
                param_to=to,
                start=guess,
                steps=args.steps,
            )
    except GuessError as exc:
        raise InputError(f"{_echo('--guess', args.guess or ()) or '--guess'}: {exc}") from None
    except ParameterError as exc:
        raise InputError(
            f"--param {args.param} --param2 {args.param2} --to2 {args.to2}: {exc}"
        ) from None
    lost = write_outputs(args.out, lambda folder: write_curve(curve, folder))
    if args.json:
        _print_json(curve.as_dict())
    else:
        print_curve(curve)
    if lost is not None:  # --out failed after the run: said on stderr, the curve printed anyway
        print(lost, file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_OK if curve.success else EXIT_NOT_FOUND


def write_curve(curve: Curve, folder: Path) -> None:
    """curve.json, curve.csv and curve.png in ``folder`` (each written atomically)."""
    from ..curves.plot import plot_curve

    write_result(curve, folder, "curve", plot_curve)


def print_curve(curve: Curve) -> None:
    """The curve as text: a header, the points, the special points."""
    print_header(curve, ("kind", curve.kind), ("condition", curve.condition))
    if curve.start is not None:
        print(f"start       {curve.start.kind} at {curve.param} = {curve.start.param:.10f}")
    if curve.cycles:
        print(f"{curve.param:>16} {curve.param2:>16} {'period':>12}  max |μ|")
        for (a, b), c in zip(curve.params, curve.cycles, strict=True):
            print(f"{a:16.10f} {b:16.10f} {c.period:12.8f}  {max(abs(c.multipliers)):.6f}")
    for sp in curve.special_points:
        where = ", ".join(f"{k} = {v:.10f}" for k, v in sp.values.items())
        print(f"    {sp.kind:<14}{where}   {sp.message}")
