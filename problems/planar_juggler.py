"""Planar juggler with the mirror law: the periodic vertical bounce, its multipliers against the
closed form, its stability region in the mirror-law gains, and convergence from perturbed throws.

Sources: Buehler, Koditschek & Kindlmann 1990, "A simple juggling robot: theory and
experimentation" (Experimental Robotics I) and "A family of robot control strategies for
intermittent dynamical environments" (IEEE Control Systems Magazine 10(2)): the planar mirror law
θ = −κ ψ + (horizontal correction), κ = κ0 + κ1 (E_d − E).  The closed forms (fixed point on the
vertical line x = x̄, the energy multiplier 1 − (1 + e) κ1 ḃ_d² of the line juggler, the linear
horizontal map and its Jury stability region) are derived in :mod:`gaitopt.models.planar_juggler`.

What it does, at the defaults of ``gaitopt.model("planar_juggler")``:

1. finds the periodic juggle by shooting (verified by simulation) and compares the fixed point and
   the three multipliers with the closed forms;
2. sweeps the horizontal gains (κ_x, κ_ẋ) on a grid, solving the orbit and its multipliers by
   shooting at each point, against the Jury region; sweeps κ1 for the energy multiplier;
3. simulates perturbed throws (off in position, horizontal velocity and energy) and compares their
   decay with the spectral radius; draws the ball's path and the paddle at each impact.

Writes ``OUT/planar_juggler_study/``: ``summary.json``, ``gains.csv``, ``kappa1.csv``,
``convergence.csv``, ``stability_gains.png``, ``trajectory.png``.  ``--fast``: coarser grids.

Usage::

    python problems/planar_juggler.py --out results [--fast]
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
from gaitopt.plotting import save_figure

STUDY = "planar_juggler_study"
COORDS = ("x", "x_dot_pre", "energy_pre")


def radius(multipliers) -> float:
    return float(np.max(np.abs(multipliers))) if len(multipliers) else math.nan


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="coarser grids (CI)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    juggler = gaitopt.model("planar_juggler")

    # 1. The juggle at the defaults.
    cycle = gaitopt.find_limit_cycle(juggler)
    closed = np.sort_complex(juggler.multipliers_closed_form())
    found = np.sort_complex(cycle.multipliers)
    fixed_error = max(
        abs(cycle.fixed_point[k] - v) for k, v in juggler.closed_form_fixed_point().items()
    )
    multiplier_error = float(np.max(np.abs(found - closed)))

    # 2. Stability against the horizontal gains (shooting) vs the Jury region (closed form).
    n = 13 if args.fast else 41
    kx_grid = np.linspace(-0.1, 1.1, n)
    kv_grid = np.linspace(-0.05, 0.45, n)
    rows, agree, solved, boundary = [], 0, 0, 0
    rho = np.full((n, n), np.nan)
    for j, kv in enumerate(kv_grid):
        for i, kx in enumerate(kx_grid):
            model = juggler.replace(kappa_x=float(kx), kappa_xdot=float(kv))
            c = gaitopt.find_limit_cycle(model, model.closed_form_fixed_point())
            ok = c.success and c.verified
            r_closed = radius(model.multipliers_closed_form())
            r = radius(c.multipliers) if ok else math.nan
            rho[j, i] = r
            solved += ok
            on_boundary = abs(r_closed - 1) < 1e-9  # e.g. κ_x = 0: λ = 1, stable undecided
            boundary += on_boundary
            agree += ok and not on_boundary and bool(c.stable) == (r_closed < 1)
            rows.append([float(kx), float(kv), r, r_closed, bool(c.stable), ok])
    write_csv(
        ["kappa_x", "kappa_xdot", "spectral_radius", "spectral_radius_closed_form", "stable",
         "verified"],
        rows,
        out / "gains.csv",
    )  # fmt: skip
    gains_error = float(np.nanmax([abs(r[2] - r[3]) for r in rows]))

    k1_grid = np.linspace(0.005, 0.135, 14 if args.fast else 53)
    k1_rows = []
    for k1 in k1_grid:
        model = juggler.replace(kappa1=float(k1))
        c = gaitopt.find_limit_cycle(model, model.closed_form_fixed_point())
        energy_mult = c.multipliers[
            np.argmin(np.abs(c.multipliers - model.multipliers_closed_form()[0]))
        ]
        k1_rows.append(
            [float(k1), float(energy_mult.real), float(model.multipliers_closed_form()[0].real),
             bool(c.stable), c.success and c.verified]
        )  # fmt: skip
    write_csv(
        ["kappa1", "energy_multiplier", "energy_multiplier_closed_form", "stable", "verified"],
        k1_rows,
        out / "kappa1.csv",
    )
    kappa1_error = float(max(abs(r[1] - r[2]) for r in k1_rows))
    kappa1_stable = [r[0] for r in k1_rows if r[3]]

    fig, ax = plt.subplots(figsize=(6.2, 4.6), layout="constrained")
    mesh = ax.pcolormesh(kx_grid, kv_grid, np.minimum(rho, 1.5), shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="spectral radius (shooting; clipped at 1.5)")
    ax.contour(kx_grid, kv_grid, rho, levels=[1.0], colors="w", linewidths=1.5)
    a = (1 + juggler.restitution) * juggler.desired_speed
    T = 2 * juggler.desired_speed / juggler.gravity
    # Jury region: κ_ẋ > 0, a κ_ẋ < 2, a T κ_x < 4 − 2 a κ_ẋ, κ_x > 0 (a triangle).
    triangle = np.array([[0, 0], [4 / (a * T), 0], [0, 2 / a], [0, 0]])
    ax.plot(*triangle.T, "r--", lw=1, label="Jury bounds (closed form)")
    dead = juggler.deadbeat_gains()
    ax.plot(dead["kappa_x"], dead["kappa_xdot"], "r*", ms=10, label="deadbeat")
    ax.plot(juggler.kappa_x, juggler.kappa_xdot, "wo", ms=5, label="default")
    ax.set_xlabel("position gain κ_x (rad/m)")
    ax.set_ylabel("velocity gain κ_ẋ (rad s/m)")
    ax.set_title(
        f"Planar juggler: stability in the horizontal gains (κ1 = {juggler.kappa1:g}; white: "
        "|λ| = 1 by shooting)",
        fontsize=8,
    )
    ax.legend(fontsize=7, loc="upper right")
    save_figure(fig, out / "stability_gains.png")

    # 3. Perturbed throws: convergence and the trajectory.
    s0 = cycle.section_point
    throws = {
        "x + 10 cm": [0.10, 0.0, 0.0],
        "ẋ = 0.3 m/s": [0.0, 0.3, 0.0],
        "E − 1.5 J/kg": [0.0, 0.0, -1.5],
        "all three": [-0.08, -0.2, 1.0],
    }
    steps = 15 if args.fast else 30
    conv_rows, rates = [], {}
    rho0 = radius(juggler.multipliers_closed_form())
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0), layout="constrained")
    for j, (label, delta) in enumerate(throws.items()):
        sim = gaitopt.simulate(juggler, dict(zip(COORDS, s0 + delta, strict=True)), steps=steps)
        sec = np.array([juggler.section_coordinates_of(x) for x in sim.section_states])
        err = np.linalg.norm(sec - s0, axis=1)
        for k, (row, e_k) in enumerate(zip(sec, err, strict=True)):
            conv_rows.append([label, k, *row, e_k])
        m0, m1 = 5, len(err) - 1
        rates[label] = float((err[m1] / err[m0]) ** (1 / (m1 - m0)))
        axes[1].semilogy(err, "o-", ms=3, color=f"C{j}", label=f"{label} ({sim.status})")
        if j == 3:
            for arc in sim.arcs:
                _, xs = arc.sample(60)
                axes[0].plot(xs[0], xs[1], color="C0", lw=0.8)
            for ev in sim.events[:8]:
                x, y, vx, vy = ev.state_before[:4]
                theta, _ = juggler.paddle_state(x, y, vx, vy)
                r = 1.1 * math.hypot(x, y)
                axes[0].plot([0, r * math.cos(theta)], [0, r * math.sin(theta)], "k-", lw=1.2)
                axes[0].plot(x, y, "o", color="C3", ms=3)
    k = np.arange(steps + 1)
    axes[1].semilogy(
        k, np.linalg.norm([0.1, 0.3, 1.5]) * rho0**k, "k:", label=f"|λ|ⁿ = {rho0:.3f}ⁿ"
    )
    axes[1].set_xlabel("impact count n (dimensionless)")
    axes[1].set_ylabel("‖section state − fixed point‖ (m and m/s mixed; SI)")
    axes[1].legend(fontsize=7)
    axes[1].grid(alpha=0.3)
    axes[0].plot(0, 0, "ks", ms=5)
    axes[0].axvline(juggler.desired_position, color="k", ls=":", lw=0.7)
    axes[0].set_xlabel("x (m)")
    axes[0].set_ylabel("y (m)")
    axes[0].set_title("ball path (throw 'all three'); paddle at the first 8 impacts", fontsize=8)
    save_figure(fig, out / "trajectory.png")
    write_csv(["throw", "impact", *COORDS, "error_norm"], conv_rows, out / "convergence.csv")

    stable_box = juggler.stable_horizontal_gains()
    k1_sampled = [min(kappa1_stable), max(kappa1_stable)] if kappa1_stable else None
    k1_bound = 2 / ((1 + juggler.restitution) * juggler.desired_speed**2)
    summary = {
        "study": STUDY,
        "source": "Buehler, Koditschek & Kindlmann 1990; closed forms in "
        "gaitopt.models.planar_juggler",
        "params": juggler.params,
        "fixed_point": cycle.fixed_point,
        "period_s": cycle.period,
        "multipliers": [[z.real, z.imag] for z in found],
        "multipliers_closed_form": [[z.real, z.imag] for z in closed],
        "fixed_point_error": fixed_error,
        "multiplier_error_vs_closed_form": multiplier_error,
        "verified": cycle.verified,
        "verification_error": cycle.verification_error,
        "gain_grid": {"points": n * n, "solved_and_verified": int(solved),
                      "stability_agrees_with_jury": int(agree),
                      "on_the_boundary": int(boundary),
                      "max_spectral_radius_error": gains_error},
        "jury_bounds_at_defaults": stable_box,
        "deadbeat_gains": dead,
        "kappa1_stable_sampled": k1_sampled,
        "kappa1_stable_closed_form": [0.0, k1_bound],
        "kappa1_multiplier_error": kappa1_error,
        "convergence_rates": rates,
        "spectral_radius": rho0,
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - start,
    }  # fmt: skip
    write_json(summary, out / "summary.json")
    print(f"fixed point {cycle.fixed_point}; error vs closed form {fixed_error:.2g}")
    print(f"multipliers {np.round(found, 6)}; error vs closed form {multiplier_error:.2g}")
    print(
        f"gain grid: {solved}/{n * n} verified, stability agrees with Jury at {agree} "
        f"({boundary} on the boundary |λ| = 1); "
        f"max |spectral radius error| {gains_error:.2g}"
    )
    print(f"κ1 sweep: energy multiplier error {kappa1_error:.2g}")
    print(f"convergence rates {rates} vs spectral radius {rho0:.4f}")
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    ok = (
        cycle.verified
        and multiplier_error < 1e-8
        and solved == agree + boundary == n * n
        and gains_error < 1e-8
        and kappa1_error < 1e-8
    )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
