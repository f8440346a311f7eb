"""``gaitopt continue``: a gait followed through a parameter; special points and cascades."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..continuation import Branch, continuation
from ..errors import (
    MAX_ORBIT_STEPS,
    GuessError,
    ParameterError,
    did_you_mean,
)
from ..parameters import check_parameter
from .common import (
    _ORBIT_LIMIT,
    EXIT_BAD_INPUT,
    EXIT_NOT_FOUND,
    EXIT_OK,
    InputError,
    _count,
    _echo,
    _gait_arguments,
    _model_arguments,
    _number,
    build_model,
    parse_guess,
)
from .output import _print_json, _solver_output_to_stderr, print_header, write_outputs, write_result


# -- gaitopt continue ----------------------------------------------------------------------------
def _continue_arguments(parser: argparse.ArgumentParser) -> None:
    _model_arguments(parser)
    parser.add_argument("--param", required=True, metavar="NAME", help="parameter to vary")
    parser.add_argument(
        "--to", required=True, metavar="VALUE", help="parameter value to continue to"
    )
    _gait_arguments(parser)
    parser.add_argument(
        "--both", action="store_true", help="also continue away from --to, to the range's end"
    )
    parser.add_argument(
        "--no-cascade",
        action="store_true",
        help="do not switch to the period-2k branches at period doublings",
    )
    parser.add_argument(
        "--max-period",
        type=_count(1, MAX_ORBIT_STEPS, _ORBIT_LIMIT),
        default=8,
        metavar="K",
        help=f"deepest period of the period-doubling cascade (default 8, at most "
        f"{MAX_ORBIT_STEPS})",
    )
    parser.add_argument(
        "--out",
        metavar="DIR",
        help="write branch.json, branch.csv and branch.png to DIR (with --follow: curve.*)",
    )
    from .curves import add_curve_arguments  # two-parameter curves (--follow)

    add_curve_arguments(parser)


def run_continue(args: argparse.Namespace) -> int:
    """``gaitopt continue``: follow a gait through a parameter; special points; cascades."""
    from .curves import run_curve, wants_curve

    if wants_curve(args):  # --follow: a special point in two parameters
        return run_curve(args)
    model = build_model(args.model, args.set)
    specs = {s.name: s for s in model.parameter_specs()}
    if args.param not in specs:
        raise InputError(
            f"--param {args.param}: {model.name} has no parameter {args.param!r}; "
            f"{did_you_mean(args.param, specs)}parameters: {', '.join(specs)}"
        )
    to = _number("--to", args.to, args.to, f"{specs[args.param].default:g}")
    try:
        check_parameter(model.name, specs[args.param], to)
    except ParameterError as exc:
        raise InputError(f"--to {args.to}: {exc}") from None
    guess = parse_guess(model, args.guess)
    try:
        with _solver_output_to_stderr():
            branch = continuation(
                model,
                args.param,
                to=to,
                start=guess,
                steps=args.steps,
                both_directions=args.both,
                cascade=not args.no_cascade,
                max_period=args.max_period,
            )
    except GuessError as exc:
        raise InputError(f"{_echo('--guess', args.guess or ()) or '--guess'}: {exc}") from None
    except ParameterError as exc:
        raise InputError(f"--param {args.param} --to {args.to}: {exc}") from None
    written = write_outputs(args.out, lambda folder: _write_branch(branch, folder))
    if args.json:
        _print_json(branch.as_dict())
    else:
        _print_branch(branch)
    if written is not None:
        print(written, file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_OK if branch.success else EXIT_NOT_FOUND


def _write_branch(branch: Branch, folder: Path) -> None:
    from ..plotting import plot_branch

    write_result(branch, folder, "branch", plot_branch)


def _print_branch(branch: Branch) -> None:
    print_header(branch)
    for sub in branch.descendants():
        if not sub.cycles:
            continue
        lam = sub.params
        print(
            f"period-{sub.steps} branch: {len(sub.cycles)} gaits, {branch.param} from "
            f"{lam.min():.8g} to {lam.max():.8g}; {sub.message}"
        )
        for sp in sub.special_points:
            mults = ", ".join(f"{abs(z):.6f}" for z in sp.cycle.multipliers) if sp.cycle else ""
            print(
                f"    {sp.kind:<9}{branch.param} = {sp.param:.10f}   |λ| = [{mults}]   {sp.message}"
            )
