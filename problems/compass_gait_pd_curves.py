"""The compass gait's first period doubling as a curve in two parameters.

Goswami, Thuilot & Espiau ("A study of the passive gait of a compass-like biped robot: symmetry
and chaos", Int. J. Robotics Research 17(12):1282–1301, 1998) found that the period-one passive
gait loses stability through period doubling at a slope that depends on the mass ratio
μ = m_H/m and on where the leg's mass sits (a from the foot, b from the hip).  The brute-force
way (problems/compass_gait_stability_map.py) solves 900 gaits on a 30 × 30 grid and reads the
boundary off the grid; here the boundary itself is followed (gaitopt.bifurcation_curve: the
orbit plus det(A + I) = 0, pseudo-arclength, every point certified by simulation):

* slope × mass ratio, μ from 0.1 to 10.  The model's parameters are ``mass_hip`` and
  ``mass_leg``; the ratio is the path ``mass_hip = μ · mass_leg`` at Drake's ``mass_leg`` = 5 kg
  (exactly the map's convention), drawn over the map (results/compass_gait_stability_map);
* slope × leg-mass position, ``a`` from the foot with ``b = 1 − a`` (leg length 1 m, the path
  ``a = s, b = 1 − s``), μ = 2.

    python problems/compass_gait_pd_curves.py --out results [--fast]

Writes results/compass_gait_pd_curves/: mass_ratio.csv/.json, leg_mass_position.csv/.json,
summary.json, pd_curves.png.
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import TwoSlopeNorm  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.curves import ParameterPath, curve_from  # noqa: E402
from gaitopt.curves.plot import draw_curve  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

MASS_LEG = 5.0  # kg (Drake's default; the map's convention)
KEY_RATIOS = (0.1, 1.0, 4.0, 10.0)
RATIO = ParameterPath(
    "mass_ratio",
    {"mass_hip": (0.0, MASS_LEG)},
    unit="1",
    doc=f"mass ratio μ = m_H/m (mass_hip = μ · {MASS_LEG:g} kg)",
)
POSITION = ParameterPath(
    "a",
    {"a": (0.0, 1.0), "b": (1.0, -1.0)},
    unit="m",
    doc="leg-mass position a from the foot (b = 1 − a)",
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small ranges for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "compass_gait_pd_curves"
    folder.mkdir(parents=True, exist_ok=True)
    ratios = (1.0, 4.0) if args.fast else (KEY_RATIOS[0], KEY_RATIOS[-1])
    positions = (0.4, 0.6) if args.fast else (0.1, 0.9)

    t0 = time.perf_counter()
    model = gaitopt.model("compass_gait", mass_leg=MASS_LEG, slope=0.07)  # μ = 2
    branch = gaitopt.continuation(model, "slope", to=0.09, cascade=False)
    pd = next(sp for sp in branch.special_points if sp.kind == "PD")
    slope_path = ParameterPath.of(model, "slope")
    curves = {}
    for name, path, ends in (("mass_ratio", RATIO, ratios), ("leg_mass_position", POSITION,
                                                               positions)):  # fmt: skip
        halves = []
        for end in ends:
            at = [r for r in KEY_RATIOS if min(2.0, end) < r < max(2.0, end)]
            at = at if path is RATIO else []
            halves.append(curve_from(pd, "PD", (slope_path, path), end, at=at))
        curves[name] = halves
    elapsed = time.perf_counter() - t0

    # -- tables ---------------------------------------------------------------------------------
    summary: dict = {
        "model": "compass_gait",
        "source": "Goswami, Thuilot & Espiau 1998 (IJRR 17(12)); Drake CompassGait parameters",
        "first_pd_at_defaults": {"mass_ratio": 2.0, "slope": pd.param},
        "elapsed_s": elapsed,
    }
    for name, halves in curves.items():
        rows, header, specials = [], None, []
        for half in halves:
            header, part = half.csv_rows()
            rows += part
            specials += [sp.as_dict() for sp in half.special_points]
        write_csv(header, sorted(rows, key=lambda r: r[1]), folder / f"{name}.csv")
        write_json([h.as_dict() for h in halves], folder / f"{name}.json")
        summary[name] = {
            "points": sum(len(h.cycles) for h in halves),
            "ends": [h.message for h in halves],
            "all_verified": all(c.verified for h in halves for c in h.cycles),
            "special_points": specials,
        }
    key = {}
    for half in curves["mass_ratio"]:
        for lam in half.params:
            for r in KEY_RATIOS + (2.0,):
                if abs(lam[1] - r) < 1e-12:
                    key[f"{r:g}"] = float(lam[0])
    summary["mass_ratio"]["pd_slope_at_mass_ratio"] = key
    grid = _grid_limits()
    if grid is not None:
        summary["mass_ratio"]["grid_limit_error"] = _grid_error(curves["mass_ratio"], grid)
    write_json(summary, folder / "summary.json")
    _figure(curves, grid, folder / "pd_curves.png")

    print(f"compass gait first-PD curves in {elapsed:.1f} s")
    for r, s in sorted(key.items(), key=lambda kv: float(kv[0])):
        print(f"  μ = m_H/m = {float(r):5g}: PD at slope {s:.10f} rad")
    for name in curves:
        sps = ", ".join(
            f"{sp['kind']} at "
            + ", ".join(
                f"{k}={sp[k]:.6g}" for k in ("slope", "mass_ratio", "a") if k in sp
            )  # fmt: skip
            for sp in summary[name]["special_points"]
        )
        print(f"  {name}: {summary[name]['points']} certified points; {sps or 'no codim-2'}")
    if grid is not None:
        e = summary["mass_ratio"]["grid_limit_error"]
        print(f"  30×30 grid's boundary vs the curve: max error {e['max']:.2e} rad in slope")
    return 0


def _grid_limits():
    """The brute-force map (results/compass_gait_stability_map/stability_map.csv), if present."""
    path = Path("results/compass_gait_stability_map/stability_map.csv")
    if not path.exists():
        return None
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    slopes = np.unique([float(r["slope"]) for r in rows])
    ratios = np.unique([float(r["mass_ratio"]) for r in rows])
    mu = np.full((slopes.size, ratios.size), np.nan)
    for r in rows:
        if r["success"] == "1" and r["max_abs_multiplier"]:
            i = np.searchsorted(slopes, float(r["slope"]))
            j = np.searchsorted(ratios, float(r["mass_ratio"]))
            mu[i, j] = float(r["max_abs_multiplier"])
    return slopes, ratios, mu


def _grid_error(halves, grid) -> dict:
    """The map's stability limit per ratio (log |μ|max interpolated between grid slopes, as the
    map's study does) against the curve (interpolated in log μ between its points, which lie
    ≤ 0.2 apart in arclength)."""
    slopes, ratios, mu = grid
    lam = np.vstack([h.params for h in halves])
    lam = lam[np.argsort(lam[:, 1])]
    errors = []
    for j, r in enumerate(ratios):
        value = np.log(mu[:, j])
        for i in range(len(slopes) - 1):
            a, b = value[i], value[i + 1]
            if np.isfinite(a) and np.isfinite(b) and a < 0 <= b:
                limit = slopes[i] + (slopes[i + 1] - slopes[i]) * (-a) / (b - a)
                curve = np.interp(np.log(r), np.log(lam[:, 1]), lam[:, 0])
                errors.append(abs(limit - curve))
                break
    return {"max": float(np.max(errors)), "median": float(np.median(errors)), "n": len(errors)}


def _figure(curves, grid, path) -> None:
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5.4), layout="constrained")
    if grid is not None:
        slopes, ratios, mu = grid
        shown = np.log10(mu)
        span = np.nanmax(np.abs(shown))
        mesh = left.pcolormesh(
            slopes, ratios, shown.T, cmap="RdBu_r", norm=TwoSlopeNorm(0.0, -span, span),
            shading="nearest", alpha=0.8,
        )  # fmt: skip
        fig.colorbar(mesh, ax=left).set_label(
            "brute-force map (30 × 30): log₁₀ max |multiplier| (1)"
        )
        S, R = np.meshgrid(slopes, ratios, indexing="ij")
        left.contour(S, R, shown, levels=[0.0], colors="0.3", linewidths=1.2, linestyles="--")
        left.plot([], [], "--", color="0.3", label="map's stability limit (grid contour)")
    for k, half in enumerate(curves["mass_ratio"]):
        draw_curve(left, half, label="PD curve (continuation)" if k == 0 else "_", colour="k")
    for half in curves["mass_ratio"]:
        for a, b in half.params:
            if any(abs(b - r) < 1e-12 for r in KEY_RATIOS):
                left.plot([a], [b], "o", color="gold", mec="k", ms=7, zorder=6)
    left.set_yscale("log")
    left.set_xlabel("ground slope γ (rad)")
    left.set_ylabel(f"mass ratio μ = m_H/m (1), m = {MASS_LEG:g} kg")
    left.set_title("First period doubling over the stability map it replaces", fontsize=10)
    left.legend(fontsize=8, loc="lower left")
    for k, half in enumerate(curves["leg_mass_position"]):
        draw_curve(right, half, label="PD curve (μ = 2)" if k == 0 else "_", colour="C3")
    right.axhline(0.5, color="0.6", lw=0.8, ls=":")
    right.set_xlabel("ground slope γ (rad)")
    right.set_ylabel("leg-mass position a from the foot (m), b = 1 − a")
    right.set_title("First period doubling vs where the leg's mass sits", fontsize=10)
    right.text(0.02, 0.02, "stable period-one gait: left of the curve", transform=right.transAxes,
               fontsize=8)  # fmt: skip
    right.legend(fontsize=8)
    right.grid(alpha=0.3)
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
