"""The simulation's two backends, per model, in one run (issue 23 item 1).

For each model, ``gaitopt.simulate(model, x0, steps=STEPS)`` from the model's default start
(computed once, outside the timing) with ``backend="python"`` (SciPy's DOP853 stepped from
Python, each step one compiled call) and with ``backend="compiled"`` (each arc one C call:
:mod:`gaitopt.simulation.compiled`), alternating,
``repeats`` times each after one warm-up call of each (the libraries loaded, nothing compiled in
the timed calls).  Reported per model: the median wall time of each, their ratio (the speed-up),
the integrator steps taken (the same for both: same method and control), the time per step of
each, and the largest difference between their event times (s) — a fast wrong answer shows.
The minima and their ratio are recorded too: on a machine shared with other work the medians
include time spent waiting for a core.

Run alone: ``python -m bench.simulate [--repeats N] [--steps N] [--out FILE] [MODEL ...]``
(default every registered model, ``results/bench_simulate.json``).  The machine is shared: read
the medians, not single runs.
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


def _once(model, x0, backend: str, steps: int) -> tuple[float, Any]:
    from gaitopt.simulation import simulate

    t0 = time.perf_counter()
    sim = simulate(model, x0, steps=steps, backend=backend)
    return time.perf_counter() - t0, sim


def _model(name: str, repeats: int, steps: int) -> dict[str, Any]:
    import gaitopt

    model = gaitopt.model(name)
    # the start state, once (a model's default start may itself take time: the Strandbeest's
    # solves its energy map, 70 ms)
    x0 = model.lift(model.default_start())
    times: dict[str, list[float]] = {"python": [], "compiled": []}
    sims = {}
    for backend in times:  # warm-up: libraries loaded, phase functions built
        _, sims[backend] = _once(model, x0, backend, steps)
    for _ in range(repeats):
        for backend in times:
            seconds, _ = _once(model, x0, backend, steps)
            times[backend].append(seconds)
    a, b = sims["python"], sims["compiled"]
    n_steps = sum(len(arc.solution.interpolants) for arc in a.arcs)
    same = a.status == b.status and len(a.events) == len(b.events)
    difference = (
        max((abs(ea.t - eb.t) for ea, eb in zip(a.events, b.events, strict=True)), default=0.0)
        if same
        else None
    )
    python, compiled = _median(times["python"]), _median(times["compiled"])
    return {
        "status": a.status,
        "events": len(a.events),
        "integrator_steps": n_steps,
        "python_s": python,
        "compiled_s": compiled,
        "speedup": python / compiled,
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
    """The medians (and the minima) as printed lines."""
    lines = [
        f"{'model':31s} {'status':9s} {'steps':>5s} {'python ms':>9s} {'compiled ms':>11s} "
        f"{'speed-up':>8s} {'min: py':>8s} {'C':>6s} {'speed-up':>8s} {'µs/step C':>9s} "
        f"{'Δt events':>9s}"
    ]
    for name, r in results.items():
        d = r["max_event_time_difference_s"]
        lines.append(
            f"{name:31s} {r['status']:9s} {r['integrator_steps']:5d} {1e3 * r['python_s']:9.1f} "
            f"{1e3 * r['compiled_s']:11.2f} {r['speedup']:7.1f}× {1e3 * r['python_min_s']:8.1f} "
            f"{1e3 * r['compiled_min_s']:6.2f} {r['speedup_of_minima']:7.1f}× "
            f"{1e6 * r['compiled_min_s'] / max(r['integrator_steps'], 1):9.1f} "
            f"{'differ' if d is None else f'{d:.1e}':>9s}"
        )
    for key, what in (("speedup", "medians"), ("speedup_of_minima", "minima")):
        values = sorted(r[key] for r in results.values())
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
