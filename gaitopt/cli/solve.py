"""``gaitopt solve``: a gait by multiple shooting, with its multipliers (and a multi-start)."""

from __future__ import annotations

import argparse

from ..errors import (
    GuessError,
)
from ..result import LimitCycle
from ..shooting import find_limit_cycle
from .common import (
    EXIT_NOT_FOUND,
    EXIT_OK,
    InputError,
    _count,
    _echo,
    _gait_arguments,
    _model_arguments,
    _scheduler_address,
    build_model,
    parse_guess,
)
from .output import (
    _print_json,
    _print_rows,
    _solver_output_to_stderr,
    print_fixed_point,
    print_header,
    print_multipliers,
    with_unit,
)


def _solve_arguments(parser: argparse.ArgumentParser) -> None:
    _model_arguments(parser)
    _gait_arguments(parser)
    parser.add_argument(
        "--method",
        choices=("newton", "ipopt"),
        default="newton",
        help="Newton rootfinder on the shooting equations (default) or IPOPT",
    )
    parser.add_argument(
        "--starts",
        type=_count(1),
        default=1,
        metavar="N",
        help="also run a seeded multi-start search from N starts around the default start and "
        "list every distinct gait found, with its stability (default 1: none)",
    )
    parser.add_argument(
        "--seed", type=_count(0), default=0, help="seed of the multi-start sample (default 0)"
    )
    parser.add_argument(
        "--scheduler",
        type=_scheduler_address,
        default=None,
        metavar="ADDRESS",
        help="run the multi-start on Dask: 'local' or a scheduler address (default: serial)",
    )


def _print_cycle(cycle: LimitCycle) -> None:
    model = cycle.model
    print_header(cycle)
    if not cycle.success:
        return
    period = with_unit(f"{cycle.period:.10g}", model.time_unit)
    _print_rows([("period", f"{period} ({cycle.steps} step(s) per orbit)")])
    print_fixed_point(model, cycle.fixed_point)
    print_multipliers(cycle.multipliers)
    _print_rows([("stable", cycle.stable), ("verified", cycle.verified)])
    if cycle.route:
        _print_rows([("route", cycle.route)])
    if cycle.gaits:
        print(f"distinct gaits of the multi-start ({len(cycle.gaits)})")
        for k, gait in enumerate(cycle.gaits, start=1):
            mods = ", ".join(f"{abs(complex(*z)):.6f}" for z in gait["multipliers"])
            where = ", ".join(f"{n}={v:.8g}" for n, v in gait["fixed_point"].items())
            kind = "stable" if gait["stable"] else "unstable"
            print(
                f"    {k}. period {gait['period']:.10g}  |λ| = [{mods}]  {kind}  "
                f"({gait['starts']} start(s))  {where}"
            )


def run_solve(args: argparse.Namespace) -> int:
    """``gaitopt solve``: find a gait by multiple shooting, with its multipliers."""
    model = build_model(args.model, args.set)
    guess = parse_guess(model, args.guess)
    try:
        with _solver_output_to_stderr():
            cycle = find_limit_cycle(
                model,
                guess,
                steps=args.steps,
                method=args.method,
                starts=args.starts,
                seed=args.seed,
                scheduler=args.scheduler,
            )
    except GuessError as exc:
        raise InputError(f"{_echo('--guess', args.guess or ()) or '--guess'}: {exc}") from None
    except OSError as exc:  # a Dask scheduler that cannot be reached
        if args.scheduler in (None, "local"):
            raise
        raise InputError(f"--scheduler {args.scheduler}: cannot reach it ({exc})") from None
    if args.json:
        _print_json(cycle.as_dict())
    else:
        _print_cycle(cycle)
    return EXIT_OK if cycle.success else EXIT_NOT_FOUND
