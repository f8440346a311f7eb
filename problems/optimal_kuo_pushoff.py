"""Kuo's push-off against hip-torque powering: the simplest walker on level ground.

Kuo (2002, "Energetics of actively powered locomotion using the simplest walking model",
J. Biomech. Eng. 124:113–120; restated in Kuo & Donelan 2010, Phys. Ther. 90:157, Fig. 4:
"pre-emptive push-off theoretically can reduce collision losses by three quarters") powers the
simplest walker on level ground in two ways: an impulsive push-off P along the trailing leg just
before heel strike, or a hip torque τ(t) on the stance leg during the step; a hip spring sets the
step frequency apart from the speed (it does no work).  In the small-angle limit the pre-emptive
push-off costs about four times less work per step.

Here both are *optimised* with :func:`gaitopt.optimize_gait`, cost = positive work per step (units
of M·g·l), at the same step length (s = 0.4 l) and period (90 % of the unsprung push-off gait's, so
that the hip spring is positive), the spring stiffness free in both:

* push-off only (τ ≡ 0): the optimum must be Kuo's steady gait, P = v tan α with v = |θ̇| at heel
  strike and α = asin(s/2) (closed form; checked to 1e-9), work P²/2;
* hip torque only (P ≡ 0, 0 ≤ τ ≤ τ_max, the torque only pushing forward) for a few bounds τ_max:
  the least work falls towards the impulsive-torque limit, a kick right after heel strike that
  leaves the stance motion of the push-off gait, so the collision costs ½ v² sin² 2α and the ratio
  to push-off is sin² 2α / tan² α = 4 cos⁴ α (3.686 at α = asin 0.2; 4 as α → 0: Kuo's factor).

Every optimum is verified by simulation (return to the fixed point, the same work) and its
discretisation error estimated by mesh refinement.

    python problems/optimal_kuo_pushoff.py --out results [--fast]

Writes results/optimal_kuo_pushoff/: pushoff.json, pushoff.csv, pushoff.png.
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
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.optimize import GaitProblem, solve_problem  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

STEP = 0.4  # step length s (leg lengths l)
PERIOD_FRACTION = 0.9  # of the unsprung push-off gait's period


def push_off_gait(step: float = STEP, fraction: float = PERIOD_FRACTION):
    """Kuo's push-off gait on level ground at ``step`` and ``fraction`` of the unsprung period
    (hip spring free): returns ``(unsprung, gait)``."""
    model = gaitopt.model("simplest_walker", slope=0.0)
    unsprung = gaitopt.optimize_gait(model, "work", step_length=step, bounds={"hip_torque": 0})
    if not unsprung.success:
        return unsprung, unsprung
    gait = gaitopt.optimize_gait(
        model,
        "work",
        step_length=step,
        period=fraction * unsprung.period,
        bounds={"hip_torque": 0},
        free="hip_stiffness",
        guess=unsprung,
    )
    return unsprung, gait


def hip_torque_gait(push, bound: float, step: float = STEP):
    """The least-work hip-torque gait (``0 ≤ τ ≤ bound``, no push-off) at ``push``'s period and
    step length, hip spring free, warm-started from ``push``."""
    model = gaitopt.model("simplest_walker", slope=0.0)
    problem = GaitProblem(
        model,
        "work",
        step_length=step,
        period=push.period,
        bounds={"hip_torque": (0.0, bound), "push_off": 0},
        free=("hip_stiffness",),
    )
    return solve_problem(problem, guess=push)


def kuo_closed_form(push) -> dict[str, float]:
    """Kuo's steady push-off gait from the optimum's own heel-strike speed and angle."""
    alpha = abs(push.fixed_point["theta"])
    v = abs(push.fixed_point["theta_dot"])
    return {
        "alpha": alpha,
        "v": v,
        "push_off": v * np.tan(alpha),
        "work": 0.5 * (v * np.tan(alpha)) ** 2,
        "ratio_impulsive_torque": 4 * np.cos(alpha) ** 4,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="two torque bounds, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_kuo_pushoff"
    folder.mkdir(parents=True, exist_ok=True)

    t0 = time.perf_counter()
    unsprung, push = push_off_gait()
    if not push.success:
        print(f"push-off gait not found: {push.message}")
        return 1
    kuo = kuo_closed_form(push)
    p_opt = float(push.inputs["push_off"][-1])
    p_error = abs(p_opt - kuo["push_off"]) / kuo["push_off"]
    print(
        f"push-off: P = {p_opt:.10g} (Kuo v·tan α = {kuo['push_off']:.10g}, rel. {p_error:.1e}), "
        f"work {push.cost:.10g} M·g·l, period {push.period:.6g}, k = "
        f"{push.params['hip_stiffness']:.6g}, |λ| = {np.max(np.abs(push.multipliers)):.4f}, "
        f"verified {push.verified} ({time.perf_counter() - t0:.1f} s)"
    )
    bounds = (0.02, 0.2) if args.fast else (0.02, 0.05, 0.1, 0.2)
    rows, records = [], []
    for bound in bounds:
        t1 = time.perf_counter()
        hip = hip_torque_gait(push, bound)
        ratio = hip.cost / push.cost if hip.success else None
        rows.append(
            (bound, hip.cost, push.cost, ratio, hip.params.get("hip_stiffness"),
             hip.discretisation_error, hip.verified, hip.success)
        )  # fmt: skip
        records.append({"bound": bound, "ratio": ratio, "gait": hip.to_json()})
        print(
            f"hip torque ≤ {bound:g}: work {hip.cost} M·g·l, ratio {ratio}, verified "
            f"{hip.verified}, discretisation error {hip.discretisation_error} "
            f"({time.perf_counter() - t1:.1f} s)"
        )

    write_json(
        {
            "step_length": STEP,
            "period": push.period,
            "kuo_closed_form": kuo,
            "push_off_relative_error": p_error,
            "push_off": push.to_json(),
            "unsprung_push_off": unsprung.to_json(),
            "hip_torque": records,
        },
        folder / "pushoff.json",
    )
    write_csv(
        ["torque_bound_Mgl", "hip_torque_work_Mgl", "push_off_work_Mgl", "work_ratio",
         "hip_stiffness", "discretisation_error", "verified", "success"],
        rows,
        folder / "pushoff.csv",
    )  # fmt: skip

    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(6.4, 7))
    ok = [r for r in rows if r[7]]
    ax1.semilogx([r[0] for r in ok], [r[3] for r in ok], "o-", label="optimised hip torque")
    ax1.axhline(
        kuo["ratio_impulsive_torque"],
        color="C1",
        ls="--",
        label=f"impulsive-torque limit 4cos⁴α = {kuo['ratio_impulsive_torque']:.3f}",
    )
    ax1.axhline(4.0, color="k", lw=0.8, label="Kuo 2002, small angles: 4")  # fmt: skip
    ax1.axhline(1.0, color="C2", lw=0.8, label="push-off (reference)")
    ax1.set_xticks([r[0] for r in rows], [f"{r[0]:g}" for r in rows])
    ax1.minorticks_off()
    ax1.set_ylim(0.0, 4.5)
    ax1.set_xlabel("hip-torque bound τ_max (M·g·l)")
    ax1.set_ylabel("work per step ratio W_τ / W_P (1)")
    ax1.set_title(f"Simplest walker, level ground, step {STEP} l, period {push.period:.3f} √(l/g)")
    ax1.legend(fontsize=8)
    for record in records:
        gait = record["gait"]
        if gait["success"]:
            ax2.plot(gait["inputs"]["time"], gait["inputs"]["hip_torque"],
                     label=f"τ_max = {record['bound']:g}")  # fmt: skip
    ax2.set_xlabel("time since heel strike t (√(l/g))")
    ax2.set_ylabel("hip torque τ (M·g·l)")
    ax2.legend(fontsize=8)
    save_figure(fig, folder / "pushoff.png")
    good = push.success and p_error <= 1e-9 and all(r[7] and r[3] > 1 for r in rows)
    return 0 if good else 1


if __name__ == "__main__":
    raise SystemExit(main())
