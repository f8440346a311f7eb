"""``make bench``: how fast and how exact :func:`gaitopt.find_limit_cycle` is, against what users
write today.

For each registered model::

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
``--out``, atomically.  Sized for a 2-core machine: about a minute with the defaults, Drake
included (the first control run adds the C compilation, about 10 s).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from gaitopt.files import write_json

from . import baselines
from . import branches as _bench_branches
from . import curves as _bench_curves
from . import optimize as _bench_optimize
from . import speed as _bench_speed

__all__ = ["main", "run"]

# -- reference numbers (docs/design.md, "Reference numbers the tests meet") ---------------------
_VDP_PERIOD = 6.6632868593231301897  # Hairer, Nørsett & Wanner, μ = 1
_COMPASS = {  # docs/design.md; agrees with Drake's CompassGait simulated to convergence (7 digits)
    "stance": -0.2187746,
    "swing": 0.3237746,
    "stance_dot": 1.0928668,
    "swing_dot": 0.3761346,
}
_GARCIA = {"theta": 0.20031090049483, "theta_dot": -0.19983247291764}  # Garcia et al. 1998


def _reference(name: str, model: Any) -> tuple[str, Callable[[dict, float], float]] | None:
    """What to compare with for ``name``: (description, error of a fixed point and period)."""
    if name == "vanderpol" and model.params.get("mu") == 1.0:
        return "period vs Hairer et al. 6.66328685932313", lambda x, T: abs(T - _VDP_PERIOD)
    if name == "rimless_wheel":
        w = model.rolling_speed()
        return "theta_dot vs closed form ω*", lambda x, T: abs(x["theta_dot"] - w)
    if name == "compass_gait" and model.params == type(model)().params:
        return "state vs docs/design.md (7 digits)", lambda x, T: max(
            abs(x[k] - v) for k, v in _COMPASS.items()
        )
    if name == "simplest_walker" and model.params.get("slope") == 0.009:
        return "theta, theta_dot vs Garcia 1998", lambda x, T: max(
            abs(x[k] - v) for k, v in _GARCIA.items()
        )
    return None


# -- small helpers ------------------------------------------------------------------------------
def _median(values: list[float]) -> float:
    return float(statistics.median(values)) if values else math.nan


def _max_diff(a: dict[str, float], b: dict[str, float]) -> float:
    keys = [k for k in a if k in b]
    return max(abs(a[k] - b[k]) for k in keys) if keys else math.nan


def _complex_list(z: np.ndarray) -> list[list[float]]:
    return [[float(v.real), float(v.imag)] for v in np.asarray(z, complex)]


def _version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def _machine() -> dict[str, Any]:
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor() or None,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "versions": {d: _version(d) for d in ("gaitopt", "casadi", "scipy", "numpy", "drake")},
    }


# -- gaitopt ------------------------------------------------------------------------------------
_FIRST_CALL = """\
import json, time
t0 = time.perf_counter()
import gaitopt
t1 = time.perf_counter()
m = gaitopt.model({name!r})
t2 = time.perf_counter()
c = gaitopt.find_limit_cycle(m, verify={verify})
t3 = time.perf_counter()
print(json.dumps({{"import_s": t1 - t0, "model_s": t2 - t1, "call_s": t3 - t2,
                  "success": bool(c.success)}}))
"""


def _first_call(name: str, verify: bool, repeats: int) -> dict[str, Any]:
    """``model()`` + ``find_limit_cycle`` as the first call of a fresh process, ``repeats``×."""
    runs, errors = [], []
    code = _FIRST_CALL.format(name=name, verify=verify)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    for _ in range(repeats):
        t0 = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300
        )
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            errors.append(proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else "?")
            continue
        run = json.loads(proc.stdout.strip().splitlines()[-1])
        run["process_s"] = wall
        runs.append(run)
    out: dict[str, Any] = {"verify": verify, "repeats": repeats, "runs": runs}
    if errors:
        out["errors"] = errors
    if runs:
        out.update(
            median_s=_median([r["model_s"] + r["call_s"] for r in runs]),
            median_call_s=_median([r["call_s"] for r in runs]),
            median_import_s=_median([r["import_s"] for r in runs]),
            median_process_s=_median([r["process_s"] for r in runs]),
            success=all(r["success"] for r in runs),
        )
    return out


def _once_built(model: Any, verify: bool, repeats: int) -> tuple[dict[str, Any], Any]:
    """Median wall time of ``find_limit_cycle`` after the graphs are built (warm-up first)."""
    import gaitopt

    cycle = gaitopt.find_limit_cycle(model, verify=verify)  # warm-up
    times, solve_times = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        cycle = gaitopt.find_limit_cycle(model, verify=verify)
        times.append(time.perf_counter() - t0)
        solve_times.append(cycle.solve_time)
    return {
        "verify": verify,
        "repeats": repeats,
        "median_s": _median(times),
        "min_s": float(min(times)),
        "median_solve_time_s": _median(solve_times),
        "success": bool(cycle.success),
    }, cycle


def _cycle_record(cycle: Any) -> dict[str, Any]:
    return {
        "success": bool(cycle.success),
        "message": cycle.message,
        "period": float(cycle.period),
        "fixed_point": {k: float(v) for k, v in cycle.fixed_point.items()},
        "multipliers": _complex_list(cycle.multipliers),
        "residual": float(cycle.residual),
        "verified": bool(cycle.verified),
        "verification_error": float(cycle.verification_error),
    }


# -- the hand-written baseline ----------------------------------------------------------------
def _baseline(model: Any, repeats: int) -> dict[str, Any]:
    hw = baselines.baseline(model.name, model.params)
    if hw is None:
        return {"skipped": f"no hand-written baseline for {model.name!r}"}
    start = model.section_vector({})
    runs = [baselines.solve(hw, start) for _ in range(repeats)]
    last = runs[-1]
    return {
        "method": (
            f"solve_ivp({baselines.METHOD}, rtol={baselines.RTOL:g}, atol={baselines.ATOL:g}) "
            f"with a terminal directional event; fsolve(xtol={baselines.XTOL:g}) on P(s) - s; "
            f"multipliers: eigvals of central differences (step {baselines.FD_STEP:g})"
        ),
        "start": dict(zip(model.section.coordinates, map(float, start), strict=True)),
        "repeats": repeats,
        "median_s": _median([r.solve_time for r in runs]),
        "min_s": float(min(r.solve_time for r in runs)),
        "success": bool(last.success),
        "message": last.message,
        "map_evaluations": last.map_evaluations,
        "period": float(last.period),
        "fixed_point": last.fixed_point,
        "multipliers": _complex_list(last.multipliers),
    }


# -- Drake -------------------------------------------------------------------------------------
def _import_drake() -> tuple[Any, float] | tuple[None, str]:
    t0 = time.perf_counter()
    try:
        import pydrake.examples as examples
        import pydrake.systems.analysis as analysis
        import pydrake.systems.framework as framework
    except Exception as err:  # ImportError, or a broken binary wheel
        return None, f"{type(err).__name__}: {err}"
    return (examples, analysis, framework), time.perf_counter() - t0


def _drake_system(drake: Any, model: Any) -> tuple[Any, Callable, Callable, list[str]] | None:
    """Drake's system for ``model``, its parameters vector, a witness near 0 at the impact, and a
    marker that changes at each forward impact."""
    examples = drake[0]
    p = model.params
    if model.name == "compass_gait":
        system = examples.CompassGait()
        params = examples.CompassGaitParams()
        params.set_mass_hip(p["mass_hip"])
        params.set_mass_leg(p["mass_leg"])
        params.set_length_leg(p["a"] + p["b"])
        params.set_center_of_mass_leg(p["b"])  # Drake: "distance from the hip"
        params.set_gravity(p["gravity"])
        params.set_slope(p["slope"])
        gamma = p["slope"]

        def witness(x):  # Drake's foot-collision witness
            return max(2 * gamma - x[0] - x[1], x[1] - x[0])

        def marker(ctx):  # the left-support indicator flips at each heel strike
            return bool(ctx.get_abstract_state(0).get_value())

        return system, params, witness, marker
    if model.name == "rimless_wheel":
        system = examples.RimlessWheel()
        params = examples.RimlessWheelParams()
        params.set_length(p["length"])
        params.set_gravity(p["gravity"])
        params.set_number_of_spokes(p["spokes"])
        params.set_slope(p["slope"])
        edge = p["slope"] + math.pi / p["spokes"]

        def witness(x):  # StepForwardGuard: θ = slope + α
            return x[0] - edge

        def marker(ctx):  # the stance toe moves down the ramp at each forward step
            return float(ctx.get_discrete_state(0).GetAtIndex(0))

        return system, params, witness, marker
    return None


def _drake_simulator(drake: Any, model: Any, x0: np.ndarray, accuracy: float) -> tuple:
    """Drake's system and a simulator at ``x0``, parameters from ``model``, the given accuracy."""
    system, params, witness, marker = _drake_system(drake, model)
    simulator = drake[1].Simulator(system)
    ctx = simulator.get_mutable_context()
    ctx.get_mutable_numeric_parameter(0).SetFromVector(params.get_value())
    ctx.SetAccuracy(accuracy)  # witness isolation needs it (AdvanceTo raises without)
    simulator.get_mutable_integrator().set_target_accuracy(accuracy)
    ctx.SetContinuousState(x0)
    return system, simulator, ctx, witness, marker


def _drake_settle(
    drake: Any, model: Any, x0: np.ndarray, accuracy: float, tol: float, max_steps: int
) -> dict[str, Any]:
    """Simulate Drake's model from ``x0`` until consecutive post-impact states differ by less
    than ``tol`` (max-norm) or ``max_steps`` impacts; time it all (system, simulator, run).

    The simulator's monitor stops ``AdvanceTo`` when a step ends on the impact witness (the
    state then is x⁻ at the isolated witness time); ``AdvancePendingEvents`` applies Drake's
    reset, and the state is read when the impact marker has changed.
    """
    framework = drake[2]
    t0 = time.perf_counter()
    system, simulator, ctx, witness, marker = _drake_simulator(drake, model, x0, accuracy)

    def monitor(c):
        x = c.get_continuous_state_vector().CopyToVector()
        if abs(witness(x)) < 1e-3:
            return framework.EventStatus.ReachedTermination(system, "at the impact witness")
        return framework.EventStatus.Succeeded()

    simulator.set_monitor(monitor)
    simulator.Initialize()
    horizon = 1e4
    posts: list[np.ndarray] = []
    delta = math.inf
    for _ in range(100 * max_steps):  # guard against a monitor that never stops
        if len(posts) >= max_steps or delta < tol:
            break
        simulator.AdvanceTo(horizon)
        if ctx.get_time() >= horizon:
            break
        before = marker(ctx)
        simulator.AdvancePendingEvents()
        if marker(ctx) != before:
            posts.append(ctx.get_continuous_state_vector().CopyToVector())
            if len(posts) > 1:
                delta = float(np.max(np.abs(posts[-1] - posts[-2])))
    elapsed = time.perf_counter() - t0
    names = model.state_names
    return {
        "time_s": elapsed,
        "steps": len(posts),
        "settled": bool(delta < tol),
        "last_change": delta,
        "simulated_time": float(ctx.get_time()),
        "integrator_steps": int(simulator.get_num_steps_taken()),
        "fixed_point": dict(zip(names, map(float, posts[-1]), strict=True)) if posts else {},
    }


def _drake_plain(drake: Any, model: Any, x0: np.ndarray, accuracy: float, t_end: float) -> float:
    """Seconds to build and simulate Drake's model from ``x0`` to ``t_end``, with no monitor."""
    t0 = time.perf_counter()
    _, simulator, _, _, _ = _drake_simulator(drake, model, x0, accuracy)
    simulator.Initialize()
    simulator.AdvanceTo(t_end)
    return time.perf_counter() - t0


def _drake(drake: Any, model: Any, repeats: int, converge: bool) -> dict[str, Any]:
    """Drake's settle-by-simulation runs for ``model`` (see the module docstring)."""
    if _drake_system(drake, model) is None:
        return {"skipped": f"no Drake peer for {model.name!r}"}
    x0 = model.lift(model.section_vector({}))
    out: dict[str, Any] = {
        "start": dict(zip(model.state_names, map(float, x0), strict=True)),
        "runs": {},
    }
    plans = [("settle, accuracy 1e-4 (default)", 1e-4, 1e-5, 200, repeats)]
    plans.append(("settle to 1e-08, accuracy 1e-4 (default)", 1e-4, 1e-8, 200, repeats))
    plans.append(("settle, accuracy 1e-10", 1e-10, 1e-5, 200, max(1, min(repeats, 3))))
    if converge:
        plans.append(("converge, accuracy 1e-4 (default)", 1e-4, 1e-10, 100, 1))
        plans.append(("converge, accuracy 1e-10", 1e-10, 1e-10, 100, 1))
    for label, accuracy, tol, max_steps, n in plans:
        runs = [_drake_settle(drake, model, x0, accuracy, tol, max_steps) for _ in range(n)]
        record = dict(runs[-1])
        record.pop("time_s")
        plain = [
            _drake_plain(drake, model, x0, accuracy, record["simulated_time"]) for _ in range(n)
        ]
        record.update(
            accuracy=accuracy,
            tolerance=tol,
            max_steps=max_steps,
            repeats=n,
            median_s=_median(plain),
            min_s=float(min(plain)),
            median_s_with_monitor=_median([r["time_s"] for r in runs]),
        )
        out["runs"][label] = record
    return out


# -- the run ----------------------------------------------------------------------------------
def run(
    *,
    repeats: int = 5,
    built_repeats: int = 20,
    models: list[str] | None = None,
    peers: bool = True,
    converge: bool = True,
    control: bool = True,
    decisions: int = 200,
    branches: bool = True,
    speed: bool = True,
    quick: bool = False,
    log: Callable[[str], None] = lambda s: print(s, file=sys.stderr, flush=True),
) -> dict[str, Any]:
    """Measure everything; the JSON-ready record (see the module docstring)."""
    import gaitopt

    started = time.perf_counter()
    names = list(gaitopt.REGISTRY) if models is None else models
    drake, drake_import = _import_drake() if peers else (None, "disabled (--no-peers)")
    record: dict[str, Any] = {
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
        log("[bench] issue 12: whole processes (gaitopt and Drake), period-8 vs period-1")
        try:
            record["speed"] = _bench_speed.run(repeats=repeats, drake=drake is not None)
        except Exception as err:  # report, never sink the benchmark
            record["speed"] = {"skipped": f"{type(err).__name__}: {err}"}
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
    record["goals_issue_12"] = _bench_speed.goals(record)
    record["elapsed_s"] = time.perf_counter() - started
    return record


# -- step-to-step control: one deadbeat decision ------------------------------------------------
_C_DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "deadbeat_policy.h"
static double now(void) {
  struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + 1e-9 * t.tv_nsec;
}
static int by_value(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b; return (x > y) - (x < y);
}
/* argv: N_P parameters, the target, then the states (one section coordinate each). */
int main(int argc, char** argv) {
  casadi_int n_arg, n_res, n_iw, n_w;
  deadbeat_policy_work(&n_arg, &n_res, &n_iw, &n_w);
  const casadi_real** arg = malloc(sizeof(*arg) * n_arg);
  casadi_real** res = malloc(sizeof(*res) * n_res);
  casadi_int* iw = malloc(sizeof(*iw) * (n_iw + 1));
  casadi_real* w = malloc(sizeof(*w) * (n_w + 1));
  double p[N_P], target[1], s[1], u[1], T[N_T], r[1];
  for (int i = 0; i < N_P; i++) p[i] = atof(argv[1 + i]);
  target[0] = atof(argv[1 + N_P]);
  int n = argc - 2 - N_P, repeats = REPEATS;
  double* dt = malloc(sizeof(double) * n * repeats);
  arg[0] = s; arg[1] = target; arg[2] = p; res[0] = u; res[1] = T; res[2] = r;
  printf("{\"u\": [");
  for (int k = 0; k < n; k++) {
    s[0] = atof(argv[2 + N_P + k]);
    for (int j = 0; j < repeats; j++) {
      double t0 = now();
      deadbeat_policy(arg, res, iw, w, 0);
      dt[k * repeats + j] = now() - t0;
    }
    printf("%s%.17g", k ? ", " : "", u[0]);
  }
  qsort(dt, (size_t)(n * repeats), sizeof(double), by_value);
  printf("], \"median_s\": %.9g, \"min_s\": %.9g, \"calls\": %d}\n",
         dt[n * repeats / 2], dt[0], n * repeats);
  return 0;
}
"""


def _deadbeat_bench(decisions: int) -> dict[str, Any]:
    """Time one deadbeat decision of the SLIP (see the module docstring)."""
    import casadi as ca
    from scipy.optimize import brentq

    import gaitopt
    from gaitopt.control import deadbeat
    from gaitopt.returnmap import return_map

    slip = gaitopt.model("slip")
    controller = deadbeat(slip)
    solver = controller.deadbeat_solver
    z_star = float(controller.target[0])
    rng = np.random.default_rng(0)
    # Apex heights from 5 mm below to 3 cm above the gait (inside the feasible range, above the
    # touchdown height): the disturbances a running controller sees.
    states = z_star + rng.uniform(-0.005, 0.03, decisions)
    out: dict[str, Any] = {
        "model": "slip",
        "params": slip.params,
        "target_z": z_star,
        "states": {"low": float(states.min()), "high": float(states.max()), "count": decisions},
    }

    controller.decide([states[0]])  # warm-up (builds the rootfinder)
    times, inputs = [], []
    for z in states:
        t0 = time.perf_counter()
        decision = controller.decide([z])
        times.append(time.perf_counter() - t0)
        inputs.append(float(decision.input[0]))
    out["python"] = {
        "method": "StepController.decide: CasADi newton rootfinder on the multiple-shooting "
        "equations (+ validity checks)",
        "median_s": _median(times),
        "min_s": float(min(times)),
    }

    t0 = time.perf_counter()
    generated = solver.codegen()
    build_s = time.perf_counter() - t0
    policy = generated.function
    external = []
    c_inputs = []
    for z in states:
        t0 = time.perf_counter()
        u, _, _ = policy([z], [z_star], slip.p)
        external.append(time.perf_counter() - t0)
        c_inputs.append(float(u))
    folder = generated.library.parent
    driver = folder / "driver"
    if not driver.exists():
        n_t = int(policy.size1_out(1))
        source = folder / "driver.c"
        source.write_text(_C_DRIVER)
        compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc") or "cc"
        subprocess.run(
            [compiler, "-O2", f"-DN_P={slip.p.size}", f"-DN_T={n_t}", "-DREPEATS=5",
             f"-I{folder}", str(source), str(generated.library), f"-Wl,-rpath,{folder}",
             "-o", str(driver), "-lm"],
            check=True, capture_output=True, text=True,
        )  # fmt: skip
    argv = [str(driver), *(repr(float(v)) for v in slip.p), repr(z_star)]
    proc = subprocess.run(
        argv + [repr(float(z)) for z in states], capture_output=True, text=True, check=True
    )
    in_c = json.loads(proc.stdout)
    agreement = float(np.max(np.abs(np.array(in_c["u"]) - np.array(inputs))))
    out["generated_c"] = {
        "method": "Deadbeat.codegen: CasADi Function.generate of a single-shooting fast_newton "
        "policy, compiled -O3 -shared; timed by a C driver (clock_gettime per call)",
        "source": str(generated.source),
        "source_bytes": generated.source.stat().st_size,
        "generate_and_compile_s": build_s,
        "median_s": in_c["median_s"],
        "min_s": in_c["min_s"],
        "calls": in_c["calls"],
        "median_s_via_casadi_external": _median(external),
        "max_abs_difference_vs_python_rad": agreement,
        "max_abs_difference_external_vs_python_rad": float(
            np.max(np.abs(np.array(c_inputs) - np.array(inputs)))
        ),
        "casadi": ca.__version__,
    }

    theta = float(controller.nominal_input[0])
    map_times = []
    for z in states[: max(10, decisions // 10)]:
        t0 = time.perf_counter()
        return_map(slip, float(z), inputs=[theta])
        map_times.append(time.perf_counter() - t0)
    brent_times, brent_errors, evaluations = [], [], []
    for z, u_ref in list(zip(states, inputs, strict=True))[: max(5, decisions // 20)]:
        count = [0]

        def defect(th: float, z: float = float(z), count: list = count) -> float:
            count[0] += 1
            return float(return_map(slip, z, inputs=[th])[0]) - z_star

        t0 = time.perf_counter()
        width = 0.04  # bracket around the answer, shrunk where the map is undefined at an end
        while not np.isfinite(defect(u_ref - width) * defect(u_ref + width)):
            width /= 2
        root = brentq(defect, u_ref - width, u_ref + width, xtol=1e-12)
        brent_times.append(time.perf_counter() - t0)
        brent_errors.append(abs(root - u_ref))
        evaluations.append(count[0])
    out["simulation"] = {
        "method": "apex map by event-located SciPy simulation (DOP853, rtol 1e-11), as in the "
        "textbook notebook; decision: brentq on it (bracket ±0.04 rad about the answer, halved "
        "while the map is undefined at an end; xtol 1e-12)",
        "map_evaluation_median_s": _median(map_times),
        "decision_median_s": _median(brent_times),
        "decision_map_evaluations_median": _median(evaluations),
        "decision_max_abs_difference_vs_python_rad": float(max(brent_errors)),
    }
    out["goal_decision_at_most_50us"] = bool(in_c["median_s"] <= 50e-6)
    return out


def _control_lines(c: dict[str, Any]) -> list[str]:
    """The control section of the printed report."""
    if "skipped" in c:
        return ["", f"Deadbeat decision (slip): skipped — {c['skipped']}"]
    py, gen, sim = c["python"], c["generated_c"], c["simulation"]

    def us(s: float) -> str:
        return f"{1e6 * s:.3g} µs" if s < 1e-3 else f"{1e3 * s:.3g} ms"

    verdict = "met" if c["goal_decision_at_most_50us"] else "NOT met"
    return [
        "",
        f"Deadbeat decision, slip touchdown angle (apex z in [{c['states']['low']:.4f}, "
        f"{c['states']['high']:.4f}] m → z* = {c['target_z']:.6f} m, {c['states']['count']} "
        f"apex heights):",
        f"  Python (CasADi rootfinder, multiple shooting)   median {us(py['median_s'])}",
        f"  generated C (fast_newton, in a C driver)        median {us(gen['median_s'])} "
        f"(via casadi.external from Python {us(gen['median_s_via_casadi_external'])}); "
        f"|Δθ| vs Python {_sci(gen['max_abs_difference_vs_python_rad'])} rad; generate + "
        f"compile {gen['generate_and_compile_s']:.1f} s (cached for later runs)",
        f"  apex map by simulation (SciPy, one evaluation)  median "
        f"{us(sim['map_evaluation_median_s'])}; deadbeat by brentq on it "
        f"{us(sim['decision_median_s'])} ({sim['decision_map_evaluations_median']:.0f} "
        f"evaluations)",
        f"  goal: a decision ≤ 50 µs from the generated code — {verdict}",
    ]


def _compare(model: Any, entry: dict[str, Any]) -> None:
    """Add errors vs gaitopt's fixed point and vs the reference numbers, in place."""
    ref = _reference(model.name, model)
    entry["reference"] = ref[0] if ref else None
    gx, gT = entry["gaitopt"]["fixed_point"], entry["gaitopt"]["period"]
    entry["gaitopt"]["error_vs_reference"] = ref[1](gx, gT) if ref and gx else None
    targets = []
    if "fixed_point" in entry.get("baseline", {}):
        targets.append((entry["baseline"], entry["baseline"]["period"]))
    for run_ in entry.get("drake", {}).get("runs", {}).values():
        targets.append((run_, math.nan))
    for target, period in targets:
        x = target["fixed_point"]
        target["error_vs_gaitopt"] = _max_diff(x, gx) if x and gx else None
        err = None
        if ref and x:
            err = ref[1](x, period)
            err = None if math.isnan(err) else err
        target["error_vs_reference"] = err


def _goals(record: dict[str, Any]) -> dict[str, Any]:
    """The issue's goals for the compass gait, with the measured numbers."""
    cg = record["models"].get("compass_gait")
    if cg is None:
        return {}
    built = cg["once_built"]["verify_false"]["median_s"]
    goals: dict[str, Any] = {
        "cycle_with_multipliers_once_built_s": built,
        "at_most_2ms": built <= 2e-3,
    }
    runs = cg.get("drake", {}).get("runs", {})
    settle = runs.get("settle, accuracy 1e-4 (default)")
    if settle:
        goals["drake_default_settle_s"] = settle["median_s"]
        goals["drake_default_settle_with_monitor_s"] = settle["median_s_with_monitor"]
        goals["speedup_vs_drake_default_settle"] = settle["median_s"] / built
        goals["at_least_20x_vs_drake"] = settle["median_s"] / built >= 20
        goals["drake_default_settled_error"] = settle["error_vs_gaitopt"]
    conv = runs.get("converge, accuracy 1e-10")
    if conv:
        goals["error_vs_drake_converged_1e-10"] = conv["error_vs_gaitopt"]
    conv_default = runs.get("converge, accuracy 1e-4 (default)")
    if conv_default:
        goals["drake_default_error_floor"] = conv_default["error_vs_gaitopt"]
    if "error_vs_gaitopt" in cg.get("baseline", {}):
        goals["error_vs_baseline"] = cg["baseline"]["error_vs_gaitopt"]
    if conv:
        goals["exact_to_1e-10"] = conv["error_vs_gaitopt"] <= 1e-10
    return goals


# -- the table ------------------------------------------------------------------------------------
def _ms(s: float | None) -> str:
    return (
        "—"
        if s is None or not math.isfinite(s)
        else f"{1e3 * s:.3g}"
        if s < 1
        else f"{1e3 * s:.0f}"
    )


def _sci(e: float | None) -> str:
    return "—" if e is None or not math.isfinite(e) else f"{e:.1e}"


def _mults(z: list[list[float]] | None) -> str:
    if not z:
        return "—"
    parts, seen = [], set()
    for re_, im in z:
        if im < 0 and (re_, -im) in seen:
            continue
        seen.add((re_, im))
        parts.append(f"{re_:.4g}±{abs(im):.4g}i" if abs(im) > 1e-12 else f"{re_:.4g}")
    return ", ".join(parts)


def rows(record: dict[str, Any]) -> list[list[str]]:
    """The table: model | method | first call | once built | × vs baseline | errors | mults."""
    out = []
    for name, e in record["models"].items():
        base = e.get("baseline", {}).get("median_s")

        def speed(t: float | None, base: float | None = base) -> str:
            if base is None or t is None or not t > 0:
                return "—"
            return f"{base / t:.3g}×"

        for key, label in (
            ("verify_false", "gaitopt verify=False"),
            ("verify_true", "gaitopt verify=True"),
        ):
            first, built = e["first_call"][key], e["once_built"][key]
            out.append(
                [
                    name,
                    label,
                    _ms(first.get("median_s")),
                    _ms(built["median_s"]),
                    speed(built["median_s"]),
                    "(ref)",
                    _sci(e["gaitopt"].get("error_vs_reference")),
                    _mults(e["gaitopt"]["multipliers"]) if key == "verify_false" else "",
                ]
            )
        b = e.get("baseline", {})
        if "skipped" in b:
            out.append([name, "hand-written baseline", "—", "—", "—", "—", "—", b["skipped"]])
        elif b:
            out.append(
                [
                    name,
                    "solve_ivp + fsolve (by hand)",
                    "—",
                    _ms(b["median_s"]),
                    "1×",
                    _sci(b.get("error_vs_gaitopt")),
                    _sci(b.get("error_vs_reference")),
                    _mults(b["multipliers"]),
                ]
            )
        for label, r in e.get("drake", {}).get("runs", {}).items():
            unmet = ", not converged" if label.startswith("converge") else ", not settled"
            note = f"{r['steps']} steps" + ("" if r["settled"] else unmet)
            out.append(
                [
                    name,
                    f"Drake {label}, {note}",
                    "—",
                    _ms(r["median_s"]),
                    speed(r["median_s"]),
                    _sci(r.get("error_vs_gaitopt")),
                    _sci(r.get("error_vs_reference")),
                    "—",
                ]
            )
    return out


_HEAD = [
    "model",
    "method",
    "first call ms",
    "once built ms",
    "× vs baseline",
    "|Δx| vs gaitopt",
    "err vs reference",
    "multipliers",
]


def format_table(record: dict[str, Any]) -> str:
    """The printed report: table, legend and the compass-gait goals."""
    table = [_HEAD, *rows(record)]
    widths = [max(len(r[i]) for r in table) for i in range(len(_HEAD))]
    lines = []
    for i, r in enumerate(table):
        lines.append("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip())
        if i == 0:
            lines.append("  ".join("-" * w for w in widths))
    m = record["machine"]
    rep = record["repeats"]
    imports = [
        run_["import_s"]
        for e in record["models"].values()
        for first in e["first_call"].values()
        for run_ in first["runs"]
    ]
    lines += [
        "",
        f"Machine: {m['platform']}, {m['cpu_count']} CPUs, Python {m['python']}; "
        + ", ".join(f"{k} {v}" for k, v in m["versions"].items() if v),
        f"first call: gaitopt.model() + find_limit_cycle() in a fresh process, median of "
        f"{rep['first_call_processes']} (`import gaitopt` excluded: median "
        f"{_ms(_median(imports))} ms); once built: median of "
        f"{rep['once_built_calls']} calls (verify=False: cycle + multipliers) and "
        f"{rep['once_built_calls_verify']} (verify=True: + SciPy simulation check).",
        f"× vs baseline = baseline time / row time. Baseline and Drake: median of "
        f"{rep['baseline_runs']} runs (Drake at accuracy 1e-10: up to 3; 'converge': 1).",
        "Drake: fresh System + Simulator simulated, with no monitor, from the start to the "
        "time the gait was seen to settle (consecutive post-impact states within 1e-5; "
        "'converge': 1e-10 or 100 steps); the run that watches it (a Python monitor per "
        "integrator step) is slower: JSON `median_s_with_monitor`.",
        "|Δx| = max-norm difference of the post-impact (section) state from gaitopt's; "
        "err vs reference: "
        + "; ".join(
            f"{n}: {e['reference']}" for n, e in record["models"].items() if e.get("reference")
        ),
    ]
    if record["drake"]["available"]:
        lines.append(f"pydrake import: {_ms(record['drake']['import_s'])} ms (not in the times).")
    else:
        lines.append(f"Drake peers skipped: {record['drake']['reason']}")
    g = record.get("goals") or {}
    if g:

        def verdict(ok: bool | None) -> str:
            return "n/a" if ok is None else ("met" if ok else "NOT met")

        lines += [
            "",
            "Compass-gait goals (issue 2, item 11):",
            f"  cycle with multipliers once built ≤ 2 ms: "
            f"{_ms(g['cycle_with_multipliers_once_built_s'])} ms — {verdict(g['at_most_2ms'])}",
        ]
        if "speedup_vs_drake_default_settle" in g:
            lines.append(
                f"  ≥ 20× faster than Drake's settle-by-simulation (default accuracy, "
                f"{_ms(g['drake_default_settle_s'])} ms; "
                f"{_ms(g['drake_default_settle_with_monitor_s'])} ms watched by a monitor): "
                f"{g['speedup_vs_drake_default_settle']:.3g}× — "
                f"{verdict(g['at_least_20x_vs_drake'])}"
            )
        if "exact_to_1e-10" in g:
            lines.append(
                f"  exact to 1e-10: |Δx| vs Drake converged at accuracy 1e-10 "
                f"{_sci(g['error_vs_drake_converged_1e-10'])}, vs the hand-written baseline "
                f"{_sci(g.get('error_vs_baseline'))}; Drake at default accuracy leaves "
                f"{_sci(g.get('drake_default_settled_error'))} when settled, "
                f"{_sci(g.get('drake_default_error_floor'))} run to convergence — "
                f"{verdict(g['exact_to_1e-10'])}"
            )
    if "control" in record:
        lines += _control_lines(record["control"])
    if "branches" in record:
        b = record["branches"]
        lines += ["", _bench_branches.table(b) if "skipped" not in b else f"branches: {b}"]
    if "curves" in record:
        c = record["curves"]
        lines += ["", _bench_curves.table(c) if "skipped" not in c else f"curves: {c}"]
    if "optimize" in record:
        o = record["optimize"]
        lines += ["", _bench_optimize.table(o) if "skipped" not in o else f"optimize: {o}"]
    if "speed" in record and "skipped" in record["speed"]:
        lines += ["", f"speed: {record['speed']}"]
    lines += ["", _bench_speed.table(record)]
    lines.append(f"Total benchmark time: {record['elapsed_s']:.0f} s.")
    return "\n".join(lines)


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
        default=5,
        help="fresh processes, baseline and Drake runs per model (default 5)",
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
        help="only these models (default: every registered model)",
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
        help="skip issue 12's whole-process and period-k timings",
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

    unknown = [n for n in args.models or [] if n not in gaitopt.REGISTRY]
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
        quick=args.quick,
    )
    record["table"] = rows(record)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json(record, args.out)
    print(format_table(record))
    print(f"Wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
