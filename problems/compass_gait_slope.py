"""Compass gait vs slope: the period-doubling route of Goswami, Thuilot & Espiau (1996).

Goswami et al. ("Compass-like biped robot part I: stability and bifurcation of passive gaits",
INRIA RR-2996, 1996; and Int. J. Robotics Research 17, 1998) found, by simulating the walker
until it settles at many slopes, that the period-1 gait period-doubles as the slope grows and
goes on doubling into chaos.  Here the same picture comes from continuation: the period-1 branch,
its first period doubling (PD), and the period-2, 4, 8 branches found by branch switching — with
the unstable continuations a simulation never shows — drawn over a brute-force orbit diagram of
the same slope range (many simulated steps per slope, through ``gaitopt.sweep``), and timed
against it.

    python problems/compass_gait_slope.py --out results [--fast] [--scheduler ADDRESS]

Writes results/compass_gait_slope/: branch.json, branch.csv, orbit_diagram.csv, timing.json,
bifurcation.png.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import plot_branch, save_figure  # noqa: E402
from gaitopt.simulation import simulate_task  # noqa: E402
from gaitopt.sweep import sweep  # noqa: E402

SLOPES = (0.0525, 0.09)  # Drake's default slope to well into the cascade


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    parser.add_argument("--scheduler", default=None, help="Dask scheduler address (default local)")
    parser.add_argument("--workers", type=int, default=2, help="local Dask workers")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "compass_gait_slope"
    folder.mkdir(parents=True, exist_ok=True)
    n_slopes, n_steps, n_keep = (24, 120, 16) if args.fast else (120, 300, 32)
    max_period = 4 if args.fast else 8

    # -- continuation ----------------------------------------------------------------------
    model = gaitopt.model("compass_gait", slope=SLOPES[0])
    t0 = time.perf_counter()
    branch = gaitopt.continuation(
        model,
        "slope",
        to=SLOPES[1],
        max_period=max_period,
        options=gaitopt.PseudoArclength(max_step=0.05),
    )
    t_continuation = time.perf_counter() - t0
    write_json(branch.as_dict(), folder / "branch.json")
    write_csv(*branch.csv_rows(), folder / "branch.csv")
    pds = [
        (b.steps, sp.param)
        for b in branch.descendants()
        for sp in b.special_points
        if sp.kind == "PD"
    ]

    # -- brute force: simulate until it settles, at every slope (what a simulation study does)
    # Each simulation starts 1e-3 off the period-1 gait at its slope (from the default start
    # the walker falls on the steeper slopes: their basins are small).
    slopes = np.linspace(*SLOPES, n_slopes)
    names = model.section.coordinates
    on_branch = np.array([c.section_point for c in branch.cycles])
    points = [
        {
            "model": "compass_gait",
            "params": {"slope": float(s)},
            "x0": {
                n: float(np.interp(s, branch.params, on_branch[:, j])) + 1e-3
                for j, n in enumerate(names)
            },
            "steps": n_steps,
            "record": n_keep,
        }
        for s in slopes
    ]
    # The journal lets an interrupted run resume; it is removed once the sweep is complete (the
    # CSV holds the data), so that every complete run times a full brute-force computation.
    journal = folder / f"orbit_diagram_{n_slopes}x{n_steps}.jsonl"
    t0 = time.perf_counter()
    brute = sweep(
        simulate_task,
        points,
        journal=journal,
        scheduler=args.scheduler,
        workers=args.workers,
        description="orbit diagram",
    )
    t_brute = time.perf_counter() - t0
    journal.unlink()
    stance = model.state_names.index("stance")
    rows = []
    for point, result in zip(points, brute.results, strict=True):
        for state in result["states"]:
            rows.append([point["params"]["slope"], result["status"], state[stance]])
    write_csv(["slope", "status", "stance"], rows, folder / "orbit_diagram.csv")

    timing = {
        "continuation_s": t_continuation,
        "continuation_points": sum(len(b.cycles) for b in branch.descendants()),
        "brute_force_s": t_brute,
        "brute_force_slopes": n_slopes,
        "brute_force_steps_per_slope": n_steps,
        "brute_force_reused_from_journal": len(brute.reused),
        "speedup": t_brute / t_continuation if t_continuation > 0 else None,
        "period_doublings": [{"period": k, "slope": s} for k, s in pds],
        "feigenbaum_ratios": _ratios([s for _, s in pds]),
    }
    write_json(timing, folder / "timing.json")

    # -- figure ------------------------------------------------------------------------------
    fig, (top, bottom) = plot_branch(branch, coordinate="stance")
    if rows:
        data = np.array([[r[0], r[2]] for r in rows if r[1] == "completed"])
        if data.size:
            top.plot(
                data[:, 0],
                data[:, 1],
                ".",
                ms=1.5,
                color="0.55",
                alpha=0.5,
                zorder=1,  # under the continuation branches, which stay visible
                label=f"simulation, last {n_keep} of {n_steps} steps",
            )
            top.legend(fontsize=8)
    save_figure(fig, folder / "bifurcation.png")

    print(
        f"compass gait vs slope: {len(pds)} period doublings at "
        + ", ".join(f"{s:.8f} (period {k}→{2 * k})" for k, s in pds)
    )
    print(
        f"continuation {t_continuation:.1f} s ({timing['continuation_points']} gaits, stable and "
        f"unstable) vs brute-force orbit diagram {t_brute:.1f} s ({n_slopes} slopes × "
        f"{n_steps} steps): {timing['speedup']:.1f}×"
    )
    print(f"wrote {folder}")
    return 0


def _ratios(points: list[float]) -> list[float]:
    """Ratios of successive period-doubling intervals (→ Feigenbaum's δ = 4.669…)."""
    gaps = np.diff(points)
    return [float(gaps[i] / gaps[i + 1]) for i in range(len(gaps) - 1)]


if __name__ == "__main__":
    raise SystemExit(main())
