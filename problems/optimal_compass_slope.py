"""The compass gait on a slope: the least-effort gait at the passive gait's step is that gait.

On its default slope (Drake's parameters, γ = 0.0525 rad) the compass gait walks with no torque
at all.  Two independent transcriptions must therefore agree: multiple shooting finds the
passive gait (:func:`gaitopt.find_limit_cycle`, period T* and step length L*), and the
least-effort optimisation (:func:`gaitopt.optimize_gait`, Radau collocation with the hip torque
τ(t) as a profile) at T* and L* must return zero effort, the passive fixed point and its
multipliers.  Away from T* the walker must work: a library of optima in the period at L*
(warm-started, checked against cold starts) shows the least effort rising from zero on both
sides, quadratically (a smooth minimum of ∫τ² dt at a gait that needs none).

    python problems/optimal_compass_slope.py --out results [--fast]

Writes results/optimal_compass_slope/: summary.json, library.csv, effort.png.
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
from gaitopt.optimize import gait_library  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402


def passive_step(model: gaitopt.HybridModel, cycle: gaitopt.LimitCycle) -> float:
    """Distance between the feet at heel strike (m): at the section the legs have only swapped
    names, so the swing foot's position there."""
    x = model.state_vector(cycle.fixed_point)
    phase = model.phases[0]
    points = np.asarray(phase.points(x, model.p), dtype=float)
    return float(np.linalg.norm(points[:, phase.point_names.index("swing_foot")]))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="five periods, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_compass_slope"
    folder.mkdir(parents=True, exist_ok=True)

    model = gaitopt.model("compass_gait")  # Drake's defaults, slope 0.0525 rad
    cycle = gaitopt.find_limit_cycle(model)
    T, L = cycle.period, passive_step(model, cycle)
    gait = gaitopt.optimize_gait(model, period=T, step_length=L)
    names = model.state_names
    x_opt = np.array([gait.fixed_point[n] for n in names]) if gait.success else None
    x_ref = np.array([cycle.fixed_point[n] for n in names])
    state_gap = float(np.max(np.abs(x_opt - x_ref))) if x_opt is not None else None
    mu_gap = (
        float(
            np.max(np.abs(np.sort_complex(gait.multipliers) - np.sort_complex(cycle.multipliers)))
        )
        if gait.success
        else None
    )
    print(
        f"passive gait (shooting): T* = {T:.10f} s, L* = {L:.10f} m; least effort there "
        f"{gait.cost:.3g} N²·m²·s, fixed point {state_gap:.2g} from shooting's, multipliers "
        f"{mu_gap:.2g} apart, verified {gait.verified}"
    )

    fractions = np.linspace(0.9, 1.1, 5 if args.fast else 11)
    library = gait_library(model, "period", T * fractions, step_length=L, cold=2)
    print(library.message)
    rows = []
    for pt in library.points:
        g = pt.gait
        mu = float(np.max(np.abs(g.multipliers))) if g.success else None
        rows.append((pt.value, pt.value / T, g.cost if g.success else None, mu, g.success))
    write_csv(["period_s", "period_over_passive", "effort_N2m2s", "max_abs_multiplier",
               "certified"], rows, folder / "library.csv")  # fmt: skip

    # Quadratic growth away from T*: effort / (T − T*)² at each period (N²·m²/s).
    curvature = [
        r[2] / (r[0] - T) ** 2 for r in rows if r[2] is not None and abs(r[0] - T) > 1e-9 * T
    ]
    summary = {
        "slope": model.params["slope"],
        "passive": {
            "period": T,
            "step_length": L,
            "fixed_point": cycle.fixed_point,
            "multipliers": [[m.real, m.imag] for m in cycle.multipliers],
        },
        "optimum_at_passive": gait.to_json(),
        "effort_at_passive": gait.cost,
        "fixed_point_difference": state_gap,
        "multiplier_difference": mu_gap,
        "library": library.to_json(),
        "effort_over_squared_period_offset": curvature,
    }
    write_json(summary, folder / "summary.json")

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    ok = [r for r in rows if r[2] is not None]
    ax1.plot([r[0] for r in ok], [r[2] for r in ok], "o-", label=f"least effort, step {L:.4f} m")
    ax1.axvline(T, color="k", lw=0.8, ls="--", label=f"passive gait, T* = {T:.4f} s")
    ax1.set_xlabel("period T (s)")
    ax1.set_ylabel("least effort ∫τ² dt (N²·m²·s)")
    ax1.set_title(f"Compass gait on a slope γ = {model.params['slope']} rad")
    ax1.legend()
    for pt in library.points[:: max(1, len(library.points) // 4)]:
        g = pt.gait
        if not g.success:
            continue
        t = np.asarray(g.inputs["time"])
        ax2.plot(t, g.inputs["hip_torque"], label=f"T = {pt.value:.3f} s")
    ax2.set_xlabel("time since heel strike t (s)")
    ax2.set_ylabel("hip torque τ (N·m)")
    ax2.set_title("Optimal torque profiles")
    ax2.legend()
    save_figure(fig, folder / "effort.png")
    ok_all = bool(
        gait.success
        and gait.cost <= 1e-8
        and state_gap is not None
        and state_gap <= 1e-6
        and library.success
    )
    return 0 if ok_all else 1


if __name__ == "__main__":
    raise SystemExit(main())
