"""The kneed walker's stable region in slope × foot radius: its first period doubling and the
boundary where its swing foot stops clearing the slope, both followed as curves.

Hsu Chen's kneed walker (2007; Tedrake, *Underactuated Robotics*, "the kneed walker") with
McGeer's curved feet (1990, radius R; R = 0 the point foot).  Continued in the slope at R = 0
(``problems/kneed_walker_slope.py``) its period-1 gait period-doubles at γ ≈ 0.1062 rad and then
stops existing at γ ≈ 0.1196 rad, not by a bifurcation of the return map but by the physics: the
trailing foot, which lifts off just after heel strike, sinks back and grazes the slope a few
milliseconds later (an interior minimum of the declared clearance constraint touches zero).
Both are followed here through the foot radius from 0 to 0.3 m (gaitopt.curves.curve_from):

* the PD curve — the orbit plus det(A + I) = 0 (minimally augmented), every point certified;
* the clearance boundary — the orbit plus the grazing condition c(x(t*)) = 0, ċ(x(t*)) = 0 with
  the time t* of the minimum an extra unknown (Nordmark 1991; di Bernardo et al. 2008, §7.1);
  each point's gait is certified just inside it (1e-9 of the slope's scale).

The period-1 gait exists and is stable below both curves (the lower slope limit, where the gait
stops existing on shallow slopes, is not followed).  The curves are checked against
one-parameter continuation in the slope at fixed radii (the PD to 1e-8 rad; the boundary, which
continuation locates by the failure of its dense-sample and simulation checks, to within that
check's own resolution, reported in summary.json).

    python problems/kneed_walker_pd_curve.py --out results [--fast]

Writes results/kneed_walker_pd_curve/: pd_curve.csv/.json, clearance_boundary.csv/.json,
summary.json, region.png.
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
from gaitopt.continuation import PseudoArclength  # noqa: E402
from gaitopt.curves import ParameterPath, curve_from  # noqa: E402
from gaitopt.curves.plot import draw_curve  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

MODEL = "kneed_walker"
SLOPES = (0.0504, 0.13)  # the default slope to past the end of the period-1 branch (rad)
RADIUS_TO = 0.3  # m
CHECK_RADII = (0.1, 0.2)  # m: one-parameter continuation in the slope there, for comparison
FAST_RADIUS_TO = 0.05
FAST_CHECK_RADII = (0.03,)


#: Step control of the one-parameter branches: steps of at most 5 % of the slope, so that no
#: special point hides in a step that ends on the boundary (with the default 25 % the branch at
#: R = 0.1 m steps from 0.1135 rad, multiplier −0.90, straight to its end at 0.1208 rad, −1.18,
#: and reports no period doubling).
BRANCH_STEPS = PseudoArclength(max_step=0.05)


def first_points(model: gaitopt.HybridModel) -> tuple:
    """The branch in the slope at the model's foot radius, and its first PD and boundary."""
    branch = gaitopt.continuation(model, "slope", to=SLOPES[1], cascade=False, options=BRANCH_STEPS)
    pd = next((sp for sp in branch.special_points if sp.kind == "PD"), None)
    end = next((sp for sp in branch.special_points if sp.kind == "boundary"), None)
    return branch, pd, end


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="R up to 0.05 m only (CI)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "kneed_walker_pd_curve"
    folder.mkdir(parents=True, exist_ok=True)
    radius_to = FAST_RADIUS_TO if args.fast else RADIUS_TO
    check_radii = FAST_CHECK_RADII if args.fast else CHECK_RADII

    t0 = time.perf_counter()
    model = gaitopt.model(MODEL, slope=SLOPES[0])
    branch, pd, end = first_points(model)
    if pd is None or end is None:
        print(f"kneed walker: no PD or no boundary on the branch in the slope ({branch.message})")
        return 1
    paths = (ParameterPath.of(model, "slope"), ParameterPath.of(model, "foot_radius"))
    curves = {
        "pd_curve": curve_from(pd, "PD", paths, radius_to, at=check_radii),
        "clearance_boundary": curve_from(
            end, "boundary", paths, radius_to, first=branch.cycles[0], at=check_radii
        ),
    }
    elapsed = time.perf_counter() - t0

    # -- one-parameter continuation at the check radii (the independent method) -----------------
    checks = [{"foot_radius": 0.0, "pd_slope": pd.param, "boundary_slope": end.param}]
    for radius in check_radii:
        _, pd_r, end_r = first_points(gaitopt.model(MODEL, slope=SLOPES[0], foot_radius=radius))
        checks.append({
            "foot_radius": radius,
            "pd_slope": pd_r.param if pd_r is not None else None,
            "boundary_slope": end_r.param if end_r is not None else None,
        })  # fmt: skip
    for entry in checks:
        for name, key in (("pd_curve", "pd_slope"), ("clearance_boundary", "boundary_slope")):
            lam = curves[name].params
            row = np.flatnonzero(np.abs(lam[:, 1] - entry["foot_radius"]) < 1e-12)
            on_curve = float(lam[row[0], 0]) if row.size else None
            entry[f"{key}_on_curve"] = on_curve
            if on_curve is not None and entry[key] is not None:
                entry[f"{key}_difference"] = on_curve - entry[key]

    # -- tables -------------------------------------------------------------------------------
    summary: dict = {
        "model": MODEL,
        "source": "Hsu Chen 2007 (parameters); McGeer 1990 (curved feet); boundary: the declared "
        "foot-clearance constraint (an interior minimum touching zero: the grazing condition)",
        "foot_radius_range_m": [0.0, radius_to],
        "elapsed_s": elapsed,
        "one_parameter_checks": checks,
    }
    for name, curve in curves.items():
        header, rows = curve.csv_rows()
        write_csv(header, rows, folder / f"{name}.csv")
        write_json(curve.as_dict(), folder / f"{name}.json")
        summary[name] = {
            "condition": curve.condition,
            "points": len(curve.cycles),
            "end": curve.message,
            "all_verified": all(c.verified for c in curve.cycles),
            "slope_at_foot_radius": {
                f"{b:g}": float(a)
                for a, b in curve.params
                if any(abs(b - r) < 1e-12 for r in (0.0, *check_radii, radius_to))
            },  # fmt: skip
            "special_points": [sp.as_dict() for sp in curve.special_points],
        }
    write_json(summary, folder / "summary.json")
    _figure(curves, checks, folder / "region.png")

    print(f"kneed walker: first PD and clearance boundary in slope × foot radius ({elapsed:.1f} s)")
    for name, curve in curves.items():
        values = summary[name]["slope_at_foot_radius"]
        text = ", ".join(f"R = {r} m: {s:.8f} rad" for r, s in values.items())
        print(f"  {name}: {len(curve.cycles)} certified points; {text}; {curve.message}")
    for name, curve in curves.items():
        for sp in curve.special_points:
            where = ", ".join(f"{k} = {v:.8f}" for k, v in sp.values.items())
            print(f"  {name}: {sp.kind} at {where}: {sp.message[:100]}")
    for entry in checks:
        text = []
        for key in ("pd_slope", "boundary_slope"):
            if entry[key] is None:
                text.append(f"{key[:-6]}: none on the branch")
                continue
            diff = entry.get(f"{key}_difference")
            text.append(
                f"{key[:-6]} {entry[key]:.10f} rad (curve − continuation "
                + (f"{diff:.1e} rad)" if diff is not None else "n/a: the curve ended before)")
            )
        print(f"  one-parameter in γ at R = {entry['foot_radius']:g} m: " + "; ".join(text))
    return 0


def _figure(curves, checks, path) -> None:
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5.2), layout="constrained")
    pd, edge = curves["pd_curve"], curves["clearance_boundary"]
    draw_curve(left, pd, label="first period doubling (a multiplier −1)", colour="k",
               annotate=False)  # fmt: skip
    draw_curve(left, edge, label="swing foot grazes the slope (the gait ends)", colour="C3",
               annotate=False)  # fmt: skip
    # The stable region: below the PD curve where it exists and below the boundary everywhere
    # (the PD curve ends on the boundary; the lower slope limit is not followed).
    if len(pd.cycles) and len(edge.cycles):
        order_pd, order_edge = np.argsort(pd.params[:, 1]), np.argsort(edge.params[:, 1])
        r_pd, s_pd = pd.params[order_pd, 1], pd.params[order_pd, 0]
        radii = np.linspace(edge.params[:, 1].min(), edge.params[:, 1].max(), 400)
        upper = np.interp(radii, edge.params[order_edge, 1], edge.params[order_edge, 0])
        under = radii <= r_pd.max()
        upper[under] = np.minimum(upper[under], np.interp(radii[under], r_pd, s_pd))
        low = min(pd.params[:, 0].min(), edge.params[:, 0].min()) - 0.01
        left.fill_betweenx(
            radii, low, upper, color="C2", alpha=0.15,
            label="period-1 gait exists and is stable (lower slope limit not followed)",
        )  # fmt: skip
    for sp in edge.special_points:
        a, b = sp.values["slope"], sp.values["foot_radius"]
        text = {
            "PD": f"corner: the PD curve meets the boundary\n(γ = {a:.6f} rad, R = {b:.4f} m)",
            "fold:slope": f"steepest slope with a period-1 gait\n(γ = {a:.6f} rad, R = {b:.4f} m)",
        }.get(sp.kind)
        if text and sp.kind == "PD":
            left.annotate(text, (a, b), xytext=(-12, 0), textcoords="offset points", ha="right",
                          fontsize=8)  # fmt: skip
        elif text:
            left.annotate(text, (a, b), xytext=(a - 0.004, b - 0.07), ha="center", fontsize=8,
                          arrowprops={"arrowstyle": "->", "color": "0.3"})  # fmt: skip
    for k, entry in enumerate(checks):
        for key, marker, what in (("pd_slope", "o", "PD"), ("boundary_slope", "s", "end")):
            if entry[key] is not None:
                left.plot(
                    [entry[key]], [entry["foot_radius"]], marker, mfc="none", mec="C0", ms=9,
                    label=f"one-parameter continuation in γ: {what}" if k == 0 else "_",
                )  # fmt: skip
    left.set_ylim(-0.01, 0.38)
    left.set_xlabel("ground slope γ (rad)")
    left.set_ylabel("foot radius R (m)")
    left.set_title("Kneed walker: where the period-1 gait exists and is stable", fontsize=10)
    left.legend(fontsize=8, loc="upper left")
    left.grid(alpha=0.3)
    for curve, colour, label in ((pd, "k", "PD curve"), (edge, "C3", "clearance boundary")):
        if curve.cycles:
            right.plot(curve.values(1), curve.periods, "-o", ms=3, color=colour, label=label)
    right.set_xlabel("foot radius R (m)")
    right.set_ylabel("orbit period T (s)")
    right.set_title("Step period along the curves", fontsize=10)
    right.legend(fontsize=8)
    right.grid(alpha=0.3)
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
