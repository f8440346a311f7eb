"""The simplest walker's first period doubling as a curve in slope × hip-spring stiffness.

Garcia, Chatterjee, Ruina & Coleman ("The simplest walking model: stability, complexity, and
scaling", J. Biomech. Eng. 120:281–288, 1998) found the long-step gait stable for
0 < γ < 0.015 rad, period-doubling at γ ≈ 0.0151 (problems/simplest_walker_slope.py:
0.0150884 rad).  The model has one physical parameter, the slope; Kuo ("Energetics of actively
powered locomotion using the simplest walking model", J. Biomech. Eng. 124:113–120, 2002) adds a
second, a spring between the legs, torque −k·φ on the swing leg (``hip_stiffness`` k, scaled by
the foot mass, so φ̈ gains −k φ; the stance leg is unaffected in the foot-mass → 0 limit).  It
swings the leg faster, shortens the step period, and moves the period doubling to steeper slopes.

Here the first PD on the branch in the slope at k = 0 is followed through k
(gaitopt.curves.curve_from: the orbit plus det(A + I) = 0, minimally augmented, pseudo-arclength,
every point certified and verified by simulation) up to k = 0.65, where the PD slope
approaches the end of the model's slope range (0.05 rad, reached near k ≈ 0.685).  At
K_CHECKS the curve is compared with one-parameter continuation in the slope at fixed k
(gaitopt.continuation from γ = 0.002, PD located by regula falsi on det(A + I)), which also
confirms that the gait is stable everywhere below the PD on that branch.

    python problems/simplest_walker_pd_curve.py --out results [--fast]

Writes results/simplest_walker_pd_curve/: pd_curve.csv/.json, summary.json, pd_curve.png.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.curves import ParameterPath, curve_from  # noqa: E402
from gaitopt.curves.plot import draw_curve  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

MODEL = "simplest_walker"
LONG_GAIT = {"theta": 0.2003, "theta_dot": -0.1998}  # Garcia et al.'s long-step gait, γ = 0.009
SLOPE_FROM, SLOPE_TO = 0.002, 0.05  # rad: the one-parameter branches (0.05: the range's end)
K_TO = 0.65  # m_f·g·l/rad: the curve's end (its PD slope 0.0495 rad, inside the slope range)
K_CHECKS = (0.1, 0.3, 0.5)  # located exactly on the curve and checked by one-parameter PD
FAST_K_TO, FAST_K_CHECKS = 0.2, (0.1,)
GARCIA_PD = 0.0151  # rad, Garcia et al. 1998 (abstract: stable for γ < 0.015)
#: Step control of the one-parameter branches: at most 10 % of the slope per step, so that no
#: special point hides in one step.
BRANCH_STEPS = gaitopt.PseudoArclength(step=0.02, max_step=0.1)


def first_pd(model: gaitopt.HybridModel) -> tuple:
    """The long-step branch in the slope from SLOPE_FROM at ``model``'s hip stiffness, and its
    first period doubling (None if it has none)."""
    branch = gaitopt.continuation(
        model.replace(slope=SLOPE_FROM), "slope", to=SLOPE_TO, start=LONG_GAIT, cascade=False,
        options=BRANCH_STEPS,
    )  # fmt: skip
    pd = next((sp for sp in branch.special_points if sp.kind == "PD"), None)
    return branch, pd


def stable_below(branch, pd) -> bool:
    """Whether every point of ``branch`` below the PD slope is a stable gait."""
    return all(
        c.stable for c, lam in zip(branch.cycles, branch.params, strict=True) if lam < pd.param
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="k up to 0.2 only (CI)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "simplest_walker_pd_curve"
    folder.mkdir(parents=True, exist_ok=True)
    k_to = FAST_K_TO if args.fast else K_TO
    k_checks = FAST_K_CHECKS if args.fast else K_CHECKS

    t0 = time.perf_counter()
    model = gaitopt.model(MODEL)  # k = 0: Garcia's passive model
    branch, pd = first_pd(model)
    if pd is None:
        print(f"simplest walker: no PD on the branch in the slope ({branch.message})")
        return 1
    paths = (ParameterPath.of(model, "slope"), ParameterPath.of(model, "hip_stiffness"))
    curve = curve_from(pd, "PD", paths, k_to, at=k_checks)
    elapsed = time.perf_counter() - t0

    # -- one-parameter continuation at the check stiffnesses (the independent method) ----------
    lam = curve.params
    checks = []
    for k in (0.0, *k_checks):
        if k == 0.0:
            branch_k, pd_k = branch, pd
        else:
            branch_k, pd_k = first_pd(model.replace(hip_stiffness=k))
        row = np.flatnonzero(np.abs(lam[:, 1] - k) < 1e-12)
        on_curve = float(lam[row[0], 0]) if row.size else None
        entry = {
            "hip_stiffness": k,
            "pd_slope": pd_k.param if pd_k is not None else None,
            "pd_slope_on_curve": on_curve,
            "stable_below_pd": stable_below(branch_k, pd_k) if pd_k is not None else None,
            "period_at_pd": pd_k.cycle.period if pd_k is not None else None,
        }
        if on_curve is not None and pd_k is not None:
            entry["difference"] = on_curve - pd_k.param
        checks.append(entry)

    header, rows = curve.csv_rows()
    write_csv(header, rows, folder / "pd_curve.csv")
    write_json(curve.as_dict(), folder / "pd_curve.json")
    summary = {
        "model": MODEL,
        "source": "Garcia, Chatterjee, Ruina & Coleman 1998 (the model, PD near γ ≈ 0.0151); "
        "Kuo 2002 (the hip spring)",
        "condition": curve.condition,
        "hip_stiffness_range": [0.0, k_to],
        "hip_stiffness_unit": "m_f*g*l/rad",
        "points": len(curve.cycles),
        "end": curve.message,
        "all_verified": all(c.verified for c in curve.cycles),
        "pd_slope_at_hip_stiffness": {
            f"{b:g}": float(a)
            for a, b in lam
            if any(abs(b - k) < 1e-12 for k in (0.0, *k_checks, k_to))
        },  # fmt: skip
        "garcia_pd_slope": GARCIA_PD,
        "special_points": [sp.as_dict() for sp in curve.special_points],
        "one_parameter_checks": checks,
        "elapsed_s": elapsed,
    }
    write_json(summary, folder / "summary.json")
    _figure(curve, checks, folder / "pd_curve.png")

    print(f"simplest walker: first PD in slope × hip stiffness ({elapsed:.1f} s)")
    values = summary["pd_slope_at_hip_stiffness"]
    print(f"  {len(curve.cycles)} certified points; {curve.message}")
    print("  " + ", ".join(f"k = {k}: γ_PD = {s:.10f} rad" for k, s in values.items()))
    for sp in curve.special_points:
        print(f"  {sp.kind} at {sp.values}: {sp.message[:100]}")
    for entry in checks:
        diff = entry.get("difference")
        print(
            f"  one-parameter in γ at k = {entry['hip_stiffness']:g}: PD {entry['pd_slope']:.12f}"
            f" rad (curve − continuation {diff:.1e} rad); stable below: "
            f"{entry['stable_below_pd']}"
        )
    return 0


def _figure(curve, checks, path) -> None:
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8), layout="constrained")
    lam = curve.params
    draw_curve(left, curve, label="first period doubling (a multiplier −1)", colour="k",
               annotate=False)  # fmt: skip
    order = np.argsort(lam[:, 1])
    left.fill_betweenx(
        lam[order, 1], SLOPE_FROM, lam[order, 0], color="C2", alpha=0.15,
        label=f"period-1 gait stable (checked from γ = {SLOPE_FROM} rad at the circled k)",
    )  # fmt: skip
    for i, entry in enumerate(checks):
        if entry["pd_slope"] is not None:
            left.plot(
                [entry["pd_slope"]], [entry["hip_stiffness"]], "o", mfc="none", mec="C0", ms=10,
                label="one-parameter continuation in γ: PD" if i == 0 else "_",
            )  # fmt: skip
    left.plot([GARCIA_PD], [0.0], "x", color="C3", ms=9, mew=2,
              label=f"Garcia et al. 1998: PD at γ ≈ {GARCIA_PD} rad (k = 0)")  # fmt: skip
    left.set_xlabel("ground slope γ (rad)")
    left.set_ylabel("hip-spring stiffness k (m_f·g·l/rad)")
    left.set_title("Simplest walker with Kuo's hip spring: where the long-step gait is stable",
                   fontsize=10)  # fmt: skip
    left.set_xlim(0.0, SLOPE_TO)
    left.legend(fontsize=8, loc="upper left")
    left.grid(alpha=0.3)
    right.plot(lam[:, 1], curve.periods, "-o", ms=3, color="k")
    right.set_xlabel("hip-spring stiffness k (m_f·g·l/rad)")
    right.set_ylabel("step period at the PD, T (τ = t·√(g/l))")
    right.set_title("Step period along the PD curve (the spring swings the leg faster)",
                    fontsize=10)  # fmt: skip
    right.grid(alpha=0.3)
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
