"""One-dimensional hopper (Tedrake's exercise): the apex map, its deadbeat region, the gaits.

Sources: Tedrake, *Underactuated Robotics*, ch. "Simple Models of Walking and Running", exercise
"One-Dimensional Hopper" and its notebook ``exercises/simple_legs/one_d_hopper.ipynb``
(github.com/RussTedrake/underactuated): body 10 kg and leg 1 kg (its URDF), spring k = 1000 N/m,
plastic touchdown and lift-off, the preload law δ̄ set at the bottom and reset at the apex, the
desired apex h = 1 m; the controller is a one-dimensional version of Raibert 1984, "Hopping in
legged systems", IEEE Trans. SMC 14(3).  Closed forms restated in
:mod:`gaitopt.models.one_d_hopper`: the bottom (eq. 2), the law (eq. 3), the next apex (eq. 4),
the passive map ``P(h) = ρ h`` with ``ρ = (m_b/(m_b + m_l))²`` (eq. 5), the deadbeat region
``(0, h_d/ρ]`` and the stroke's highest apex ``h_max = k s²/(2 m_b g) − s``.

What it does, at the defaults of ``gaitopt.model("one_d_hopper")``:

1. samples the apex map by simulation over ``(0, h_max]`` and compares it with the closed form
   (deadbeat ``h_d`` below ``h_d/ρ``, passive ``ρ h`` above), with the preload applied;
2. measures the passive apex ratio from simulated hops with the preload clamped at 0 and from
   the fully passive hopper (``desired_apex = 0``), and asks the gait search for the passive
   hopper's gait (there is none: the report says why);
3. simulates hops from apexes 0.3, 1.6 and 2.1 m (deadbeat at once; passive decay into the
   deadbeat region, then one hop to ``h_d``);
4. solves the gait by multiple shooting for several desired apexes (fixed point ``h_d``,
   multiplier 0), continues in ``desired_apex`` to the stroke boundary and compares it with
   ``h_max``.

Writes ``OUT/one_d_hopper_study/``: ``apex_map.csv``, ``convergence.csv``, ``gaits.csv``,
``summary.json`` and ``apex_map.png`` (the map with the deadbeat region shaded, the preload).
``--fast``: fewer samples.  Exit status 0 only if every check holds.

Usage::

    python problems/one_d_hopper.py --out results [--fast]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_csv, write_json
from gaitopt.plotting import save_figure
from gaitopt.returnmap import return_map

STUDY = "one_d_hopper_study"
SOURCE = (
    "Tedrake, Underactuated Robotics, One-Dimensional Hopper exercise "
    "(exercises/simple_legs/one_d_hopper.ipynb); Raibert 1984; closed forms in "
    "gaitopt.models.one_d_hopper"
)
STARTS = (0.3, 1.6, 2.1)  # m: deadbeat at once; passive decay, then deadbeat


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="fewer samples (CI)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    hopper = gaitopt.model("one_d_hopper")
    rho, h_max, h_d = hopper.apex_ratio, hopper.highest_apex(), hopper.desired_apex
    edge = hopper.deadbeat_region()[1]

    # 1. The apex map by simulation vs the closed form.
    grid = np.linspace(0.02, h_max, 25 if args.fast else 120)
    rows = []
    for h in grid:
        simulated = float(return_map(hopper, float(h))[0])
        region = "deadbeat" if hopper.preload_law(float(h)) >= 0 else "passive"
        rows.append(
            [
                float(h),
                simulated,
                hopper.closed_form_map(float(h)),
                hopper.preload_law(float(h)),
                hopper.preload(float(h)),
                region,
            ]
        )
    write_csv(
        ["apex_m", "next_apex_simulated_m", "next_apex_closed_form_m", "preload_law_m",
         "preload_m", "region"],
        rows,
        out / "apex_map.csv",
    )  # fmt: skip
    map_error = max(abs(r[1] - r[2]) for r in rows)
    deadbeat_error = max(abs(r[1] - h_d) for r in rows if r[5] == "deadbeat")
    passive_ratio_error = max(abs(r[1] / r[0] - rho) for r in rows if r[5] == "passive")

    # 2. The passive hopper: ratio from simulation, and no gait.
    passive = hopper.replace(desired_apex=0.0)
    passive_ratios = [float(return_map(passive, h)[0]) / h for h in (0.2, 1.0, 2.0)]
    passive_ratio_error = max(passive_ratio_error, max(abs(r - rho) for r in passive_ratios))
    no_gait = gaitopt.find_limit_cycle(passive, follow=False)

    # 3. Hops from a few apexes.
    conv_rows, trajectories = [], {}
    for first in STARTS:
        sim = gaitopt.simulate(hopper, {"z_b": first}, steps=6)
        apexes = [first] + [float(x[0]) for x in sim.section_states]
        trajectories[first] = apexes
        conv_rows += [[first, n, h] for n, h in enumerate(apexes)]
    write_csv(["start_m", "hop", "apex_m"], conv_rows, out / "convergence.csv")

    # 4. Gaits by shooting, continuation to the stroke boundary.
    targets = (0.2, 1.0, 2.0) if args.fast else (0.05, 0.2, 0.5, 1.0, 1.5, 2.0, 2.15)
    gait_rows = []
    for target in targets:
        cycle = gaitopt.find_limit_cycle(hopper.replace(desired_apex=target))
        gait_rows.append(
            [
                target,
                cycle.fixed_point["z_b"] if cycle.success else float("nan"),
                float(abs(cycle.multipliers[0])) if cycle.success else float("nan"),
                cycle.period if cycle.success else float("nan"),
                hopper.replace(desired_apex=target).preload(target),
                bool(cycle.success and cycle.verified),
            ]
        )
    write_csv(
        ["desired_apex_m", "fixed_point_m", "abs_multiplier", "period_s", "preload_m",
         "verified"],
        gait_rows,
        out / "gaits.csv",
    )  # fmt: skip
    default_cycle = gaitopt.find_limit_cycle(hopper)
    branch = gaitopt.continuation(hopper, "desired_apex", to=2.5)
    boundaries = [sp.param for sp in branch.special_points if sp.kind == "boundary"]
    boundary = boundaries[0] if boundaries else float("nan")
    branch_error = max(
        abs(c.fixed_point["z_b"] - c.model.desired_apex) for c in branch.cycles if c.success
    )
    branch_multiplier = max(float(abs(c.multipliers[0])) for c in branch.cycles if c.success)

    # The figure: the map with the deadbeat region shaded, the staircases, the preload.
    fig, axes = plt.subplots(1, 2, figsize=(10.5, 4.4), layout="constrained")
    ax = axes[0]
    fine = np.linspace(1e-3, h_max, 400)
    ax.axvspan(
        0.0, edge, color="C2", alpha=0.12, label=f"deadbeat region 0 < h ≤ h_d/ρ = {edge:.4g} m"
    )
    ax.plot(fine, [hopper.closed_form_map(h) for h in fine], "k-", lw=1.0, label="closed form P(h)")
    ax.plot(grid, [r[1] for r in rows], "o", ms=3, color="C0", label="simulated (SciPy)")
    ax.plot(fine, rho * fine, ":", color="C3", lw=0.9, label=f"passive ρ h, ρ = {rho:.6f}")
    ax.plot(fine, fine, "--", color="0.5", lw=0.7, label="h[n+1] = h[n]")
    for j, first in enumerate(STARTS):
        xs = trajectories[first]
        stair_x, stair_y = [xs[0]], [xs[0]]
        for a, b in zip(xs[:-1], xs[1:], strict=True):
            stair_x += [a, b]
            stair_y += [b, b]
        ax.plot(stair_x, stair_y, "-", color=f"C{4 + j}", lw=0.8, alpha=0.8,
                label=f"hops from {first:g} m")  # fmt: skip
    ax.axvline(h_max, color="C1", lw=0.8, ls="-.", label=f"stroke limit h_max = {h_max:.5g} m")
    ax.plot([h_d], [h_d], "o", color="k", ms=6, label=f"gait h* = h_d = {h_d:g} m, λ = 0")
    ax.set_xlabel("apex height h[n] = z_b at apex (m)")
    ax.set_ylabel("next apex height h[n+1] (m)")
    ax.set_xlim(0, h_max * 1.03)
    ax.set_ylim(0, h_max * 1.03)
    ax.legend(fontsize=6.5, loc="upper left")
    ax.grid(alpha=0.3)
    ax.set_title("apex-to-apex map P", fontsize=9)
    ax = axes[1]
    ax.axvspan(0.0, edge, color="C2", alpha=0.12, label="deadbeat region")
    ax.plot(fine, [hopper.preload_law(h) for h in fine], "--", color="C0", lw=0.9,
            label="law δ̄ (eq. 3)")  # fmt: skip
    ax.plot(fine, [hopper.preload(h) for h in fine], "-", color="C0", lw=1.4,
            label="preload applied δ = max(δ̄, 0)")  # fmt: skip
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("apex height h[n] = z_b at apex (m)")
    ax.set_ylabel("spring preload δ at the bottom (m)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax.set_title(f"preload law for h_d = {h_d:g} m", fontsize=9)
    fig.suptitle(
        f"One-dimensional hopper (Tedrake's exercise): m_b = {hopper.body_mass:g} kg, "
        f"m_l = {hopper.leg_mass:g} kg, k = {hopper.stiffness:g} N/m, s = {hopper.stroke:g} m",
        fontsize=10,
    )
    save_figure(fig, out / "apex_map.png")

    all_verified = all(r[5] for r in gait_rows) and default_cycle.verified
    summary = {
        "study": STUDY,
        "source": SOURCE,
        "params": hopper.params,
        "fixed_point": default_cycle.fixed_point["z_b"],
        "fixed_point_closed_form": hopper.closed_form_fixed_point(),
        "multiplier_abs": float(abs(default_cycle.multipliers[0])),
        "multiplier_closed_form": hopper.multiplier(),
        "period_s": default_cycle.period,
        "bottom_at_fixed_point_m": hopper.bottom(h_d),
        "preload_at_fixed_point_m": hopper.preload(h_d),
        "apex_ratio_closed_form": rho,
        "apex_ratio_simulated": passive_ratios,
        "passive_ratio_max_error": passive_ratio_error,
        "deadbeat_region_m": list(hopper.deadbeat_region()),
        "deadbeat_max_error_m": deadbeat_error,
        "map_max_error_vs_closed_form_m": map_error,
        "highest_apex_closed_form_m": h_max,
        "stroke_boundary_continuation_m": boundary,
        "stroke_boundary_error_m": abs(boundary - h_max),
        "branch_max_fixed_point_error_m": branch_error,
        "branch_max_abs_multiplier": branch_multiplier,
        "branch_points": len(branch.cycles),
        "passive_hopper_gait": {
            "success": no_gait.success,
            "status": no_gait.status,
            "message": no_gait.message,
        },
        "hops": {f"{k:g}": v for k, v in trajectories.items()},
        "all_verified": all_verified,
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - start,
    }
    write_json(summary, out / "summary.json")
    print(
        f"gait h* = {summary['fixed_point']:.12f} m (closed form {h_d:g}), |λ| = "
        f"{summary['multiplier_abs']:.2g} (closed form 0), period {default_cycle.period:.10f} s, "
        f"preload δ̄ = {hopper.preload(h_d):.10f} m"
    )
    print(
        f"map vs closed form: max error {map_error:.2g} m; deadbeat hops reach h_d within "
        f"{deadbeat_error:.2g} m; passive ratio ρ = {rho:.10f}, simulated within "
        f"{passive_ratio_error:.2g}"
    )
    print(
        f"deadbeat region (0, {edge:.6g}] m; stroke boundary by continuation {boundary:.9f} m vs "
        f"h_max = {h_max:.9f} m; passive hopper: success {no_gait.success} ({no_gait.status})"
    )
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    ok = (
        map_error < 1e-8
        and deadbeat_error < 1e-8
        and passive_ratio_error < 1e-9
        and abs(boundary - h_max) < 1e-7
        and branch_error < 1e-9
        and branch_multiplier < 1e-9
        and not no_gait.success
        and all_verified
    )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
