"""``make bench``: how fast and how exact :func:`gaitopt.find_limit_cycle` is, against what users
write today.

For the compass gait, the rimless wheel and the kneed walker (``--models all``: every registered
model)::

    python -m bench --out results/bench.json

measures

* **gaitopt, first call in a process** — ``gaitopt.model(name)`` and ``find_limit_cycle`` in a
  fresh ``python -c`` subprocess (CasADi graphs built and compiled then), median of ``--repeats``
  processes; the import time of ``gaitopt`` is recorded separately;
* **gaitopt, once built** — the median of ``--built-repeats`` further calls in this process, with
  ``verify=False`` (the cycle with its multipliers) and ``verify=True`` (plus the independent
  SciPy simulation from the fixed point);
* **a hand-written baseline** (:mod:`bench.baselines`): single shooting with
  ``solve_ivp`` events and ``scipy.optimize.fsolve`` on the return map from the same start,
  multipliers by finite differences of the simulated map — median of ``--repeats`` runs;
* **Drake** (only where ``pydrake`` imports: ``pip install -e '.[peers]'``): ``CompassGait`` and
  ``RimlessWheel`` simulated from the same start until the gait settles (two consecutive
  post-impact states within 1e-5, max-norm), with Drake's default accuracy 1e-4 and with 1e-10;
  once more run to convergence (consecutive states within 1e-10, or 100 steps) to show where
  Drake's event isolation leaves the fixed point.  A Python monitor watches each run for the
  impacts; the time reported is that of a fresh simulation to the same end time without the
  monitor (the monitored time is in the JSON too), so Drake is not charged for Python callbacks.

and compares every fixed point with gaitopt's and with docs/design.md's reference numbers.

**Step-to-step control** (``--no-control`` skips it): one deadbeat decision of the SLIP's
touchdown angle from an apex (``P(z, θ) = z*``), timed

* in Python — :meth:`gaitopt.control.StepController.decide` (CasADi Newton rootfinder on the
  multiple-shooting equations), median over ``--decisions`` apex heights;
* as generated C — :meth:`gaitopt.control.Deadbeat.codegen` (``Function.generate`` of a
  single-shooting ``fast_newton`` policy, compiled with the system's C compiler, cached in
  ``<tmp>/gaitopt-codegen``), timed inside a small C driver (``clock_gettime`` around each call)
  and through ``casadi.external`` from Python; its decisions are compared with Python's;
* against what the textbook notebook does — the apex map evaluated by event-located simulation
  (one evaluation of :func:`gaitopt.returnmap.return_map`), and a deadbeat decision found by
  ``brentq`` on that simulated map — in the same run.

It prints a table and writes everything (with the machine, the versions and the date) to
``--out``, atomically, with every goal of issue 23 as a row (:mod:`bench.goals`).  Sized for a
2-core machine: about 10 minutes with the defaults, Drake
included (the first control run adds the C compilation, about 10 s).

Modules: this one (the driver: :func:`run` and :func:`main`); :mod:`bench.cycles` (gaitopt and
the hand-written baseline timed), :mod:`bench.drake` (Drake's runs), :mod:`bench.control` (the
deadbeat decision), :mod:`bench.reference` (reference numbers, errors, goals),
:mod:`bench.table` (the printed report), :mod:`bench.common` (shared helpers).
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from gaitopt.files import write_json

from . import basin as _bench_basin
from . import branches as _bench_branches
from . import curves as _bench_curves
from . import first_call as _bench_first_call
from . import goals as _bench_goals
from . import install_compile as _bench_install_compile
from . import optimize as _bench_optimize
from . import simulate as _bench_simulate
from . import speed as _bench_speed
from .common import _machine
from .control import _deadbeat_bench
from .cycles import _baseline, _cycle_record, _first_call, _once_built
from .drake import _drake, _import_drake
from .reference import _compare, _goals
from .table import format_table, rows

__all__ = ["main", "run", "rows", "format_table"]


#: The models of the per-model sections by default (``--models all``: every registered model,
#: some 20 minutes more): the compass gait and the rimless wheel (Drake has both) and the kneed
#: walker (issue 23's 5 ms goal), so that ``make bench`` stays near 10 minutes on 2 cores.
DEFAULT_MODELS = ("compass_gait", "rimless_wheel", "kneed_walker")


# -- the run ----------------------------------------------------------------------------------
def run(
    *,
    repeats: int = 3,
    built_repeats: int = 20,
    models: list[str] | None = None,
    peers: bool = True,
    converge: bool = True,
    control: bool = True,
    decisions: int = 200,
    branches: bool = True,
    speed: bool = True,
    basin: bool = True,
    quick: bool = False,
    install_compile: bool = False,
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True),
) -> dict[str, Any]:
    """Measure everything; the JSON-ready record (see the module docstring)."""
    import gaitopt

    started = time.perf_counter()
    every = models == ["all"]
    names = list(gaitopt.REGISTRY) if every else list(DEFAULT_MODELS if models is None else models)
    drake, drake_import = _import_drake() if peers else (None, "disabled (--no-peers)")
    record: dict[str, Any] = {
        "load_at_start": _bench_goals.load(),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": " ".join([Path(sys.executable).name, "-m", "bench", *sys.argv[1:]]),
        "machine": _machine(),
        "repeats": {
            "first_call_processes": repeats,
            "once_built_calls": built_repeats,
            "once_built_calls_verify": max(1, built_repeats // 2),
            "baseline_runs": repeats,
            "drake_runs": repeats,
        },
        "drake": (
            {"available": True, "import_s": drake_import}
            if drake is not None
            else {"available": False, "reason": drake_import}
        ),
        "models": {},
    }
    for name in names:
        model = gaitopt.model(name)
        entry: dict[str, Any] = {"params": model.params}
        log(f"[bench] {name}: first calls in fresh processes ({repeats}× each)")
        entry["first_call"] = {
            "verify_false": _first_call(name, False, repeats),
            "verify_true": _first_call(name, True, repeats),
        }
        log(f"[bench] {name}: once built ({built_repeats}×)")
        built_f, cycle = _once_built(model, False, built_repeats)
        built_t, cycle_t = _once_built(model, True, max(1, built_repeats // 2))
        entry["once_built"] = {"verify_false": built_f, "verify_true": built_t}
        entry["gaitopt"] = _cycle_record(cycle_t if cycle_t.success else cycle)
        log(f"[bench] {name}: hand-written baseline ({repeats}×)")
        try:
            entry["baseline"] = _baseline(model, repeats)
        except Exception as err:  # the baseline must never sink the benchmark
            entry["baseline"] = {"skipped": f"{type(err).__name__}: {err}"}
        if drake is not None:
            log(f"[bench] {name}: Drake")
            try:
                entry["drake"] = _drake(drake, model, repeats, converge)
            except Exception as err:
                entry["drake"] = {"skipped": f"{type(err).__name__}: {err}"}
        _compare(model, entry)
        record["models"][name] = entry
    record["goals"] = _goals(record)
    if speed:
        log("[bench] speed goals: whole processes (gaitopt and Drake), period-8 vs period-1")
        try:
            record["speed"] = _bench_speed.run(repeats=repeats, drake=drake is not None)
        except Exception as err:  # report, never sink the benchmark
            record["speed"] = {"skipped": f"{type(err).__name__}: {err}"}
        log("[bench] the optimiser's first call in fresh processes (five-link, compass gait)")
        try:
            record["first_call"] = _bench_first_call.run(repeats=min(repeats, 3))
        except Exception as err:  # report, never sink the benchmark
            record["first_call"] = {"skipped": f"{type(err).__name__}: {err}"}
        log("[bench] the simulation's backends: compiled arcs vs the Python loop, per model")
        try:
            simulated = None if every else ["compass_gait", "slip", "kneed_walker"]
            record["simulate"] = _bench_simulate.run(simulated, repeats=max(repeats, 3))
        except Exception as err:  # report, never sink the benchmark
            record["simulate"] = {"skipped": f"{type(err).__name__}: {err}"}
    if control:
        log(f"[bench] slip deadbeat decision: Python, generated C, simulation ({decisions}×)")
        try:
            record["control"] = _deadbeat_bench(decisions)
        except Exception as err:  # e.g. no C compiler: report, never sink the benchmark
            record["control"] = {"skipped": f"{type(err).__name__}: {err}"}
    if branches:
        log("[bench] continuation and sweeps: branch rate, slope study vs orbit diagram, workers")
        try:
            record["branches"] = _bench_branches.run(quick=quick)
        except Exception as err:  # report, never sink the benchmark
            record["branches"] = {"skipped": f"{type(err).__name__}: {err}"}
        log("[bench] two-parameter curves: compass-gait stability boundary vs the 30×30 grid")
        try:
            record["curves"] = _bench_curves.run(quick=quick)
        except Exception as err:  # report, never sink the benchmark
            record["curves"] = {"skipped": f"{type(err).__name__}: {err}"}
        log("[bench] optimal gaits: compass gait vs a Hermite–Simpson baseline, five-link biped")
        try:
            record["optimize"] = _bench_optimize.run(quick=quick)
        except Exception as err:  # report, never sink the benchmark
            record["optimize"] = {"skipped": f"{type(err).__name__}: {err}"}
    if basin:
        log("[bench] basin throughput: batch simulation vs the per-start loop (compass gait)")
        try:
            record["basin"] = _bench_basin.run(quick=quick, rounds=1 if quick else 3)
        except Exception as err:  # report, never sink the benchmark
            record["basin"] = {"skipped": f"{type(err).__name__}: {err}"}
    if install_compile:  # 5–10 min of CPU: only when asked; else the latest recorded run
        log("[bench] the kernel compile of make install from an empty cache")
        record["install_compile"] = _bench_install_compile.run()
    else:
        record["install_compile"] = _bench_install_compile.latest()
    record["goals_issue_12"] = _bench_speed.goals(record)
    log("[bench] issue 23's goals: whole processes vs the baseline's, sweep vs bare Dask")
    record["goals_issue_23_measured"] = _bench_goals.measure(
        record, repeats=repeats, sweep=branches
    )
    record["goals_issue_23"] = _bench_goals.rows(record)
    record["elapsed_s"] = time.perf_counter() - started
    return record


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bench",
        description="Time find_limit_cycle against a hand-written SciPy baseline and Drake.",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("results/bench.json"),
        help="JSON file to write (default: results/bench.json)",
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=3,
        help="fresh processes, baseline and Drake runs per model (default 3)",
    )
    parser.add_argument(
        "--built-repeats",
        type=int,
        default=20,
        help="calls once built, verify=False (half that with verify=True)",
    )
    parser.add_argument(
        "--models",
        nargs="+",
        metavar="NAME",
        help="the models of the per-model sections (default: "
        + ", ".join(DEFAULT_MODELS)
        + "; 'all': every registered model)",
    )
    parser.add_argument("--no-peers", action="store_true", help="skip Drake even if installed")
    parser.add_argument(
        "--no-control", action="store_true", help="skip the deadbeat-decision timing"
    )
    parser.add_argument(
        "--decisions",
        type=int,
        default=200,
        help="apex heights the deadbeat decision is timed from (default 200)",
    )
    parser.add_argument(
        "--no-branches", action="store_true", help="skip the continuation and sweep timings"
    )
    parser.add_argument(
        "--no-speed",
        action="store_true",
        help="skip the whole-process and period-k timings",
    )
    parser.add_argument(
        "--no-basin", action="store_true", help="skip the basin throughput (batch vs loop)"
    )
    parser.add_argument(
        "--install-compile",
        action="store_true",
        help="measure the kernel compile from an empty cache too (5-10 min; default: the "
        "latest results/bench_install_compile.json)",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="2 repeats, 5 calls once built, no Drake convergence runs",
    )
    args = parser.parse_args(argv)
    if args.repeats < 1 or args.built_repeats < 1:
        parser.error(
            f"--repeats and --built-repeats must be ≥ 1, got "
            f"{args.repeats} and {args.built_repeats}"
        )
    import gaitopt

    unknown = [n for n in args.models or [] if n not in gaitopt.REGISTRY and args.models != ["all"]]
    if unknown:
        parser.error(f"unknown model {unknown[0]!r}; available: {', '.join(gaitopt.REGISTRY)}")
    repeats, built = (2, 5) if args.quick else (args.repeats, args.built_repeats)
    record = run(
        repeats=repeats,
        built_repeats=built,
        models=args.models,
        peers=not args.no_peers,
        converge=not args.quick,
        control=not args.no_control,
        decisions=max(20, args.decisions // (4 if args.quick else 1)),
        branches=not args.no_branches,
        speed=not args.no_speed,
        basin=not args.no_basin,
        quick=args.quick,
        install_compile=args.install_compile,
    )
    record["table"] = rows(record)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json(record, args.out)
    print(format_table(record))
    print(f"Wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
