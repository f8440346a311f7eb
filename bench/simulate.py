"""The simulation's two backends, per model, in one run (issue 23 item 1).

For each model, ``gaitopt.simulate(model, x0, steps=STEPS)`` from the model's default start
(computed once, outside the timing) with ``backend="python"`` (SciPy's DOP853 stepped from
Python, each step one compiled call) and with ``backend="compiled"`` (each arc one C call:
:mod:`gaitopt.simulation.compiled`), alternating,
``repeats`` times each after one warm-up call of each (the libraries loaded, nothing compiled in
the timed calls).  Reported per model: the median wall time of each, their ratio (the speed-up),
the integrator steps taken (the same for both: same method and control), the time per step of
each, and the largest difference between their event times (s) — a fast wrong answer shows.
The medians of the CPU times (``time.process_time``) and the minima of the wall times, with
their ratios, are recorded too.  On a machine shared with other work the wall times include
time spent waiting for a core, which the CPU times do not: the CPU-time ratio is the one to
read there (a short compiled run may finish within one time slice while a long Python run
always waits, which inflates the wall-time ratios, the minima's most).

Run alone: ``python -m bench.simulate [--repeats N] [--steps N] [--out FILE] [MODEL ...]``
(default every registered model, ``results/bench_simulate.json``); ``make bench`` runs it too
(``simulate`` in ``results/bench.json``; three models with ``--quick``).  The machine is
shared: read the medians, not single runs.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from .common import _machine, _median

__all__ = ["run", "table"]

STEPS = 10


def _once(model, x0, backend: str, steps: int) -> tuple[float, float, Any]:
    from gaitopt.simulation import simulate

    t0, c0 = time.perf_counter(), time.process_time()
    sim = simulate(model, x0, steps=steps, backend=backend)
    return time.perf_counter() - t0, time.process_time() - c0, sim


def _model(name: str, repeats: int, steps: int) -> dict[str, Any]:
    import gaitopt

    model = gaitopt.model(name)
    # the start state, once (a model's default start may itself take time: the Strandbeest's
    # solves its energy map, 70 ms)
    x0 = model.lift(model.default_start())
    times: dict[str, list[float]] = {"python": [], "compiled": []}
    cpu: dict[str, list[float]] = {"python": [], "compiled": []}
    sims = {}
    for backend in times:  # warm-up: libraries loaded, phase functions built
        _, _, sims[backend] = _once(model, x0, backend, steps)
    for _ in range(repeats):
        for backend in times:
            seconds, cpu_seconds, _ = _once(model, x0, backend, steps)
            times[backend].append(seconds)
            cpu[backend].append(cpu_seconds)
    a, b = sims["python"], sims["compiled"]
    n_steps = sum(len(arc.solution.interpolants) for arc in a.arcs)
    same = a.status == b.status and len(a.events) == len(b.events)
    difference = (
        max((abs(ea.t - eb.t) for ea, eb in zip(a.events, b.events, strict=True)), default=0.0)
        if same
        else None
    )
    python, compiled = _median(times["python"]), _median(times["compiled"])
    python_cpu, compiled_cpu = _median(cpu["python"]), _median(cpu["compiled"])
    return {
        "status": a.status,
        "events": len(a.events),
        "integrator_steps": n_steps,
        "python_s": python,
        "compiled_s": compiled,
        "speedup": python / compiled,
        "python_cpu_s": python_cpu,
        "compiled_cpu_s": compiled_cpu,
        "speedup_cpu": python_cpu / compiled_cpu if compiled_cpu > 0 else None,
        "python_min_s": min(times["python"]),
        "compiled_min_s": min(times["compiled"]),
        "speedup_of_minima": min(times["python"]) / min(times["compiled"]),
        "python_us_per_step": 1e6 * python / max(n_steps, 1),
        "compiled_us_per_step": 1e6 * compiled / max(n_steps, 1),
        "max_event_time_difference_s": difference,
        "python_runs_s": times["python"],
        "compiled_runs_s": times["compiled"],
    }


def run(names: list[str] | None = None, repeats: int = 5, steps: int = STEPS) -> dict[str, Any]:
    """Both backends on each model (see the module docstring)."""
    from gaitopt.models import model_names

    return {name: _model(name, repeats, steps) for name in names or model_names()}


def table(results: dict[str, Any]) -> str:
    """The medians (wall and CPU) and the wall minima as printed lines."""
    lines = [
        f"{'model':31s} {'status':9s} {'steps':>5s} {'wall ms: py':>11s} {'C':>6s} {'×':>6s} "
        f"{'CPU ms: py':>10s} {'C':>6s} {'×':>6s} {'min ms: py':>10s} {'C':>6s} {'×':>6s} "
        f"{'Δt events':>9s}"
    ]
    for name, r in results.items():
        d = r["max_event_time_difference_s"]
        cpu = r["speedup_cpu"]
        lines.append(
            f"{name:31s} {r['status']:9s} {r['integrator_steps']:5d} "
            f"{1e3 * r['python_s']:11.1f} {1e3 * r['compiled_s']:6.2f} {r['speedup']:5.1f}× "
            f"{1e3 * r['python_cpu_s']:10.1f} {1e3 * r['compiled_cpu_s']:6.2f} "
            f"{'—' if cpu is None else f'{cpu:5.1f}×':>6s} "
            f"{1e3 * r['python_min_s']:10.1f} {1e3 * r['compiled_min_s']:6.2f} "
            f"{r['speedup_of_minima']:5.1f}× {'differ' if d is None else f'{d:.1e}':>9s}"
        )
    for key, what in (
        ("speedup", "wall-time medians"),
        ("speedup_cpu", "CPU-time medians"),
        ("speedup_of_minima", "wall-time minima"),
    ):
        values = sorted(r[key] for r in results.values() if r[key] is not None)
        if values:
            lines.append(
                f"speed-up per simulation ({what}): median {_median(values):.1f}×, "
                f"range {values[0]:.1f}–{values[-1]:.1f}×"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.simulate", description=__doc__)
    parser.add_argument("models", nargs="*", help="model names (default: every registered one)")
    parser.add_argument("--repeats", type=int, default=5, help="timed calls per backend")
    parser.add_argument("--steps", type=int, default=STEPS, help="returns to the section")
    parser.add_argument("--out", type=Path, default=Path("results/bench_simulate.json"))
    args = parser.parse_args(argv)
    results = run(args.models or None, args.repeats, args.steps)
    record = {
        "machine": _machine(),
        "repeats": args.repeats,
        "steps": args.steps,
        "simulate": results,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=2) + "\n")
    print(table(results))
    print(f"Wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
