"""The options of ``gaitopt optimize`` (:func:`add_arguments`) and their argparse types."""

from __future__ import annotations

import argparse
import math
from typing import Any

__all__ = ["add_arguments", "bound_value", "tolerance"]


def tolerance(text: str) -> float:
    """An argparse ``type`` for ``--tol``: a positive finite number."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(
            f"expected a positive relative error, got {text!r}; e.g. --tol 1e-6"
        )
    return value


def bound_value(option: str, example: str) -> Any:
    """An argparse ``type`` for ``--max-multiplier`` and ``--max-roughness``: a positive finite
    number."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(
                f"expected a positive finite number, got {text!r}; e.g. {option} {example}"
            )
        return value

    return parse


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``gaitopt optimize``: the problem, the solver, what follows."""
    from .common import _model_arguments

    _model_arguments(parser)
    problem_arguments(parser)
    solver_arguments(parser)
    after_arguments(parser)


def problem_arguments(parser: argparse.ArgumentParser) -> None:
    """The statement: cost, fixed quantities, bounds, path constraints, free parameters."""
    parser.add_argument(
        "--cost",
        choices=("effort", "work", "cot"),
        default="effort",
        help="∫Σu² dt (default), positive actuator work, or cost of transport",
    )
    parser.add_argument(
        "--fix",
        action="append",
        metavar="NAME=VALUE",
        help="fix period=S (s), step_length=M (m) or speed=V (m/s); repeatable",
    )
    parser.add_argument(
        "--bound",
        action="append",
        metavar="NAME=LOW:HIGH",
        help="INPUT=MAX: |INPUT| <= MAX at every collocation point (input units; 0 switches the "
        "input off), INPUT=LOW:HIGH; or STATE=LOW:HIGH (STATE=MAX: |STATE| <= MAX), a joint or "
        "rate limit in state units; repeatable",
    )
    parser.add_argument(
        "--constrain",
        action="append",
        metavar="LIMIT",
        help="impose a path constraint the model declares, e.g. knee_flexion (five_link_biped, "
        "kneed_walker: knees that do not hyperextend); repeatable",
    )
    parser.add_argument(
        "--free", action="append", metavar="PARAM", help="optimise this parameter too"
    )


def solver_arguments(parser: argparse.ArgumentParser) -> None:
    """Steps, multi-start, tolerance, the spectral bound and where the starts run."""
    from ..optimize.problem import MAX_STEPS
    from ..optimize.solve import MAX_SEED, MAX_STARTS
    from .common import _count, _scheduler_address

    why_steps = (
        "the transcription grows faster than the number of steps (the five-link biped: 9 GB at "
        f"4); use --steps {MAX_STEPS} or fewer"
    )
    why_starts = (
        "each start is a full solve (1-3 s on the five-link biped) and each minimum it finds is "
        f"refined and simulated; use --starts {MAX_STARTS} or fewer, or several runs with other "
        f"--seed values"
    )
    parser.add_argument(
        "--steps",
        type=_count(1, MAX_STEPS, why_steps),
        default=1,
        metavar="K",
        help=f"steps per orbit (default 1, at most {MAX_STEPS})",
    )
    parser.add_argument(
        "--starts",
        type=_count(1, MAX_STARTS, why_starts),
        default=1,
        metavar="N",
        help=f"seeded multi-start (default 1, at most {MAX_STARTS})",
    )
    parser.add_argument(
        "--seed",
        type=_count(0, MAX_SEED, "seeds are non-negative 64-bit integers; e.g. --seed 0"),
        default=0,
        metavar="S",
        help="seed of the multi-start (default 0)",
    )
    parser.add_argument(
        "--tol",
        type=tolerance,
        default=1e-8,
        metavar="TOL",
        help="target of the relative discretisation error of cost and orbit under mesh "
        "refinement, a positive number (default 1e-8)",
    )
    parser.add_argument(
        "--max-multiplier",
        type=bound_value("--max-multiplier", "1"),
        metavar="R",
        help="bound the spectral radius of the return map's Jacobian, |multiplier| <= R, inside "
        "the optimisation (R < 1: open-loop stable by design)",
    )
    parser.add_argument(
        "--max-roughness",
        type=bound_value("--max-roughness", "120"),
        metavar="S",
        help="with --max-multiplier: bound on the integral of the squared input rates over the "
        "orbit ((input unit)^2/s; default: twice that of the optimum without the bound)",
    )
    parser.add_argument(
        "--scheduler",
        type=_scheduler_address,
        default=None,
        metavar="ADDRESS",
        help="run the --starts (or the --library's cold checks) on Dask: 'local' or a scheduler "
        "address (default: serial)",
    )


def after_arguments(parser: argparse.ArgumentParser) -> None:
    """What follows the optimum: its stabilisation, a library, the output directory."""
    from .common import _count

    parser.add_argument(
        "--stabilise",
        action="store_true",
        help="stabilise the optimum by an input offset per step (LQR) and simulate the closed loop",
    )
    parser.add_argument(
        "--q", metavar="Q", help="--stabilise: LQR state weight, a number or a diagonal (default 1)"
    )
    parser.add_argument(
        "--r", metavar="R", help="--stabilise: LQR offset weight, a number or a diagonal (1e-3)"
    )
    parser.add_argument(
        "--orbits",
        type=_count(1, 1000, "each orbit is simulated for every perturbed start"),
        default=20,
        help="--stabilise: orbits simulated from each perturbed state (default 20)",
    )
    parser.add_argument(
        "--library",
        metavar="NAME=FIRST:LAST:COUNT",
        help="continue the optimum in period, step_length, speed or a parameter over COUNT "
        "values, e.g. step_length=0.2:0.5:7",
    )
    parser.add_argument(
        "--cold",
        type=_count(0, 200, "a library has at most 200 points (--library ...:COUNT)"),
        default=2,
        help="--library: points checked against cold starts (default 2)",
    )
    parser.add_argument("--out", metavar="DIR", help="write JSON, CSV and figures to DIR")
