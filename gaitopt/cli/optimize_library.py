"""``gaitopt optimize --library NAME=FIRST:LAST:COUNT``: a library of optimal gaits, the optimum
continued in a constraint or parameter (:func:`gaitopt.optimize.gait_library`); its parsing, text
and files (see :mod:`gaitopt.cli.optimize` for the JSON)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..errors import GaitoptInputError, did_you_mean

__all__ = ["run_library"]


def _parse_library(args: argparse.Namespace, model: Any, options: dict[str, Any]):
    """``--library NAME=FIRST:LAST:COUNT`` as (name, values)."""
    import numpy as np

    from ..optimize.library import CONSTRAINTS
    from .common import InputError

    item = args.library
    name, sep, text = (part.strip() for part in item.partition("="))
    parts = text.split(":")
    example = "--library step_length=0.2:0.5:7"
    if not sep or not name or len(parts) != 3:
        raise InputError(f"--library {item}: expected NAME=FIRST:LAST:COUNT, e.g. {example}")
    try:
        first, last = float(parts[0]), float(parts[1])
        count = int(parts[2])
    except ValueError:
        raise InputError(
            f"--library {item}: FIRST and LAST must be numbers and COUNT an integer, e.g. {example}"
        ) from None
    if not (np.isfinite(first) and np.isfinite(last)) or first == last or not 2 <= count <= 200:
        raise InputError(
            f"--library {item}: FIRST and LAST must be finite and differ, COUNT in 2..200, "
            f"e.g. {example}"
        )
    choices = (*CONSTRAINTS, *model.params)
    if name not in choices:
        raise InputError(
            f"--library {item}: {name!r} cannot be continued; {did_you_mean(name, choices)}"
            f"choose period, step_length, speed or a parameter of {model.name}"
        )
    if name in CONSTRAINTS and options.get(name) is not None:
        raise InputError(f"--library {item}: {name} is also fixed by --fix; drop that --fix")
    if args.starts > 1:
        raise InputError("--starts applies to one optimum, not a --library; drop one of them")
    return name, np.linspace(first, last, count)


def run_library(args: argparse.Namespace, model: Any, options: dict[str, Any]) -> int:
    """Build the library ``--library`` asks for; print (or ``--json``) and write (``--out``) it;
    the exit status."""
    from ..optimize.library import gait_library
    from .common import EXIT_BAD_INPUT, EXIT_NOT_FOUND, EXIT_OK, InputError
    from .optimize_advice import for_the_cli
    from .output import _print_json, _solver_output_to_stderr, write_outputs

    vary, values = _parse_library(args, model, options)
    try:
        with _solver_output_to_stderr():
            library = gait_library(
                model,
                vary,
                values,
                args.cost,
                steps=args.steps,
                cold=args.cold,
                scheduler=args.scheduler,
                **options,
            )
    except GaitoptInputError as exc:
        raise InputError(for_the_cli(str(exc))) from None
    except OSError as exc:
        if args.scheduler in (None, "local"):
            raise
        raise InputError(f"--scheduler {args.scheduler}: cannot reach it ({exc})") from None
    report = {
        "model": model.name,
        "params": model.params,
        "cost_kind": args.cost,
        **library.to_json(),
    }
    report["message"] = for_the_cli(report["message"])
    for entry in (*report["points"], *report["events"], *report["cold_checks"]):
        if "message" in entry:
            entry["message"] = for_the_cli(entry["message"])
    lost = write_outputs(args.out, lambda folder: _write_library(library, report, folder))
    if args.json:
        _print_json(report)
    else:
        _print_library(report)
    if lost is not None:
        print(lost, file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_OK if library.success else EXIT_NOT_FOUND


def _print_library(report: dict[str, Any]) -> None:
    from .output import _print_rows

    rows = [
        ("model", report["model"]),
        ("success", report["success"]),
        ("message", report["message"]),
    ]
    for pt in report["points"]:
        cost = "none" if pt["cost"] is None else f"{pt['cost']:.10g}"
        rows.append((f"{report['vary']} = {pt['value']:.6g}", f"{report['cost_kind']} {cost}"))
    for e in report["events"]:
        rows.append((e["kind"], e["message"]))
    _print_rows(rows)


def _write_library(library: Any, report: dict[str, Any], folder: Path) -> None:
    """library.json and library.csv (each written atomically)."""
    from ..files import write_csv, write_json

    folder.mkdir(parents=True, exist_ok=True)
    write_json(report, folder / "library.json")
    rows = [
        (pt["value"], pt["cost"], pt["success"], pt["period"], pt["step_length"], pt["speed"],
         max((abs(complex(*z)) for z in pt["multipliers"]), default=None), pt["time"])
        for pt in report["points"]
    ]  # fmt: skip
    write_csv(
        [library.vary, "cost", "success", "period_s", "step_length_m", "speed_m_per_s",
         "max_abs_multiplier", "time_s"],
        rows,
        folder / "library.csv",
    )  # fmt: skip
