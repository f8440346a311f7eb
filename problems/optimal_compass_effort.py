"""Least-effort gaits of the compass gait on level ground: effort against period (a library).

The compass gait (Drake's parameters, slope 0) cannot walk passively on level ground; with a hip
torque profile ``τ(t)`` it can.  For a step of 0.3 m the least ``∫τ² dt`` over one step is found
at a range of periods with :func:`gaitopt.optimize_gait`, each optimum warm-started from its
neighbour (a library of gaits), and checked against a cold start from the model's default start
at every period: the two must give the same cost (to 1e-8 relative; both are verified by
simulation and refined to a discretisation error below 1e-8).  The stability of each open-loop
optimum (largest Floquet multiplier modulus, u(t) as a feedforward) is drawn too.

    python problems/optimal_compass_effort.py --out results [--fast]

Writes results/optimal_compass_effort/: library.json, library.csv, effort.png.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

STEP = 0.3  # m


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="few periods, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_compass_effort"
    folder.mkdir(parents=True, exist_ok=True)

    model = gaitopt.model("compass_gait", slope=0.0)
    periods = np.linspace(0.6, 1.1, 4 if args.fast else 11)
    rows, records, previous = [], [], None
    for period in periods:
        t0 = time.perf_counter()
        warm = gaitopt.optimize_gait(model, period=period, step_length=STEP, guess=previous)
        t_warm = time.perf_counter() - t0
        cold = gaitopt.optimize_gait(model, period=period, step_length=STEP)
        agree = (
            warm.success and cold.success and abs(warm.cost - cold.cost) <= 1e-8 * abs(cold.cost)
        )
        mu = float(np.max(np.abs(warm.multipliers))) if warm.success else float("nan")
        rows.append((period, warm.cost, cold.cost, mu, warm.discretisation_error, t_warm, agree))
        records.append({"period": period, "warm": warm.to_json(), "cold_cost": cold.cost})
        print(
            f"T = {period:.3f} s: effort {warm.cost:.10g} (cold {cold.cost:.10g}), "
            f"max|mu| {mu:.4f}, verified {warm.verified}, agree {agree}"
        )
        previous = warm if warm.success else None

    write_json({"step_length": STEP, "points": records}, folder / "library.json")
    write_csv(
        ["period_s", "effort_N2m2s", "effort_cold_N2m2s", "max_abs_multiplier",
         "discretisation_error", "time_warm_s", "warm_equals_cold"],
        rows,
        folder / "library.csv",
    )  # fmt: skip
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(6, 6), sharex=True)
    ax1.plot(periods, [r[1] for r in rows], "o-", label="warm-started library")
    ax1.plot(periods, [r[2] for r in rows], "x", label="cold start")
    ax1.set_ylabel("least effort ∫τ² dt (N²·m²·s)")
    ax1.set_title(f"Compass gait, level ground, step {STEP} m")
    ax1.legend()
    ax2.plot(periods, [r[3] for r in rows], "o-")
    ax2.axhline(1.0, color="k", lw=0.8)
    ax2.set_xlabel("period T (s)")
    ax2.set_ylabel("largest multiplier |μ| (1)")
    save_figure(fig, folder / "effort.png")
    return 0 if all(r[6] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
