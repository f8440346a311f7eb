"""Multi-start HZD design and HZD gait libraries in speed (issue 20, items 2–3).

Two design problems (``gaitopt.hzd.multistart.design_problem``): the three-link walker's (degree
4, cost ``(1/L) ∫‖u‖² dt``, SLSQP over ``α_2, α_3`` of both outputs, slope ≤ 0.9,
``ζ ≥ 0.05 ζ⁺``, ``N ≥ 0``, swing foot on or above the ground;
``problems/three_link_hzd_optimal.py``)
and FROST's RABBIT problem on the five-link biped (degree 5, effort ``∫‖u‖² dt``, 0.75 m/s,
swing foot ≥ 0.1 m at mid-step, ``|u| ≤ 100 N·m``, ``N ≥ 0``, ``|F_t| ≤ 0.6 N``;
``gaitopt.hzd.rabbit``).  For each:

* **multi-start**: 8 starts (seed 0; start 0 the problem's start, the others perturbed by
  U(−0.1, 0.1) rad in every free coefficient, redrawn until the start walks, all in one box of
  bounds: the three-link start ± 0.3 rad, the five-link biped's |q| ≤ π/2), every distinct minimum
  listed cheapest first with its cost, restricted-map slope, speed and whether the full-order
  closed loop (ω_n = 20 rad/s) certifies it with μ₁ = δ² (``Minimum.verified``);
* **speed library**: the cheapest minimum continued in its average speed (natural-parameter
  continuation, each point warm-started from its neighbour, in the same box), cost and slope
  against speed.

    python problems/hzd_multistart.py --out results [--fast]

Writes results/hzd_multistart/: minima.csv, starts.csv, library.csv, hzd_multistart.json,
library.png.  ``--fast``: the three-link walker only, 2 starts and 3 speeds.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.hzd.multistart import multistart_design, speed_library  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

MINIMA = ["model", "minimum", "objective", "cost", "slope", "speed_m_s", "step_time_s",
          "step_length_m", "max_abs_torque_Nm", "starts", "at_bound", "verified",
          "full_order_period_s", "full_order_mu_minus_slope"]  # fmt: skip
STARTS = ["model", "start", "draws", "converged", "cost", "minimum", "message"]
LIBRARY = ["model", "speed_m_s", "objective", "cost", "slope", "step_time_s", "step_length_m",
           "max_abs_torque_Nm", "achieved_speed_m_s", "success"]  # fmt: skip
UNITS = {"per_length": "(1/L)∫‖u‖² dt (N²·m·s)", "effort": "∫‖u‖² dt (N²·m²·s)"}


def _minima_rows(name: str, result) -> list[list]:
    rows = []
    for k, m in enumerate(result.minima):
        d = m.as_dict(result.objective)
        full = d.get("full_order", {})
        mu = m.gait.cycle.multipliers if m.gait is not None and m.gait.cycle is not None else None
        gap = None if mu is None else float(np.min(np.abs(mu - m.design.slope)))
        rows.append([name, k, result.objective, d["cost"], d["slope"], d["speed"],
                     d["step_time"], d["step_length"], d["max_torque"],
                     " ".join(map(str, m.starts)), " ".join(m.at_bound), d["verified"],
                     full.get("period"), gap])  # fmt: skip
    return rows


def _library(name: str, plant, degree: int, start, speeds_down, speeds_up, points: int):
    """Both branches from ``start`` (the free optimum), rows sorted by speed."""
    rows = []
    for branch in (speeds_down, speeds_up):
        if not branch:
            continue
        for v, g, _message in speed_library(plant, degree, branch, start=start, points=points):
            objective = "effort" if name == "five_link_biped" else "per_length"
            if g is None:
                rows.append([name, v, objective, None, None, None, None, None, None, False])
                continue
            cost = g.effort if objective == "effort" else g.cost
            rows.append([name, v, objective, cost, g.slope, g.step_time, g.step_length,
                         g.max_torque, g.speed, True])  # fmt: skip
    unique = {r[1]: r for r in rows}
    return [unique[v] for v in sorted(unique)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="CI mode (three-link walker only)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "hzd_multistart"
    folder.mkdir(parents=True, exist_ok=True)

    problems = [("three_link_walker", 4, 201, 8 if not args.fast else 2)]
    if not args.fast:
        problems.append(("five_link_biped", 5, 101, 8))
    minima_rows, start_rows, library_rows, summary = [], [], [], {}
    for name, degree, points, starts in problems:
        plant = gaitopt.model(name)
        result = multistart_design(plant, degree, starts=starts, seed=0, spread=0.1,
                                   omega_n=20.0, points=points)  # fmt: skip
        minima_rows += _minima_rows(name, result)
        for s in result.starts:
            start_rows.append([name, s["start"], s["draws"], s["converged"], s["cost"],
                               s["minimum"], s["message"]])  # fmt: skip
        summary[name] = {"degree": degree, "points": points, **result.as_dict()}
        if not result.minima:
            continue
        best = result.minima[0].design
        v0 = round(best.speed, 3)
        if name == "three_link_walker":
            down = [v0, 0.5, 0.45, 0.4] if not args.fast else [v0]
            up = [0.55, 0.6, 0.65] if not args.fast else [0.55, 0.6]
        else:
            down = [0.75, 0.7, 0.65, 0.6]
            up = [0.8, 0.85, 0.9]
        library_rows += _library(name, plant, degree, best.model, down, up, points)
    write_csv(MINIMA, minima_rows, folder / "minima.csv")
    write_csv(STARTS, start_rows, folder / "starts.csv")
    write_csv(LIBRARY, library_rows, folder / "library.csv")
    write_json(summary, folder / "hzd_multistart.json")

    names = sorted({r[0] for r in library_rows})
    fig, axes = plt.subplots(2, len(names), figsize=(5 * len(names), 6), squeeze=False)
    for col, name in enumerate(names):
        rows = [r for r in library_rows if r[0] == name and r[-1]]
        v = [r[1] for r in rows]
        axes[0, col].plot(v, [r[3] for r in rows], "o-")
        axes[0, col].set_ylabel(f"cost {UNITS[rows[0][2]]}" if rows else "cost")
        axes[0, col].set_title(f"{name}: optimal HZD gaits against speed")
        axes[1, col].plot(v, [r[4] for r in rows], "o-", color="C1")
        axes[1, col].set_ylabel("restricted-map slope δ² (1)")
        axes[1, col].set_xlabel("average speed v (m/s)")
        for ax in axes[:, col]:
            ax.grid(True, alpha=0.3)
    save_figure(fig, folder / "library.png")
    for row in minima_rows:
        print(f"{row[0]} minimum {row[1]}: cost {row[3]:.6f}, slope {row[4]:.6f}, speed "
              f"{row[5]:.4f} m/s, starts {row[9]}, verified {row[11]}")  # fmt: skip
    print(f"wrote {folder}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
