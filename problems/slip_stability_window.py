"""SLIP running vs touchdown angle and vs energy: the window of self-stable running.

The spring-loaded inverted pendulum runs stably without any control only in a narrow window of
touchdown angles (Seyfarth, Geyer, Günther & Blickhan 2002, "A movement criterion for running",
J. Biomech. 35; Geyer, Seyfarth & Blickhan 2005; Tedrake, Underactuated Robotics, "SLIP"): at the
textbook's k̃ = 10.7 and Ẽ = 1.61 the apex map has a stable fixed point near z = 0.87 m and an
unstable one near 0.92 m (gaitopt's defaults).  Continuation from the stable gait in the touchdown
angle finds where the window ends — a fold (LP), where the stable and the unstable gait meet and
vanish, and a period doubling (PD) — and likewise in the energy.

    python problems/slip_stability_window.py --out results [--fast]

Writes results/slip_stability_window/: angle.json/.csv, energy.json/.csv, window.json and
branches.png.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import plot_branch, save_figure  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "slip_stability_window"
    folder.mkdir(parents=True, exist_ok=True)
    options = gaitopt.PseudoArclength(max_step=0.1 if args.fast else 0.03)
    model = gaitopt.model("slip")
    start = gaitopt.find_limit_cycle(model, {"z": 0.87})
    if not start.success:
        print(f"no stable SLIP gait at the defaults: {start.message}")
        return 1

    t0 = time.perf_counter()
    # Bounded intervals around the defaults: past each fold the unstable branch runs far away.
    bounds = {"touchdown_angle": (0.45, 0.6), "energy": (1150.0, 1500.0)}
    branches = {
        name: gaitopt.continuation(
            model,
            name,
            start=start,
            to=hi,
            bounds=(lo, hi),
            both_directions=True,
            cascade=not args.fast,
            max_period=4,
            options=options,
        )
        for name, (lo, hi) in bounds.items()
    }
    elapsed = time.perf_counter() - t0

    window = {}
    for name, branch in branches.items():
        write_json(branch.as_dict(), folder / f"{name}.json")
        write_csv(*branch.csv_rows(), folder / f"{name}.csv")
        ends = [
            (sp.kind, sp.param) for sp in branch.special_points if sp.kind in ("LP", "PD", "NS")
        ]
        near = sorted(ends, key=lambda kp: abs(kp[1] - getattr(model, name)))[:2]
        window[name] = {
            "special_points": [{"kind": k, "param": p} for k, p in ends],
            "stable_window": sorted(p for _, p in near) if len(near) == 2 else None,
            "bounded_by": [k for k, _ in sorted(near, key=lambda kp: kp[1])],
        }
    window["touchdown_angle"]["stable_window_degrees"] = (
        [math.degrees(a) for a in window["touchdown_angle"]["stable_window"]]
        if window["touchdown_angle"]["stable_window"]
        else None
    )
    window["elapsed_s"] = elapsed
    write_json(window, folder / "window.json")

    fig = plt.figure(figsize=(12, 6.5))
    grid = fig.add_gridspec(2, 2)
    for col, (name, branch) in enumerate(branches.items()):
        axes = (fig.add_subplot(grid[0, col]), fig.add_subplot(grid[1, col]))
        plot_branch(branch, coordinate="z", axes=axes)
        axes[1].set_yscale("log")
        lo, hi = window[name]["stable_window"] or bounds[name]
        pad = 2 * (hi - lo)
        for ax in axes:
            ax.set_xlim(lo - pad, hi + pad)
            ax.axvspan(lo, hi, color="tab:green", alpha=0.12)
        axes[0].set_ylim(0.8, 1.1)
        axes[0].set_title(f"SLIP apex height vs {name} (green: stable window)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, folder / "branches.png")

    for name, info in window.items():
        if name == "elapsed_s":
            continue
        print(
            f"{name}: special points {info['special_points']}; stable window "
            f"{info['stable_window']} bounded by {info['bounded_by']}"
        )
    print(f"wrote {folder} in {elapsed:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
