"""Benchmarks of the bifurcation tools run by ``make bench``.

* **points per second along a branch** — the compass gait's period-1 branch from slope 0.0525
  to 0.075, every point certified and verified by simulation;
* **the compass-gait slope study vs brute force** — continuation with the period-doubling cascade
  (period 1 → 8, special points located to 1e-10) against what a simulation study does: an orbit
  diagram (simulate until settled at each slope, keep the last steps) at slope resolution 2.5e-4,
  through ``sweep`` on 2 local Dask workers, each slope simulated two ways: by the brute-force
  per-slope loop a user writes (``backend="python"``: SciPy's DOP853 stepper driven from Python,
  :func:`simulate_python_task`; the baseline issue 23 set its ≥ 20× goal against, when that was
  gaitopt's own simulation too) and by gaitopt's compiled simulation (``simulate_task``: each arc
  one C call, 8× faster).  The Dask cluster is started before the diagrams' timers (a user's
  running cluster) and its start is timed on its own (``dask_cluster_start_seconds``; 1–2 s).
  ``speedup`` is the goal's ratio, against the brute-force loop; ``speedup_compiled`` the one
  against the compiled simulation.  Both times, and how well each locates the first period
  doubling (the orbit diagram only to its resolution, and biased by the slow transients near the
  bifurcation, where the multiplier is close to −1);
* **sweep throughput** with 1 and 2 local Dask workers (and serially).

Run alone, ``python -m bench.branches [--repeats N] [--quick] [--out FILE]`` repeats the slope
study only (default 3 times, ``results/bench_cascade.json``): each repeat times the continuation
(wall and CPU), the two orbit diagrams on 2 local Dask workers (wall; the cluster started before
the timers, its start timed apart) and the compiled orbit diagram in this process
(``scheduler="serial"``: wall and CPU, which a loaded machine distorts less), with the load
average before each; the medians and their ratios.  On a machine shared with other jobs read the
CPU ratio next to the wall ratio.  It also times one linear solve of the compass gait's period-k
shooting system (k = 8 … 64) dense and structured (:mod:`gaitopt.orbit.structured`).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path
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


def simulate_python_task(point: dict[str, Any]) -> dict[str, Any]:
    """:func:`gaitopt.simulation.simulate_task` with ``backend="python"``: SciPy's DOP853
    stepper driven from Python, the brute-force per-slope loop a user writes (``solve_ivp`` with
    events, one step after another; the same convention as :mod:`bench.basin`'s per-start loop).
    A module-level function, so that Dask pickles it by reference."""
    return simulate_task({**point, "backend": "python"})


#: The orbit diagram's simulations: the baseline issue 23 set its goal against (the brute-force
#: per-slope loop) and gaitopt's own compiled simulation (each arc one C call).
_DIAGRAMS = {"python": simulate_python_task, "compiled": simulate_task}


def _local_cluster(workers: int) -> tuple[Any, float]:
    """A local Dask cluster of ``workers`` single-threaded processes (as :func:`sweep` starts
    one) with its client, and the seconds its start took (wall)."""
    from dask.distributed import Client, LocalCluster

    t0 = time.perf_counter()
    cluster = LocalCluster(
        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
    )
    client = Client(cluster)
    client.wait_for_workers(workers)
    return (cluster, client), time.perf_counter() - t0


def _slope_study(
    quick: bool,
    workers: int,
    scheduler: str | None,
    *,
    resolution: float | None = None,
    steps: tuple[int, int] | None = None,
    diagrams: tuple[str, ...] = ("python", "compiled"),
) -> dict[str, Any]:
    """The slope study: the continuation with its cascade, then the orbit diagram at
    ``resolution`` with each of ``diagrams``' simulations (``steps``: simulated and kept per
    slope).  With ``scheduler`` None the diagrams run on a local Dask cluster of ``workers``
    started before their timers (a user's running cluster; its start is timed on its own)."""
    model = make_model("compass_gait", slope=_SLOPES[0])
    max_period = 4 if quick else 8
    t0, c0 = time.perf_counter(), time.process_time()
    branch = continuation(
        model, "slope", to=_SLOPES[1], max_period=max_period, options=PseudoArclength(max_step=0.05)
    )
    t_continuation, c_continuation = time.perf_counter() - t0, time.process_time() - c0
    pds = sorted(
        sp.param for b in branch.descendants() for sp in b.special_points if sp.kind == "PD"
    )
    first_pd = pds[0] if pds else float("nan")

    resolution = resolution or (1e-3 if quick else 2.5e-4)
    steps, keep = steps or ((100, 8) if quick else (200, 16))
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
    out: dict[str, Any] = {
        "continuation_seconds": t_continuation,
        "continuation_cpu_seconds": c_continuation,
        "continuation_gaits": sum(len(b.cycles) for b in branch.descendants()),
        "period_doublings": pds,
        "first_pd_continuation": first_pd,
        "orbit_diagram_slopes": len(slopes),
        "orbit_diagram_resolution": resolution,
        "orbit_diagram_steps_per_slope": steps,
        "orbit_diagram_workers": workers if scheduler is None else None,
        "orbit_diagram_scheduler": "local Dask cluster" if scheduler is None else str(scheduler),
    }
    own, target = None, scheduler
    if scheduler is None:
        own, out["dask_cluster_start_seconds"] = _local_cluster(workers)
        target = own[1]
    stance = model.state_names.index("stance")
    states = {}
    try:
        for name in diagrams:
            t0, c0 = time.perf_counter(), time.process_time()
            brute = sweep(
                _DIAGRAMS[name],
                points,
                scheduler=target,
                workers=workers,
                progress=False,
                description=f"orbit diagram ({name})",
            )
            t_brute, c_brute = time.perf_counter() - t0, time.process_time() - c0
            # First slope where the settled states take two or more distinct values.
            doubled = [
                s
                for s, r in zip(slopes, brute.results, strict=True)
                if r["states"] and np.ptp(np.array(r["states"])[:, stance]) > 1e-6
            ]
            brute_pd = float(doubled[0]) if doubled else float("nan")
            states[name] = [np.array(r["states"]) for r in brute.results]
            out[f"orbit_diagram_{name}"] = {
                "seconds": t_brute,
                "cpu_seconds_in_process": c_brute if scheduler == "serial" else None,
                "first_pd": brute_pd,
                "first_pd_error": abs(brute_pd - first_pd),
                "speedup": t_brute / t_continuation,
            }
    finally:
        if own is not None:
            own[1].close()
            own[0].close()
    if len(states) == 2:  # the two simulations of the same slopes (None: a shorter record)
        pairs = list(zip(*states.values(), strict=True))
        same = all(a.shape == b.shape for a, b in pairs)
        out["orbit_diagrams_max_difference"] = (
            max((float(np.max(np.abs(a - b))) for a, b in pairs if a.size), default=0.0)
            if same
            else None
        )
    # The goal's ratio: against the baseline issue 23 set it against (the brute-force loop);
    # the compiled simulation's beside it.
    main = out.get("orbit_diagram_python") or out[f"orbit_diagram_{diagrams[0]}"]
    out["orbit_diagram_seconds"] = main["seconds"]
    out["first_pd_orbit_diagram"] = main["first_pd"]
    out["first_pd_orbit_diagram_error"] = main["first_pd_error"]
    out["speedup"] = main["speedup"]
    out["speedup_baseline"] = "python" if "orbit_diagram_python" in out else diagrams[0]
    if "orbit_diagram_compiled" in out:
        out["speedup_compiled"] = out["orbit_diagram_compiled"]["speedup"]
    return out


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
        f"{s['continuation_seconds']:.2f} s, {s['continuation_gaits']} gaits, first PD at "
        f"{s['first_pd_continuation']:.10f} (located to 1e-10)",
        *_diagram_lines(s),
        "  sweep throughput (points/s): "
        + ", ".join(f"{k} {v:.1f}" for k, v in w["points_per_second"].items())
        + f" ({w['points']} simulations of {w['steps_per_point']} steps; {w['note']})",
    ]
    return "\n".join(lines)


def _diagram_lines(s: dict[str, Any]) -> list[str]:
    """The orbit diagrams' lines of :func:`table`."""
    where = (
        f"on {s['orbit_diagram_workers']} Dask workers (cluster started before the timer: "
        f"{s['dask_cluster_start_seconds']:.1f} s, not counted)"
        if s.get("dask_cluster_start_seconds") is not None
        else f"scheduler {s['orbit_diagram_scheduler']}"
    )
    lines = [
        f"  orbit diagram, {s['orbit_diagram_slopes']} slopes at resolution "
        f"{s['orbit_diagram_resolution']:g} × {s['orbit_diagram_steps_per_slope']} steps, {where}:"
    ]
    what = {
        "python": "brute-force per-slope loop (backend='python': SciPy's DOP853 from Python)",
        "compiled": "gaitopt's compiled simulation (each arc one C call)",
    }
    for name in ("python", "compiled"):
        d = s.get(f"orbit_diagram_{name}")
        if d:
            lines.append(
                f"    {what[name]}: {d['seconds']:.2f} s, {d['speedup']:.1f}× the continuation's; "
                f"first PD seen at {d['first_pd']:.5f} (off by {d['first_pd_error']:.1e})"
            )
    verdict = "met" if s["speedup"] >= 20 else "NOT met"
    lines.append(
        f"  goal ≥ 20× against the {s['speedup_baseline']} baseline (issue 23's): "
        f"{s['speedup']:.1f}×, {verdict}"
        + (
            f"; against the compiled simulation {s['speedup_compiled']:.1f}×"
            + (" (under 20×)" if s["speedup_compiled"] < 20 else "")
            if "speedup_compiled" in s
            else ""
        )
    )
    return lines


def cascade(repeats: int = 3, workers: int = 2, quick: bool = False) -> dict[str, Any]:
    """The slope study ``repeats`` times: the continuation; the orbit diagram on ``workers``
    Dask workers (one cluster per repeat, started before the timers and timed apart) with the
    brute-force per-slope loop (``backend="python"``, issue 23's baseline) and with the compiled
    simulation; the compiled diagram again serially in this process (its CPU time, which a loaded
    machine distorts less); medians and ratios (see the module docstring)."""
    runs = []
    for _ in range(repeats):
        load = os.getloadavg()[0]
        dask = _slope_study(quick, workers, None)
        serial = _slope_study(quick, workers, "serial", diagrams=("compiled",))
        runs.append(
            {
                "load_1min_before": load,
                "continuation_seconds": [
                    dask["continuation_seconds"],
                    serial["continuation_seconds"],
                ],
                "continuation_cpu_seconds": [
                    dask["continuation_cpu_seconds"],
                    serial["continuation_cpu_seconds"],
                ],
                "dask_cluster_start_seconds": dask["dask_cluster_start_seconds"],
                "orbit_diagram_python_dask_seconds": dask["orbit_diagram_python"]["seconds"],
                "orbit_diagram_dask_seconds": dask["orbit_diagram_compiled"]["seconds"],
                "orbit_diagram_serial_seconds": serial["orbit_diagram_compiled"]["seconds"],
                "orbit_diagram_serial_cpu_seconds": serial["orbit_diagram_compiled"][
                    "cpu_seconds_in_process"
                ],
                "period_doublings": dask["period_doublings"],
            }
        )

    def median(key: str) -> float:
        values = [v for r in runs for v in np.atleast_1d(r[key])]
        return float(statistics.median(values))

    out = {
        "repeats": repeats,
        "workers": workers,
        "orbit_diagram_slopes": dask["orbit_diagram_slopes"],
        "orbit_diagram_steps_per_slope": dask["orbit_diagram_steps_per_slope"],
        "continuation_gaits": dask["continuation_gaits"],
        "period_doublings": dask["period_doublings"],
        "load_1min": [r["load_1min_before"] for r in runs],
        "runs": runs,
    }
    for key in (
        "continuation_seconds",
        "continuation_cpu_seconds",
        "dask_cluster_start_seconds",
        "orbit_diagram_python_dask_seconds",
        "orbit_diagram_dask_seconds",
        "orbit_diagram_serial_seconds",
        "orbit_diagram_serial_cpu_seconds",
    ):
        out[f"median_{key}"] = median(key)
    out["speedup_wall_dask_python"] = (
        out["median_orbit_diagram_python_dask_seconds"] / out["median_continuation_seconds"]
    )
    out["speedup_wall_dask"] = (
        out["median_orbit_diagram_dask_seconds"] / out["median_continuation_seconds"]
    )
    out["speedup_cpu_serial"] = (
        out["median_orbit_diagram_serial_cpu_seconds"] / out["median_continuation_cpu_seconds"]
    )
    return out


def structured_solves(ks=(8, 16, 32, 64), repeats: int = 20) -> dict[str, Any]:
    """Median time of one Newton step's linear solve of the compass gait's period-k shooting
    system at its repeated period-1 orbit (slope 0.0525), dense (LAPACK) vs on the block pattern
    (:mod:`gaitopt.orbit.structured`, forced for every k), one BLAS thread; and the largest
    difference of the two solutions relative to the solution."""
    import gaitopt
    from gaitopt.orbit import structured
    from gaitopt.shooting import shooting_problem
    from gaitopt.shooting.pattern import shooting_pattern
    from gaitopt.threads import single_blas_thread

    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait", slope=_SLOPES[0]))
    one = cycle.problem
    rows = []

    def timed(f) -> float:
        f()
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            f()
            times.append(time.perf_counter() - t0)
        return float(statistics.median(times))

    @single_blas_thread
    def measure(k: int) -> dict[str, Any]:
        problem = shooting_problem(one.model_cls, one.disc, k)
        s, nodes, durations = one.unpack(cycle.solution, cycle.model.p)
        w = problem.pack(s, nodes * k, list(durations) * k)
        ev = problem.evaluate(w, cycle.inputs, cycle.model.p)
        J, F = ev.F_w, ev.F
        pattern = shooting_pattern(problem)
        threshold = structured.STRUCTURED_MIN_SIZE
        structured.STRUCTURED_MIN_SIZE = 0
        try:
            x_sparse = structured.solve(J, F, pattern)
            t_sparse = timed(lambda: structured.solve(J, F, pattern))
        finally:
            structured.STRUCTURED_MIN_SIZE = threshold
        x_dense = np.linalg.solve(J, F)
        return {
            "k": k,
            "unknowns": problem.size,
            "pattern_nonzeros": pattern.nnz,
            "dense_seconds": timed(lambda: np.linalg.solve(J, F)),
            "structured_seconds": t_sparse,
            "relative_difference": float(
                np.max(np.abs(x_sparse - x_dense)) / np.max(np.abs(x_dense))
            ),
        }

    for k in ks:
        rows.append(measure(k))
    return {
        "threshold": structured.STRUCTURED_MIN_SIZE,
        "load_1min": os.getloadavg()[0],
        "rows": rows,
    }


def cascade_table(c: dict[str, Any]) -> str:
    return "\n".join(
        [
            f"compass cascade (continuation, {c['continuation_gaits']} gaits) vs orbit "
            f"diagram ({c['orbit_diagram_slopes']} slopes × {c['orbit_diagram_steps_per_slope']} "
            f"steps), medians of {c['repeats']} (load {min(c['load_1min']):.1f}–"
            f"{max(c['load_1min']):.1f}):",
            f"  continuation {c['median_continuation_seconds']:.3f} s wall, "
            f"{c['median_continuation_cpu_seconds']:.3f} s CPU",
            f"  orbit diagram on {c['workers']} Dask workers (the cluster started before the "
            f"timer, {c['median_dask_cluster_start_seconds']:.2f} s, not counted):",
            f"    brute-force per-slope loop (backend='python', issue 23's baseline) "
            f"{c['median_orbit_diagram_python_dask_seconds']:.2f} s wall: "
            f"{c['speedup_wall_dask_python']:.1f}× (goal ≥ 20×)",
            f"    compiled simulation {c['median_orbit_diagram_dask_seconds']:.2f} s wall: "
            f"{c['speedup_wall_dask']:.2f}×",
            f"  compiled orbit diagram serially {c['median_orbit_diagram_serial_seconds']:.2f} s "
            f"wall, {c['median_orbit_diagram_serial_cpu_seconds']:.2f} s CPU: "
            f"{c['speedup_cpu_serial']:.2f}× in CPU",
        ]
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.branches", description=__doc__)
    parser.add_argument("--repeats", type=int, default=3, help="repeats of the slope study")
    parser.add_argument("--workers", type=int, default=2, help="local Dask workers")
    parser.add_argument("--out", type=Path, default=Path("results/bench_cascade.json"))
    parser.add_argument(
        "--quick", action="store_true", help="the cascade to period 4, 38 slopes × 100 steps"
    )
    args = parser.parse_args(argv)
    from .common import _machine

    record = {
        "machine": _machine(),
        "structured_solves": structured_solves(ks=(8,) if args.quick else (8, 16, 32, 64)),
        "cascade": cascade(args.repeats, args.workers, quick=args.quick),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=2) + "\n")
    print(cascade_table(record["cascade"]))
    for r in record["structured_solves"]["rows"]:
        print(
            f"  period-{r['k']} solve ({r['unknowns']} unknowns): dense "
            f"{1e3 * r['dense_seconds']:.3g} ms, structured {1e3 * r['structured_seconds']:.3g} ms"
            f" (relative difference {r['relative_difference']:.1e})"
        )
    print(f"Wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
