"""Grizzle's three-link walker vs the gain of its virtual-constraint controller (issue 20).

The walker of Grizzle, Abba & Plestan 2001 ("Asymptotically stable walking for biped robots:
analysis via systems with impulse effects", IEEE TAC 46(1)) under the fixed virtual constraints
h = [θ3 − π/8, θ1 + θ2], enforced by input–output linearisation with ḧ + 2ζω_n ḣ + ω_n² h = 0
(``gaitopt.models.three_link_walker``; ζ = 1.1 as in issue 20).  The constraints are not hybrid
invariant: each impact throws the state off them (h⁺, L_f h⁺ ≠ 0) and the controller pulls it
back through the step.  So the return map has five multipliers: the zero dynamics' one, and four
transverse ones that decay like exp(λ T) for the roots λ of s² + 2ζω_n s + ω_n² (the slow root
λ_s = −ω_n (ζ − √(ζ² − 1)) gives the largest).  As ω_n grows the transverse multipliers go to 0
(below ~1e-13 they are at the Jacobian's rounding) and the gait
approaches the one of the hybrid zero dynamics (Westervelt, Grizzle & Koditschek 2003, IEEE TAC
48(1): the restriction dynamics of a high-gain closed loop), at the price of
torques that grow with ω_n.  Each ω_n is solved by multiple shooting (warm-started from the
previous gait, a mesh scaled to the stiffness) and verified by simulation.

    python problems/three_link_walker_gains.py --out results [--fast]

Writes results/three_link_walker_gains/: gains.csv, gains.json (the table and a summary),
gains.png.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

GAINS = (5.0, 100.0)  # ω_n (rad/s): issue 20's value up to a high-gain closed loop
HEADER = [
    "omega_n",
    "step_time_s",
    "mu1",
    "abs_mu2",
    "abs_mu3",
    "abs_mu4",
    "abs_mu5",
    "exp_slow_root_T",
    "max_abs_torque_Nm",
    "h1_plus_rad",
    "h2_plus_rad",
    "dh1_plus_rad_s",
    "dh2_plus_rad_s",
    "verification_error",
]


def _mesh(omega_n: float) -> gaitopt.MultipleShooting:
    """Eight segments, RK8 steps growing with ω_n: step h ≈ T/(8 k) with |λ_fast| h ≲ 1.3 at
    T ≈ 1.5 s (λ_fast = −ω_n (ζ + √(ζ² − 1)) = −1.56 ω_n at ζ = 1.1), well inside the method's
    stability region."""
    return gaitopt.MultipleShooting(segments=8, rk_steps=max(2, math.ceil(omega_n / 4)))


def _slow_root(omega_n: float, zeta: float) -> float:
    """The slow root of s² + 2ζω_n s + ω_n² (1/s; the real part for ζ < 1)."""
    if zeta >= 1:
        return -omega_n * (zeta - math.sqrt(zeta**2 - 1))
    return -zeta * omega_n


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "three_link_walker_gains"
    folder.mkdir(parents=True, exist_ok=True)
    n = 6 if args.fast else 25
    gains = np.geomspace(*GAINS, n)

    rows, guess = [], None
    for omega_n in gains:
        model = gaitopt.model("three_link_walker", omega_n=float(omega_n))
        cycle = gaitopt.find_limit_cycle(model, guess, discretisation=_mesh(omega_n))
        if not cycle.success:
            print(f"ω_n = {omega_n:.4g}: {cycle.message}")
            return 1
        guess = dict(zip(cycle.section_coordinates, cycle.section_point, strict=True))
        mu = cycle.multipliers[np.argsort(-np.abs(cycle.multipliers))]
        h, dh = model.outputs(cycle.x)
        rows.append(
            [
                float(omega_n),
                cycle.period,
                float(mu[0].real),
                *map(float, np.abs(mu[1:])),
                math.exp(_slow_root(omega_n, model.zeta) * cycle.period),
                model.max_torque(cycle),
                *map(float, h),
                *map(float, dh),
                cycle.verification_error,
            ]
        )
    table = np.array(rows)
    write_csv(HEADER, rows, folder / "gains.csv")
    first, last = table[0], table[-1]
    summary = {
        "source": "Grizzle, Abba & Plestan 2001 (IEEE TAC 46(1)); issue 20 (zeta = 1.1)",
        "zeta": 1.1,
        "omega_n": [float(g) for g in gains],
        "default_gait": {
            "omega_n": first[0],
            "step_time_s": first[1],
            "dominant_multiplier": first[2],
            "transverse_multipliers_abs": list(first[3:7]),
            "max_abs_torque_Nm": first[8],
            "h_plus_rad": list(first[9:11]),
            "dh_plus_rad_s": list(first[11:13]),
        },
        "high_gain_gait": {
            "omega_n": last[0],
            "step_time_s": last[1],
            "dominant_multiplier": last[2],
            "largest_transverse_multiplier_abs": last[3],
            "max_abs_torque_Nm": last[8],
        },
        # |μ₂| / exp(λ_slow T) where the prediction is above the Jacobian's rounding (1e-11):
        # the slow transverse multiplier follows the linear output dynamics' decay over a step.
        "transverse_over_exp_slow_root_T": [float(r[3] / r[7]) for r in rows if r[7] > 1e-11],
        "transverse_at_rounding_above_omega_n": float(
            min((r[0] for r in rows if r[7] <= 1e-11), default=math.nan)
        ),
        "largest_transverse_abs_by_omega_n": [float(r[3]) for r in rows],
        "max_verification_error": float(np.max(table[:, 13])),
        "table": [dict(zip(HEADER, map(float, r), strict=True)) for r in rows],
    }
    write_json(summary, folder / "gains.json")

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True)
    top.plot(table[:, 0], table[:, 1], "o-", ms=3)
    top.set_ylabel("step time (s)")
    top.set_title("Three-link walker, I/O linearisation (ζ = 1.1): gait vs ω_n")
    top.grid(True, alpha=0.3)
    bottom.semilogy(table[:, 0], np.abs(table[:, 2]), "o-", ms=3, label="|μ₁| (zero dynamics)")
    for k, style in zip(range(3, 7), ("s-", "^-", "v-", "d-"), strict=True):
        bottom.semilogy(table[:, 0], table[:, k], style, ms=3, label=f"|μ{k - 1}|")
    bottom.semilogy(table[:, 0], table[:, 7], "k--", lw=1, label="exp(λ_slow T)")
    bottom.axhspan(1e-18, 1e-13, color="0.9", zorder=0)  # the Jacobian's rounding
    bottom.set_ylim(1e-18, 3.0)
    bottom.set_xscale("log")
    bottom.set_xlabel("ω_n (rad/s)")
    bottom.set_ylabel("|Floquet multiplier|")
    bottom.grid(True, which="both", alpha=0.3)
    bottom.legend(fontsize=7, ncol=2)
    save_figure(fig, folder / "gains.png")

    print(
        f"three-link walker: ω_n = {first[0]:g}: step {first[1]:.10f} s, μ₁ = {first[2]:.7f}, "
        f"|μ₂| = {first[3]:.3e}, max |u| = {first[8]:.2f} N·m; ω_n = {last[0]:g}: step "
        f"{last[1]:.10f} s, μ₁ = {last[2]:.7f}, |μ₂| = {last[3]:.3e}, max |u| = "
        f"{last[8]:.1f} N·m"
    )
    print(f"wrote {folder}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
