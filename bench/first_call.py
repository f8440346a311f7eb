"""The optimiser's first call in a fresh process (issue 24 item 6, issue 23 item 4).

* **five-link biped** — ``gaitopt optimize five_link_biped --fix step_length=0.4 --fix
  period=0.6 --json`` as a fresh process (kernel cache warm), wall time; goal ≤ 3 s;
* **compass gait** — ``gaitopt optimize compass_gait --set slope=0 --fix step_length=0.3 --fix
  period=0.8``: the first :func:`gaitopt.optimize_gait` call of a fresh process (after ``import
  gaitopt``), goal ≤ 0.5 s; and the whole process.

Each is the median of ``repeats`` processes after one that is not counted (file caches warm for
every process alike); each process also reports its first call's time from inside (after
``import gaitopt``), its cost and success, so that a fast wrong answer shows.  ``ratio`` is the
measured time over the goal (≤ 1: met).  The CPU times (user + system) are recorded beside the
wall times: on a machine shared with other work the wall time of a single-threaded process is
its CPU time plus the time it waited for a core.

Run alone: ``python -m bench.first_call [--repeats N] [--out FILE]`` (default
``results/bench_first_call.json``); ``make bench`` runs it too (``first_call`` in
``results/bench.json``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from .common import _machine, _median

__all__ = ["run", "table", "GOALS"]

#: Goals (s): the five-link biped's whole process, the compass gait's first call.
GOALS = {"five_link_biped": 3.0, "compass_gait": 0.5}

_CLI = "import sys; from gaitopt.cli import main; sys.exit(main())"
_ARGS = {
    "five_link_biped": ["five_link_biped", "--fix", "step_length=0.4", "--fix", "period=0.6"],
    "compass_gait": [
        "compass_gait", "--set", "slope=0", "--fix", "step_length=0.3", "--fix", "period=0.8"
    ],
}  # fmt: skip
_INSIDE = """\
import json, time
t0 = time.perf_counter()
import gaitopt
t1, c1 = time.perf_counter(), time.process_time()
model = gaitopt.model({name!r}, **{params!r})
gait = gaitopt.optimize_gait(model, period={period!r}, step_length={step!r})
t2 = time.perf_counter()
c2 = time.process_time()
print(json.dumps({{"import_s": t1 - t0, "first_call_s": t2 - t1, "first_call_cpu_s": c2 - c1,
                  "cost": gait.cost, "success": bool(gait.success)}}))
"""
_STATEMENTS = {
    "five_link_biped": ({}, 0.6, 0.4),
    "compass_gait": ({"slope": 0.0}, 0.8, 0.3),
}


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _runs(argv: list[str], repeats: int) -> tuple[list[float], list[float], list[str]]:
    """Wall and CPU (user + system) times of ``repeats`` fresh processes, and their outputs."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    times, cpus, outputs = [], [], []
    for i in range(repeats + 1):
        t0, c0 = time.perf_counter(), _cpu()
        proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=900)
        if i:
            times.append(time.perf_counter() - t0)
            cpus.append(_cpu() - c0)
            outputs.append(proc.stdout if proc.returncode == 0 else f"exit {proc.returncode}")
    return times, cpus, outputs


def _model(name: str, repeats: int) -> dict[str, Any]:
    cli = [sys.executable, "-c", _CLI, "optimize", *_ARGS[name], "--json"]
    process_times, process_cpu, outs = _runs(cli, repeats)
    try:
        result = json.loads(outs[-1])
        cost, success = result.get("cost"), result.get("success")
    except (ValueError, IndexError):
        cost, success = None, False
    params, period, step = _STATEMENTS[name]
    code = _INSIDE.format(name=name, params=params, period=period, step=step)
    _, _, inside = _runs([sys.executable, "-c", code], repeats)
    calls = [json.loads(o.strip().splitlines()[-1]) for o in inside if o.startswith("{")]
    first = _median([c["first_call_s"] for c in calls])
    whole = _median(process_times)
    five = name == "five_link_biped"
    measured = whole if five else first
    cpu = _median(process_cpu) if five else _median([c["first_call_cpu_s"] for c in calls])
    goal = GOALS[name]
    return {
        "command": "gaitopt optimize " + " ".join(_ARGS[name]) + " --json",
        "process_s": whole,
        "process_min_s": min(process_times),
        "process_cpu_s": _median(process_cpu),
        "first_call_s": first,
        "first_call_cpu_s": _median([c["first_call_cpu_s"] for c in calls]),
        "import_s": _median([c["import_s"] for c in calls]),
        "cost": cost,
        "success": success,
        "goal": {
            "measure": "process_s" if five else "first_call_s",
            "goal_s": goal,
            "measured_s": measured,
            "ratio": measured / goal,
            "met": bool(measured <= goal),
            "measured_cpu_s": cpu,
            "ratio_cpu": cpu / goal,
        },
    }


def run(repeats: int = 3) -> dict[str, Any]:
    """Both first-call measurements (see the module docstring)."""
    return {name: _model(name, repeats) for name in GOALS}


def table(first_call: dict[str, Any]) -> str:
    """The goals as printed lines: measured (wall and CPU), goal, ratio."""
    if "skipped" in first_call:
        return f"first call: {first_call}"
    lines = ["The optimiser's first call in a fresh process (wall; CPU):"]
    for name, entry in first_call.items():
        g = entry["goal"]
        lines.append(
            f"  {name:16s} {g['measure']} {g['measured_s']:.2f} s; {g['measured_cpu_s']:.2f} s "
            f"(goal {g['goal_s']} s: ratio {g['ratio']:.2f}; {g['ratio_cpu']:.2f}), "
            f"cost {entry['cost']}, success {entry['success']}"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.first_call", description=__doc__)
    parser.add_argument("--repeats", type=int, default=3, help="processes per measure")
    parser.add_argument("--out", type=Path, default=Path("results/bench_first_call.json"))
    args = parser.parse_args(argv)
    record = {"machine": _machine(), "repeats": args.repeats, "first_call": run(args.repeats)}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=2) + "\n")
    print(table(record["first_call"]))
    print(f"Wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
