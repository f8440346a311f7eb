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
def _lazy(help: str, module: str, add_arguments: str, run: str) -> Subcommand:
    """A subcommand whose module (``gaitopt.cli.<module>``) is imported only when its arguments
    are declared or it runs: ``gaitopt solve`` imports the solver, not the basins, continuation,
    optimal gaits or plotting of the other subcommands."""
    from importlib import import_module

    def declare(parser: argparse.ArgumentParser) -> None:
        getattr(import_module(f".{module}", __name__), add_arguments)(parser)

    def execute(args: argparse.Namespace) -> int:
        return getattr(import_module(f".{module}", __name__), run)(args)

    declare.__qualname__ = f"{module}.{add_arguments}"
    execute.__qualname__ = f"{module}.{run}"
    return Subcommand(help, declare, execute)


#: Each subcommand: its one-line help (as its module's ``HELP`` where it has one:
#: tests/test_cli_lazy.py checks they agree) and its module's two functions.
SUBCOMMANDS: dict[str, Subcommand] = {
    "list": _lazy("list the models and their parameters", "list_", "_list_arguments", "run_list"),
    "solve": _lazy(
        "find a gait (periodic orbit) by multiple shooting",
        "solve",
        "_solve_arguments",
        "run_solve",
    ),  # fmt: skip
    "simulate": _lazy(
        "simulate a model and print its returns to the section",
        "simulate",
        "_simulate_arguments",
        "run_simulate",
    ),
    "control": _lazy(
        "design a step-to-step controller (LQR, pole placement, deadbeat) around a gait",
        "control",
        "_control_arguments",
        "run_control",
    ),
    "continue": _lazy(
        "follow a gait through a parameter: special points, period-doubling cascades",
        "continue_",
        "_continue_arguments",
        "run_continue",
    ),
    "linkage": _lazy(
        "kinematics of a leg linkage (Jansen's Strandbeest): foot path, ground contact, "
        "ride height",
        "linkage",
        "add_arguments",
        "run",
    ),
    "optimize": _lazy(
        "synthesise an optimal gait (least effort, work or cost of transport) with input profiles",
        "optimize",
        "add_arguments",
        "run",
    ),
    "basin": _lazy(
        "a gait's basin of attraction: radii along rays and a sampled fraction, all simulated",
        "basin",
        "add_arguments",
        "run",
    ),
    "stabilise": _lazy(
        "stabilise a gait's orbit by transverse LQR (continuous feedback along the orbit)",
        "stabilise",
        "add_arguments",
        "run",
    ),
}


def __getattr__(name: str):
    """``gaitopt.cli.solve`` and the other subcommands' modules, imported on first use (PEP 562)."""
    modules = {"list_", "solve", "simulate", "control", "continue_", "linkage", "optimize",
               "basin", "stabilise"}  # fmt: skip
    if name in modules:
        from importlib import import_module

        return import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class _Version(argparse.Action):
    """``--version``: the installed package's version, looked up only when asked for (reading
    the package metadata imports :mod:`importlib.metadata` and the ``email`` parser, about 30 ms
    that every other command would pay at start)."""

    def __init__(self, option_strings: Sequence[str], dest: str, **kwargs) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        from .. import __version__

        parser._print_message(f"{PROG} {__version__}\n", sys.stdout)  # as argparse's "version"
        parser.exit()


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``gaitopt`` argument parser, one subparser per entry of :data:`SUBCOMMANDS`.

    Parameters
    ----------
    command : str, optional
        Declare the arguments of this subcommand only (the others are listed with their help but
        take no arguments), so that only its module is imported; default: every subcommand's.
    """
    parser = _Parser(
        prog=PROG,
        description="Gaits of simple legged-locomotion models as periodic orbits of hybrid "
        "systems. Exit status: 0 found, 1 not found, 2 bad input.",
    )
    parser.add_argument("--version", action=_Version, help="show program's version number and exit")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, sub_command in SUBCOMMANDS.items():
        sub = commands.add_parser(name, help=sub_command.help, description=sub_command.help)
        if command is None or name == command:
            sub_command.add_arguments(sub)
        sub.set_defaults(run=sub_command.run)
    return parser


def _chosen(argv: Sequence[str]) -> str:
    """The subcommand ``argv`` names (its first word not an option: ``gaitopt`` itself has only
    ``--help`` and ``--version``), or ``""`` for none or an unknown one (then no subcommand's
    arguments are declared: argparse's usage message or help needs none)."""
    word = next((a for a in argv if not a.startswith("-")), None)
    return word if word in SUBCOMMANDS else ""


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
    from ..threads import start_with_blas_threads

    start_with_blas_threads()  # before NumPy loads its BLAS (a fresh `gaitopt` process)

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
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(_chosen(argv))
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
