"""Line juggler with the mirror law: the pre-impact return map, its stable range of energy gains
and the deadbeat gain, each checked by simulation.

Sources: Buehler, Koditschek & Kindlmann 1990, "A family of robot control strategies for
intermittent dynamical environments", IEEE Control Systems Magazine 10(2) (the mirror law
r = −κ b, κ = κ0 + κ1 (E_d − E)); the textbook pre-impact map
``ḃ[n+1] = ḃ[n] (1 + (1 + e) κ1 (E_d − ½ ḃ[n]²))`` with ``κ0 = (1 − e)/(1 + e)``, its fixed point
``−ḃ_d``, stable range ``0 < κ1 < 2/((1 + e) ḃ_d²)`` and deadbeat gain ``1/((1 + e) ḃ_d²)``
(derived in :mod:`gaitopt.models.line_juggler`).

What it does, at the defaults of ``gaitopt.model("line_juggler")`` (e = 0.8, ḃ_d = 3 m/s):

1. samples the map by simulation and compares it with the closed form;
2. solves the fixed point by shooting for a range of κ1 and compares the multiplier with
   ``1 − (1 + e) κ1 ḃ_d²``; continues in κ1 to locate the period doubling at the upper end;
3. simulates 12 impacts from ḃ = −1.5 and −5 m/s for κ1 = 0.02, the default 0.04, the deadbeat
   gain, 0.11 and 0.13 (unstable).

Writes ``OUT/line_juggler_mirror_law/``: ``return_map.csv``, ``gains.csv``, ``convergence.csv``,
``summary.json``, ``return_map.png``, ``convergence.png``.  ``--fast``: fewer samples.

Usage::

    python problems/line_juggler_mirror_law.py --out results [--fast]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_csv, write_json
from gaitopt.plotting import plot_return_map, save_figure
from gaitopt.returnmap import return_map

STUDY = "line_juggler_mirror_law"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="fewer samples (CI)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    juggler = gaitopt.model("line_juggler")
    lo, hi = juggler.map_domain()

    # 1. The simulated map vs the closed form.
    grid = np.linspace(lo, hi, 40 if args.fast else 200)
    rows = [[v, return_map(juggler, float(v))[0], juggler.closed_form_map(float(v))] for v in grid]
    write_csv(["b_dot", "P_simulated", "P_closed_form"], rows, out / "return_map.csv")
    map_error = float(np.nanmax([abs(r[1] - r[2]) for r in rows]))
    fig, ax = plot_return_map(
        juggler, (lo, hi), start=-5.5, iterations=8, closed_form=juggler.closed_form_map
    )
    ax.set_title(
        f"Line juggler, mirror law: pre-impact map (e = {juggler.restitution:g}, "
        f"κ1 = {juggler.kappa1:g}, ḃ_d = {juggler.desired_speed:g} m/s)",
        fontsize=9,
    )
    save_figure(fig, out / "return_map.png")

    # 2. Multiplier against κ1 by shooting vs the closed form; the PD by continuation.
    gains = np.linspace(0.005, 0.135, 14 if args.fast else 53)
    gain_rows = []
    for k1 in gains:
        model = juggler.replace(kappa1=float(k1))
        cycle = gaitopt.find_limit_cycle(model)
        gain_rows.append(
            [
                float(k1),
                cycle.fixed_point.get("b_dot"),
                cycle.multipliers[0].real if cycle.success else float("nan"),
                model.multiplier(),
                bool(cycle.stable),
                cycle.success and cycle.verified,
            ]
        )
    write_csv(
        ["kappa1", "b_dot", "multiplier", "multiplier_closed_form", "stable", "verified"],
        gain_rows,
        out / "gains.csv",
    )
    multiplier_error = float(max(abs(r[2] - r[3]) for r in gain_rows))
    branch = gaitopt.continuation(juggler, "kappa1", to=0.2, cascade=False)
    pd = [sp.param for sp in branch.special_points if sp.kind == "PD"]

    # 3. Convergence in simulation.
    cases = {
        "0.02": 0.02,
        "0.04 (default)": juggler.kappa1,
        f"{juggler.deadbeat_gain():.4f} (deadbeat)": juggler.deadbeat_gain(),
        "0.11": 0.11,
        "0.13 (unstable)": 0.13,
    }
    conv_rows = []
    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.6), layout="constrained", sharey=True)
    for ax_, first in zip(axes, (-1.5, -5.0), strict=True):
        for j, (label, k1) in enumerate(cases.items()):
            sim = gaitopt.simulate(juggler.replace(kappa1=k1), {"b_dot": first}, steps=12)
            speeds = sim.section_states[:, 2]
            for n, v in enumerate(speeds):
                conv_rows.append([k1, first, n, float(v)])
            ax_.plot(speeds, "o-", ms=3, color=f"C{j}", label=f"κ1 = {label}")
        ax_.axhline(-juggler.desired_speed, color="k", lw=0.7, ls=":")
        ax_.set_xlabel("impact count n (dimensionless)")
        ax_.set_title(f"from ḃ = {first:g} m/s", fontsize=9)
        ax_.grid(alpha=0.3)
    for ax_ in axes:
        ax_.set_ylabel("pre-impact velocity ḃ[n] (m/s)")
    axes[1].legend(fontsize=7)
    save_figure(fig, out / "convergence.png")
    write_csv(["kappa1", "start", "impact", "b_dot"], conv_rows, out / "convergence.csv")

    summary = {
        "study": STUDY,
        "source": "Buehler, Koditschek & Kindlmann 1990; closed forms in "
        "gaitopt.models.line_juggler",
        "params": juggler.params,
        "kappa0": juggler.kappa0,
        "map_max_error_vs_closed_form": map_error,
        "multiplier_max_error_vs_closed_form": multiplier_error,
        "stable_gains_closed_form": list(juggler.stable_gains()),
        "period_doubling_located": pd[0] if pd else None,
        "deadbeat_gain": juggler.deadbeat_gain(),
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - start,
    }
    write_json(summary, out / "summary.json")
    print(f"map vs closed form: max error {map_error:.2g}; multipliers: {multiplier_error:.2g}")
    print(
        f"stable κ1 range (0, {juggler.stable_gains()[1]:.10f}) closed form; PD located at "
        f"{pd[0] if pd else float('nan'):.10f}; deadbeat κ1 = {juggler.deadbeat_gain():.10f}"
    )
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    ok = map_error < 1e-8 and multiplier_error < 1e-8 and bool(pd)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
