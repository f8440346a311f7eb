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
    hzd = parser.add_argument_group(
        "virtual constraints (an actuated model with a manipulator form, e.g. three_link_walker)"
    )
    hzd.add_argument(
        "--controller",
        choices=("hzd",),
        default=None,
        help="close the loop with Bézier virtual constraints fitted to the model's gait, made "
        "hybrid invariant, with the zero dynamics' restricted map (gaitopt.hzd)",
    )
    hzd.add_argument("--degree", type=int, default=4, metavar="M",
                     help="Bézier degree of every output, 3 to 20 (default 4)")  # fmt: skip
    hzd.add_argument(
        "--phase-variable",
        action="append",
        metavar="STATE=C",
        help="θ = Σ C·STATE of configuration states (repeatable; default the model's)",
    )
    hzd.add_argument("--omega-n", type=float, default=None, metavar="W",
                     help="gain ω_n (rad/s, > 0): K_p = ω_n², K_d = 2ζω_n")  # fmt: skip
    hzd.add_argument("--zeta", type=float, default=None, metavar="Z",
                     help="damping ratio ζ (> 0)")  # fmt: skip
    hzd.add_argument("--torque-limit", type=float, default=None, metavar="NM",
                     help="refuse a gait that needs more than this |u| (N·m)")  # fmt: skip
    hzd.add_argument("--design", action="store_true",
                     help="optimise the Bézier coefficients over the zero dynamics (the model's "
                     "design problem: three_link_walker, or five_link_biped's RABBIT problem) "
                     "from --starts seeded starts and certify every distinct minimum")  # fmt: skip
    hzd.add_argument("--speed", type=float, default=None, metavar="V",
                     help="--design: average speed to keep (m/s; five_link_biped: "
                     "0.75)")  # fmt: skip
    hzd.add_argument("--spread", type=float, default=0.1, metavar="R",
                     help="--design: half-width of the starts' perturbations (rad, default "
                     "0.1)")  # fmt: skip
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
    if args.controller == "hzd":
        return _run_hzd(model, args)
    for option, used in (("--design", args.design), ("--speed", args.speed is not None),
                         ("--spread", args.spread != 0.1)):  # fmt: skip
        if used:
            raise InputError(f"{option}: only with --controller hzd (an HZD design); add "
                             f"--controller hzd or leave it out")  # fmt: skip
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


def _run_hzd(model, args: argparse.Namespace) -> int:
    """``solve --controller hzd``: the HZD gait of ``model`` (:func:`gaitopt.hzd.gait.hzd_gait`);
    every bad argument is one line naming the option (exit 2)."""
    from ..errors import GaitoptInputError
    from ..hzd.gait import hzd_gait

    unused = [
        option
        for option, used in (
            ("--guess", bool(args.guess)),
            ("--steps", args.steps != 1),
            ("--starts", args.starts != 1 and not args.design),
            ("--seed", args.seed != 0 and not args.design),
            ("--speed", args.speed is not None and not args.design),
            ("--spread", args.spread != 0.1 and not args.design),
            ("--method", args.method != "newton"),
            ("--scheduler", args.scheduler is not None),
        )
        if used
    ]
    if unused:
        raise InputError(
            f"{unused[0]}: not used with --controller hzd (the gait starts from the zero "
            f"dynamics' fixed point, one step, Newton); leave it out"
        )
    phase = None
    if args.phase_variable:
        phase = {}
        for item in args.phase_variable:
            name, sep, value = item.partition("=")
            try:
                phase[name.strip()] = float(value)
            except ValueError:
                sep = ""
            if not sep:
                raise InputError(
                    f"--phase-variable {item}: expected STATE=COEFFICIENT, e.g. stance=1"
                ) from None
    options = {
        "degree": "--degree",
        "phase_variable": "--phase-variable",
        "omega_n": "--omega-n",
        "zeta": "--zeta",
        "torque_limit": "--torque-limit",
        "model": "MODEL",
        "starts": "--starts",
        "spread": "--spread",
        "speed": "--speed",
    }
    if args.design:
        return _run_hzd_design(model, args, phase, options)
    try:
        with _solver_output_to_stderr():
            gait = hzd_gait(model, args.degree, phase_variable=phase, omega_n=args.omega_n,
                            zeta=args.zeta, torque_limit=args.torque_limit)  # fmt: skip
    except GaitoptInputError as exc:
        text = str(exc)
        key = text.split(":", 1)[0]
        option = options.get(key)
        raise InputError(
            text if option is None else f"{option}: {text.split(':', 1)[1].strip()}"
        ) from None
    if args.json:
        _print_json(gait.as_dict())
    else:
        if gait.cycle is not None:
            _print_cycle(gait.cycle)
        rm = gait.rmap
        _print_rows(
            [
                ("controller", f"hzd, degree {gait.model.degree}, ω_n = {gait.model.omega_n:g}, "
                               f"ζ = {gait.model.zeta:g}"),
                ("restricted map", f"ζ* = {rm.fixed_point}, slope δ² = {rm.slope:.8g}"),
                ("invariance residual", f"{gait.invariance_residual:.2e} rad"),
                ("max |u|", "null" if gait.max_torque is None else f"{gait.max_torque:.6g} N·m"),
                ("success", f"{gait.success}: {gait.message}"),
            ]
        )  # fmt: skip
    return EXIT_OK if gait.success else EXIT_NOT_FOUND


def _run_hzd_design(model, args: argparse.Namespace, phase, options: dict[str, str]) -> int:
    """``solve --controller hzd --design``: every distinct minimum of the model's HZD design
    problem from ``--starts`` seeded starts, each certified on the full-order closed loop
    (:func:`gaitopt.hzd.multistart.multistart_design`)."""
    from ..errors import GaitoptInputError
    from ..hzd.multistart import multistart_design

    if phase is not None:
        raise InputError("--phase-variable: --design uses the model's own phase variable; "
                         "leave it out")  # fmt: skip
    for name, value in (("--omega-n", args.omega_n), ("--zeta", args.zeta)):
        if value is not None and not value > 0:
            raise InputError(f"{name}: {value!r} must be a positive number, e.g. 10")
    try:
        with _solver_output_to_stderr():
            result = multistart_design(
                model, args.degree, starts=args.starts, seed=args.seed, spread=args.spread,
                speed=args.speed, omega_n=args.omega_n or 20.0, zeta=args.zeta,
            )  # fmt: skip
    except GaitoptInputError as exc:
        text = str(exc)
        option = options.get(text.split(":", 1)[0])
        raise InputError(
            text if option is None else f"{option}: {text.split(':', 1)[1].strip()}"
        ) from None
    ok = any(m.verified for m in result.minima)
    if args.json:
        _print_json({"model": model.name, "success": ok, "degree": args.degree,
                     **result.as_dict()})  # fmt: skip
    else:
        unit = "N²·m·s" if result.objective == "per_length" else "N²·m²·s"
        print(f"{model.name}: HZD design, degree {args.degree}, {args.starts} start(s), seed "
              f"{args.seed}: {len(result.minima)} distinct minimum/minima")  # fmt: skip
        for k, m in enumerate(result.minima, start=1):
            d = m.as_dict(result.objective)
            print(f"    {k}. cost {d['cost']:.8g} {unit}  slope {d['slope']:.7f}  speed "
                  f"{d['speed']:.6g} m/s  step {d['step_time']:.7g} s  max |u| "
                  f"{d['max_torque']:.5g} N·m  verified {d['verified']}  starts "
                  f"{', '.join(map(str, m.starts))}")  # fmt: skip
        for s in result.starts:
            if s["minimum"] is None:
                print(f"    start {s['start']}: no minimum ({s['message']})")
    return EXIT_OK if ok else EXIT_NOT_FOUND
