"""The kernel compile of ``make install`` from an empty cache (issue 23 item 4): goal ≤ 2 min.

``python -m gaitopt.kernels --warm`` runs as a fresh process with ``GAITOPT_CACHE`` a new empty
directory (removed afterwards), as ``make install`` runs it on a clean machine; measured are its
wall time, its CPU time (user + system of the process, its workers and their compilers), each
model's line as it prints it (wall and CPU seconds), and the machine's load before and after: on
a shared machine the wall time includes waiting for a core, and the CPU time over the number of
cores is what an idle machine would take at best.

Run alone (5–10 min of CPU): ``python -m bench.install_compile [--jobs N] [--out FILE]
[MODEL ...]`` (default ``results/bench_install_compile.json``, every built-in model, the default
``--jobs``); ``make bench`` does not run it but reads the latest file into its goals table
(:mod:`bench.goals`), and measures it anew with ``python -m bench --install-compile``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from .common import _machine

__all__ = ["GOAL_S", "RESULTS", "latest", "run", "table"]

#: The goal: the whole compile under 2 min (wall).
GOAL_S = 120.0
#: Where :func:`main` writes by default and :func:`latest` reads.
RESULTS = Path("results/bench_install_compile.json")

# gaitopt.kernels.__main__._report: "<name> <how> <wall> s (CPU <cpu> s)"
_LINE = re.compile(r"^(\S+)\s+(.+?)\s+([\d.]+) s \(CPU\s+([\d.]+) s\)$")


def _load() -> list[float]:
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:
        return []


def run(models: list[str] | None = None, jobs: int | None = None) -> dict[str, Any]:
    """One compile of every kernel (or of ``models``) from an empty cache (see the module)."""
    argv = [sys.executable, "-m", "gaitopt.kernels", "--warm", *(models or [])]
    if jobs is not None:
        argv += ["--jobs", str(jobs)]
    cache = Path(tempfile.mkdtemp(prefix="gaitopt-install-bench-"))
    env = {**os.environ, "GAITOPT_CACHE": str(cache)}
    load_before = _load()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=3600)
    finally:
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        shutil.rmtree(cache, ignore_errors=True)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    per_model = {}
    for line in proc.stdout.splitlines():
        match = _LINE.match(line.strip())
        if match:
            name, how, seconds, model_cpu = match.groups()
            per_model[name] = {"how": how, "wall_s": float(seconds), "cpu_s": float(model_cpu)}
    return {
        "command": "python -m gaitopt.kernels --warm" + ("" if jobs is None else f" --jobs {jobs}"),
        "models": models or "all",
        "exit_code": proc.returncode,
        "wall_s": wall,
        "cpu_s": cpu,
        "cpus": os.cpu_count(),
        "load_before": load_before,
        "load_after": _load(),
        "goal_s": GOAL_S,
        "met": proc.returncode == 0 and wall <= GOAL_S,
        "met_cpu": proc.returncode == 0 and cpu / max(os.cpu_count() or 1, 1) <= GOAL_S,
        "per_model": per_model,
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        **({"stderr_tail": proc.stderr.strip().splitlines()[-3:]} if proc.returncode else {}),
    }


def latest(path: Path = RESULTS) -> dict[str, Any] | None:
    """The last measurement :func:`main` wrote (its ``install_compile``), or None."""
    try:
        return json.loads(Path(path).read_text())["install_compile"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def table(entry: dict[str, Any]) -> str:
    """The measurement as printed lines: the whole compile, then the slowest models."""
    lines = [
        f"Kernel compile from an empty cache ({entry['command']}, {entry['cpus']} CPUs, load "
        f"{entry['load_before']} → {entry['load_after']}): {entry['wall_s']:.1f} s wall, "
        f"{entry['cpu_s']:.1f} s CPU (goal ≤ {entry['goal_s']:.0f} s wall: "
        f"{'met' if entry['met'] else 'not met'})"
    ]
    slow = sorted(entry["per_model"].items(), key=lambda kv: -kv[1]["cpu_s"])
    for name, m in slow[:6]:
        lines.append(f"  {name:18s} {m['wall_s']:6.1f} s wall, {m['cpu_s']:6.1f} s CPU")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.install_compile", description=__doc__)
    parser.add_argument("--jobs", type=int, help="models compiled at once (default: the CPUs)")
    parser.add_argument("--out", type=Path, default=RESULTS)
    parser.add_argument("models", nargs="*", help="model names (default: every built-in one)")
    args = parser.parse_args(argv)
    entry = run(args.models or None, args.jobs)
    record = {"machine": _machine(), "install_compile": entry}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=2) + "\n")
    print(table(entry))
    print(f"Wrote {args.out}")
    return 0 if entry["exit_code"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
