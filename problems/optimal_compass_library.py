"""A library of least-effort compass gaits across step lengths (level ground, 0.8 s per step).

The compass gait (Drake's parameters, slope 0) walks on level ground only with a hip torque
``τ(t)``.  For steps of 0.2–0.5 m taken in 0.8 s the least ``∫τ² dt`` is continued in the step
length with :func:`gaitopt.optimize.gait_library`: each optimum warm started from its neighbour,
the active sets of neighbours compared (a change located by bisection), the reduced Hessian's
smallest eigenvalue watched for a fold, and every point checked against a cold start from the
model's default start (the same cost to 1e-8 relative).  Each optimum is refined until its
discretisation error is below 1e-8 and re-simulated by the independent simulator; its largest
Floquet multiplier (τ(t) as a feedforward) is drawn too.  The wall-clock time of each library
point is compared with its cold start.

    python problems/optimal_compass_library.py --out results [--fast]

Writes results/optimal_compass_library/: library.json, library.csv, cost.png.
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
from gaitopt.optimize import gait_library  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

PERIOD = 0.8  # s


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="three step lengths, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_compass_library"
    folder.mkdir(parents=True, exist_ok=True)

    model = gaitopt.model("compass_gait", slope=0.0)
    steps = np.linspace(0.2, 0.3, 3) if args.fast else np.linspace(0.2, 0.5, 7)
    library = gait_library(model, "step_length", steps, period=PERIOD, cold=len(steps))
    print(library.message)
    cold_time = {c.value: c.time for c in library.cold_checks}
    cold_cost = {c.value: c.cold_cost for c in library.cold_checks}
    rows = []
    for pt in library.points:
        g = pt.gait
        mu = float(np.max(np.abs(g.multipliers))) if g.multipliers.size else float("nan")
        rows.append(
            (pt.value, g.cost if g.success else None, cold_cost.get(pt.value), g.success, mu,
             g.discretisation_error, pt.hessian_ratio, pt.time, cold_time.get(pt.value),
             "; ".join(a for a in g.active_constraints if "(fixed)" not in a))
        )  # fmt: skip
        print(
            f"step {pt.value:.3f} m: effort {g.cost!s:>22} (success {g.success}), max|mu| "
            f"{mu:.4f}, library {pt.time:.2f} s, cold {cold_time.get(pt.value, float('nan')):.2f}"
            f" s, active {rows[-1][-1] or 'none'}"
        )
    warm_times = [pt.time for pt in library.points if pt.warm]
    cold_times = list(cold_time.values())
    summary = {
        "period": PERIOD,
        "median_time_library_point_s": float(np.median(warm_times)) if warm_times else None,
        "median_time_cold_start_s": float(np.median(cold_times)) if cold_times else None,
    }
    print(summary)
    write_json({**summary, "library": library.to_json()}, folder / "library.json")
    write_csv(
        ["step_length_m", "effort_N2m2s", "effort_cold_N2m2s", "success", "max_abs_multiplier",
         "discretisation_error", "reduced_hessian_ratio", "time_library_s", "time_cold_s",
         "active_inequalities"],
        rows,
        folder / "library.csv",
    )  # fmt: skip

    ok = np.array([r[3] for r in rows], dtype=bool)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(6, 6.5), sharex=True)
    ax1.semilogy(steps[ok], [r[1] for r in rows if r[3]], "o-", label="warm-started library")
    checked = [(r[0], r[2]) for r in rows if r[2] is not None]
    if checked:
        ax1.semilogy(*zip(*checked, strict=True), "x", ms=9, label="cold start")
    for e in library.events:
        for ax in (ax1, ax2):
            ax.axvline(e.value, color="grey", ls="--", lw=0.8)
        ax1.annotate(e.kind, (e.value, ax1.get_ylim()[0]), rotation=90, va="bottom", fontsize=8)
    ax1.set_ylabel("least effort ∫τ² dt (N²·m²·s)")
    ax1.set_title(f"Compass gait, level ground, step period T = {PERIOD} s")
    ax1.legend()
    ax2.plot(steps[ok], [r[4] for r in rows if r[3]], "o-")  # certified optima only
    ax2.axhline(1.0, color="k", lw=0.8)
    ax2.set_xlabel("step length L (m)")
    ax2.set_ylabel("largest Floquet multiplier |μ| (1)")
    save_figure(fig, folder / "cost.png")
    # The study holds if the library and the cold starts give the same answer everywhere: the
    # same certified cost, or no certified gait from either (0.5 m: a grazing heel strike).
    same = all(c.agree or (c.library_cost is None and c.cold_cost is None)
               for c in library.cold_checks)  # fmt: skip
    return 0 if same and len(library.cold_checks) == len(steps) else 1


if __name__ == "__main__":
    raise SystemExit(main())
