"""Kneed walker vs slope: where the passive gait stops existing because its foot stops clearing.

Hsu Chen's kneed walker (2007; Tedrake, *Underactuated Robotics*, "the kneed walker") walks
passively down slopes from its default 0.0504 rad.  Continued in the slope, its period-1 gait
period-doubles (a multiplier through −1) and then meets a boundary that is not a bifurcation of
the return map at all but of the physics: the trailing foot's lift-off speed after heel strike
falls to zero, and beyond it the orbit's foot would move down into the slope.  The model declares
"swing foot above the slope" as a unilateral constraint (zero at heel strike, it must rise at
once), so certification refuses such orbits and continuation reports a ``boundary`` special
point there, located to 1e-10 in the slope like the period doublings.  The period-2 branch born
at the doubling ends the same way.

    python problems/kneed_walker_slope.py --out results [--fast]

Writes results/kneed_walker_slope/: branch.json, branch.csv, summary.json, bifurcation.png.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.hybrid import rate_along  # noqa: E402
from gaitopt.plotting import plot_branch, save_figure  # noqa: E402

MODEL = "kneed_walker"
SLOPES = (0.0504, 0.13)  # the default slope to past the end of the branch


def lift_off_speed(cycle: gaitopt.LimitCycle) -> float:
    """The trailing foot's speed away from the slope just after heel strike (m/s): the rate of
    the declared clearance constraint at the start of the three-link phase."""
    phase = cycle.model.phases[0]
    clearance = next(c for c in phase.constraints if c.outcome == "trip")
    return float(
        rate_along(phase.flow, clearance.function)(cycle.orbit[0].x[:, 0], [], cycle.model.p)
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="period 1 and 2 only (CI)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "kneed_walker_slope"
    folder.mkdir(parents=True, exist_ok=True)

    t0 = time.perf_counter()
    branch = gaitopt.continuation(
        gaitopt.model(MODEL, slope=SLOPES[0]),
        "slope",
        to=SLOPES[1],
        max_period=2 if args.fast else 8,
    )
    elapsed = time.perf_counter() - t0
    write_json(branch.as_dict(), folder / "branch.json")
    header, rows = branch.csv_rows()
    write_csv(header, rows, folder / "branch.csv")

    special = []
    for b in branch.descendants():
        for sp in b.special_points:
            entry = {"period": b.steps, "kind": sp.kind, "slope": sp.param, "message": sp.message}
            if sp.kind == "boundary" and sp.cycle is not None and sp.cycle.success:
                entry["lift_off_speed_m_per_s"] = lift_off_speed(sp.cycle)
            special.append(entry)
    boundary = next(s for s in special if s["period"] == 1 and s["kind"] == "boundary")
    summary = {
        "model": MODEL,
        "source": "Hsu Chen 2007 (parameters); boundary: the declared foot-clearance constraint",
        "slope_range": list(SLOPES),
        "special_points": special,
        "period_1_branch_ends_at_slope": boundary["slope"],
        "lift_off_speed_at_start_m_per_s": lift_off_speed(branch.cycles[0]),
        "continuation_seconds": elapsed,
    }
    write_json(summary, folder / "summary.json")

    fig, (top, bottom) = plot_branch(branch, coordinate="q1")
    top.axvline(boundary["slope"], color="0.3", ls=":", lw=1)
    top.annotate(
        "trailing foot\nstops lifting off",
        (boundary["slope"], 0.2),
        xycoords=("data", "axes fraction"),
        xytext=(-6, 0),
        textcoords="offset points",
        ha="right",
        fontsize=8,
    )
    top.set_title(
        f"Kneed walker: gaits vs slope (the branch ends at γ = {boundary['slope']:.6f} rad)"
    )
    save_figure(fig, folder / "bifurcation.png")
    print(
        f"kneed walker: the period-1 branch from slope {SLOPES[0]} ends at "
        f"{boundary['slope']:.10f} rad "
        f"({boundary['message'][:90]}...); {len(special)} special points in {elapsed:.1f} s; "
        f"lift-off speed {summary['lift_off_speed_at_start_m_per_s']:.4f} m/s at the default"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
