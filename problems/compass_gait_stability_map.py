"""Compass gait stability map over (slope, mass ratio) and its basin of attraction.

Goswami, Thuilot & Espiau ("A study of the passive gait of a compass-like biped robot: symmetry
and chaos", Int. J. Robotics Research 17(12):1282–1301, 1998; INRIA RR-2996, 1996) showed that
the passive gait of the compass biped depends on the slope and on the mass ratio
μ = m_H/m (hip mass over leg mass): the period-one gait is stable on shallow slopes and loses
stability through period doubling as the slope grows, at a slope that depends on μ.  Here that
dependence is mapped directly: on a grid of (slope, μ), with μ varied through ``mass_hip`` at
Drake's ``mass_leg`` = 5 kg, the period-one gait is solved and its largest |multiplier| is drawn
— a sweep of ``solve_task`` through ``gaitopt.sweep`` (Dask).  The guesses come from
continuation: the gait of Drake's defaults followed in ``mass_hip``, then in the slope at a few
mass ratios, interpolated onto the grid, so that every grid point is solved on the same family
of gaits (from the model's default start, other gaits are found at some parameters).  Grid
points where no gait is found are marked.

Second, the basin of attraction of the gait at the defaults, in a 2-D slice of the Poincaré
section (``stance_dot`` × ``swing_dot`` at the gait's ``stance``): each start is simulated for
``N`` steps (``simulate_task`` through ``sweep``) and counts as in the basin if it is then
within 1e-6 of the fixed point.  The basin is a thin band (compare Schwab & Wisse 2001, "Basin of
attraction of the simplest walking model", Proc. ASME DETC, for the simplest walker).

    python problems/compass_gait_stability_map.py --out results [--fast] [--scheduler ADDRESS]

Writes results/compass_gait_stability_map/: stability_map.csv, basin.csv, summary.json,
stability_map.png.
"""

from __future__ import annotations

import argparse
import contextlib
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap, TwoSlopeNorm  # noqa: E402
from scipy.interpolate import CubicSpline  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402
from gaitopt.shooting import solve_task  # noqa: E402
from gaitopt.simulation import simulate_task  # noqa: E402
from gaitopt.sweep import sweep  # noqa: E402

MASS_LEG = 5.0  # kg, Drake's default (the mass ratio is varied through mass_hip)
SLOPES = (0.005, 0.15)  # rad
RATIOS = (0.1, 10.0)  # μ = mass_hip / mass_leg (Drake's default: 2)
# The basin slice: stance_dot × swing_dot (rad/s) at the fixed point's stance angle.
BASIN_STANCE_DOT = (0.4, 1.8)
BASIN_SWING_DOT = (-8.0, 4.0)
# A solution farther than this from its guess (max over the section coordinates) is counted as
# another gait: the guesses are within ~1e-2 of the family (cubic interpolation between
# continuation branches), and the other period-1 gait at small slopes lies ~2e-2 away.
SAME_GAIT = 0.02
BASIN_TOL = 1e-6  # distance from the fixed point (max over the state) after N steps


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    parser.add_argument("--scheduler", default=None, help="Dask scheduler address (default local)")
    parser.add_argument("--workers", type=int, default=2, help="local Dask workers")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "compass_gait_stability_map"
    folder.mkdir(parents=True, exist_ok=True)
    if args.fast:
        n_slopes, n_ratios, n_anchors, n_basin, n_steps = 8, 8, 5, 12, 60
    else:
        n_slopes, n_ratios, n_anchors, n_basin, n_steps = 30, 30, 8, 40, 60
    slopes = np.linspace(*SLOPES, n_slopes)
    ratios = np.geomspace(*RATIOS, n_ratios)
    model = gaitopt.model("compass_gait", mass_leg=MASS_LEG)

    # -- guesses: one family of gaits, by continuation ---------------------------------------
    t0 = time.perf_counter()
    guesses, anchors = _family_guesses(model, slopes, ratios, n_anchors)
    t_guesses = time.perf_counter() - t0
    # cross-check of the map's stability limit: the period doubling at Drake's defaults (μ = 2)
    pd_default = [
        sp.param
        for sp in gaitopt.continuation(model, "slope", to=SLOPES[1], cascade=False).special_points
        if sp.kind == "PD"
    ]
    pd_default = pd_default[0] if pd_default else None

    with _scheduler(args.scheduler, args.workers) as scheduler:
        # -- the stability map: solve_task on the grid ------------------------------------
        points = [
            {
                "model": "compass_gait",
                "params": {
                    "slope": float(s),
                    "mass_hip": float(MASS_LEG * r),
                    "mass_leg": MASS_LEG,
                },
                "guess": guesses[i, j],
            }
            for i, s in enumerate(slopes)
            for j, r in enumerate(ratios)
        ]
        journal = folder / f"stability_map_{n_slopes}x{n_ratios}.jsonl"
        t0 = time.perf_counter()
        solved = sweep(
            solve_task,
            points,
            journal=journal,
            scheduler=scheduler,
            workers=args.workers,
            description="stability map",
        )
        t_map = time.perf_counter() - t0
        journal.unlink()

        # -- the basin of attraction at the defaults: simulate_task on a slice -------------
        gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
        stance_dots = np.linspace(*BASIN_STANCE_DOT, n_basin)
        swing_dots = np.linspace(*BASIN_SWING_DOT, n_basin)
        starts = [
            {
                "model": "compass_gait",
                "x0": {
                    "stance": gait.fixed_point["stance"],
                    "stance_dot": float(a),
                    "swing_dot": float(b),
                },
                "steps": n_steps,
                "record": 1,
            }
            for a in stance_dots
            for b in swing_dots
        ]
        journal = folder / f"basin_{n_basin}x{n_basin}x{n_steps}.jsonl"
        t0 = time.perf_counter()
        simulated = sweep(
            simulate_task,
            starts,
            journal=journal,
            scheduler=scheduler,
            workers=args.workers,
            description="basin",
        )
        t_basin = time.perf_counter() - t0
        journal.unlink()

    # -- the map's table ----------------------------------------------------------------------
    names = ("stance", "stance_dot", "swing_dot")
    rows, max_mu, status = [], np.full((n_slopes, n_ratios), np.nan), np.zeros_like(slopes, int)
    status = np.zeros((n_slopes, n_ratios), dtype=int)  # 0 no gait, 1 gait, 2 another gait
    for k, (point, result) in enumerate(zip(points, solved.results, strict=True)):
        i, j = divmod(k, n_ratios)
        guess = point["guess"]
        distance = None
        if result["success"]:
            fp = result["fixed_point"]
            distance = max(abs(fp[n] - guess[n]) for n in names) if guess is not None else None
            max_mu[i, j] = result["max_abs_multiplier"]
            status[i, j] = 1 if distance is not None and distance < SAME_GAIT else 2
        rows.append(
            [
                point["params"]["slope"],
                ratios[j],
                point["params"]["mass_hip"],
                int(bool(result["success"])),
                result.get("max_abs_multiplier"),
                int(bool(result["stable"])) if result["success"] else None,
                distance,
                *(result["fixed_point"][n] if result["success"] else None for n in names),
                result["message"],
            ]
        )
    write_csv(
        [
            "slope",
            "mass_ratio",
            "mass_hip",
            "success",
            "max_abs_multiplier",
            "stable",
            "distance_from_guess",
            *names,
            "message",
        ],
        rows,
        folder / "stability_map.csv",
    )

    # -- the basin's table ------------------------------------------------------------------
    # 0 in the basin, 1 fell, 2 walks N steps but not (yet) at the gait, 3 other (timeout, ...)
    basin = np.zeros((n_basin, n_basin), dtype=int)
    basin_rows = []
    for k, (start, result) in enumerate(zip(starts, simulated.results, strict=True)):
        i, j = divmod(k, n_basin)
        distance = None
        if result["status"] == "completed":
            distance = float(np.max(np.abs(np.array(result["states"][-1]) - gait.x)))
            basin[i, j] = 0 if distance < BASIN_TOL else 2
        else:
            basin[i, j] = 1 if result["status"] == "fell" else 3
        basin_rows.append(
            [
                start["x0"]["stance_dot"],
                start["x0"]["swing_dot"],
                result["status"],
                result["steps"],
                distance,
                int(basin[i, j] == 0),
            ]
        )
    write_csv(
        ["stance_dot", "swing_dot", "status", "steps", "distance_after_n", "in_basin"],
        basin_rows,
        folder / "basin.csv",
    )

    # -- summary --------------------------------------------------------------------------------
    default = _nearest(slopes, ratios, 0.0525, 2.0)
    stable = (status == 1) & (max_mu < 1)
    summary = {
        "model": "compass_gait",
        "source": "Goswami, Thuilot & Espiau 1998 (IJRR 17(12)); INRIA RR-2996 (1996)",
        "mass_leg": MASS_LEG,
        "grid": {"slopes": slopes, "mass_ratios": ratios},
        "map": {
            "points": int(status.size),
            "gait_found": int(np.sum(status == 1)),
            "other_gait": int(np.sum(status == 2)),
            "no_gait": int(np.sum(status == 0)),
            "stable": int(stable.sum()),
            "stable_fraction_of_found": float(stable.sum() / max(np.sum(status == 1), 1)),
            "stability_limit_by_ratio": {
                f"{r:.6g}": _limit(slopes, max_mu[:, j], status[:, j] == 1)
                for j, r in enumerate(ratios)
            },
            "period_doubling_at_mass_ratio_2": {
                "continuation": pd_default,
                "map_nearest_ratio": float(ratios[default[1]]),
                "map_limit": _limit(slopes, max_mu[:, default[1]], status[:, default[1]] == 1),
            },
            "largest_stable_slope_by_ratio": {
                f"{r:.6g}": (float(slopes[stable[:, j]].max()) if stable[:, j].any() else None)
                for j, r in enumerate(ratios)
            },
            "nearest_to_defaults": {
                "slope": float(slopes[default[0]]),
                "mass_ratio": float(ratios[default[1]]),
                "max_abs_multiplier": _float(max_mu[default]),
                "stable": bool(stable[default]),
            },
            "anchors": anchors,
        },
        "basin": {
            "params": gait.model.params,
            "fixed_point": gait.fixed_point,
            "multipliers": gait.multipliers,
            "slice": {
                "stance": gait.fixed_point["stance"],
                "stance_dot": BASIN_STANCE_DOT,
                "swing_dot": BASIN_SWING_DOT,
                "points": n_basin * n_basin,
            },
            "steps": n_steps,
            "tolerance": BASIN_TOL,
            "area_fraction": float(np.mean(basin == 0)),
            "fell_fraction": float(np.mean(basin == 1)),
            "walking_not_converged_fraction": float(np.mean(basin == 2)),
            "other_fraction": float(np.mean(basin == 3)),
            "nearest_start_in_basin": _in_basin_at(basin, stance_dots, swing_dots, gait),
            "perturbed_fixed_point_converges": _converges(gait, n_steps),
        },
        "timing_s": {"guesses": t_guesses, "map_sweep": t_map, "basin_sweep": t_basin},
    }
    write_json(summary, folder / "summary.json")

    _figure(
        slopes,
        ratios,
        max_mu,
        status,
        stance_dots,
        swing_dots,
        basin,
        gait,
        n_steps,
        folder / "stability_map.png",
    )

    m = summary["map"]
    print(
        f"compass gait stability map ({n_slopes} slopes × {n_ratios} mass ratios): gait found at "
        f"{m['gait_found']} points ({m['stable']} stable), another gait at {m['other_gait']}, "
        f"none at {m['no_gait']}"
    )
    p = m["period_doubling_at_mass_ratio_2"]
    print(
        f"stability limit of the map at μ = {p['map_nearest_ratio']:.3f}: slope "
        f"{p['map_limit']:.4f}; period doubling by continuation at μ = 2: {p['continuation']:.6f}"
    )
    d = m["nearest_to_defaults"]
    print(
        f"near the defaults (slope {d['slope']:.4f}, μ {d['mass_ratio']:.3f}): max |multiplier| "
        f"{d['max_abs_multiplier']:.4f}, {'stable' if d['stable'] else 'UNSTABLE'}"
    )
    b = summary["basin"]
    print(
        f"basin of attraction ({n_basin}×{n_basin} starts, {n_steps} steps): area fraction "
        f"{b['area_fraction']:.4f} of the slice, fell {b['fell_fraction']:.4f}, walking but not "
        f"converged {b['walking_not_converged_fraction']:.4f}"
    )
    print(
        f"guesses {t_guesses:.1f} s, map sweep {t_map:.1f} s, basin sweep {t_basin:.1f} s; "
        f"wrote {folder}"
    )
    return 0


@contextlib.contextmanager
def _scheduler(address: str | None, workers: int):
    """One local Dask cluster for both sweeps (unless an address or "serial" is given)."""
    if address not in (None, "local"):
        yield address
        return
    from dask.distributed import LocalCluster

    with LocalCluster(
        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        yield cluster.scheduler_address


def _family_guesses(model, slopes, ratios, n_anchors):
    """Section-point guesses on the grid, all from the family of Drake's default gait: that gait
    followed in mass_hip over the ratio range, then in the slope at ``n_anchors`` ratios,
    interpolated (cubic splines) in the slope and in log μ.  Returns the guesses (None where the
    family was not reached) and the anchors' slope ranges."""
    names = ("stance", "stance_dot", "swing_dot")
    base = gaitopt.find_limit_cycle(model)
    cycles = [base]
    for target in (RATIOS[0] * MASS_LEG, RATIOS[1] * MASS_LEG):
        branch = gaitopt.continuation(model, "mass_hip", to=target, start=base, cascade=False)
        cycles += branch.cycles[1:]
    cycles.sort(key=lambda c: c.model.mass_hip)
    mu = np.array([c.model.mass_hip / MASS_LEG for c in cycles])
    picks = sorted(
        {int(np.argmin(np.abs(np.log(mu / a)))) for a in np.geomspace(*RATIOS, n_anchors)}
    )
    table, anchor_mu, anchors = [], [], []
    for k in picks:
        start = cycles[k]
        along = [start]
        for target in SLOPES:
            branch = gaitopt.continuation(
                start.model, "slope", to=target, start=start, cascade=False
            )
            along += branch.cycles[1:]
        along.sort(key=lambda c: c.model.slope)
        s = np.array([c.model.slope for c in along])
        x = np.array([[c.fixed_point[n] for n in names] for c in along])
        table.append(CubicSpline(s, x, axis=0, extrapolate=False)(slopes))  # NaN outside
        anchor_mu.append(mu[k])
        anchors.append({"mass_ratio": float(mu[k]), "slopes": [float(s.min()), float(s.max())]})
    table = np.array(table)  # anchors × slopes × 3
    guesses = np.empty((len(slopes), len(ratios)), dtype=object)
    for i in range(len(slopes)):
        column = table[:, i, :]
        if not np.all(np.isfinite(column)):
            continue  # the family was not followed to this slope at every anchor: no guess
        values = CubicSpline(np.log(anchor_mu), column, axis=0)(np.log(ratios))
        for j in range(len(ratios)):
            guesses[i, j] = {n: float(v) for n, v in zip(names, values[j], strict=True)}
    return guesses, anchors


def _limit(slopes, max_mu, found) -> float | None:
    """Slope where max |multiplier| first crosses 1 upwards along a column (linear interpolation
    of log max |multiplier| between grid points)."""
    value = np.where(found, np.log(max_mu), np.nan)
    for i in range(len(slopes) - 1):
        a, b = value[i], value[i + 1]
        if np.isfinite(a) and np.isfinite(b) and a < 0 <= b:
            return float(slopes[i] + (slopes[i + 1] - slopes[i]) * (-a) / (b - a))
    return None


def _nearest(slopes, ratios, slope, ratio) -> tuple[int, int]:
    return int(np.argmin(np.abs(slopes - slope))), int(np.argmin(np.abs(np.log(ratios / ratio))))


def _float(value) -> float | None:
    return float(value) if np.isfinite(value) else None


def _in_basin_at(basin, stance_dots, swing_dots, gait) -> bool:
    i = int(np.argmin(np.abs(stance_dots - gait.fixed_point["stance_dot"])))
    j = int(np.argmin(np.abs(swing_dots - gait.fixed_point["swing_dot"])))
    return bool(basin[i, j] == 0)


def _converges(gait, n_steps: int) -> bool:
    """A start 1e-2 off the fixed point in the slice (both rates) reaches it within BASIN_TOL
    in ``n_steps`` steps: the basin contains a neighbourhood of the gait."""
    x0 = {
        "stance": gait.fixed_point["stance"],
        "stance_dot": gait.fixed_point["stance_dot"] + 1e-2,
        "swing_dot": gait.fixed_point["swing_dot"] + 1e-2,
    }
    sim = gaitopt.simulate(gait.model, x0, steps=n_steps)
    return bool(sim.success and np.max(np.abs(sim.section_states[-1] - gait.x)) < BASIN_TOL)


def _edges(values: np.ndarray, log: bool = False) -> np.ndarray:
    v = np.log(values) if log else values
    mid = 0.5 * (v[1:] + v[:-1])
    e = np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])
    return np.exp(e) if log else e


def _figure(slopes, ratios, max_mu, status, stance_dots, swing_dots, basin, gait, n_steps, path):
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5.6), layout="constrained")

    # (a) the stability map
    shown = np.where(status == 1, np.log10(max_mu), np.nan)
    finite = shown[np.isfinite(shown)]
    span = max(abs(finite.min()), abs(finite.max()), 0.1) if finite.size else 1.0
    mesh = left.pcolormesh(
        _edges(slopes),
        _edges(ratios, log=True),
        shown.T,
        cmap="RdBu_r",
        norm=TwoSlopeNorm(vcenter=0.0, vmin=-span, vmax=span),
        shading="flat",
    )
    bar = fig.colorbar(mesh, ax=left)
    bar.set_label(r"$\log_{10}$ largest Floquet multiplier modulus $|\lambda|$ (dimensionless)")
    S, R = np.meshgrid(slopes, ratios, indexing="ij")
    if np.isfinite(shown).sum() > 3 and np.nanmin(shown) < 0 < np.nanmax(shown):
        left.contour(S, R, shown, levels=[0.0], colors="k", linewidths=1.8)
        left.plot([], [], "-", color="k", lw=1.8, label=r"stability limit ($|\lambda|_{max}$ = 1)")
    none = status == 0
    other = status == 2
    if none.any():
        left.plot(S[none], R[none], "x", color="k", ms=6, label="no gait found")
    if other.any():
        left.plot(S[other], R[other], "+", color="0.3", ms=7, label="a different gait found")
    left.plot(
        [0.0525],
        [2.0],
        "*",
        color="gold",
        mec="k",
        ms=14,
        label="Drake's defaults (slope 0.0525, μ = 2)",
    )
    left.set_yscale("log")
    left.set_xlabel(r"slope $\gamma$ (rad)")
    left.set_ylabel(r"mass ratio $\mu = m_H/m$, $m$ = 5 kg (dimensionless)")
    left.set_title(
        "Period-1 passive gait: stability over (slope, mass ratio)\n"
        "(cf. Goswami, Thuilot & Espiau 1998)",
        fontsize=10,
    )
    left.legend(fontsize=8, loc="lower left")

    # (b) the basin of attraction
    colours = ListedColormap(["#1f4e79", "#f2f2f2", "#f4a259", "#b0b0b0"])
    right.pcolormesh(
        _edges(stance_dots),
        _edges(swing_dots),
        basin.T,
        cmap=colours,
        vmin=-0.5,
        vmax=3.5,
        shading="flat",
    )
    right.plot(
        [gait.fixed_point["stance_dot"]],
        [gait.fixed_point["swing_dot"]],
        "*",
        color="gold",
        mec="k",
        ms=14,
        label="the gait's fixed point",
    )
    for colour, label in zip(
        colours.colors,
        (
            f"in the basin (within {BASIN_TOL:g} after {n_steps} steps)",
            "falls",
            f"walks {n_steps} steps, not at the gait",
            "other (timeout)",
        ),
        strict=True,
    ):
        if label.startswith("other") and not np.any(basin == 3):
            continue
        if label.startswith("walks") and not np.any(basin == 2):
            continue
        right.fill_between([], [], color=colour, label=label, ec="0.5")
    right.set_xlabel(r"stance_dot just after heel strike (rad/s)")
    right.set_ylabel(r"swing_dot just after heel strike (rad/s)")
    right.set_title(
        f"Basin of attraction at Drake's defaults: {np.mean(basin == 0):.1%} of the slice\n"
        f"(section slice at stance = {gait.fixed_point['stance']:.4f} rad, "
        f"{len(stance_dots)}×{len(swing_dots)} starts)",
        fontsize=10,
    )
    right.legend(fontsize=8, loc="upper left")
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
