"""FROST's RABBIT gait design on the five-link biped, verified self-consistently (issue 20).

The problem (``gaitopt.hzd.rabbit``; FROST's RABBIT example, Westervelt et al. 2007, §6.6) on
``five_link_biped`` with OptimTraj's parameters: one step under hybrid-invariant Bézier virtual
constraints of degree 5 on the four actuated links, phase variable θ = (q1 + q2)/2, minimising
the effort ``∫‖u‖² dt`` subject to an average speed of 0.75 m/s, the swing foot ≥ 0.1 m at
mid-step, ``|u| ≤ 100 N·m``, the stance foot's normal force ``N ≥ 0`` and friction cone
``|F_t| ≤ 0.6 N`` (declared unilateral constraints of the closed loop), θ monotonic and hybrid
invariance.  The mass and inertia values are OptimTraj's, not FROST's, so no published optimum
applies; the design is checked against itself:

* two resolutions of the design's quadrature (``points`` phases) reach the same optimum, and the
  coarse optimum re-evaluated on the fine grid has the fine cost to the quadrature's error;
* the invariance residual (``max(|y⁺|, |ẏ⁺|/θ̇⁻)`` after the impact) is ≤ 1e-10;
* the full-order closed loop (multiple shooting, dense checks of every declared constraint, the
  independent simulation) for growing ω_n: its period is the zero dynamics' step time, one
  multiplier is the restricted map's slope δ²_zero and the others fall towards 0;
* the effort integrated again by DOP853 along the full-order closed loop (rtol 1e-11);
* the closed loop simulated from perturbed post-impact states returns to the gait.

    python problems/rabbit_hzd.py --out results [--fast]

Writes results/rabbit_hzd/: rabbit_hzd.csv (the full-order gait against ω_n), design.csv (the
design at each resolution), perturbed.csv (distance to the fixed point per step), rabbit_hzd.json
(summary), outputs.png (outputs against θ), torques.png, zero_dynamics.png (phase portrait and
restricted map with its fixed point).  ``--fast``: one coarse resolution, one gain, two
perturbed starts (the same checks, looser grid).
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
from gaitopt.hzd.bezier import bezier  # noqa: E402
from gaitopt.hzd.design import surface_gait  # noqa: E402
from gaitopt.hzd.gait import hzd_gait  # noqa: E402
from gaitopt.hzd.rabbit import RABBIT, design_rabbit, rabbit_start  # noqa: E402
from gaitopt.hzd.zero_dynamics import restricted_map  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

DEGREE, ZETA = 5, 1.0
HEADER = ["omega_n", "period_s", "hzd_step_time_s", "mu_slope", "hzd_slope", "mu_minus_slope",
          "max_abs_other_mu", "max_abs_torque_Nm", "min_normal_force_N",
          "min_friction_margin_N", "verified", "verification_error"]  # fmt: skip
DESIGN_HEADER = ["points", "effort_N2m2s", "speed_m_s", "step_length_m", "step_time_s", "slope",
                 "max_abs_torque_Nm", "mid_step_foot_m", "min_normal_force_N",
                 "min_friction_margin_N", "success"]  # fmt: skip


def simulated_effort(model, x0: np.ndarray) -> tuple[float, float]:
    """``∫‖u‖² dt`` (N²·m²·s) and the step time (s) by DOP853 (rtol 1e-11) of the closed loop
    from ``x0`` to its guard (independent of the shooting and of the quadrature)."""
    flow = model.phases[0].flow
    guard = model.phases[0].transitions[0].guard
    n = len(x0)

    def rhs(t, y):
        del t
        dx = np.asarray(flow(y[:n], [], model.p), dtype=float).ravel()
        return np.r_[dx, np.sum(model.torques(y[:n]) ** 2)]

    def hit(t, y):
        del t
        return float(guard(y[:n], [], model.p)) if t_ok(y) else 1.0

    def t_ok(y):  # the guard counts only ahead of the stance foot (the model's admissibility)
        return float(model.phases[0].transitions[0].admissible(y[:n], [], model.p)) > 0

    hit.terminal, hit.direction = True, -1
    sol = solve_ivp(rhs, (0, 5), np.r_[x0, 0.0], method="DOP853", rtol=1e-11, atol=1e-11,
                    events=hit)  # fmt: skip
    return float(sol.y[n, -1]), float(sol.t[-1])


def _margins(g) -> tuple[float, float, float]:
    """Mid-step foot height (m), least normal force and friction margin (N) of a design."""
    c = g.conditions
    friction = min(np.min(c["stance foot does not slip forward"]),
                   np.min(c["stance foot does not slip backward"]))  # fmt: skip
    return (float(g.foot[len(g.foot) // 2]), float(np.min(c["stance foot pushes on the ground"])),
            float(friction))  # fmt: skip


def _orbit_margins(gait) -> tuple[float, float]:
    """Least normal force and friction margin (N) on the full-order orbit's dense samples."""
    X = np.hstack([arc.x for arc in gait.cycle.orbit])
    values = {c.name: np.asarray(c.function(X, [], gait.model.p), dtype=float).ravel()
              for c in gait.model.phases[0].constraints}  # fmt: skip
    friction = min(np.min(values["stance foot does not slip forward"]),
                   np.min(values["stance foot does not slip backward"]))  # fmt: skip
    return float(np.min(values["stance foot pushes on the ground"])), float(friction)


def perturbed_runs(gait, starts: int, steps: int, seed: int = 1) -> list[list[float]]:
    """Simulate the closed loop from ``starts`` perturbed post-impact states (each section
    coordinate moved by U(−0.02, 0.02) rad or U(−0.1, 0.1) rad/s) for ``steps`` steps; rows of
    ``[start, step, distance]`` with the distance to the fixed point on the section (rad-rad/s
    mixed norm)."""
    model = gait.model
    names = model.section.coordinates
    fixed = np.asarray(model.section_coordinates_of(gait.cycle.x), dtype=float)
    rng = np.random.default_rng(seed)
    rows = []
    for k in range(starts):
        scale = np.array([0.1 if n.endswith("_dot") else 0.02 for n in names])
        start = fixed + rng.uniform(-1, 1, fixed.size) * scale
        run = gaitopt.simulate(model, dict(zip(names, map(float, start), strict=True)),
                               steps=steps)  # fmt: skip
        rows.append([k, 0, float(np.linalg.norm(start - fixed))])
        for j, x in enumerate(run.section_states, start=1):
            s = np.asarray(model.section_coordinates_of(x), dtype=float)
            rows.append([k, j, float(np.linalg.norm(s - fixed))])
        if not run.success and len(run.section_states) < steps:
            rows.append([k, -1, float("nan")])  # the run ended early (a fall): marked
    return rows


def figures(folder: Path, design, gait) -> None:
    model = gait.model
    names = model.state_names
    X = np.hstack([arc.x for arc in gait.cycle.orbit])
    theta = model.phase_value(X)
    s = (theta - model.theta_plus) / (model.theta_minus - model.theta_plus)
    fig, axes = plt.subplots(2, 2, figsize=(8, 6), sharex=True)
    for ax, joint in zip(axes.ravel(), model.joints, strict=True):
        ax.plot(theta, X[names.index(joint)], color="k", lw=2.5, alpha=0.4,
                label="full-order orbit q_a")  # fmt: skip
        ax.plot(theta, bezier(model.alpha[joint], s), "--", color="C0", label="Bézier h_d(s(θ))")
        ax.set_ylabel(f"{joint.replace('_', ' ')} angle (rad)")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    for ax in axes[1]:
        ax.set_xlabel("phase variable θ = (q1 + q2)/2 (rad)")
    fig.suptitle("RABBIT (five-link biped): virtual constraints, degree 5")
    save_figure(fig, folder / "outputs.png")

    fig, ax = plt.subplots(figsize=(6.4, 4))
    labels = ("stance knee u2", "stance hip u3", "swing hip u4", "swing knee u5")
    U = model.torques(X)
    for k, label in enumerate(labels):
        ax.plot(design.theta, design.torques[k], color=f"C{k}", label=f"{label} (design)")
        ax.plot(theta, U[k], ":", color="k", lw=0.8)
    ax.axhline(RABBIT["torque_limit"], color="r", lw=0.8)
    ax.axhline(-RABBIT["torque_limit"], color="r", lw=0.8)
    ax.set_xlabel("phase variable θ (rad)")
    ax.set_ylabel("joint torque u (N·m)")
    ax.set_title("Torques: design (quadrature) and full-order orbit (dotted); bound ±100 N·m")
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)
    save_figure(fig, folder / "torques.png")

    rmap = restricted_map(model)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    zeta_plus = rmap.slope * rmap.fixed_point
    for factor in (0.4, 0.7, 1.0, 1.5, 2.2):
        zeta = factor * zeta_plus - rmap.V_zero
        ok = zeta > 0
        rate = -np.sqrt(2 * np.where(ok, zeta, np.nan)) / np.abs(rmap.inertia)
        style = dict(color="k", lw=2) if factor == 1.0 else dict(color="C0", lw=0.8)
        ax1.plot(rmap.theta, rate, **style,
                 label="gait (ζ⁺ = δ² ζ*)" if factor == 1.0 else None)  # fmt: skip
    ax1.set_xlabel("phase variable θ (rad)")
    ax1.set_ylabel("phase rate θ̇ (rad/s)")
    ax1.set_title("Zero dynamics: orbits from ζ⁺ = (0.4 … 2.2) δ² ζ*")
    ax1.legend(fontsize=7)
    ax1.grid(True, alpha=0.3)
    z = np.linspace(0, 2 * rmap.fixed_point, 50)
    ax2.plot(z, [rmap(v) for v in z], label=f"ρ(ζ⁻), slope δ² = {rmap.slope:.4f}")
    ax2.plot(z, z, "--", color="gray", label="ρ = ζ⁻")
    ax2.plot([rmap.fixed_point], [rmap.fixed_point], "o", color="k",
             label=f"fixed point ζ* = {rmap.fixed_point:.2f}")  # fmt: skip
    ax2.set_xlabel("pre-impact ζ⁻ = σ⁻²/2 ((kg·m²/s)²)")
    ax2.set_ylabel("next ζ⁻ ((kg·m²/s)²)")
    ax2.set_title("Restricted Poincaré map")
    ax2.legend(fontsize=7)
    ax2.grid(True, alpha=0.3)
    save_figure(fig, folder / "zero_dynamics.png")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="CI mode (coarse grid, one gain)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "rabbit_hzd"
    folder.mkdir(parents=True, exist_ok=True)
    resolutions = (101,) if args.fast else (101, 201)
    gains = (20.0,) if args.fast else (10.0, 20.0, 40.0, 80.0)
    starts, steps = (2, 6) if args.fast else (6, 20)

    plant = gaitopt.model("five_link_biped")
    start = rabbit_start(plant, DEGREE)
    designs = {}
    for points in resolutions:
        result = design_rabbit(start, points=points)
        if not result.success:
            print(f"the design at {points} phases failed: {result.message}")
            return 1
        designs[points] = result.optimum
    fine = designs[resolutions[-1]]
    coarse = designs[resolutions[0]]
    rows = []
    for points, g in designs.items():
        mid, normal, friction = _margins(g)
        rows.append([points, g.effort, g.speed, g.step_length, g.step_time, g.slope,
                     g.max_torque, mid, normal, friction, True])  # fmt: skip
    write_csv(DESIGN_HEADER, rows, folder / "design.csv")
    recheck = surface_gait(coarse.model, resolutions[-1])
    agreement = {
        "effort_difference": abs(fine.effort - coarse.effort),
        "slope_difference": abs(fine.slope - coarse.slope),
        "max_coefficient_difference_rad": float(
            max(
                np.max(np.abs(fine.model.alpha[j] - coarse.model.alpha[j]))
                for j in fine.model.joints
            )
        ),  # fmt: skip
        "coarse_optimum_on_fine_grid_effort": recheck.effort,
    }

    table, certified = [], {}
    for w in gains:
        gait = hzd_gait(plant, DEGREE, alpha=fine.model, omega_n=w, zeta=ZETA)
        if gait.cycle is None or not gait.cycle.success:
            table.append([w, None, fine.step_time, None, fine.slope, None, None, None, None,
                          None, False, None])  # fmt: skip
            continue
        mu = gait.cycle.multipliers
        k = int(np.argmin(np.abs(mu - fine.slope)))
        others = np.delete(mu, k)
        normal, friction = _orbit_margins(gait)
        table.append([w, gait.cycle.period, fine.step_time, float(mu[k].real), fine.slope,
                      float(abs(mu[k] - fine.slope)), float(np.max(np.abs(others))),
                      gait.max_torque, normal, friction, bool(gait.success and
                      gait.cycle.verified), gait.cycle.verification_error])  # fmt: skip
        certified[w] = gait
    write_csv(HEADER, table, folder / "rabbit_hzd.csv")
    if not certified:
        print("no full-order gait was certified")
        return 1
    w_ref = 20.0 if 20.0 in certified else min(certified)
    gait = certified[w_ref]
    effort, step_time = simulated_effort(gait.model, gait.cycle.x)
    runs = perturbed_runs(gait, starts, steps)
    write_csv(["start", "step", "distance"], runs, folder / "perturbed.csv")
    final = [r[2] for r in runs if r[1] == steps]
    initial = [r[2] for r in runs if r[1] == 0]
    summary = {
        "source": "FROST's RABBIT design problem (Hereid & Ames 2017) on OptimTraj's five-link "
        "biped (Kelly 2017); Westervelt et al. 2007, §6.3–6.6",
        "problem": {**RABBIT, "objective": "integral of |u|^2 dt over one step (N^2 m^2 s)",
                    "phase_variable": "(stance_shank + stance_thigh)/2", "zeta": ZETA},
        "design": dict(zip(DESIGN_HEADER, rows[-1], strict=True)),
        "resolutions": list(resolutions),
        "agreement": agreement,
        "bezier": {j: [float(v) for v in a] for j, a in fine.model.alpha.items()},
        "theta_plus": fine.model.theta_plus,
        "theta_minus": fine.model.theta_minus,
        "invariance_residual": gait.invariance_residual,
        "full_order_omega_n": w_ref,
        "simulated_effort": effort,
        "simulated_step_time": step_time,
        "perturbed": {"starts": starts, "steps": steps, "initial_max": max(initial),
                      "final_max": max(final) if len(final) == starts else None,
                      "all_returned": len(final) == starts and max(final) < 1e-2 * min(initial)},
    }  # fmt: skip
    write_json(summary, folder / "rabbit_hzd.json")
    figures(folder, fine, gait)
    print(
        f"RABBIT HZD optimum: effort {fine.effort:.6f} N²·m²·s at {fine.speed:.6f} m/s (step "
        f"{fine.step_length:.6f} m in {fine.step_time:.6f} s), δ² {fine.slope:.7f}; resolutions "
        f"{resolutions} differ by {agreement['effort_difference']:.2e}; full order at ω_n "
        f"{w_ref:g}: period {gait.cycle.period:.7f} s, residual {gait.invariance_residual:.1e}, "
        f"simulated effort {effort:.6f}; perturbed runs {summary['perturbed']}"
    )
    print(f"wrote {folder}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
