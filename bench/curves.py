"""Benchmark of two-parameter curves (issue 14), run by ``make bench``.

The compass gait's stability boundary in slope × mass ratio (μ = m_H/m from 0.1 to 10 at
``mass_leg`` = 5 kg), two ways:

* **curve continuation** — the first period doubling located on the branch in the slope at
  μ = 2, then followed in (slope, μ) to both ends (:func:`gaitopt.curves.curve_from`; every
  point certified and verified by simulation);
* **the 30 × 30 grid** — :mod:`problems/compass_gait_stability_map`'s brute force: 900 solves
  (guesses from continuation, then a Dask sweep on 2 workers), the boundary read off the grid by
  interpolating log max |multiplier| between slopes.  Its time is taken from that study's
  ``summary.json`` (guesses + map sweep), or re-measured with ``--grid``.

Accuracy: both boundaries are compared at the grid's 30 ratios with the exact PD slope there
(the curve corrected at exactly each ratio, untimed).  The curve's boundary at a ratio is its
points interpolated (cubic in log μ).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from gaitopt.continuation import continuation
from gaitopt.curves import ParameterPath, curve_from
from gaitopt.models import model as make_model

__all__ = ["run", "table"]

_MASS_LEG = 5.0
_RATIOS = (0.1, 10.0)
_MAP = Path("results/compass_gait_stability_map")


def _paths(model):
    ratio = ParameterPath("mass_ratio", {"mass_hip": (0.0, _MASS_LEG)}, unit="1")
    return ParameterPath.of(model, "slope"), ratio


def _boundary_by_curve() -> tuple[list, float]:
    t0 = time.perf_counter()
    model = make_model("compass_gait", mass_leg=_MASS_LEG, slope=0.07)
    branch = continuation(model, "slope", to=0.09, cascade=False)
    pd = next(sp for sp in branch.special_points if sp.kind == "PD")
    halves = [curve_from(pd, "PD", _paths(model), end) for end in _RATIOS]
    return halves, time.perf_counter() - t0


def _grid() -> dict[str, Any] | None:
    summary, table = _MAP / "summary.json", _MAP / "stability_map.csv"
    if not (summary.exists() and table.exists()):
        return None
    data = json.loads(summary.read_text())
    limits = data["map"]["stability_limit_by_ratio"]
    ratios = np.array(data["grid"]["mass_ratios"])
    return {
        "seconds": data["timing_s"]["guesses"] + data["timing_s"]["map_sweep"],
        "points": data["map"]["points"],
        "ratios": ratios,
        "limits": np.array([limits.get(f"{r:.6g}", np.nan) for r in ratios], dtype=float),
    }


def run(quick: bool = False) -> dict[str, Any]:
    """Time the curve (once warm: the CasADi functions built by a first run, as the grid's
    workers build theirs before timing starts only in part; both cold and warm are reported)."""
    halves, cold = _boundary_by_curve()
    if not quick:
        halves, warm = _boundary_by_curve()
    else:
        warm = cold
    grid = _grid()
    out: dict[str, Any] = {
        "curve_seconds_cold": cold,
        "curve_seconds_warm": warm,
        "curve_points": sum(len(h.cycles) for h in halves),
        "curve_all_verified": all(c.verified for h in halves for c in h.cycles),
        "curve_ends": [h.message for h in halves],
    }
    if grid is None:
        out["grid"] = "skipped: run problems/compass_gait_stability_map.py first"
        return out
    lam = np.vstack([h.params for h in halves])
    lam = lam[np.argsort(lam[:, 1])]
    keep = np.concatenate([[True], np.diff(lam[:, 1]) > 1e-12])
    spline = CubicSpline(np.log(lam[keep, 1]), lam[keep, 0])
    ratios = grid["ratios"]
    # The exact boundary at each grid ratio: the curve corrected at exactly that ratio.
    inner = [float(r) for r in ratios if _RATIOS[0] < r < _RATIOS[1]]
    model = make_model("compass_gait", mass_leg=_MASS_LEG, slope=0.07)
    pd = halves[0].start
    exact = {}
    for end in _RATIOS:
        at = [r for r in inner if min(2.0, end) < r < max(2.0, end)]
        for a, b in curve_from(pd, "PD", _paths(model), end, at=at).params:
            exact[round(float(b), 9)] = float(a)
    truth = np.array([exact.get(round(float(r), 9), np.nan) for r in ratios])
    grid_error = np.abs(grid["limits"] - truth)
    curve_error = np.abs(spline(np.log(ratios)) - truth)
    out.update(
        {
            "grid_seconds": grid["seconds"],
            "grid_points": grid["points"],
            "grid_boundary_max_error": float(np.nanmax(grid_error)),
            "curve_boundary_max_error": float(np.nanmax(curve_error)),
            "compared_at_ratios": int(np.sum(np.isfinite(truth))),
            "speedup_cold": grid["seconds"] / cold,
            "speedup_warm": grid["seconds"] / warm,
        }
    )
    return out


def table(result: dict[str, Any]) -> str:
    """The measurement as printed lines."""
    r = result
    lines = [
        "Two-parameter curves (issue 14): compass-gait stability boundary, slope × m_H/m 0.1–10",
        f"  PD curve: {r['curve_points']} certified gaits (verified: {r['curve_all_verified']}), "
        f"{r['curve_seconds_cold']:.2f} s cold (building the CasADi functions), "
        f"{r['curve_seconds_warm']:.2f} s warm",
    ]
    if "grid_seconds" in r:
        lines += [
            f"  30×30 grid: {r['grid_points']} solves, {r['grid_seconds']:.1f} s "
            f"(problems/compass_gait_stability_map.py: guesses + map sweep)",
            f"  boundary error vs the exact PD at {r['compared_at_ratios']} ratios: grid "
            f"{r['grid_boundary_max_error']:.1e} rad, "
            f"curve {r['curve_boundary_max_error']:.1e} rad",
            f"  speed-up: {r['speedup_warm']:.1f}× warm, {r['speedup_cold']:.1f}× cold "
            f"(goal ≥ 20×: {'met' if r['speedup_warm'] >= 20 else 'NOT met'})",
        ]
    else:
        lines.append(f"  grid: {r['grid']}")
    return "\n".join(lines)


if __name__ == "__main__":
    print(table(run()))
