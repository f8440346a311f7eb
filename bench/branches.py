"""Benchmarks of the bifurcation tools run by ``make bench``.

* **points per second along a branch** — the compass gait's period-1 branch from slope 0.0525
  to 0.075, every point certified and verified by simulation;
* **the compass-gait slope study vs brute force** — continuation with the period-doubling cascade
  (period 1 → 8, special points located to 1e-10) against what a simulation study does: an orbit
  diagram (simulate until settled at each slope, keep the last steps) at slope resolution 2.5e-4,
  through ``sweep`` on the same 2 workers; both times, and how well each locates the first
  period doubling (the orbit diagram only to its resolution, and biased by the slow transients
  near the bifurcation, where the multiplier is close to −1);
* **sweep throughput** with 1 and 2 local Dask workers (and serially).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from gaitopt.continuation import PseudoArclength, continuation
from gaitopt.models import model as make_model
from gaitopt.simulation import simulate_task
from gaitopt.sweep import sweep

__all__ = ["run"]

_SLOPES = (0.0525, 0.09)


def run(quick: bool = False, workers: int = 2, scheduler: str | None = None) -> dict[str, Any]:
    """All three measurements; ``quick`` shrinks the sizes (for tests)."""
    out: dict[str, Any] = {}
    out["branch_rate"] = _branch_rate()
    out["slope_study"] = _slope_study(quick, workers, scheduler)
    out["sweep_throughput"] = _sweep_throughput(quick, scheduler)
    return out


def _branch_rate() -> dict[str, Any]:
    model = make_model("compass_gait")
    continuation(model, "slope", to=0.0526, cascade=False)  # build the functions once
    t0 = time.perf_counter()
    branch = continuation(
        model, "slope", to=0.075, cascade=False, options=PseudoArclength(max_step=0.02)
    )
    elapsed = time.perf_counter() - t0
    return {
        "points": len(branch.cycles),
        "seconds": elapsed,
        "points_per_second": len(branch.cycles) / elapsed,
        "verified": all(c.verified for c in branch.cycles),
    }


def _slope_study(quick: bool, workers: int, scheduler: str | None) -> dict[str, Any]:
    model = make_model("compass_gait", slope=_SLOPES[0])
    max_period = 4 if quick else 8
    t0 = time.perf_counter()
    branch = continuation(
        model, "slope", to=_SLOPES[1], max_period=max_period, options=PseudoArclength(max_step=0.05)
    )
    t_continuation = time.perf_counter() - t0
    pds = sorted(
        sp.param for b in branch.descendants() for sp in b.special_points if sp.kind == "PD"
    )
    first_pd = pds[0] if pds else float("nan")

    resolution = 1e-3 if quick else 2.5e-4
    steps, keep = (100, 8) if quick else (200, 16)
    slopes = np.arange(_SLOPES[0], _SLOPES[1] + resolution / 2, resolution)
    names = model.section.coordinates
    on_branch = np.array([c.section_point for c in branch.cycles])
    points = [
        {
            "model": "compass_gait",
            "params": {"slope": float(s)},
            "steps": steps,
            "record": keep,
            "x0": {
                n: float(np.interp(s, branch.params, on_branch[:, j])) + 1e-3
                for j, n in enumerate(names)
            },
        }
        for s in slopes
    ]
    t0 = time.perf_counter()
    brute = sweep(
        simulate_task,
        points,
        scheduler=scheduler,
        workers=workers,
        progress=False,
        description="orbit diagram",
    )
    t_brute = time.perf_counter() - t0
    # First slope where the settled states take two or more distinct values.
    stance = model.state_names.index("stance")
    doubled = [
        s
        for s, r in zip(slopes, brute.results, strict=True)
        if r["states"] and np.ptp(np.array(r["states"])[:, stance]) > 1e-6
    ]
    brute_pd = float(doubled[0]) if doubled else float("nan")
    return {
        "continuation_seconds": t_continuation,
        "continuation_gaits": sum(len(b.cycles) for b in branch.descendants()),
        "period_doublings": pds,
        "first_pd_continuation": first_pd,
        "orbit_diagram_seconds": t_brute,
        "orbit_diagram_slopes": len(slopes),
        "orbit_diagram_resolution": resolution,
        "orbit_diagram_steps_per_slope": steps,
        "first_pd_orbit_diagram": brute_pd,
        "first_pd_orbit_diagram_error": abs(brute_pd - first_pd),
        "speedup": t_brute / t_continuation,
    }


def _sweep_throughput(quick: bool, scheduler: str | None) -> dict[str, Any]:
    n, steps = (8, 20) if quick else (60, 150)
    points = [
        {"model": "compass_gait", "params": {"slope": float(s)}, "x0": None, "steps": steps}
        for s in np.linspace(0.03, 0.06, n)
    ]
    rows = {}
    t0 = time.perf_counter()
    sweep(simulate_task, points, scheduler="serial", progress=False)
    rows["serial"] = time.perf_counter() - t0
    for w in (1, 2):
        t0 = time.perf_counter()
        sweep(simulate_task, points, scheduler=scheduler, workers=w, progress=False)
        rows[f"dask_{w}_workers"] = time.perf_counter() - t0
    return {
        "points": n,
        "steps_per_point": steps,
        "seconds": rows,
        "points_per_second": {k: n / v for k, v in rows.items()},
        "note": "Dask times include starting the local cluster (about 1–2 s)",
    }


def table(result: dict[str, Any]) -> str:
    """The measurements as printed lines."""
    b, s, w = result["branch_rate"], result["slope_study"], result["sweep_throughput"]
    lines = [
        "Continuation and sweeps:",
        f"  points along a branch: {b['points']} certified gaits in {b['seconds']:.2f} s = "
        f"{b['points_per_second']:.0f} points/s (each verified by simulation: {b['verified']})",
        f"  compass gait vs slope, continuation through {len(s['period_doublings'])} period "
        f"doublings: "
        f"{s['continuation_seconds']:.1f} s, {s['continuation_gaits']} gaits, first PD at "
        f"{s['first_pd_continuation']:.10f} (located to 1e-10)",
        f"  brute-force orbit diagram, {s['orbit_diagram_slopes']} slopes at resolution "
        f"{s['orbit_diagram_resolution']:g} × {s['orbit_diagram_steps_per_slope']} steps: "
        f"{s['orbit_diagram_seconds']:.1f} s; first PD seen at {s['first_pd_orbit_diagram']:.5f} "
        f"(off by {s['first_pd_orbit_diagram_error']:.1e})",
        f"  speed-up of continuation over the orbit diagram: {s['speedup']:.1f}× "
        f"(goal ≥ 20× for the same information: {'met' if s['speedup'] >= 20 else 'NOT met'})",
        "  sweep throughput (points/s): "
        + ", ".join(f"{k} {v:.1f}" for k, v in w["points_per_second"].items())
        + f" ({w['points']} simulations of {w['steps_per_point']} steps; {w['note']})",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    print(table(run()))
