"""An optimal HZD gait of the three-link walker: Bézier coefficients by optimisation over the
zero dynamics, certified on the full-order closed loop (issue 20, item 3).

Westervelt, Grizzle & Koditschek 2003, §VI: on a hybrid-invariant surface the gait is the zero
dynamics' fixed point, so its cost follows from the coefficients by quadrature
(``gaitopt.hzd.design.surface_gait``).  Start: the degree-4 invariant design fitted to the
fixed-constraint gait (``problems/three_link_hzd.py``).  Free: the swing leg's and the torso's
``α_2``, ``α_3`` (``α_0``, ``α_1`` are the impact's; ``α_4`` fixes the posture at impact and the
step length).  Cost ``J = (1/L) ∫ ‖u‖² dt`` (N²·m·s), SLSQP, subject to: restricted-map slope
``δ² ≤ 0.9``, ``ζ(θ) ≥ 0.05 ζ⁺`` (the walker passes mid-stance with speed), the stance foot
pushes (``N ≥ 0``) and the swing foot stays on or above the ground inside the step (the plant
itself lets a straight swing leg scuff, as Grizzle et al. 2001; the design forbids it on its
grid of 201 phases — between them the foot of the optimum, which touches the ground mid-step,
dips by the grid's interpolation error: ``min_swing_foot_height_on_orbit_samples`` reports it).

The optimum is then solved as a full-order gait (multiple shooting from the zero dynamics' fixed
point, ω_n = 20 rad/s, ζ = 1.1), whose period and dominant multiplier must equal the zero
dynamics' step time and slope, and whose cost is integrated again by an independent DOP853
simulation of the closed loop (rtol 1e-11) from its fixed point to the impact.

    python problems/three_link_hzd_optimal.py --out results [--fast]

Writes results/three_link_hzd_optimal/: optimal.json, optimal.csv (per design), optimal.png
(the start's and the optimum's stance-leg rate, torques and swing-foot height against θ1).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.hzd.design import free_interior, optimise_alpha  # noqa: E402
from gaitopt.hzd.gait import hzd_gait  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

DEGREE, OMEGA_N = 4, 20.0
CLEARANCE = 0.0  # m: the swing foot's least height inside the step, on the design's grid
HEADER = ["design", "cost_N2ms", "step_time_s", "speed_m_s", "slope", "max_abs_torque_Nm",
          "min_normal_force_N", "min_foot_height_m"]  # fmt: skip


def simulated_cost(model, x0: np.ndarray, step_length: float) -> tuple[float, float]:
    """``(1/L) ∫ ‖u‖² dt`` (N²·m·s) and the step time (s) by DOP853 (rtol 1e-11) of the closed
    loop from ``x0`` to its guard (an integration independent of the shooting and of the
    zero-dynamics quadrature)."""
    flow = model.phases[0].flow
    guard = model.phases[0].transitions[0].guard
    n = len(x0)

    def rhs(t, y):
        del t
        dx = np.asarray(flow(y[:n], [], model.p), dtype=float).ravel()
        return np.r_[dx, np.sum(model.torques(y[:n]) ** 2)]

    def hit(t, y):
        del t
        return float(guard(y[:n], [], model.p))

    hit.terminal, hit.direction = True, 1
    sol = solve_ivp(rhs, (0, 10), np.r_[x0, 0.0], method="DOP853", rtol=1e-11, atol=1e-11,
                    events=hit)  # fmt: skip
    return float(sol.y[n, -1]) / step_length, float(sol.t[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="CI mode (the same optimisation)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "three_link_hzd_optimal"
    folder.mkdir(parents=True, exist_ok=True)

    plant = gaitopt.model("three_link_walker")
    start = hzd_gait(plant, DEGREE, omega_n=OMEGA_N)
    if not start.success:
        print(start.message)
        return 1
    free = free_interior(start.model, fixed=("alpha_swing_4", "alpha_torso_4"))
    design = optimise_alpha(start.model, free, max_slope=0.9, margin=0.05, clearance=CLEARANCE)
    if not design.success:
        print(f"the optimisation failed: {design.message}")
        return 1
    opt = design.optimum
    gait = hzd_gait(plant, DEGREE, omega_n=OMEGA_N, alpha=opt.model.alpha)
    if not gait.success:
        print(f"the optimum is no full-order gait: {gait.message}")
        return 1
    cycle = gait.cycle
    mu = cycle.multipliers[np.argsort(-np.abs(cycle.multipliers))]
    sim_cost, sim_time = simulated_cost(gait.model, cycle.x, opt.step_length)
    X = np.hstack([arc.x for arc in cycle.orbit])
    points = gait.model.phases[0].points
    names = gait.model.phases[0].point_names
    foot = np.asarray(points(X, gait.model.p), dtype=float)[
        1, names.index("swing_foot") :: len(names)
    ]

    rows = []
    for name, g in (("start", design.start), ("optimum", opt)):
        inner = slice(4, -4)
        rows.append([name, g.cost, g.step_time, g.speed, g.slope, g.max_torque,
                     float(np.min(g.normal_force)), float(np.min(g.foot[inner]))])  # fmt: skip
    write_csv(HEADER, rows, folder / "optimal.csv")
    summary = {
        "source": "Westervelt, Grizzle & Koditschek 2003 (IEEE TAC 48(1)), §VI; Grizzle, Abba & "
        "Plestan 2001's three-link walker",
        "degree": DEGREE,
        "free": list(design.free),
        "constraints": {
            "max_slope": 0.9,
            "zeta_margin": 0.05,
            "normal_force": ">= 0",
            "swing_foot_height": ">= 0 inside the step",
        },  # fmt: skip
        "start": dict(zip(HEADER[1:], rows[0][1:], strict=True)),
        "optimum": dict(zip(HEADER[1:], rows[1][1:], strict=True)),
        "cost_reduction": 1 - opt.cost / design.start.cost,
        "bezier": {j: [float(v) for v in a] for j, a in gait.model.alpha.items()},
        "full_order": {
            "omega_n": OMEGA_N,
            "success": gait.success,
            "period": cycle.period,
            "dominant_multiplier": float(mu[0].real),
            "other_multipliers_abs_max": float(np.max(np.abs(mu[1:]))),
            "verified": cycle.verified,
            "verification_error": cycle.verification_error,
            "invariance_residual": gait.invariance_residual,
            "max_torque": gait.max_torque,
            "min_swing_foot_height_on_orbit_samples": float(np.min(foot[2:-2])),
            "simulated_cost": sim_cost,
            "simulated_step_time": sim_time,
        },
        "step_length_m": opt.step_length,
        "optimiser": design.message,
    }
    write_json(summary, folder / "optimal.json")

    fig, axes = plt.subplots(3, 1, figsize=(6.4, 7.6), sharex=True)
    for name, g, style in (("start", design.start, "--"), ("optimum", opt, "-")):
        axes[0].plot(g.theta, g.rate, style, color="k", label=f"{name}: J = {g.cost:.1f} N²·m·s")
        axes[1].plot(g.theta, g.torques[0], style, color="C0", label=f"u₁ (stance hip), {name}")
        axes[1].plot(g.theta, g.torques[1], style, color="C1", label=f"u₂ (swing hip), {name}")
        axes[2].plot(g.theta, 1000 * g.foot, style, color="C2", label=name)
    axes[0].set_ylabel("stance-leg rate θ̇1 (rad/s)")
    axes[0].set_title("Three-link walker: optimal HZD gait (Bézier degree 4)")
    axes[1].set_ylabel("torque u (N·m)")
    axes[2].set_ylabel("swing-foot height (mm)")
    axes[2].axhline(0, color="k", lw=0.8)
    axes[2].set_xlabel("stance-leg angle θ1 (rad)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    save_figure(fig, folder / "optimal.png")

    print(
        f"optimal HZD gait: J {design.start.cost:.4f} → {opt.cost:.4f} N²·m·s "
        f"({100 * summary['cost_reduction']:.1f} % less), step {opt.step_time:.8f} s "
        f"(full order {cycle.period:.8f} s), δ² {opt.slope:.7f} (μ₁ {mu[0].real:.7f}), max |u| "
        f"{gait.max_torque:.2f} N·m, simulated J {sim_cost:.4f}"
    )
    print(f"wrote {folder}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
