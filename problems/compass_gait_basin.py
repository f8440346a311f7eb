"""Compass gait: the basin of its passive gait — ray estimate, brute-force slice, volume fraction.

The passive compass gait at Drake's defaults (slope 0.0525 rad, Goswami, Thuilot & Espiau 1996)
is stable (largest |multiplier| 0.58) but its basin is small: starts 10 % off the fixed point
already fall.  Here it is measured three ways, every start simulated (:mod:`gaitopt.basin`):

* the star-shaped inner estimate: the largest radius along each ray, in the (stance,
  stance_dot) plane (swing_dot at the fixed point) and in the full 3-D section, that a
  simulation confirms converging below the first failure (scan, then bisection) — an inner
  estimate only under the assumption that the basin is star-shaped along each ray;
* a brute-force grid over the same plane: every grid point the ray estimate claims (within the
  smaller radius of its two neighbouring rays, none next to a non-monotone ray, where the basin
  is not star-shaped) is checked to converge on the grid — and, to show what the assumption
  costs, also the points next to the flagged rays;
* the 3-D volume fraction of the box x* ± 0.3 |x*| from uniform random starts, with its 95 %
  Wilson interval, checked against a brute-force 3-D grid of the same box.

A start converges if its simulation returns within 1e-4 |x*| of the fixed point within 40 steps
and stays for 5 more.  Coordinates are scaled by |x*_i| (so radii are fractions of the fixed
point's coordinates).

    python problems/compass_gait_basin.py --out results [--fast] [--scheduler ADDRESS]

Every start is classified by the batch simulation (:mod:`gaitopt.simulation.batch`: all starts
of an estimate stepped together, the rays bisected in lockstep), each start still simulated.

Writes results/compass_gait_basin/: summary.json, slice.csv, rays.csv, basin_slice.png and
basin.npz (columnar: every classified start of the slice, the 3-D fraction and the 3-D grid with
its outcome, and the rays).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.basin import basin, basin_fraction, basin_slice, classify_starts  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402
from gaitopt.plotting.labels import state_label, state_quantity  # noqa: E402

PAIR = ("stance", "stance_dot")
WINDOW = 0.3  # half width of the slice and of the fraction's box, in units of |x*_i|


def _label(model, name: str) -> str:
    return f"{state_quantity(model, name)} {state_label(model, name)}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    parser.add_argument("--scheduler", default=None, help="Dask: 'local' or an address")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "compass_gait_basin"
    folder.mkdir(parents=True, exist_ok=True)
    if args.fast:
        rays2, rays3, grid, grid3, samples, scan, bisections = 8, 6, 11, 5, 40, 4, 5
    else:
        rays2, rays3, grid, grid3, samples, scan, bisections = 24, 26, 31, 15, 400, 8, 8

    t0, cpu0 = time.perf_counter(), time.process_time()
    gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    assert gait.success and gait.stable, gait.message
    model, timings = gait.model, {"solve_s": time.perf_counter() - t0}
    common = {"scheduler": args.scheduler}

    t = time.perf_counter()
    plane = basin(
        gait,
        rays=rays2,
        coordinates=PAIR,
        max_radius=WINDOW,
        scan=scan,
        bisections=bisections,
        chunk=rays2,  # every ray in one batch (bisected in lockstep)
        **common,
    )
    timings["rays_plane_s"] = time.perf_counter() - t
    t = time.perf_counter()
    space = basin(
        gait, rays=rays3, max_radius=WINDOW, scan=scan, bisections=bisections, chunk=rays3, **common
    )
    timings["rays_3d_s"] = time.perf_counter() - t
    t = time.perf_counter()
    cut = basin_slice(gait, PAIR, points=grid, window=WINDOW, **common)
    timings["slice_s"] = time.perf_counter() - t
    t = time.perf_counter()
    fraction = basin_fraction(gait, samples=samples, window=WINDOW, **common)
    timings["fraction_s"] = time.perf_counter() - t

    # brute-force 3-D grid (cell centres) of the fraction's box
    t = time.perf_counter()
    box = fraction.window
    names = list(model.section.coordinates)
    axes = [box[c][0] + (box[c][1] - box[c][0]) * (np.arange(grid3) + 0.5) / grid3 for c in names]
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(names))
    outcomes = classify_starts(gait, mesh, **common)
    brute_fraction = float(np.mean([o == "converged" for o in outcomes]))
    timings["grid_3d_s"] = time.perf_counter() - t

    claimed = plane.claims(cut.points()).reshape(cut.converged.shape)
    confirmed = int(np.sum(cut.converged[claimed]))
    # the sectors next to non-monotone rays too (where the star-shaped assumption is known to
    # fail): how often the interpolation between rays is then wrong
    loose = plane.claims(cut.points(), next_to_flags=True).reshape(cut.converged.shape)
    timings["total_s"] = time.perf_counter() - t0
    timings["total_cpu_s"] = time.process_time() - cpu0  # this process's CPU (shared machines)

    write_csv(
        [*PAIR, "outcome", "converged", "claimed_by_rays"],
        [
            [p[0], p[1], o, int(c), int(k)]
            for p, o, c, k in zip(
                cut.points(),
                cut.outcomes.ravel(),
                cut.converged.ravel(),
                claimed.ravel(),
                strict=True,
            )
        ],
        folder / "slice.csv",
    )
    rows = []
    for kind, est in (("plane", plane), ("3d", space)):
        for i, (d, r, f) in enumerate(
            zip(est.directions, est.radii, est.first_failure, strict=True)
        ):
            rows.append([kind, i, " ".join(f"{v:.6f}" for v in d), r, None if np.isnan(f) else f])
    write_csv(["rays", "ray", "direction", "radius", "first_failure"], rows, folder / "rays.csv")
    summary = {
        "model": "compass_gait",
        "params": model.params,
        "fixed_point": gait.fixed_point,
        "max_abs_multiplier": float(np.max(np.abs(gait.multipliers))),
        "scale": dict(zip(names, np.abs(gait.section_point).tolist(), strict=True)),
        "criterion": "within 1e-4 |x*| of the fixed point within 40 steps, for 5 more",
        "assumption": "ray radii are an inner estimate only if the basin is star-shaped along "
        "each ray",
        "plane_rays": {
            "coordinates": list(PAIR),
            "rays": len(plane.radii),
            "radius_min": float(plane.radii.min()),
            "radius_max": float(plane.radii.max()),
            "radii": plane.radii.tolist(),
            "flags": plane.flags,
            "capped": int(plane.capped.sum()),
            "simulations": plane.simulations,
        },
        "rays_3d": {
            "rays": len(space.radii),
            "radius_min": float(space.radii.min()),
            "radius_max": float(space.radii.max()),
            "radii": space.radii.tolist(),
            "flags": space.flags,
            "simulations": space.simulations,
        },
        "slice": {
            "points": int(cut.converged.size),
            "window_scaled": WINDOW,
            "fraction_converged": cut.fraction,
            "claimed_by_rays": int(claimed.sum()),
            "claimed_and_confirmed": confirmed,
            "claimed_next_to_flags_too": int(loose.sum()),
            "claimed_next_to_flags_too_confirmed": int(np.sum(cut.converged[loose])),
            "outcomes": {o: int(np.sum(cut.outcomes == o)) for o in np.unique(cut.outcomes)},
        },
        "fraction_3d": {
            **fraction.as_dict(),
            "brute_force_grid": grid3,
            "brute_force_fraction": brute_fraction,
            "interval_contains_brute_force": bool(
                fraction.interval[0] <= brute_fraction <= fraction.interval[1]
            ),
        },
        "timings": timings,
        "fast": args.fast,
    }
    write_json(summary, folder / "summary.json")
    np.savez_compressed(
        folder / "basin.npz",
        coordinates=np.array(names),
        slice_points=cut.points(),
        slice_outcomes=cut.outcomes.ravel().astype(str),
        slice_claimed=claimed.ravel(),
        fraction_starts=fraction.starts,
        fraction_outcomes=fraction.outcomes.astype(str),
        grid_starts=mesh,
        grid_outcomes=np.array(outcomes, dtype=str),
        plane_directions=plane.directions,
        plane_radii=plane.radii,
        plane_first_failure=plane.first_failure,
        space_directions=space.directions,
        space_radii=space.radii,
        space_first_failure=space.first_failure,
    )

    # -- figure: the grid's outcomes with the ray estimate drawn over it ----------------------
    fig, ax = plt.subplots(figsize=(7, 5.5))
    (a, b), grid_ok = cut.values, cut.converged
    step_a, step_b = a[1] - a[0], b[1] - b[0]
    ax.imshow(
        grid_ok.astype(int),
        origin="lower",
        aspect="auto",
        extent=(a[0] - step_a / 2, a[-1] + step_a / 2, b[0] - step_b / 2, b[-1] + step_b / 2),
        cmap=ListedColormap(["#f4c7c3", "#b7e1cd"]),
        vmin=0,
        vmax=1,
    )
    centre = np.array([gait.fixed_point[c] for c in PAIR])
    ends = plane.endpoints()
    flagged = {flag["ray"] for flag in plane.flags}
    for i, end in enumerate(ends):
        style = ("--", "tab:orange") if i in flagged else ("-", "tab:green")
        ax.plot([centre[0], end[0]], [centre[1], end[1]], style[0], color=style[1], lw=1)
    if flagged:
        ax.plot([], [], "--", color="tab:orange", label="non-monotone ray (flagged)")
    closed = ends[np.argsort(np.arctan2(plane.directions[:, 1], plane.directions[:, 0]))]
    ax.plot(
        *np.vstack([closed, closed[:1]]).T,
        "-",
        color="darkgreen",
        lw=1.5,
        label="ray estimate (confirmed radii)",
    )
    fails = centre + plane.first_failure[:, None] * plane.directions * plane.scale
    ax.plot(fails[:, 0], fails[:, 1], "x", color="tab:red", label="first failure on a ray")
    ax.plot(*centre, "ko", label="fixed point")
    ax.set_xlabel(_label(model, PAIR[0]))
    ax.set_ylabel(_label(model, PAIR[1]))
    ax.set_title(
        f"compass gait basin slice (swing_dot = {gait.fixed_point['swing_dot']:.4g} rad/s): "
        f"green converges on the {grid}×{grid} grid",
        fontsize=9,
    )
    ax.legend(fontsize=8, loc="upper right")
    save_figure(fig, folder / "basin_slice.png")
    plt.close(fig)
    print(
        f"compass_gait_basin: {confirmed}/{int(claimed.sum())} claimed points confirmed, "
        f"fraction {fraction.fraction:.3f} {fraction.interval}, grid {brute_fraction:.3f}, "
        f"{timings['total_s']:.1f} s"
    )
    return 0 if confirmed == int(claimed.sum()) else 1


if __name__ == "__main__":
    raise SystemExit(main())
