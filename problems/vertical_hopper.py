"""Vertical hopper with energy-controlled thrust: the apex map, convergence, stability vs gain.

Sources: Raibert 1984, "Hopping in legged systems — modeling and simulation for the
two-dimensional one-legged case", IEEE Trans. SMC 14(3), and *Legged Robots That Balance* (1986),
ch. 2 (vertical hopping, thrust by lengthening the leg spring in stance); Tedrake, *Underactuated
Robotics*, the one-dimensional hopper exercise.  Closed forms derived in
:mod:`gaitopt.models.vertical_hopper`: thrust work ``W = k δ c + ½ k δ²`` (eq. 1), the controller
``W = (E_a − E_b) + K (E_d − E_a)`` (eq. 2), the undamped apex map ``y' = y + K (h_d − y)`` with
fixed point ``h_d`` and multiplier ``1 − K`` (eq. 3), and the fixed-point thrust (eq. 4).

What it does, at the defaults of ``gaitopt.model("vertical_hopper")`` (m = 10 kg, l0 = 0.5 m,
k = 4000 N/m, ε = 0.1, h_d = 0.7 m, K = 0.5) and with damping b = 20 N·s/m (ζ = 0.05):

1. samples the apex map by simulation and compares it with the closed form; staircase plot;
2. simulates 10 hops from apex heights 0.55, 0.9, 1.2 and 1.6 m, undamped and damped, and
   compares the error ratio with the multiplier;
3. solves the fixed point by shooting for gains K in (0, 2.4) and compares the multiplier with
   ``1 − K`` (undamped) and reports the damped multiplier and fixed point; continues in K to
   locate the period doubling that ends the stable range (closed form K = 2 undamped).

Writes ``OUT/vertical_hopper_study/``: ``return_map.csv``, ``convergence.csv``, ``gains.csv``,
``summary.json``, ``return_map.png``, ``convergence.png``, ``gains.png``.  ``--fast``: fewer
samples.

Usage::

    python problems/vertical_hopper.py --out results [--fast]
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

STUDY = "vertical_hopper_study"
DAMPING = 20.0  # N·s/m: ζ = b / (2 sqrt(k m)) = 0.05 at the defaults


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="fewer samples (CI)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    hopper = gaitopt.model("vertical_hopper")
    damped = hopper.replace(damping=DAMPING)
    lo, hi = hopper.map_domain()

    # 1. The simulated apex map vs the closed form, undamped and damped.
    grid = np.linspace(lo, hi, 25 if args.fast else 120)
    rows = [
        [y, return_map(hopper, float(y))[0], hopper.closed_form_map(float(y))]
        + [return_map(damped, float(y))[0]]
        for y in grid
    ]
    write_csv(["apex", "P_simulated", "P_closed_form", "P_damped"], rows, out / "return_map.csv")
    map_error = float(np.nanmax([abs(r[1] - r[2]) for r in rows]))
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.4), layout="constrained")
    samples = 30 if args.fast else 80
    plot_return_map(
        hopper,
        (lo, hi),
        start=1.4,
        iterations=8,
        ax=axes[0],
        closed_form=hopper.closed_form_map,
        samples=samples,
    )
    axes[0].set_title(f"undamped (closed form dashed), K = {hopper.gain:g}", fontsize=9)
    plot_return_map(damped, (lo, hi), start=1.4, iterations=8, ax=axes[1], samples=samples)
    axes[1].set_title(f"damped, b = {DAMPING:g} N·s/m (ζ = 0.05)", fontsize=9)
    fig.suptitle(
        f"Vertical hopper: apex-to-apex map (h_d = {hopper.desired_height:g} m, "
        f"ε = {hopper.touchdown_loss:g})",
        fontsize=10,
    )
    save_figure(fig, out / "return_map.png")

    # 2. Convergence in simulation vs the multiplier.
    cycle = gaitopt.find_limit_cycle(hopper)
    cycle_damped = gaitopt.find_limit_cycle(damped)
    conv_rows = []
    ratio_error = {}
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 3.6), layout="constrained", sharey=True)
    for ax, model, cyc, label in (
        (axes[0], hopper, cycle, "undamped"),
        (axes[1], damped, cycle_damped, "damped"),
    ):
        y_star = cyc.fixed_point["y"]
        lam = cyc.multipliers[0].real
        worst = 0.0
        for j, first in enumerate((0.55, 0.9, 1.2, 1.6)):
            sim = gaitopt.simulate(model, {"y": first}, steps=10)
            apexes = sim.section_states[:, 0]
            for n, y in enumerate(apexes):
                conv_rows.append([label, first, n, float(y)])
            err = apexes - y_star
            # The last ratios with the error above the simulation's accuracy (1e-8 m).
            ratios = [b / a for a, b in zip(err[:-1], err[1:], strict=True) if 1e-8 < abs(a) < 3e-3]
            if ratios:
                worst = max(worst, abs(ratios[-1] - lam))
            ax.plot(apexes, "o-", ms=3, color=f"C{j}", label=f"from {first:g} m")
        ratio_error[label] = float(worst)
        ax.axhline(y_star, color="k", lw=0.7, ls=":")
        ax.set_xlabel("hop count n (dimensionless)")
        ax.set_title(f"{label}: y* = {y_star:.4f} m, λ = {lam:.4f}", fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes:
        ax.set_ylabel("apex height y[n] (m)")
    axes[1].legend(fontsize=7)
    save_figure(fig, out / "convergence.png")
    write_csv(["case", "start", "hop", "apex"], conv_rows, out / "convergence.csv")

    # 3. Stability against the controller gain.
    gains = np.linspace(0.1, 2.4, 12 if args.fast else 47)
    gain_rows = []
    for K in gains:
        a = gaitopt.find_limit_cycle(hopper.replace(gain=float(K)))
        b = gaitopt.find_limit_cycle(damped.replace(gain=float(K)))
        gain_rows.append(
            [
                float(K),
                a.multipliers[0].real if a.success else float("nan"),
                1 - float(K),
                b.fixed_point.get("y", float("nan")) if b.success else float("nan"),
                b.multipliers[0].real if b.success else float("nan"),
                bool(a.stable),
                bool(b.stable),
                a.success and a.verified and b.success and b.verified,
            ]
        )
    write_csv(
        [
            "gain",
            "multiplier",
            "multiplier_closed_form",
            "damped_fixed_point",
            "damped_multiplier",
            "stable",
            "damped_stable",
            "verified",
        ],
        gain_rows,
        out / "gains.csv",
    )
    table = np.array([r[:5] for r in gain_rows], dtype=float)
    multiplier_error = float(np.nanmax(np.abs(table[:, 1] - table[:, 2])))
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 3.6), layout="constrained")
    axes[0].plot(table[:, 0], table[:, 1], "o", ms=4, label="shooting (AD), undamped")
    axes[0].plot(table[:, 0], table[:, 2], "k--", lw=0.8, label="1 − K (closed form)")
    axes[0].plot(table[:, 0], table[:, 4], "s", ms=3, label=f"shooting, b = {DAMPING:g}")
    for level in (-1, 1):
        axes[0].axhline(level, color="r", lw=0.6, ls=":")
    axes[0].set_xlabel("thrust gain K (dimensionless)")
    axes[0].set_ylabel("Floquet multiplier λ (dimensionless)")
    axes[0].legend(fontsize=7)
    axes[0].grid(alpha=0.3)
    axes[1].plot(table[:, 0], table[:, 3], "s-", ms=3, color="C2")
    axes[1].axhline(hopper.desired_height, color="k", lw=0.7, ls=":", label="h_d")
    axes[1].set_xlabel("thrust gain K (dimensionless)")
    axes[1].set_ylabel(f"damped fixed point y*, b = {DAMPING:g} N s/m (m)")
    axes[1].legend(fontsize=7)
    axes[1].grid(alpha=0.3)
    save_figure(fig, out / "gains.png")

    # The period doubling that ends the stable range, by continuation in K.
    pd = {}
    for label, model in (("undamped", hopper), ("damped", damped)):
        branch = gaitopt.continuation(model, "gain", to=2.4, cascade=False)
        found = [sp.param for sp in branch.special_points if sp.kind == "PD"]
        pd[label] = found[0] if found else None

    c_star, delta_star, work = hopper.fixed_point_thrust()
    all_verified = all(r[7] for r in gain_rows)
    summary = {
        "study": STUDY,
        "source": "Raibert 1984, 1986; Tedrake, Underactuated Robotics; closed forms in "
        "gaitopt.models.vertical_hopper",
        "params": hopper.params,
        "damping_studied": DAMPING,
        "fixed_point": cycle.fixed_point["y"],
        "fixed_point_closed_form": hopper.closed_form_fixed_point(),
        "multiplier": cycle.multipliers[0].real,
        "multiplier_closed_form": hopper.multiplier(),
        "fixed_point_thrust_closed_form": {"c": c_star, "delta": delta_star, "work": work},
        "damped_fixed_point": cycle_damped.fixed_point["y"],
        "damped_multiplier": cycle_damped.multipliers[0].real,
        "map_max_error_vs_closed_form": map_error,
        "multiplier_max_error_vs_closed_form": multiplier_error,
        "convergence_ratio_error_vs_multiplier": ratio_error,
        "stable_gains_closed_form": list(hopper.stable_gains()),
        "period_doubling_gain_located": pd,
        "all_verified": all_verified,
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - start,
    }
    write_json(summary, out / "summary.json")
    print(
        f"fixed point {cycle.fixed_point['y']:.12f} m "
        f"(closed form {hopper.closed_form_fixed_point():g}), "
        f"multiplier {cycle.multipliers[0].real:.12f} (closed form {hopper.multiplier():g})"
    )
    print(f"map vs closed form: max error {map_error:.2g} m; multipliers: {multiplier_error:.2g}")
    print(
        f"damped (b = {DAMPING:g}): y* = {cycle_damped.fixed_point['y']:.6f} m, "
        f"λ = {cycle_damped.multipliers[0].real:.6f}; convergence ratio vs λ: {ratio_error}"
    )
    print(f"period doubling at K = {pd} (closed form, undamped: 2)")
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    ok = map_error < 1e-8 and multiplier_error < 1e-8 and all_verified and None not in pd.values()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
