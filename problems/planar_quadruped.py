"""The planar quadruped's passive pronk and bound against energy and touchdown angle.

The energy-conserving sagittal template of Scout II (Poulakakis, Papadopoulos & Buehler 2006,
"On the stability of the passive dynamics of quadrupedal running with a bounding gait", IJRR
25(3); the spring-leg running of Raibert 1986, *Legged Robots That Balance*): a rigid body in
pitch on a back and a front massless spring leg (gaitopt/models/planar_quadruped.py).
Poulakakis et al. report that the passive bound can be self-stable for some touchdown angles and
energies.  This study asks where, for the model's defaults (Scout II values as given in issue 22):

* the **pronk** (`planar_quadruped_pronk`, pitch-free, = the SLIP of stiffness 2k) continued in
  energy and in the common touchdown angle.  Its one multiplier is that of the pitch-free
  direction only (the section is the invariant set φ = φ̇ = 0);
* the **bound** (`planar_quadruped`) continued in energy at the default symmetric touchdown angle
  θ_b = θ_f = 0.21 rad, a 1-D scan of the symmetric angle θ_b = θ_f at 90 J (natural-parameter
  continuation: each gait warm-starts the next, the step halved at a failure down to 1e-3 rad,
  since the model has no single parameter for both angles), and energy continuations at further
  angles of that scan, all with their largest |multiplier| (three multipliers: z, φ, φ̇).

Every point reports the forward speed at the apex, ẋ = sqrt(2 (E − m g z − ½ I φ̇²)/m).  A
self-stable window is any computed bound with every multiplier inside the unit circle; the
summary says whether one was found and the ranges searched.

    python problems/planar_quadruped.py --out results [--fast]

Writes results/planar_quadruped_study/: pronk_energy, pronk_angle, bound_energy_theta_<θ>
(.json/.csv branches), theta_scan.json/.csv, summary.json and branches.png.
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
from gaitopt.errors import GaitoptInputError  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import plot_branch, save_figure  # noqa: E402

SECTION = ("z", "phi", "phi_dot")


def _max_mod(cycle) -> float:
    return float(np.max(np.abs(cycle.multipliers)))


def _special(branch) -> list[dict]:
    """Special points with the gait's speed, |λ|max and shortest phase there (a phase whose
    duration reaches zero is where the gait leaves its phase sequence)."""
    out = []
    for sp in branch.special_points:
        row = {"kind": sp.kind, "param": float(sp.param), "message": sp.message}
        if sp.cycle is not None and sp.cycle.success:
            d = np.asarray(sp.cycle.durations)
            row.update(
                speed=float(sp.cycle.fixed_point["x_dot"]),
                max_abs_multiplier=_max_mod(sp.cycle),
                shortest_phase=sp.cycle.model.phases[int(np.argmin(d))].name,
                shortest_phase_duration=float(d.min()),
            )
        out.append(row)
    return out


def _summary(branch) -> dict:
    mods = [_max_mod(c) for c in branch.cycles]
    speeds = [float(c.fixed_point["x_dot"]) for c in branch.cycles]
    stable = [float(getattr(c.model, branch.param)) for c in branch.cycles if c.stable]
    return {
        "param": branch.param,
        "range": [float(branch.params.min()), float(branch.params.max())],
        "points": len(branch.cycles),
        "speed_range": [min(speeds), max(speeds)],
        "max_abs_multiplier_range": [min(mods), max(mods)],
        "stable_points": len(stable),
        "stable_param_range": [min(stable), max(stable)] if stable else None,
        "special_points": _special(branch),
        "message": branch.message,
    }


def _bound_at(model, theta, guess):
    """The symmetric bound at θ_b = θ_f = theta warm-started from ``guess`` (or None)."""
    try:
        at = model.replace(back_touchdown_angle=theta, front_touchdown_angle=theta)
        cycle = gaitopt.find_limit_cycle(at, {k: guess.fixed_point[k] for k in SECTION})
    except GaitoptInputError as err:
        return None, str(err)
    if cycle.success and cycle.verified:
        return cycle, ""
    return None, cycle.message


def theta_scan(model, start, step, lo, hi, min_step=1e-3):
    """Natural-parameter continuation of the bound in θ_b = θ_f from ``start`` both ways; at a
    failure the step is halved down to ``min_step``: the returned ends bracket where the scan
    lost the gait (last found, first failed) with the failure's reason."""
    theta0 = float(model.back_touchdown_angle)
    rows, ends = [(theta0, start)], {}
    for direction in (+1, -1):
        cycle, theta, h = start, theta0, step
        while True:
            nxt = round(theta + direction * h, 6)
            if not lo <= nxt <= hi:
                ends[direction] = {"reached_scan_limit": nxt, "last": theta}
                break
            found, reason = _bound_at(model, nxt, cycle)
            if found is None:
                if h / 2 >= min_step:
                    h /= 2
                    continue
                ends[direction] = {"last": theta, "first_failed": nxt, "reason": reason}
                break
            cycle, theta, h = found, nxt, min(step, 2 * h)
            rows.append((theta, cycle))
    rows.sort(key=lambda r: r[0])
    for end in ends.values():
        last = next(c for t, c in rows if t == end["last"])
        d = np.asarray(last.durations)
        end["shortest_phase_at_last"] = last.model.phases[int(np.argmin(d))].name
        end["shortest_phase_duration_at_last"] = float(d.min())
    return rows, {"up": ends[+1], "down": ends[-1]}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "planar_quadruped_study"
    folder.mkdir(parents=True, exist_ok=True)
    fast = args.fast
    t0 = time.perf_counter()

    timings = {}

    def follow(model, param, start, bounds, max_step):
        t = time.perf_counter()
        branch = gaitopt.continuation(
            model,
            param,
            start=start,
            to=bounds[1],
            bounds=bounds,
            both_directions=True,
            cascade=False,
            options=gaitopt.PseudoArclength(max_step=max_step),
        )
        timings[f"{start.model.name} {param} from {getattr(model, param):g}"] = (
            time.perf_counter() - t
        )
        return branch

    # -- pronk --------------------------------------------------------------------------------
    pronk_model = gaitopt.model("planar_quadruped_pronk")
    pronk = gaitopt.find_limit_cycle(pronk_model)
    quad = gaitopt.model("planar_quadruped")
    bound = gaitopt.find_limit_cycle(quad)
    if not (pronk.success and bound.success):
        print(f"no gait at the defaults: {pronk.message} / {bound.message}")
        return 1
    e_range = (70.0, 200.0)  # 70 J: above the touchdown height's E = m g l0 cos θ ≈ 64 J
    a_range = (0.2, 0.3) if fast else (0.05, 0.6)
    branches = {
        "pronk_energy": follow(pronk_model, "energy", pronk, e_range, 20.0 if fast else 2.0),
        "pronk_angle": follow(
            pronk_model, "touchdown_angle", pronk, a_range, 0.2 if fast else 0.02
        ),
    }
    # -- bound: energy at the default angle, the symmetric-angle scan, energy at more angles --
    be_range = (60.0, 250.0)
    branches["bound_energy_theta_0.21"] = follow(
        quad, "energy", bound, be_range, 4.0 if fast else 0.5
    )
    scan_range = (0.17, 0.25) if fast else (0.0, 0.6)
    t_scan = time.perf_counter()
    rows, scan_ends = theta_scan(quad, bound, 0.02 if fast else 0.01, *scan_range, min_step=1e-3)
    timings["theta scan"] = time.perf_counter() - t_scan
    for theta in [] if fast else [0.1, 0.3]:
        near_theta, near = min(rows, key=lambda r: abs(r[0] - theta))
        if abs(near_theta - theta) > 0.005:
            continue  # not on the scan (the gait was not found there at 90 J)
        branches[f"bound_energy_theta_{near_theta:.3g}"] = follow(
            near.model, "energy", near, be_range, 0.5
        )
    elapsed = time.perf_counter() - t0

    # -- output -------------------------------------------------------------------------------
    summary = {"elapsed_s": elapsed, "timings_s": timings, "fast": fast, "branches": {}}
    for name, branch in branches.items():
        write_json(branch.as_dict(), folder / f"{name}.json")
        write_csv(*branch.csv_rows(), folder / f"{name}.csv")
        summary["branches"][name] = _summary(branch)
    header = ["theta_rad", "energy_J", "period_s", *quad.state_names]
    header += ["abs_multiplier_0", "abs_multiplier_1", "abs_multiplier_2", "max_abs_multiplier"]
    header += ["stable", "shortest_phase_duration_s"]
    table = [
        [theta, c.model.energy, c.period, *c.x, *np.sort(np.abs(c.multipliers))[::-1]]
        + [_max_mod(c), int(bool(c.stable)), float(np.min(c.durations))]
        for theta, c in rows
    ]
    write_csv(header, table, folder / "theta_scan.csv")
    mods = [_max_mod(c) for _, c in rows]
    summary["theta_scan"] = {
        "energy_J": quad.energy,
        "searched": list(scan_range),
        "found": [rows[0][0], rows[-1][0]],
        "points": len(rows),
        "ends": scan_ends,
        "speed_range": [
            min(c.fixed_point["x_dot"] for _, c in rows),
            max(c.fixed_point["x_dot"] for _, c in rows),
        ],
        "max_abs_multiplier_range": [min(mods), max(mods)],
        "stable_thetas": [t for t, c in rows if c.stable],
    }
    write_json({"header": header, "rows": table, "ends": scan_ends}, folder / "theta_scan.json")
    # Every bound computed: is any self-stable?
    bounds_all = [c for _, c in rows] + [
        c for n, b in branches.items() if n.startswith("bound") for c in b.cycles
    ]
    stable = [c for c in bounds_all if c.stable]
    least = min(bounds_all, key=_max_mod)
    summary["bound_self_stable_window"] = [
        {
            "theta": c.model.back_touchdown_angle,
            "energy": c.model.energy,
            "max_abs_multiplier": _max_mod(c),
        }
        for c in stable
    ] or None
    summary["bound_points_examined"] = len(bounds_all)
    summary["bound_least_unstable"] = {
        "theta": least.model.back_touchdown_angle,
        "energy": least.model.energy,
        "speed": float(least.fixed_point["x_dot"]),
        "max_abs_multiplier": _max_mod(least),
        "abs_multipliers": sorted((float(abs(z)) for z in least.multipliers), reverse=True),
    }
    summary["defaults"] = {
        "pronk": {
            "z": pronk.fixed_point["z"],
            "speed": pronk.fixed_point["x_dot"],
            "max_abs_multiplier": _max_mod(pronk),
        },
        "bound": {
            "z": bound.fixed_point["z"],
            "phi_dot": bound.fixed_point["phi_dot"],
            "speed": bound.fixed_point["x_dot"],
            "max_abs_multiplier": _max_mod(bound),
        },
    }
    write_json(summary, folder / "summary.json")

    # -- figure -------------------------------------------------------------------------------
    fig = plt.figure(figsize=(16, 7.5))
    grid = fig.add_gridspec(2, 3)
    panels = [
        ("pronk_energy", "z", "pronk: apex height vs energy"),
        ("pronk_angle", "z", "pronk: apex height vs touchdown angle"),
    ]
    for col, (name, coord, title) in enumerate(panels):
        axes = (fig.add_subplot(grid[0, col]), fig.add_subplot(grid[1, col]))
        plot_branch(branches[name], coordinate=coord, axes=axes)
        axes[0].set_title(f"{title} (solid stable, dotted unstable)", fontsize=9)
    top, bottom = fig.add_subplot(grid[0, 2]), fig.add_subplot(grid[1, 2])
    for name, branch in branches.items():
        if not name.startswith("bound"):
            continue
        label = f"θ = {name.rsplit('_', 1)[1]} rad"
        lam = branch.params
        ls = ["-" if s else ":" for s in branch.stable]
        style = "-" if all(s == "-" for s in ls) else ":"
        top.plot(lam, [c.fixed_point["phi_dot"] for c in branch.cycles], style, label=label)
        bottom.plot(lam, [_max_mod(c) for c in branch.cycles], style, label=label)
        for sp in branch.special_points:
            if sp.cycle is not None:
                top.plot([sp.param], [sp.cycle.fixed_point["phi_dot"]], "ko", ms=4)
                bottom.plot([sp.param], [_max_mod(sp.cycle)], "ko", ms=4)
    top.set_ylabel("apex pitch rate φ̇ (rad/s)")
    top.set_title("bound: apex pitch rate vs energy (dotted: unstable; ● boundary)", fontsize=9)
    bottom.axhline(1.0, color="0.3", lw=0.9, ls="--", label="|λ| = 1 (stability limit)")
    bottom.set_yscale("log")
    bottom.set_ylabel("largest multiplier |λ| (1, log scale)")
    bottom.set_xlabel("energy E (J)")
    # inset: the θ scan at 90 J
    inset = bottom.inset_axes([0.55, 0.55, 0.42, 0.4])
    inset.plot([t for t, _ in rows], mods, "k:", marker=".")
    inset.axhline(1.0, color="0.3", lw=0.8, ls="--")
    inset.set_xlabel("θ_b = θ_f (rad), E = 90 J", fontsize=7)
    inset.set_ylabel("|λ|max (1)", fontsize=7)
    inset.tick_params(labelsize=6)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    save_figure(fig, folder / "branches.png")

    for name, info in summary["branches"].items():
        kinds = [(s["kind"], round(s["param"], 6)) for s in info["special_points"]]
        mu = info["max_abs_multiplier_range"]
        print(
            f"{name}: {info['param']} {info['range'][0]:.6g}..{info['range'][1]:.6g}, "
            f"|λ|max {mu[0]:.4g}..{mu[1]:.4g}, "
            f"speed {info['speed_range'][0]:.4g}..{info['speed_range'][1]:.4g} m/s, "
            f"stable points {info['stable_points']}, special {kinds}"
        )
    scan = summary["theta_scan"]
    print(
        f"theta scan at 90 J: found {scan['found']}, ends {scan['ends']}, |λ|max "
        f"{scan['max_abs_multiplier_range']}"
    )
    print(
        f"bound self-stable window: {summary['bound_self_stable_window']} "
        f"({len(bounds_all)} bounds examined; least unstable {summary['bound_least_unstable']})"
    )
    print("timings (s):", {k: round(v, 1) for k, v in timings.items()})
    print(f"wrote {folder} in {elapsed:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
