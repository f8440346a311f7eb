"""Timing :func:`gaitopt.find_limit_cycle` (first call in a fresh process, and once built) and the
hand-written SciPy baseline (:mod:`bench.baselines`) from the same start."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from typing import Any

from . import baselines
from .common import _complex_list, _median

__all__: list[str] = []


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
