"""The whole ``gaitopt solve compass_gait --json`` process against Drake's, and what it spends
its time on (issue 23 item 3: a fast start).

* **processes** — fresh processes run in turn, ``repeats`` rounds after one that is not counted
  (file caches warm for every process alike): ``python -c pass``, ``python -c "import
  gaitopt"``, the command (as its console script runs it) and, where ``pydrake`` imports, Drake's
  process (:data:`bench.speed._DRAKE_PROCESS`: ``CompassGait`` from the same start until
  consecutive post-impact states agree to 1e-8).  Alternating them puts the machine's load on
  every command alike; and the hand-written SciPy baseline's process (:mod:`bench.goals`: events
  + ``fsolve`` from the same start), the comparison where Drake cannot be installed.  Median
  wall and CPU (user + system) times; the goal is the command's wall time ≤ 0.5× Drake's.
* **stages** — the command's CPU time taken apart by processes that stop earlier, each the
  median of ``repeats``: the interpreter (``pass``), NumPy (with one BLAS thread, as the command
  starts it), CasADi, gaitopt's modules of the solve path (the list a run of the command
  reports, the cache warm), the whole command;
* **inside** — one process timing the command's steps in turn (CPU): the imports, the model's
  structure (unpickled from the kernel cache), the first ``find_limit_cycle`` (kernels loaded
  from the cache, CasADi functions built, the solve), a second one (the warm solve: what the
  first spent beyond it is loading), the JSON.

Run alone: ``python -m bench.process [--repeats N] [--no-peers] [--out FILE]`` (default
``results/bench_process.json``).
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

__all__ = ["run", "table"]

_CLI = "import sys; from gaitopt.cli import main; sys.exit(main())"
_ARGS = ["solve", "compass_gait", "--json"]

_MODULES = """\
import contextlib, io, json, sys
from gaitopt.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    main({args!r})
print(json.dumps(sorted(m for m in sys.modules if m.startswith("gaitopt"))))
"""

_IMPORT_PATH = """\
import importlib, os
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as the command starts its BLAS
import numpy, casadi
for name in {modules!r}:
    importlib.import_module(name)
"""

_INSIDE = """\
import json, time
def now():
    return time.process_time()
t = [now()]
import gaitopt.cli
from gaitopt.threads import start_with_blas_threads
start_with_blas_threads()
import numpy, casadi
t.append(now())
import importlib
for name in {modules!r}:
    importlib.import_module(name)
t.append(now())
from gaitopt.models import model_class
from gaitopt.search import find_limit_cycle
cls = model_class("compass_gait")
cls.structure()
t.append(now())
first = find_limit_cycle(cls())
t.append(now())
second = find_limit_cycle(cls())
t.append(now())
from gaitopt.files import jsonable
text = json.dumps(jsonable(first.as_dict()), indent=2, ensure_ascii=False, allow_nan=False)
t.append(now())
steps = ["gaitopt.cli, NumPy, CasADi", "gaitopt's solve-path modules", "structure",
         "first find_limit_cycle", "second find_limit_cycle", "JSON"]
print(json.dumps({{"cpu_s": dict(zip(steps, [b - a for a, b in zip(t, t[1:])])),
                  "same": first.fixed_point == second.fixed_point and first.success}}))
"""


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _drake_code() -> str | None:
    """Drake's process as :mod:`bench.speed` times it, or None where pydrake does not import."""
    probe = subprocess.run(
        [sys.executable, "-c", "import pydrake.examples"], capture_output=True, timeout=300
    )
    if probe.returncode:
        return None
    import gaitopt

    from .speed import _DRAKE_PROCESS, _SETTLE

    model = gaitopt.model("compass_gait")
    x0 = [float(v) for v in model.lift(model.section_vector({}))]
    return _DRAKE_PROCESS.format(params=dict(model.params), x0=x0, tol=_SETTLE)


def _baseline_code() -> str:
    """The hand-written SciPy baseline's process as :mod:`bench.goals` times it."""
    import gaitopt

    from .goals import _BASELINE_PROCESS

    model = gaitopt.model("compass_gait")
    start = [float(v) for v in model.section_vector({})]
    return _BASELINE_PROCESS.format(params=dict(model.params), start=start)


def _alternating(commands: dict[str, list[str]], repeats: int) -> dict[str, Any]:
    """Wall and CPU times of each command, the commands run in turn ``repeats`` rounds (after
    one round that is not counted); the 1-minute load average after each round."""
    root = str(Path(__file__).resolve().parents[1])  # this checkout's gaitopt and bench
    path = os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH", "")) if p)
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": path}
    runs: dict[str, dict[str, list]] = {k: {"wall": [], "cpu": [], "codes": []} for k in commands}
    loads = []
    for i in range(repeats + 1):
        for name, argv in commands.items():
            t0, c0 = time.perf_counter(), _cpu()
            proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=900)
            if i:
                runs[name]["wall"].append(time.perf_counter() - t0)
                runs[name]["cpu"].append(_cpu() - c0)
                runs[name]["codes"].append(proc.returncode)
        if i:
            loads.append(os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan"))
    out: dict[str, Any] = {"load_1min": [min(loads), max(loads)]}
    for name, r in runs.items():
        out[name] = {
            "median_s": _median(r["wall"]),
            "min_s": float(min(r["wall"])),
            "cpu_median_s": _median(r["cpu"]),
            "exit_codes": r["codes"],
        }
    return out


def run(repeats: int = 7, drake: bool = True) -> dict[str, Any]:
    """The record :func:`table` prints (see the module's docstring)."""
    python = sys.executable
    for _ in range(2):  # the second run's list: the first may find a cold cache and build
        listed = subprocess.run(
            [python, "-c", _MODULES.format(args=_ARGS)], capture_output=True, text=True, check=True
        )
    modules = json.loads(listed.stdout.strip().splitlines()[-1])
    commands = {
        "python_startup": [python, "-c", "pass"],
        "import_gaitopt": [python, "-c", "import gaitopt"],
        "gaitopt": [python, "-c", _CLI, *_ARGS],
    }
    code = _drake_code() if drake else None
    if code is not None:
        commands["drake"] = [python, "-c", code]
    commands["baseline"] = [python, "-c", _baseline_code()]
    record: dict[str, Any] = {
        "machine": _machine(),
        "repeats": repeats,
        "command": "gaitopt " + " ".join(_ARGS),
        "processes": _alternating(commands, repeats),
    }
    if code is None:
        record["processes"]["drake"] = {"skipped": "pydrake does not import" if drake else "off"}
    stages = {
        "python": [python, "-c", "pass"],
        "+ NumPy (one BLAS thread)": [
            python, "-c", "import os; os.environ['OPENBLAS_NUM_THREADS'] = '1'; import numpy"
        ],
        "+ CasADi": [
            python, "-c",
            "import os; os.environ['OPENBLAS_NUM_THREADS'] = '1'; import numpy, casadi",
        ],
        "+ gaitopt's solve-path modules": [python, "-c", _IMPORT_PATH.format(modules=modules)],
        "+ the solve and its output (the whole command)": [python, "-c", _CLI, *_ARGS],
    }  # fmt: skip
    measured = _alternating(stages, repeats)
    record["stages"] = {"load_1min": measured.pop("load_1min"), **measured}
    record["modules"] = len(modules)
    inside = subprocess.run(
        [python, "-c", _INSIDE.format(modules=modules)], capture_output=True, text=True, check=True
    )
    record["inside"] = json.loads(inside.stdout.strip().splitlines()[-1])
    processes = record["processes"]
    if "median_s" in processes.get("drake", {}):
        g, d = processes["gaitopt"], processes["drake"]
        record["ratio_wall"] = g["median_s"] / d["median_s"]
        record["ratio_cpu"] = g["cpu_median_s"] / d["cpu_median_s"]
        record["met"] = record["ratio_wall"] <= 0.5
    g, b = processes["gaitopt"], processes["baseline"]
    record["ratio_baseline_wall"] = g["median_s"] / b["median_s"]
    record["ratio_baseline_cpu"] = g["cpu_median_s"] / b["cpu_median_s"]
    return record


def table(record: dict[str, Any]) -> str:
    """The record as text: the processes, the ratio, the stages and the steps inside."""

    def ms(s: float) -> str:
        return f"{1e3 * s:.0f} ms"

    p = record["processes"]
    lo, hi = p["load_1min"]
    lines = [f"whole processes ({record['repeats']} rounds, alternating; load {lo:.1f}–{hi:.1f})"]
    for name in ("python_startup", "import_gaitopt", "gaitopt", "drake", "baseline"):
        r = p.get(name, {})
        if "median_s" in r:
            lines.append(
                f"  {name:16s} wall {ms(r['median_s']):>8s} (fastest {ms(r['min_s'])})  "
                f"CPU {ms(r['cpu_median_s'])}"
            )
        else:
            lines.append(f"  {name:16s} {r.get('skipped', '—')}")
    if "ratio_wall" in record:
        verdict = "met" if record["met"] else "not met"
        lines.append(
            f"  gaitopt / Drake: {record['ratio_wall']:.2f}× wall, {record['ratio_cpu']:.2f}× CPU "
            f"(goal ≤ 0.5× wall: {verdict})"
        )
    lines.append(
        f"  gaitopt / the hand-written baseline: {record['ratio_baseline_wall']:.2f}× wall, "
        f"{record['ratio_baseline_cpu']:.2f}× CPU"
    )
    s = record["stages"]
    lines.append(f"stages (CPU, median; load {s['load_1min'][0]:.1f}–{s['load_1min'][1]:.1f})")
    previous = 0.0
    for name, r in s.items():
        if name == "load_1min":
            continue
        cpu = r["cpu_median_s"]
        lines.append(f"  {name:48s} {ms(cpu):>8s}  (+{ms(cpu - previous)})")
        previous = cpu
    lines.append(f"inside one process (CPU; {record['modules']} gaitopt modules)")
    for name, cpu in record["inside"]["cpu_s"].items():
        lines.append(f"  {name:48s} {ms(cpu):>8s}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.process", description=__doc__)
    parser.add_argument("--repeats", type=int, default=7, help="rounds counted (default 7)")
    parser.add_argument("--no-peers", action="store_true", help="skip Drake even if installed")
    parser.add_argument("--out", type=Path, default=Path("results/bench_process.json"))
    args = parser.parse_args(argv)
    record = run(repeats=args.repeats, drake=not args.no_peers)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=2) + "\n")
    print(table(record))
    return 0


if __name__ == "__main__":
    sys.exit(main())
