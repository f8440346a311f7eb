"""``gaitopt basin``: a gait's region of attraction on its section, every start simulated.

::

    gaitopt basin MODEL [--set NAME=VALUE ...] [--guess STATE=VALUE ...] [--rays N] [--steps N]
                        [--samples N] [--max-radius R] [--scheduler ADDRESS] [--json] [--out DIR]

Finds the gait (as ``gaitopt solve``), then :func:`gaitopt.basin.basin` (the star-shaped
estimate: radii along ``--rays`` rays, in units of each coordinate's scale ``|x*_i|``) and
:func:`gaitopt.basin.basin_fraction` (``--samples`` uniform starts in the box ``x* ± max-radius ·
scale``, with the 95 % Wilson interval).  ``--out DIR`` writes basin.json, basin.png and basin.npz
(columnar: the sampled starts with their outcomes, the rays).
Exit status 0 with a basin, 1 if no gait was found or the gait is unstable (empty basin).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from .common import (
    EXIT_BAD_INPUT,
    EXIT_NOT_FOUND,
    EXIT_OK,
    InputError,
    _count_option,
    _items_option,
    _model_arguments,
    _scheduler_address,
    build_model,
    parse_guess,
)
from .output import _print_json, _print_rows, _solver_output_to_stderr, print_header, write_outputs

HELP = "a gait's basin of attraction: radii along rays and a sampled fraction, all simulated"


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare ``gaitopt basin``'s arguments (counts with their limits, checked before work)."""
    from ..basin import _LIMIT, MAX_RAYS, MAX_SAMPLES, MAX_STEPS

    _model_arguments(parser)
    _items_option(
        parser, "--guess", "initial guess of a section coordinate for the gait (repeatable)"
    )
    _count_option(parser, "--rays", 16, (1, MAX_RAYS, _LIMIT), "rays from the fixed point")
    _count_option(
        parser,
        "--steps",
        40,
        (1, MAX_STEPS, _LIMIT),
        "periods within which a start must reach the fixed point",
    )
    _count_option(
        parser, "--samples", 100, (1, MAX_SAMPLES, _LIMIT), "random starts of the volume fraction"
    )
    parser.add_argument(
        "--max-radius",
        type=_positive,
        default=1.0,
        metavar="R",
        help="largest radius probed and half width of the fraction's box, in units of each "
        "coordinate's |fixed point| (default 1)",
    )
    parser.add_argument(
        "--scheduler",
        type=_scheduler_address,
        default=None,
        metavar="ADDRESS",
        help="run the simulations on Dask: 'local' or a scheduler address (default: serial)",
    )
    parser.add_argument(
        "--out", metavar="DIR", help="write basin.json, basin.png and basin.npz there"
    )


def _axis_label(model: Any, name: str) -> str:
    """``quantity symbol (unit)``: ``"angular rate theta_dot (rad/s)"``."""
    from ..plotting.labels import state_label, state_quantity

    return f"{state_quantity(model, name)} {state_label(model, name)}"


def plot_basin(summary: dict[str, Any], model: Any):
    """The rays' segments and end points in the first two section coordinates (one coordinate:
    the interval on its axis), the first failures marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    coords = summary["coordinates"]
    centre = np.array([summary["fixed_point"][c] for c in coords])
    scale = np.array(summary["scale"])
    directions = np.array(summary["directions"])
    ends = np.array(summary["endpoints"])
    fail = [np.nan if f is None else f for f in summary["first_failure"]]
    fails = centre + np.array(fail)[:, None] * directions * scale
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    if len(coords) == 1:
        for end, bad in zip(ends[:, 0], fails[:, 0], strict=True):
            ax.plot([centre[0], end], [0, 0], "-", color="tab:green", lw=6)
            ax.plot([bad], [0], "x", color="tab:red", ms=10)
        ax.plot([centre[0]], [0], "ko")
        ax.set_yticks([])
        ax.set_xlabel(_axis_label(model, coords[0]))
    else:
        for end, bad in zip(ends, fails, strict=True):
            ax.plot([centre[0], end[0]], [centre[1], end[1]], "-", color="tab:green")
            ax.plot([bad[0]], [bad[1]], "x", color="tab:red")
        ax.plot(ends[:, 0], ends[:, 1], ".", color="tab:green", label="confirmed radius")
        ax.plot([centre[0]], [centre[1]], "ko", label="fixed point")
        ax.set_xlabel(_axis_label(model, coords[0]))
        ax.set_ylabel(_axis_label(model, coords[1]))
        if len(coords) > 2:
            ax.set_title(f"projection on ({coords[0]}, {coords[1]})", fontsize=9)
        ax.legend(fontsize=8)
    fig.suptitle(f"{model.name}: basin, star-shaped inner estimate (× first failure)", fontsize=10)
    return fig


def run(args: argparse.Namespace) -> int:
    """``gaitopt basin``: the gait, its ray estimate and sampled fraction."""
    from ..basin import basin, basin_fraction
    from ..shooting import find_limit_cycle

    started = time.perf_counter()
    model = build_model(args.model, args.set)
    guess = parse_guess(model, args.guess)
    with _solver_output_to_stderr():
        gait = find_limit_cycle(model, guess)
    solved = time.perf_counter()
    if not gait.success:
        summary = {
            "model": model.name,
            "params": model.params,
            "success": False,
            "message": f"no gait found: {gait.message}",
        }
        if args.json:
            _print_json(summary)
        else:
            print_header(gait)
        return EXIT_NOT_FOUND
    try:
        shared = {"steps": args.steps, "scheduler": args.scheduler}
        estimate = basin(gait, rays=args.rays, max_radius=args.max_radius, **shared)
        rayed = time.perf_counter()
        fraction = basin_fraction(gait, samples=args.samples, window=args.max_radius, **shared)
    except OSError as exc:  # a Dask scheduler that cannot be reached
        raise InputError(f"--scheduler {args.scheduler}: cannot reach it ({exc})") from None
    done = time.perf_counter()
    summary = estimate.as_dict()
    summary["fraction"] = fraction.as_dict()
    summary["timings"] = {
        "solve_s": solved - started,
        "rays_s": rayed - solved,
        "fraction_s": done - rayed,
        "total_s": done - started,
    }
    if args.json:
        _print_json(summary)
    else:
        low, high = fraction.interval
        print_header(estimate, ("rays", len(estimate.radii)))
        _print_rows(
            [
                ("radii", ", ".join(f"{r:.4g}" for r in estimate.radii) + " (scaled)"),
                (
                    "scale",
                    ", ".join(
                        f"{c}={s:.6g}"
                        for c, s in zip(estimate.coordinates, estimate.scale, strict=True)
                    ),
                ),
                ("flags", len(estimate.flags)),
                (
                    "fraction",
                    f"{fraction.fraction:.4g} (95 % Wilson {low:.4g}…{high:.4g}, "
                    f"{fraction.samples} starts in x* ± {args.max_radius:g} scale)",
                ),
                ("time", f"{done - started:.3g} s"),
            ]
        )

    def write(folder: Path) -> None:
        from ..files import write_json
        from ..plotting import save_figure

        folder.mkdir(parents=True, exist_ok=True)
        write_json(summary, folder / "basin.json")
        save_figure(plot_basin(summary, model), folder / "basin.png")
        import numpy as np

        np.savez_compressed(  # columnar: every classified start with its outcome
            folder / "basin.npz",
            coordinates=np.array(model.section.coordinates),
            fraction_starts=fraction.starts,
            fraction_outcomes=fraction.outcomes.astype(str),
            ray_coordinates=np.array(estimate.coordinates),
            ray_directions=estimate.directions,
            ray_radii=estimate.radii,
            ray_first_failure=estimate.first_failure,
        )

    error = write_outputs(args.out, write)
    if error:
        import sys

        print(error, file=sys.stderr)
        return EXIT_BAD_INPUT
    return EXIT_OK if estimate.success else EXIT_NOT_FOUND
