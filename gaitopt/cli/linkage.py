"""``gaitopt linkage``: the kinematics of a leg linkage (Jansen's Strandbeest).

::

    gaitopt linkage jansen [--set NAME=VALUE ...] [--samples N] [--json]

prints the foot path's width and height (m), the share of a crank turn the foot spends within
5 mm of its lowest point, its stride, and the ride-height ripple (m) of six leg pairs on one crank
and of one pair (see :mod:`gaitopt.linkage`).  Exit status 0; 2 for bad input (an unknown linkage
or length, a value out of range, or lengths for which the leg cannot be assembled through a whole
crank turn), reported on one line.

The subcommand's two functions, :func:`add_arguments` and :func:`run`, are an entry of
``gaitopt.cli.SUBCOMMANDS``; the command-line helpers come from :mod:`gaitopt.cli` (imported when
the subcommand runs, so that the two modules can name each other).
"""

from __future__ import annotations

import argparse
from typing import Any

from ..errors import ParameterError, did_you_mean
from ..linkage import LINKAGES
from ..linkage.jansen import MAX_SAMPLES, SAMPLES_LIMIT

__all__ = ["HELP", "add_arguments", "run", "describe"]

HELP = "kinematics of a leg linkage (Jansen's Strandbeest): foot path, ground contact, ride height"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare ``LINKAGE``, ``--set``, ``--samples`` and ``--json``."""
    parser.add_argument("linkage", metavar="LINKAGE", help=f"one of: {', '.join(LINKAGES)}")
    from .common import _count_option, _items_option

    _items_option(
        parser,
        "--set",
        "change a length (m), e.g. --set j=0.52 (repeatable; see `gaitopt linkage jansen`)",
        metavar="NAME=VALUE",
    )
    _count_option(
        parser,
        "--samples",
        720,
        (16, MAX_SAMPLES, SAMPLES_LIMIT),
        "crank steps per turn of the continuation",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def describe(name: str, settings: list[str] | None, samples: int) -> dict[str, Any]:
    """The numbers of linkage ``name`` with the ``--set`` items applied.

    Raises
    ------
    gaitopt.cli.InputError
        For bad input, on one line naming the argument.
    """
    from .common import InputError, _echo, _parameter

    if name not in LINKAGES:
        raise InputError(
            f"LINKAGE {name!r} is not a linkage; {did_you_mean(name, LINKAGES)}"
            f"available: {', '.join(LINKAGES)}"
        )
    if samples < 16:
        raise InputError(f"--samples {samples}: expected an integer >= 16, e.g. --samples 720")
    cls = LINKAGES[name]
    specs = {spec.name: spec for spec in cls.parameter_specs()}
    listing = "parameters (lengths, m): {}"
    lengths = dict(_parameter(name, specs, item, listing) for item in settings or ())
    try:
        numbers = cls(**lengths).numbers(samples)
    except ParameterError as exc:  # the leg cannot be assembled through a whole turn
        raise InputError(f"{_echo('--set', settings or ())}: {exc}".lstrip(": ")) from None
    return {"success": True, **numbers}


def run(args: argparse.Namespace) -> int:
    """Print the linkage's numbers; 0, or :class:`gaitopt.cli.InputError` for bad input."""
    from .common import EXIT_OK
    from .output import _print_json

    report = describe(args.linkage, args.set, args.samples)
    if args.json:
        _print_json(report)
        return EXIT_OK
    units = report["units"]
    print(f"{report['linkage']}: {LINKAGES[report['linkage']].title}")
    for key in (
        "width", "height", "ground_fraction", "stride", "ripple_six_pairs", "ripple_one_pair",
        "ground_speed",
    ):  # fmt: skip
        unit = "" if units[key] == "1" else f" {units[key]}"
        print(f"  {key:<18}{report[key]:.6g}{unit}")
    x, y = report["lowest_point"]
    theta = report["lowest_point_theta"]
    print(f"  {'lowest_point':<18}({x:.6g}, {y:.6g}) m at θ = {theta:.6g} rad")
    return EXIT_OK
