"""SLIP's window of self-stable running as curves: the fold (LP) and the period doubling (PD)
that bound it, followed in touchdown angle × energy and in touchdown angle × stiffness.

Seyfarth, Geyer, Günther & Blickhan ("A movement criterion for running", J. Biomech. 35:649–655,
2002) and Geyer, Seyfarth & Blickhan (J. Theor. Biol. 232, 2005) mapped where the spring-mass
runner is self-stable by brute force over (θ_td, k̃) and (θ_td, Ẽ).  Along a touchdown-angle
branch through the stable gait (z ≈ 0.87 m at Tedrake's k̃ = 10.7, Ẽ = 1.61) the window ends at a
PD (steeper legs) and an LP (flatter legs, the stable and unstable gaits meet): problems/
slip_stability_window.py.  Here both ends are followed through a second parameter
(gaitopt.bifurcation_curve; every point certified by simulation), giving the window's edges.

    python problems/slip_window_curves.py --out results [--fast]

Writes results/slip_window_curves/: <kind>_<param2>.csv/.json, summary.json, window.png.
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
from gaitopt.curves import ParameterPath, curve_from  # noqa: E402
from gaitopt.curves.plot import draw_curve  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

# Ranges of the second parameter (from Tedrake's defaults, both directions).
RANGES = {"energy": (1150.0, 1500.0), "stiffness": (6500.0, 11000.0)}
FAST = {"energy": (1230.0, 1300.0), "stiffness": (8000.0, 8800.0)}
SEARCH = {"PD": 0.45, "LP": 0.6}  # touchdown angles to search the branch towards (rad)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small ranges for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "slip_window_curves"
    folder.mkdir(parents=True, exist_ok=True)
    ranges = FAST if args.fast else RANGES
    model = gaitopt.model("slip")
    start = gaitopt.find_limit_cycle(model, {"z": 0.87})
    t0 = time.perf_counter()
    specials = {}
    for kind, towards in SEARCH.items():
        branch = gaitopt.continuation(
            model, "touchdown_angle", start=start, to=towards, cascade=False
        )
        specials[kind] = next(sp for sp in branch.special_points if sp.kind == kind)
    angle = ParameterPath.of(model, "touchdown_angle")
    curves: dict[str, list] = {}
    summary: dict = {
        "model": "slip",
        "source": "Seyfarth et al. 2002 (J. Biomech. 35); Geyer et al. 2005; Tedrake, "
        "Underactuated Robotics (SLIP apex map)",
        "start": {k: sp.param for k, sp in specials.items()},
    }
    for name, ends in ranges.items():
        second = ParameterPath.of(model, name)
        for kind, sp in specials.items():
            halves = [curve_from(sp, kind, (angle, second), end) for end in ends]
            key = f"{kind}_{name}"
            curves[key] = halves
            rows = []
            header = None
            for h in halves:
                header, part = h.csv_rows()
                rows += part
            if header:
                write_csv(header, sorted(rows, key=lambda r: r[1]), folder / f"{key}.csv")
            write_json([h.as_dict() for h in halves], folder / f"{key}.json")
            summary[key] = {
                "points": sum(len(h.cycles) for h in halves),
                "ends": [h.message for h in halves],
                "special_points": [s.as_dict() for h in halves for s in h.special_points],
                "all_verified": all(c.verified for h in halves for c in h.cycles),
            }
    summary["elapsed_s"] = time.perf_counter() - t0
    write_json(summary, folder / "summary.json")
    _figure(curves, folder / "window.png")
    print(f"SLIP window curves in {summary['elapsed_s']:.1f} s")
    for key in curves:
        s = summary[key]
        sps = ", ".join(
            s_["kind"] + " at θ=" + f"{s_['touchdown_angle']:.6f}" for s_ in s["special_points"]
        )
        print(f"  {key}: {s['points']} points; ends: {'; '.join(s['ends'])}; {sps or 'no codim-2'}")
    return 0


def _figure(curves, path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), layout="constrained")
    labels = {"energy": "system energy E (J)", "stiffness": "leg stiffness k (N/m)"}
    colours = {"PD": "C3", "LP": "C0"}
    for ax, name in zip(axes, ("energy", "stiffness"), strict=True):
        for kind in ("PD", "LP"):
            for k, half in enumerate(curves[f"{kind}_{name}"]):
                draw_curve(
                    ax,
                    half,
                    transform=lambda a, b: (a * 180 / math.pi, b),
                    label=f"{kind} curve" if k == 0 else "_",
                    colour=colours[kind],
                )
        ax.set_xlabel("touchdown angle θ_td from vertical (deg)")
        ax.set_ylabel(labels[name])
        ax.set_title(f"Self-stable running between the PD and LP curves ({name})", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
