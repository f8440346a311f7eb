"""Benchmark of two-parameter curves, run by ``make bench``.

The compass gait's stability boundary in slope × mass ratio (μ = m_H/m from 0.1 to 10 at
``mass_leg`` = 5 kg), two ways:

* **curve continuation** — the first period doubling located on the branch in the slope at
  μ = 2, then followed in (slope, μ) to both ends (:func:`gaitopt.curves.curve_from`; every
  point certified and verified by simulation), with steps of up to 1.0 in scaled arclength
  (:data:`STEPS`: the points are located as exactly as with small steps; only their spacing, and
  so the interpolation between them, changes — measured below).  Timed twice: with the
  one-parameter search for the start, and from a cached start (the PD slope at μ = 2 from an
  earlier run, results/compass_gait_pd_curves/summary.json: the gait solved there and the exact
  PD found by Newton on the extended system at fixed μ, no search along the branch);
* **the 30 × 30 grid** — :mod:`problems/compass_gait_stability_map`'s brute force: 900 solves
  (guesses from continuation, then a Dask sweep on 2 workers), the boundary read off the grid by
  interpolating log max |multiplier| between slopes.  Its time is taken from that study's
  ``summary.json`` (guesses + map sweep), or re-measured with ``--grid`` (the study run into a
  temporary folder; its basin sweep is run too but not counted).

    python -m bench.curves [--grid]

Accuracy: both boundaries are compared at the grid's 30 ratios with the exact PD slope there
(the curve corrected at exactly each ratio, untimed).  The curve's boundary at a ratio is its
points interpolated (cubic in log μ).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from gaitopt.continuation import PseudoArclength, SpecialPoint, continuation
from gaitopt.curves import ParameterPath, curve_from
from gaitopt.models import model as make_model
from gaitopt.shooting import find_limit_cycle

__all__ = ["run", "table"]

_MASS_LEG = 5.0
_RATIOS = (0.1, 10.0)
_MAP = Path("results/compass_gait_stability_map")
_CACHE = Path("results/compass_gait_pd_curves/summary.json")
#: Step control of the timed curve (scaled arclength; the default is step 0.05, max_step 0.2).
STEPS = PseudoArclength(step=0.1, max_step=1.0)


def _paths(model):
    ratio = ParameterPath("mass_ratio", {"mass_hip": (0.0, _MASS_LEG)}, unit="1")
    return ParameterPath.of(model, "slope"), ratio


def _cached_slope() -> float | None:
    """The PD slope at μ = 2 of an earlier run (None if there is none)."""
    if not _CACHE.exists():
        return None
    data = json.loads(_CACHE.read_text())
    return float(data["first_pd_at_defaults"]["slope"])


def _boundary_by_curve(cached: float | None = None) -> tuple[list, float]:
    """The curve to both ends; the start searched on the branch in the slope, or (``cached``)
    the gait solved at a cached PD slope and the PD corrected exactly by the curve's start."""
    t0 = time.perf_counter()
    model = make_model("compass_gait", mass_leg=_MASS_LEG, slope=0.07)
    if cached is None:
        branch = continuation(model, "slope", to=0.09, cascade=False)
        pd = next(sp for sp in branch.special_points if sp.kind == "PD")
    else:
        cycle = find_limit_cycle(model.replace(slope=cached))
        pd = SpecialPoint("PD", cached, 0, cycle, "cached start (corrected on the curve)")
    halves = [curve_from(pd, "PD", _paths(model), end, options=STEPS) for end in _RATIOS]
    return halves, time.perf_counter() - t0


def _grid_seconds_now() -> float:
    """Re-measure the grid: the stability-map study run into a temporary folder."""
    study = Path(__file__).resolve().parents[1] / "problems" / "compass_gait_stability_map.py"
    with tempfile.TemporaryDirectory() as folder:
        subprocess.run([sys.executable, str(study), "--out", folder], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
        data = json.loads((Path(folder) / _MAP.name / "summary.json").read_text())
    return data["timing_s"]["guesses"] + data["timing_s"]["map_sweep"]


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


def run(quick: bool = False, regrid: bool = False) -> dict[str, Any]:
    """Time the curve (once warm: the CasADi functions built by a first run, as the grid's
    workers build theirs before timing starts only in part; both cold and warm are reported)."""
    halves, cold = _boundary_by_curve()
    if not quick:
        halves, warm = _boundary_by_curve()
    else:
        warm = cold
    cached = _cached_slope()
    cached_halves, warm_cached = _boundary_by_curve(cached) if cached is not None else (None, None)
    grid = _grid()
    if grid is not None and regrid:
        grid["seconds"] = _grid_seconds_now()
        grid["remeasured"] = True
    out: dict[str, Any] = {
        "curve_steps": {"step": STEPS.step, "max_step": STEPS.max_step},
        "curve_seconds_cold": cold,
        "curve_seconds_warm": warm,
        "curve_seconds_cached_start": warm_cached,
        "curve_points": sum(len(h.cycles) for h in halves),
        "curve_all_verified": all(c.verified for h in halves for c in h.cycles),
        "curve_ends": [h.message for h in halves],
    }
    if grid is None:
        out["grid"] = "skipped: run problems/compass_gait_stability_map.py first"
        return out
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
    curve_error = np.abs(_spline(halves)(np.log(ratios)) - truth)
    out.update(
        {
            "grid_seconds": grid["seconds"],
            "grid_remeasured": bool(grid.get("remeasured", False)),
            "grid_points": grid["points"],
            "grid_boundary_max_error": float(np.nanmax(grid_error)),
            "curve_boundary_max_error": float(np.nanmax(curve_error)),
            "compared_at_ratios": int(np.sum(np.isfinite(truth))),
            "speedup_cold": grid["seconds"] / cold,
            "speedup_warm": grid["seconds"] / warm,
        }
    )
    if cached_halves is not None:
        error = np.abs(_spline(cached_halves)(np.log(ratios)) - truth)
        out["curve_cached_boundary_max_error"] = float(np.nanmax(error))
        out["speedup_cached_start"] = grid["seconds"] / warm_cached
    return out


def _spline(halves) -> CubicSpline:
    """The curve's boundary between its points: cubic in log μ."""
    lam = np.vstack([h.params for h in halves])
    lam = lam[np.argsort(lam[:, 1])]
    keep = np.concatenate([[True], np.diff(lam[:, 1]) > 1e-12])
    return CubicSpline(np.log(lam[keep, 1]), lam[keep, 0])


def table(result: dict[str, Any]) -> str:
    """The measurement as printed lines."""
    r = result
    lines = [
        "Two-parameter curves: compass-gait stability boundary, slope × m_H/m 0.1–10",
        f"  PD curve: {r['curve_points']} certified gaits (verified: {r['curve_all_verified']}), "
        f"{r['curve_seconds_cold']:.2f} s cold (building the CasADi functions), "
        f"{r['curve_seconds_warm']:.2f} s warm (steps up to {r['curve_steps']['max_step']:g})",
    ]
    if r.get("curve_seconds_cached_start") is not None:
        lines.append(
            f"  from a cached PD slope (no search along the branch): "
            f"{r['curve_seconds_cached_start']:.2f} s"
        )
    if "grid_seconds" in r:
        lines += [
            f"  30×30 grid: {r['grid_points']} solves, {r['grid_seconds']:.1f} s "
            f"(problems/compass_gait_stability_map.py: guesses + map sweep, "
            f"{'re-measured now' if r.get('grid_remeasured') else 'from its summary.json'})",
            f"  boundary error vs the exact PD at {r['compared_at_ratios']} ratios: grid "
            f"{r['grid_boundary_max_error']:.1e} rad, "
            f"curve {r['curve_boundary_max_error']:.1e} rad",
            f"  speed-up: {r['speedup_warm']:.1f}× warm, {r['speedup_cold']:.1f}× cold "
            f"(goal ≥ 20×: {'met' if r['speedup_warm'] >= 20 else 'NOT met'})",
        ]
        if "speedup_cached_start" in r:
            lines.append(
                f"  from the cached start: {r['speedup_cached_start']:.1f}× (boundary error "
                f"{r['curve_cached_boundary_max_error']:.1e} rad)"
            )
    else:
        lines.append(f"  grid: {r['grid']}")
    return "\n".join(lines)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="two-parameter curves vs the 30×30 grid")
    parser.add_argument("--grid", action="store_true", help="re-measure the grid now")
    print(table(run(regrid=parser.parse_args().grid)))
