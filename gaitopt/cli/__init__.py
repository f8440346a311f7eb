"""The ``gaitopt`` command: list the models, find a gait, simulate a model.

::

    gaitopt list [--json]
    gaitopt solve MODEL [--set NAME=VALUE ...] [--guess STATE=VALUE ...] [--steps K]
                        [--method newton|ipopt] [--json]
    gaitopt simulate MODEL [--set NAME=VALUE ...] [--x0 STATE=VALUE ...] [--steps N]
                           [--controller lqr|acker|deadbeat|blind] [--terrain SEED:AMPLITUDE]
                           [--json]
    gaitopt control MODEL --kind lqr|acker|deadbeat [--set ...] [--guess ...] [--target ...]
                          [--q Q] [--r R] [--poles P] [--from STATE=VALUE ...] [--json]
    gaitopt continue MODEL --param NAME --to VALUE [--set ...] [--guess ...] [--steps K]
                           [--both] [--no-cascade] [--max-period K] [--step H] [--min-step H]
                           [--max-step H] [--max-points N] [--bounds LOW:HIGH] [--out DIR] [--json]
    gaitopt basin MODEL [--set ...] [--guess ...] [--rays N] [--steps N] [--samples N]
                        [--max-radius R] [--scheduler ADDRESS] [--json] [--out DIR]
    gaitopt stabilise MODEL --transverse [--set ...] [--guess ...] [--steps K] [--cost ...]
                            [--fix ...] [--bound ...] [--q Q] [--r R] [--orbits N]
                            [--perturbation A] [--survival K] [--compare] [--json]

Exit status (docs/design.md, public contract): 0 gait found / simulation completed; 1 no gait found
(the JSON is still printed, with ``success: false``) or the simulation did not complete; 2 bad
input, reported as one line on stderr that starts with ``gaitopt: error:``, names the argument,
shows the value and suggests a fix; 130 interrupted (Ctrl-C: the one line ``gaitopt:
interrupted`` on stderr, and an ``--out`` folder as it was before the run, never half-written).

Each subcommand is an entry of :data:`SUBCOMMANDS`: a function that declares its arguments and a
function that runs it.  Adding one (``continue``, ``control``) means writing those two functions
and adding the entry.

The module imports the library's submodules directly (not the package ``gaitopt``), so the
console script works however the package is installed.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import warnings
from collections.abc import Sequence

from ..errors import GaitoptInputError
from . import basin, continue_, control, linkage, list_, optimize, simulate, solve, stabilise
from .common import (
    EXIT_BAD_INPUT,
    EXIT_INTERRUPTED,
    EXIT_NOT_FOUND,
    EXIT_OK,
    PROG,
    InputError,
    Subcommand,
    _Parser,
    build_model,
    parse_guess,
    parse_x0,
)
from .output import write_outputs

__all__ = [
    "main",
    "build_parser",
    "Subcommand",
    "SUBCOMMANDS",
    "EXIT_OK",
    "EXIT_NOT_FOUND",
    "EXIT_BAD_INPUT",
    "EXIT_INTERRUPTED",
    "InputError",
    "build_model",
    "parse_guess",
    "parse_x0",
    "write_outputs",
]

# -- the command ---------------------------------------------------------------------------------
SUBCOMMANDS: dict[str, Subcommand] = {
    "list": Subcommand(
        "list the models and their parameters", list_._list_arguments, list_.run_list
    ),
    "solve": Subcommand(
        "find a gait (periodic orbit) by multiple shooting", solve._solve_arguments, solve.run_solve
    ),
    "simulate": Subcommand(
        "simulate a model and print its returns to the section",
        simulate._simulate_arguments,
        simulate.run_simulate,
    ),
    "control": Subcommand(
        "design a step-to-step controller (LQR, pole placement, deadbeat) around a gait",
        control._control_arguments,
        control.run_control,
    ),
    "continue": Subcommand(
        "follow a gait through a parameter: special points, period-doubling cascades",
        continue_._continue_arguments,
        continue_.run_continue,
    ),
    "linkage": Subcommand(linkage.HELP, linkage.add_arguments, linkage.run),
    "optimize": Subcommand(optimize.HELP, optimize.add_arguments, optimize.run),
    "basin": Subcommand(basin.HELP, basin.add_arguments, basin.run),
    "stabilise": Subcommand(stabilise.HELP, stabilise.add_arguments, stabilise.run),
}


def build_parser() -> argparse.ArgumentParser:
    """The ``gaitopt`` argument parser, one subparser per entry of :data:`SUBCOMMANDS`."""
    from .. import __version__

    parser = _Parser(
        prog=PROG,
        description="Gaits of simple legged-locomotion models as periodic orbits of hybrid "
        "systems. Exit status: 0 found, 1 not found, 2 bad input.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, command in SUBCOMMANDS.items():
        sub = commands.add_parser(name, help=command.help, description=command.help)
        command.add_arguments(sub)
        sub.set_defaults(run=command.run)
    return parser


def _check_out(args: argparse.Namespace) -> None:
    """``--out DIR`` of any subcommand: checked before the computation, so that an unusable path
    fails in a second instead of after a long run (:func:`gaitopt.files.check_output_folder`)."""
    out = getattr(args, "out", None)
    if out is None:
        return
    from ..files import check_output_folder

    try:
        check_output_folder(out)
    except GaitoptInputError as exc:
        raise InputError(f"--out {out}: {exc}") from None


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``gaitopt`` with ``argv`` (default ``sys.argv[1:]``); return the exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after the program name.

    Returns
    -------
    int
        0 found / completed, 1 not found / not completed, 2 bad input, 130 interrupted (Ctrl-C;
        ``gaitopt: interrupted`` on stderr, no traceback).
    """
    from ..interrupts import caused_by_interrupt, interrupts_outside_casadi

    try:
        with interrupts_outside_casadi():  # else CasADi may turn Ctrl-C into another error
            return _run(argv)
    except KeyboardInterrupt:  # Ctrl-C: wherever it landed, one line and the shell's 128 + 2
        _interrupted()
        return EXIT_INTERRUPTED
    except Exception as exc:
        if not caused_by_interrupt(exc):  # a bug: its traceback is wanted
            raise
        _interrupted()
        return EXIT_INTERRUPTED


def _interrupted() -> None:
    """Say ``gaitopt: interrupted`` on stderr (after what stdout holds), once."""
    with contextlib.suppress(Exception):
        sys.stdout.flush()
    print(f"{PROG}: interrupted", file=sys.stderr, flush=True)


def _run(argv: Sequence[str] | None) -> int:
    """:func:`main` without its handling of Ctrl-C."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # usage errors (2) and --help (0) exit from inside argparse
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    try:
        _check_out(args)
        with warnings.catch_warnings():
            # The results say in words what went wrong; NumPy's and SciPy's numerical warnings
            # (an overflow while a diverging guess is simulated) would only add lines to stderr.
            warnings.simplefilter("ignore", RuntimeWarning)
            return args.run(args)
    except InputError as exc:
        message = " ".join(str(exc).split())  # one line, whatever the message holds
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except GaitoptInputError as exc:  # raised by the library, wherever the input reached it
        message = " ".join(str(exc).split())
        print(f"{PROG}: error: {args.command}: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # `gaitopt ... | head`: the reader left; say nothing more
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_NOT_FOUND


if __name__ == "__main__":
    sys.exit(main())
