"""Ball on a vibrating table: the period-1 window in table acceleration and the period-doubling
cascade beyond it.

Sources: Holmes 1982, "The dynamics of repeated impacts with a sinusoidally vibrating table",
J. Sound Vib. 84; Guckenheimer & Holmes 1983, *Nonlinear Oscillations…*, §2.4 (the impact map,
its period-n orbits ``γ cos φ = 2nπ(1 − α)`` and their window); the exact-model window
``Γ_SN = π(1 − e)/(1 + e) < Γ < Γ_PD = sqrt(Γ_SN² + (2(1 + e²)/(1 + e)²)²)`` is derived in
:mod:`gaitopt.models.bouncing_ball`; Feigenbaum 1978 for the ratio δ = 4.669….

What it does, at the defaults of ``gaitopt.model("bouncing_ball")`` (e = 0.5, 5 Hz):

1. solves the stable period-1 orbit and continues it in the table acceleration Γ up to 1.9 with
   ``gaitopt.continuation`` (period doublings located, branch switching down the cascade);
2. compares the located PD and the period-1 orbits with the closed forms (and Holmes'
   high-bounce approximation of the window);
3. draws the continuation's bifurcation diagram over a brute-force orbit diagram (the impact phase
   of the last 32 of 300 simulated impacts per Γ).

Writes ``OUT/bouncing_ball_cascade/``: ``branch.csv`` (every point, all periods),
``orbit_diagram.csv``, ``summary.json``, ``cascade.png``.  ``--fast``: fewer orbit-diagram
samples.

Usage::

    python problems/bouncing_ball_cascade.py --out results [--fast]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_csv, write_json
from gaitopt.plotting import plot_branch, save_figure

STUDY = "bouncing_ball_cascade"
FEIGENBAUM = 4.669201609102990


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="fewer samples (CI)")
    args = parser.parse_args(argv)

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    ball = gaitopt.model("bouncing_ball")
    top = 1.9

    # 1. Continuation in the table acceleration, with the cascade.
    branch = gaitopt.continuation(
        ball, "acceleration", to=top, bounds=(1.0, top), both_directions=True, max_period=16
    )
    header, rows = branch.csv_rows()
    write_csv(header, rows, out / "branch.csv")
    cascade, node = [], branch
    while True:
        pds = [sp.param for sp in node.special_points if sp.kind == "PD"]
        if pds:
            cascade.append({"period": node.steps, "acceleration": pds[0]})
        if not node.children:
            break
        node = node.children[0]
    values = [c["acceleration"] for c in cascade]
    gaps = np.diff(values)
    ratios = (gaps[:-1] / gaps[1:]).tolist() if len(gaps) > 1 else []

    # 2. Closed forms.
    sn, pd = ball.saddle_node_acceleration(), ball.period_doubling_acceleration()
    lps = [sp.param for sp in branch.special_points if sp.kind == "LP"]
    period_one = [
        {
            "acceleration": float(c.model.acceleration),
            "phase": c.fixed_point["phase"],
            "phase_closed_form": c.model.period_orbit(1, stable=c.fixed_point["phase"] >= 0)[
                "phase"
            ],
            "max_abs_multiplier": float(np.max(np.abs(c.multipliers))),
        }
        for c in branch.cycles
    ]
    phase_error = max(abs(r["phase"] - r["phase_closed_form"]) for r in period_one)

    # 3. Brute-force orbit diagram by simulation.
    grid = np.linspace(1.0, top, 60 if args.fast else 300)
    diagram = []
    for gamma in grid:
        model = ball.replace(acceleration=float(gamma))
        sim = gaitopt.simulate(model, {"phase": 0.6, "y_dot": 1.0}, steps=300, rtol=1e-9)
        for phase in sim.section_states[-32:, 0] if sim.success else []:
            diagram.append([float(gamma), float(phase)])
    write_csv(["acceleration", "impact_phase"], diagram, out / "orbit_diagram.csv")

    fig, (ax, ax_mult) = plot_branch(branch, coordinate="phase")
    d = np.array(diagram)
    ax.scatter(
        d[:, 0], d[:, 1], s=0.3, color="0.75", alpha=0.6, zorder=0, lw=0, label="orbit diagram"
    )
    for x, name in (
        (sn, "Γ_SN"),
        (pd, "Γ_PD exact"),
        (ball.holmes_period_doubling_acceleration(), "Γ_PD Holmes"),
    ):
        for a in (ax, ax_mult):
            a.axvline(x, color="C3" if "exact" in name else "C2", lw=0.7, ls="--")
        ax.annotate(
            name,
            (x, 0.98),
            xycoords=("data", "axes fraction"),
            xytext=(2, 0),
            textcoords="offset points",
            fontsize=7,
            va="top",
            rotation=90,
        )
    ax.set_xlim(1.0, top)
    ax_mult.set_ylim(0.05, 3)
    ax.set_ylabel("impact phase ωt (rad)")
    ax.set_title(
        f"Ball on a vibrating table, e = {ball.restitution:g}: period-1 window and cascade "
        "(continuation over simulation)",
        fontsize=9,
    )
    save_figure(fig, out / "cascade.png")

    summary = {
        "study": STUDY,
        "source": "Holmes 1982; Guckenheimer & Holmes 1983 §2.4; closed forms derived in "
        "gaitopt.models.bouncing_ball",
        "params": ball.params,
        "saddle_node_closed_form": sn,
        "period_doubling_closed_form": pd,
        "period_doubling_holmes_approximation": ball.holmes_period_doubling_acceleration(),
        "period_doubling_located": values[0] if values else None,
        "saddle_node_located": lps[0] if lps else None,
        "period_doubling_error": abs(values[0] - pd) if values else None,
        "period_one_phase_max_error": phase_error,
        "cascade": cascade,
        "feigenbaum_ratios": ratios,
        "feigenbaum_delta": FEIGENBAUM,
        "branch_message": branch.message,
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - start,
    }
    write_json(summary, out / "summary.json")
    print(f"period-1 window: Γ in ({sn:.10f}, {pd:.10f}) closed form")
    print(f"located: LP at Γ = {lps[0] if lps else float('nan'):.10f}")
    for c in cascade:
        print(f"PD of the period-{c['period']} orbit at Γ = {c['acceleration']:.10f}")
    print(f"Feigenbaum ratios {', '.join(f'{r:.3f}' for r in ratios)} (δ = {FEIGENBAUM:.4f})")
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    ok = bool(values) and abs(values[0] - pd) < 1e-6 and len(cascade) >= 3
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
