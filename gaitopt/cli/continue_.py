"""``gaitopt continue``: a gait followed through a parameter; special points and cascades."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ..continuation import DEFAULT_MAX_PERIOD, Branch, PseudoArclength, continuation
from ..errors import (
    MAX_ORBIT_STEPS,
    GaitoptInputError,
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
        default=DEFAULT_MAX_PERIOD,
        metavar="K",
        help=f"deepest period of the period-doubling cascade (default {DEFAULT_MAX_PERIOD}, at "
        f"most {MAX_ORBIT_STEPS})",
    )
    # The step control (gaitopt.PseudoArclength), for branches that need smaller steps.
    defaults = PseudoArclength()
    steps = parser.add_argument_group("step control (pseudo-arclength)")
    for flag, dest, what in (
        ("--step", "step", "first arclength step"),
        ("--min-step", "min_step", "smallest step before the branch is given up"),
        ("--max-step", "max_step", "largest step (smaller: special points found more surely)"),
    ):
        steps.add_argument(
            flag,
            dest=f"arclength_{dest}",
            metavar="H",
            default=None,
            help=f"{what} (scaled units; default {getattr(defaults, dest):g})",
        )
    steps.add_argument(
        "--max-points",
        dest="arclength_max_points",
        type=_count(1, MAX_BRANCH_POINTS, "points per branch direction"),
        default=None,
        metavar="N",
        help=f"most points per branch direction (default {defaults.max_points}, at most "
        f"{MAX_BRANCH_POINTS})",
    )
    parser.add_argument(
        "--bounds",
        metavar="LOW:HIGH",
        default=None,
        help="parameter interval the branch stays in (default: the parameter's valid range)",
    )
    parser.add_argument(
        "--out",
        metavar="DIR",
        help="write branch.json, branch.csv and branch.png to DIR (with --follow: curve.*)",
    )
    from .curves import add_curve_arguments  # two-parameter curves (--follow)
    from .optimal_file import add_optimal_argument

    add_curve_arguments(parser)
    add_optimal_argument(parser)


def run_continue(args: argparse.Namespace) -> int:
    """``gaitopt continue``: follow a gait through a parameter; special points; cascades."""
    from .curves import run_curve, wants_curve
    from .optimal_file import optimal_from_args

    if wants_curve(args):  # --follow: a special point in two parameters
        return run_curve(args)
    optimal = optimal_from_args(args)  # --optimal FILE: its open loop, the profile held fixed
    model = optimal.model if optimal is not None else build_model(args.model, args.set)
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
    options = _arclength_options(args)
    bounds = _bounds(args.bounds, args.param, float(getattr(model, args.param)))
    try:
        with _solver_output_to_stderr():
            branch = continuation(
                model if optimal is None else optimal,
                args.param,
                to=to,
                start=guess,
                steps=args.steps,
                both_directions=args.both,
                cascade=not args.no_cascade,
                max_period=args.max_period,
                options=options,
                bounds=bounds,
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


#: The most points per branch direction the CLI accepts (each is a certified, simulated gait).
MAX_BRANCH_POINTS = 10_000


def _arclength_options(args: argparse.Namespace) -> PseudoArclength:
    """``--step/--min-step/--max-step/--max-points`` as :class:`PseudoArclength` (defaults for
    those not given); a value it refuses is an :class:`InputError` naming the option."""
    given = {
        name: _number(f"--{name.replace('_', '-')}", text, text, "0.01")
        for name in ("step", "min_step", "max_step")
        if (text := getattr(args, f"arclength_{name}")) is not None
    }
    if args.arclength_max_points is not None:
        given["max_points"] = args.arclength_max_points
    if "step" not in given:  # the default first step, kept inside the bounds given
        default = PseudoArclength().step
        given_lo, given_hi = given.get("min_step", 0.0), given.get("max_step", math.inf)
        if not given_lo <= default <= given_hi:
            given["step"] = min(max(default, given_lo), given_hi)
    try:
        return PseudoArclength(**given)
    except GaitoptInputError as exc:
        echo = " ".join(f"--{k.replace('_', '-')} {v:g}" for k, v in given.items())
        raise InputError(f"{echo}: {exc}; the defaults are {PseudoArclength()}") from None


def _bounds(text: str | None, param: str, start: float) -> tuple[float, float] | None:
    """``--bounds LOW:HIGH`` as a pair that contains the start value."""
    if text is None:
        return None
    parts = text.split(":")
    if len(parts) != 2:
        raise InputError(f"--bounds {text}: expected LOW:HIGH, e.g. --bounds 0.45:0.6")
    lo, hi = (_number("--bounds", text, part, "0.45:0.6") for part in parts)
    if not lo < start < hi:
        raise InputError(
            f"--bounds {text}: the interval must contain the start value {param} = {start:g}, "
            f"with LOW < HIGH"
        )
    return lo, hi


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
            if sp.switch:
                print(f"             {sp.switch}")
