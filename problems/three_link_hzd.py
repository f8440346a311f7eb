"""The three-link walker's hybrid zero dynamics: restricted map against the full-order loop.

Grizzle, Abba & Plestan 2001's three-link walker (``gaitopt.models.three_link_walker``) closed
by Bézier virtual constraints of degree 4 on the swing leg and the torso, phase variable the
stance-leg angle θ1 (``gaitopt.hzd``), for two designs:

* **fixed**: issue 20's fixed constraints θ3 = π/8, θ2 = −θ1 written as Bézier polynomials
  (exact), *not* hybrid invariant (the impact throws the state off the surface);
* **invariant**: coefficients fitted to the fixed-constraint gait at ω_n = 5, then α0, α1 set
  from the impact (Westervelt et al. 2007, eqs (6.37)), so the surface is hybrid invariant.

For each, the zero dynamics' restricted Poincaré map ρ(ζ⁻) = δ²_zero ζ⁻ − V_zero(θ⁻)
(Westervelt, Grizzle & Koditschek 2003; ``gaitopt.hzd.restricted_map``) gives a fixed point, its
slope δ²_zero and a step time ∫ I/√(2ζ) dθ; the full-order closed loop is solved by multiple
shooting and verified by simulation for ω_n from 5 to 100 rad/s (ζ = 1.1).  On the invariant
surface the gait *is* the HZD gait at every gain (same step time; δ² is one of its multipliers)
and the other multipliers go to 0 as ω_n grows; the fixed constraints' gait approaches the HZD
one only as ω_n grows.

    python problems/three_link_hzd.py --out results [--fast]

Writes results/three_link_hzd/: hzd.csv, hzd.json (table and summary), hzd.png (zero-dynamics
phase portrait and restricted map of the invariant design), multipliers.png (|μ| vs ω_n).
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
from gaitopt.hzd import virtual_constraint_model  # noqa: E402
from gaitopt.hzd.gait import hzd_gait, mesh_for  # noqa: E402
from gaitopt.hzd.zero_dynamics import fixed_point_state, restricted_map  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

DEGREE = 4
HEADER = [
    "design",
    "omega_n",
    "step_time_s",
    "hzd_step_time_s",
    "mu1",
    "hzd_slope",
    "mu1_minus_slope",
    "max_abs_other_mu",
    "max_abs_torque_Nm",
    "verification_error",
]


def _sweep(design: str, model, rmap, gains) -> list[list]:
    """The full-order gait of ``model`` at each ω_n, warm-started (the HZD fixed point first)."""
    rows = []
    x = fixed_point_state(model, rmap)
    guess = dict(zip(model.section.coordinates, model.section_coordinates_of(x), strict=True))
    for omega_n in gains:
        m = model.replace(omega_n=float(omega_n))
        cycle = gaitopt.find_limit_cycle(m, guess, discretisation=mesh_for(omega_n))
        if not cycle.success:
            raise SystemExit(f"{design}, ω_n = {omega_n:g}: {cycle.message}")
        guess = dict(zip(cycle.section_coordinates, cycle.section_point, strict=True))
        mu = cycle.multipliers[np.argsort(-np.abs(cycle.multipliers))]
        rows.append(
            [
                design,
                float(omega_n),
                cycle.period,
                rmap.step_time,
                float(mu[0].real),
                rmap.slope,
                float(mu[0].real - rmap.slope),
                float(np.max(np.abs(mu[1:]))),
                m.max_torque(cycle),
                cycle.verification_error,
            ]
        )
    return rows


def _portrait(ax_left, ax_right, rmap) -> None:
    """Zero-dynamics phase portrait θ̇(θ) for several ζ⁺ and the restricted map ρ(ζ⁻)."""
    theta, V, inertia = rmap.theta, rmap.V_zero, rmap.inertia
    z_plus = rmap.delta**2 * rmap.fixed_point
    for scale in (0.7, 0.85, 1.0, 1.15, 1.3):
        zeta = scale * z_plus - V
        ok = zeta > 0
        rate = np.where(ok, np.sqrt(2 * np.clip(zeta, 0, None)) / inertia, np.nan)
        style = "k-" if scale == 1.0 else "-"
        ax_left.plot(theta, rate, style, lw=2 if scale == 1.0 else 1, label=f"ζ⁺ = {scale:g} ζ⁺*")
    # the impact: θ⁻ → θ⁺ with σ⁺ = δ σ⁻ on the gait
    r_minus = np.sqrt(2 * rmap.fixed_point) / inertia[-1]
    r_plus = np.sqrt(2 * z_plus) / inertia[0]
    ax_left.plot([theta[-1], theta[0]], [r_minus, r_plus], "k:", lw=1, label="impact")
    ax_left.set_xlabel("stance-leg angle θ1 (rad)")
    ax_left.set_ylabel("stance-leg rate θ̇1 (rad/s)")
    ax_left.set_title("zero dynamics on the invariant surface")
    ax_left.grid(True, alpha=0.3)
    ax_left.legend(fontsize=7)
    z = np.linspace(0.0, 2.0 * rmap.fixed_point, 200)
    ax_right.plot(z, [rmap(v) for v in z], label=f"ρ(ζ⁻), slope δ² = {rmap.slope:.4f}")
    ax_right.plot(z, z, "k--", lw=1, label="ζ⁻ = ρ(ζ⁻)")
    ax_right.plot([rmap.fixed_point], [rmap.fixed_point], "ko", label="fixed point ζ*")
    ax_right.set_xlabel("pre-impact ζ⁻ = σ⁻²/2 ((kg·m²/s)²)")
    ax_right.set_ylabel("next pre-impact ζ⁻ ((kg·m²/s)²)")
    ax_right.set_title("restricted Poincaré map")
    ax_right.grid(True, alpha=0.3)
    ax_right.legend(fontsize=7)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "three_link_hzd"
    folder.mkdir(parents=True, exist_ok=True)
    gains = np.geomspace(5.0, 100.0, 3 if args.fast else 9)

    plant = gaitopt.model("three_link_walker")
    fixed = virtual_constraint_model(plant, DEGREE)()
    fixed_map = restricted_map(fixed)
    design = hzd_gait(plant, DEGREE, omega_n=5.0)
    if not design.success:
        print(design.message)
        return 1
    inv_map = design.rmap
    rows = _sweep("fixed", fixed, fixed_map, gains) + _sweep(
        "invariant", design.model, inv_map, gains
    )
    write_csv(HEADER, rows, folder / "hzd.csv")
    inv = [r for r in rows if r[0] == "invariant"]
    fix = [r for r in rows if r[0] == "fixed"]
    summary = {
        "source": "Westervelt, Grizzle & Koditschek 2003 (IEEE TAC 48(1)); Grizzle, Abba & "
        "Plestan 2001's three-link walker; issue 20 (zeta = 1.1)",
        "degree": DEGREE,
        "omega_n": [float(g) for g in gains],
        "invariant": {
            "bezier": {j: [float(v) for v in a] for j, a in design.model.alpha.items()},
            "theta_plus": design.model.theta_plus,
            "theta_minus": design.model.theta_minus,
            "invariance_residual": design.invariance_residual,
            "restricted_map": inv_map.as_dict(),
            "max_abs_mu1_minus_slope": max(abs(r[6]) for r in inv),
            "max_abs_step_time_minus_hzd": max(abs(r[2] - r[3]) for r in inv),
            "other_mu_at_lowest_and_highest_omega_n": [inv[0][7], inv[-1][7]],
            "max_torque_at_lowest_and_highest_omega_n": [inv[0][8], inv[-1][8]],
        },
        "fixed": {
            "invariance_residual": fixed_map.invariance_residual,
            "restricted_map": fixed_map.as_dict(),
            "mu1_by_omega_n": [r[4] for r in fix],
            "step_time_by_omega_n": [r[2] for r in fix],
            "mu1_minus_slope_at_lowest_and_highest_omega_n": [fix[0][6], fix[-1][6]],
        },
        "max_verification_error": max(r[9] for r in rows),
        "table": [dict(zip(HEADER, r, strict=True)) for r in rows],
    }
    write_json(summary, folder / "hzd.json")

    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.2))
    _portrait(left, right, inv_map)
    save_figure(fig, folder / "hzd.png")

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True)
    for (name, table, marker), color, rmap in zip(
        (("fixed", fix, "o"), ("invariant", inv, "s")),
        ("C0", "C1"),
        (fixed_map, inv_map),
        strict=True,
    ):
        t = np.array([r[1:] for r in table], dtype=float)
        top.plot(t[:, 0], t[:, 3], marker + "-", color=color, ms=4, label=f"μ₁, {name}")
        top.axhline(rmap.slope, color=color, lw=0.8, ls="--", label=f"δ²_zero, {name}")
        bottom.semilogy(t[:, 0], np.maximum(t[:, 6], 1e-18), marker + "-", color=color, ms=4,
                        label=f"max |μ₂…₅|, {name}")  # fmt: skip
    top.set_ylabel("dominant multiplier μ₁ (1)")
    top.set_title("Three-link walker, Bézier degree 4: full order vs zero dynamics")
    top.grid(True, alpha=0.3)
    top.legend(fontsize=7)
    bottom.axhspan(1e-18, 1e-13, color="0.9", zorder=0)  # the Jacobian's rounding
    bottom.set_ylim(1e-18, 1.0)
    bottom.set_xscale("log")
    bottom.set_xlabel("ω_n (rad/s)")
    bottom.set_ylabel("|Floquet multiplier| (1)")
    bottom.grid(True, which="both", alpha=0.3)
    bottom.legend(fontsize=7)
    save_figure(fig, folder / "multipliers.png")

    print(
        f"invariant: δ² = {inv_map.slope:.8f}, HZD step {inv_map.step_time:.10f} s, max |μ1 − δ²| "
        f"= {summary['invariant']['max_abs_mu1_minus_slope']:.1e}, other |μ| {inv[0][7]:.2e} "
        f"(ω_n = {gains[0]:g}) → {inv[-1][7]:.2e} (ω_n = {gains[-1]:g}); fixed: δ² = "
        f"{fixed_map.slope:.8f}, μ1 {fix[0][4]:.7f} → {fix[-1][4]:.7f}"
    )
    print(f"wrote {folder}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
