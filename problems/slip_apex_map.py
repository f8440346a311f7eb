"""SLIP apex-to-apex return map and its fixed points (the textbook's staircase plot).

Sources: Tedrake, *Underactuated Robotics*, ch. "Simple models of walking and running",
§"The spring-loaded inverted pendulum (SLIP)": the apex map ``z[n+1] = P(z[n])`` at k̃ = 10.7,
θ_td = 30°, Ẽ = 1.61 (after Geyer's thesis, 2005; Geyer, Seyfarth & Blickhan 2006) with a stable
fixed point near 0.87 m and an unstable one near 0.92 m; the map is undefined below the touchdown
height ``l0 cos θ_td`` and the runner falls back when too little of the energy is forward speed.

What it does, at the defaults of ``gaitopt.model("slip")`` (docs/design.md's table):

1. samples the apex map by event-located SciPy simulation over the whole apex domain
   ``(l0 cos θ_td, E/(m g))`` and records where (and why) it is undefined;
2. finds every fixed point on the domain (sign changes, brentq, then ``find_limit_cycle`` with the
   multiplier by AD) and the two textbook ones from the guesses 0.87 and 0.92;
3. draws the staircase plot (from 0.915 m: it walks down to the stable fixed point) and the map
   for touchdown angles 26°–34° (the input a step-to-step controller changes).

Writes ``OUT/slip_apex_map/``: ``apex_map.csv`` (z, P(z), what happened), ``fixed_points.csv``,
``summary.json``, ``staircase.png``, ``maps_by_angle.png``.  ``--fast``: fewer samples.

Usage::

    python problems/slip_apex_map.py --out results [--fast]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_csv, write_json
from gaitopt.plotting import plot_return_map, save_figure
from gaitopt.returnmap import fixed_points_1d, return_map

STUDY = "slip_apex_map"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="fewer samples (CI)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    slip = gaitopt.model("slip")
    lo, hi = slip.apex_domain()
    samples = 60 if args.fast else 300

    # 1. The map over the whole apex domain, with the reason wherever it is undefined.
    grid = np.linspace(lo - 0.05, hi, samples)
    rows = []
    for z in grid:
        sim = gaitopt.simulate(slip, {"z": float(z)}, steps=1)
        value = sim.section_states[-1][1] if sim.success else math.nan
        rows.append([float(z), value, sim.status, "" if sim.success else sim.message])
    write_csv(["z", "P_z", "status", "why_undefined"], rows, out / "apex_map.csv")
    defined = [r[0] for r in rows if r[2] == "completed"]

    # 2. Every fixed point on the domain, and the textbook ones from their guesses.
    found = fixed_points_1d(slip, (lo + 1e-4, max(defined)), samples=40 if args.fast else 120)
    textbook = {z: gaitopt.find_limit_cycle(slip, {"z": z}) for z in (0.87, 0.92)}
    fp_rows = [
        [c.fixed_point["z"], c.fixed_point["x_dot"], c.multipliers[0].real, c.stable, c.period]
        for c in found.cycles
    ]
    write_csv(["z", "x_dot", "multiplier", "stable", "period_s"], fp_rows, out / "fixed_points.csv")

    # 3. Figures: the staircase plot, and the map for several touchdown angles.
    fig, ax = plot_return_map(
        slip, (lo + 1e-4, 1.0), start=0.915, iterations=12, samples=40 if args.fast else 120
    )
    ax.set_xlim(lo - 0.006, 1.0)
    ax.axvline(lo, color="C3", lw=0.8, ls="--")
    ax.text(
        lo,
        1.0,
        " map undefined to the left:\n apex below l0 cos θ_td",
        color="C3",
        fontsize=7,
        va="top",
    )
    ax.set_title(
        f"SLIP apex map, k̃ = {slip.relative_stiffness:.3g}, θ_td = 30°, "
        f"Ẽ = {slip.relative_energy:.3g} (Tedrake / Geyer)",
        fontsize=9,
    )
    save_figure(fig, out / "staircase.png")

    fig, ax = plt.subplots(figsize=(5.6, 5.0), layout="constrained")
    for k, degrees in enumerate((26, 28, 30, 32, 34)):
        angle = math.radians(degrees)
        z = np.linspace(lo - 0.02, 1.2, 40 if args.fast else 150)
        values = [return_map(slip, float(v), inputs=[angle])[0] for v in z]
        ax.plot(z, values, color=f"C{k}", label=f"θ_td = {degrees}°")
        ax.axvline(slip.touchdown_height(angle), color=f"C{k}", lw=0.6, ls=":")
    ax.plot([lo - 0.02, 1.2], [lo - 0.02, 1.2], "k:", lw=0.8, label="P(z) = z")
    ax.set_xlabel("apex height z[n] (m)")
    ax.set_ylabel("apex height z[n+1] (m)")
    ax.set_xlim(lo - 0.02, 1.2)
    ax.set_ylim(0.8, 1.25)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(
        "SLIP apex map for several touchdown angles (dotted: touchdown heights)", fontsize=9
    )
    save_figure(fig, out / "maps_by_angle.png")

    summary = {
        "study": STUDY,
        "source": "Tedrake, Underactuated Robotics, SLIP apex map (after Geyer 2005)",
        "params": slip.params,
        "relative_stiffness": slip.relative_stiffness,
        "relative_energy": slip.relative_energy,
        "apex_domain": {"touchdown_height": lo, "highest_apex": hi},
        "defined_on": [min(defined), max(defined)],
        "undefined_reasons": sorted({r[3].split(" at t")[0] for r in rows if r[3]}),
        "fixed_points": [
            {
                "z": c.fixed_point["z"],
                "x_dot": c.fixed_point["x_dot"],
                "multiplier": c.multipliers[0].real,
                "stable": c.stable,
                "period": c.period,
            }
            for c in found.cycles
        ],
        "textbook_guesses": {
            str(z): {
                "success": c.success,
                "z": c.fixed_point.get("z"),
                "multiplier": c.multipliers[0].real if c.success else None,
                "stable": c.stable,
            }
            for z, c in textbook.items()
        },
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - start,
    }
    write_json(summary, out / "summary.json")
    for c in found.cycles:
        kind = "stable" if c.stable else "unstable"
        z, lam = c.fixed_point["z"], c.multipliers[0].real
        print(f"fixed point z = {z:.10f} m, λ = {lam:.6f} ({kind})")
    print(f"apex map defined on [{min(defined):.4f}, {max(defined):.4f}] m of ({lo:.4f}, {hi:.4f})")
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    ok = len(found.cycles) == 2 and all(c.success for c in textbook.values())
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
