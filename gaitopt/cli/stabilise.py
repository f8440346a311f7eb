"""``gaitopt stabilise``: stabilise a gait's orbit by transverse LQR.

::

    gaitopt stabilise MODEL --transverse [--set NAME=VALUE ...] [--guess STATE=VALUE ...]
                          [--steps K] [--cost effort|work|cot] [--fix NAME=VALUE ...]
                          [--bound NAME=LOW:HIGH ...] [--tol TOL] [--q Q] [--r R] [--orbits N]
                          [--perturbation A] [--survival K] [--compare] [--json]

The gait is the model's passive gait (``gaitopt solve``'s options: ``--guess``, ``--steps``)
or, with ``--cost``, ``--fix`` or ``--bound``, its optimum (``gaitopt optimize``'s options and
their parsing).  ``--q`` weighs the state error (a number, or the diagonal over phase 0's
states, comma-separated), ``--r`` the input correction (a positive number or diagonal).
``--survival K`` adds the largest survived perturbation along each section coordinate (K
bisection steps up to 0.2, every probe simulated); ``--compare`` (an optimum only) also designs
step-to-step LQR (:func:`gaitopt.optimize.stabilise`, its default weights) and compares both.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

import numpy as np

from ..errors import GaitoptInputError

__all__ = ["HELP", "add_arguments", "run"]

HELP = "stabilise a gait's orbit by transverse LQR (continuous feedback along the orbit)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``gaitopt stabilise``."""
    from .common import _count, _gait_arguments, _model_arguments
    from .optimize import _tolerance

    _model_arguments(parser)
    _gait_arguments(parser)
    parser.add_argument(
        "--transverse",
        action="store_true",
        help="transverse LQR along the orbit (Manchester et al. 2011; the method available)",
    )
    parser.add_argument(
        "--cost",
        choices=("effort", "work", "cot"),
        default=None,
        help="stabilise the optimum of this cost (as gaitopt optimize) instead of the passive gait",
    )
    parser.add_argument(
        "--fix", action="append", metavar="NAME=VALUE", help="as gaitopt optimize (implies --cost)"
    )
    parser.add_argument(
        "--bound", action="append", metavar="NAME=LOW:HIGH", help="as gaitopt optimize"
    )
    parser.add_argument("--tol", type=_tolerance, default=1e-8, metavar="TOL", help="as optimize")
    parser.add_argument(
        "--q", metavar="Q", help="state weight: a number or phase 0's diagonal (default 1)"
    )
    parser.add_argument(
        "--r", metavar="R", help="input weight: a positive number or diagonal (default 1)"
    )
    parser.add_argument(
        "--orbits",
        type=_count(1, 1000, "each orbit is simulated for every perturbed start"),
        default=15,
        help="orbits simulated from each perturbed start (default 15)",
    )
    parser.add_argument(
        "--perturbation",
        type=float,
        default=1e-2,
        metavar="A",
        help="each section coordinate displaced by ±A to start the runs (default 0.01)",
    )
    parser.add_argument(
        "--survival",
        type=_count(0, 20, "each bisection step simulates every direction once more"),
        default=0,
        metavar="K",
        help="bisection steps for the largest survived perturbation per direction (default 0)",
    )
    parser.add_argument(
        "--compare", action="store_true", help="also step-to-step LQR on the optimum, compared"
    )
    parser.set_defaults(constrain=None, library=None, free=None)


def _weights(args: argparse.Namespace, model: Any) -> dict[str, Any]:
    from .common import InputError, _numbers

    weights: dict[str, Any] = {}
    for option, name in (("--q", "Q"), ("--r", "R")):
        value = _numbers(option, getattr(args, name.lower()))
        if value is not None:
            weights[name] = value[0] if len(value) == 1 else value
    if not np.isfinite(args.perturbation) or not 0 < args.perturbation <= 0.5:
        raise InputError(
            f"--perturbation {args.perturbation}: must be in (0, 0.5] (section units); "
            f"e.g. --perturbation 0.01"
        )
    if not model.inputs:
        raise InputError(
            f"{args.model}: the model has no inputs, so nothing can stabilise it; choose a model "
            f"with one (compass_gait, kneed_walker)"
        )
    return weights


def run(args: argparse.Namespace) -> int:
    """``gaitopt stabilise``: the gait, its transverse LQR, the checks (and the comparison)."""
    import time

    from ..optimize import optimize_gait
    from ..shooting import find_limit_cycle
    from ..transverse import transverse_lqr
    from ..transverse.design import check_weights
    from .common import EXIT_NOT_FOUND, EXIT_OK, InputError, build_model, parse_guess
    from .optimize import _parse
    from .optimize_advice import for_the_cli
    from .output import _solver_output_to_stderr

    model = build_model(args.model, args.set)
    if not args.transverse:
        raise InputError(
            "gaitopt stabilise: give --transverse (transverse LQR, the method available); for "
            "step-to-step LQR use gaitopt optimize --stabilise or gaitopt control --kind lqr"
        )
    weights = _weights(args, model)
    try:
        check_weights(model, weights.get("Q"), weights.get("R"))
    except GaitoptInputError as exc:
        option = "--q" if str(exc).startswith("`Q`") else "--r"
        raise InputError(f"{option} {getattr(args, option[2:])}: {exc}") from None
    optimal = args.cost is not None or bool(args.fix) or bool(args.bound)
    guess = parse_guess(model, args.guess)  # checked before any work, whichever gait
    if optimal and args.guess:
        raise InputError(
            f"--guess {args.guess[0]}: a guess applies to the passive gait; drop it, or drop "
            f"--cost/--fix/--bound"
        )
    if optimal:
        options = _parse(args, model)
    if args.compare and not optimal:
        raise InputError(
            "--compare needs an optimum (step-to-step LQR acts on an optimum's offset); add "
            "--cost effort --fix period=... or drop --compare"
        )
    clock = time.perf_counter()
    try:
        with _solver_output_to_stderr():
            if optimal:
                gait = optimize_gait(model, args.cost or "effort", steps=args.steps, **options)
            else:
                gait = find_limit_cycle(model, guess, steps=args.steps)
    except GaitoptInputError as exc:
        raise InputError(for_the_cli(str(exc))) from None
    gait_s = time.perf_counter() - clock
    report: dict[str, Any] = {
        "model": model.name,
        "params": model.params,
        "gait": {
            "kind": "optimal gait" if optimal else "limit cycle",
            "success": gait.success,
            "message": gait.message,
            "fixed_point": gait.fixed_point,
            "multipliers": [[float(z.real), float(z.imag)] for z in np.asarray(gait.multipliers)],
        },
    }
    if not gait.success:
        report.update(success=False, message=f"no gait to stabilise: {gait.message}")
        _out(args, report)
        return EXIT_NOT_FOUND
    with _solver_output_to_stderr():
        result = transverse_lqr(gait, **weights, orbits=args.orbits, perturbation=args.perturbation)
    report.update(result.to_json())
    report["timings"] = {"gait_s": gait_s, **report["timings"]}
    if args.survival or args.compare:
        report["comparison"] = _compare(args, gait, result)
    _out(args, report)
    return EXIT_OK if result.success else EXIT_NOT_FOUND


def _compare(args: argparse.Namespace, gait: Any, result: Any) -> list[dict[str, Any]]:
    from ..transverse.compare import compare, step_to_step_runner, transverse_runner

    controllers = {
        "transverse LQR": (
            transverse_runner(gait, result.law, args.orbits),
            result.closed_loop_multipliers,
        )
    }
    if args.compare:
        from ..optimize import stabilise

        step = stabilise(gait, orbits=args.orbits)
        controllers["step-to-step LQR"] = (
            step_to_step_runner(gait, step.gain, args.orbits),
            step.closed_loop_multipliers,
        )
    return compare(gait, controllers, iterations=args.survival)


def _out(args: argparse.Namespace, report: dict[str, Any]) -> None:
    from .output import _print_json

    if args.json:
        _print_json(report)
        return
    lines = [
        f"model        {report['model']}",
        f"gait         {report['gait']['kind']}: {report['gait']['message']}",
        f"success      {report.get('success')}",
        f"message      {report.get('message')}",
    ]
    for key in (
        "open_loop_multipliers",
        "closed_loop_multipliers",
        "measured_closed_loop_multipliers",
    ):
        if key in report:
            values = ", ".join(f"{complex(re, im):.6g}" for re, im in report[key])
            lines.append(f"{key.replace('_', ' ')}: {values}")
    for row in report.get("comparison", ()):
        survived = ", ".join(
            f"{s['coordinate']}{'+' if s['sign'] > 0 else '-'} {s['survived']:.4g}"
            for s in row["survived"]
        )
        lines.append(
            f"{row['controller']}: |λ|max {row['largest_modulus']:.4g}; survived {survived}"
        )
    print("\n".join(lines), file=sys.stdout)
