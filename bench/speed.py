"""The speed goals, each against its baseline measured in the same run.

* **whole process** — ``gaitopt solve compass_gait --json`` as a fresh process (kernel cache
  warm), median of ``repeats``; against Drake's whole process where ``pydrake`` imports: a fresh
  ``python -c`` that imports pydrake, builds ``CompassGait`` and simulates it from the same start
  until consecutive post-impact states agree to 1e-8 (default accuracy 1e-4);
* **period-k** — the compass gait at slope 0.09 (past its period-doubling cascade): a verified
  solve of the period-8 gait against the period-1 gait at the same slope, each from its own fixed
  point's section coordinates (a ``steps``-return simulation guess, then Newton), median of
  ``repeats``.  The period-8 fixed point is found once, untimed, from a state that a long
  simulation settles to.

The verified warm solves of every model (and Drake's in-process settle time) are measured by
:mod:`bench.run`; :func:`goals` combines them with these into the issue's ratios.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import time
from typing import Any

import numpy as np

__all__ = ["run", "goals", "table"]

_SLOPE = 0.09  # past the compass gait's cascade (first PD near 0.0634)
_SETTLE = 1e-8  # Drake: consecutive post-impact states within this (max-norm)

_DRAKE_PROCESS = """\
import math
import numpy as np
from pydrake.examples import CompassGait, CompassGaitParams
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import EventStatus
p = {params!r}
system = CompassGait()
params = CompassGaitParams()
params.set_mass_hip(p["mass_hip"]); params.set_mass_leg(p["mass_leg"])
params.set_length_leg(p["a"] + p["b"]); params.set_center_of_mass_leg(p["b"])
params.set_gravity(p["gravity"]); params.set_slope(p["slope"])
gamma = p["slope"]
simulator = Simulator(system)
ctx = simulator.get_mutable_context()
ctx.get_mutable_numeric_parameter(0).SetFromVector(params.get_value())
ctx.SetAccuracy(1e-4)
simulator.get_mutable_integrator().set_target_accuracy(1e-4)
ctx.SetContinuousState({x0!r})
def monitor(c):
    x = c.get_continuous_state_vector().CopyToVector()
    if abs(max(2 * gamma - x[0] - x[1], x[1] - x[0])) < 1e-3:
        return EventStatus.ReachedTermination(system, "impact")
    return EventStatus.Succeeded()
simulator.set_monitor(monitor)
simulator.Initialize()
posts, delta = [], math.inf
for _ in range(20000):
    if len(posts) >= 400 or delta < {tol!r}:
        break
    simulator.AdvanceTo(1e4)
    before = bool(ctx.get_abstract_state(0).get_value())
    simulator.AdvancePendingEvents()
    if bool(ctx.get_abstract_state(0).get_value()) != before:
        posts.append(ctx.get_continuous_state_vector().CopyToVector())
        if len(posts) > 1:
            delta = float(np.max(np.abs(posts[-1] - posts[-2])))
print(len(posts), delta)
"""


def _median(values: list[float]) -> float:
    return float(statistics.median(values)) if values else math.nan


def _process(argv: list[str], repeats: int) -> dict[str, Any]:
    """Median wall time of ``argv`` run as a fresh process ``repeats`` times (after one run
    that is not counted, so that file caches are warm for every process alike)."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    times, codes, last = [], [], ""
    for i in range(repeats + 1):
        t0 = time.perf_counter()
        proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=600)
        if i:
            times.append(time.perf_counter() - t0)
            codes.append(proc.returncode)
        last = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else proc.stderr[-300:]
    return {"median_s": _median(times), "min_s": float(min(times)), "exit_codes": codes,
            "last_line": last[:300]}  # fmt: skip


def _whole_process(repeats: int, drake: bool) -> dict[str, Any]:
    import gaitopt

    gaitopt_cli = [os.path.join(os.path.dirname(sys.executable), "gaitopt")]
    out: dict[str, Any] = {
        "gaitopt": {
            "command": "gaitopt solve compass_gait --json",
            **_process([*gaitopt_cli, "solve", "compass_gait", "--json"], repeats),
        }
    }
    out["python_startup"] = _process([sys.executable, "-c", "pass"], repeats)
    out["import_gaitopt"] = _process([sys.executable, "-c", "import gaitopt"], repeats)
    if drake:
        m = gaitopt.model("compass_gait")
        x0 = [float(v) for v in m.lift(m.section_vector({}))]
        code = _DRAKE_PROCESS.format(params=dict(m.params), x0=x0, tol=_SETTLE)
        out["drake"] = {
            "command": f"python -c <import pydrake, CompassGait settled to {_SETTLE:g}>",
            **_process([sys.executable, "-c", code], repeats),
        }
    return out


def _period_k(repeats: int) -> dict[str, Any]:
    """Verified solves of the period-1 and period-8 compass gaits at slope 0.09."""
    import gaitopt

    model = gaitopt.model("compass_gait", slope=_SLOPE)
    names = model.section.coordinates
    # A state the gait settles to (the stable period-8 orbit), untimed: simulated from near the
    # (unstable) period-1 gait, found by following the default gait to this slope.
    cycle1 = gaitopt.find_limit_cycle(model)
    x1 = model.lift(np.array([cycle1.fixed_point[c] for c in names]))
    sim = gaitopt.simulate(model, x1 + 1e-4, steps=400)
    for state in sim.section_states[::-1][:16]:  # the last returns, until one converges
        settled = dict(zip(model.state_names, state, strict=True))
        guess8 = {c: float(settled[c]) for c in names}
        cycle8 = gaitopt.find_limit_cycle(model, guess8, steps=8, follow=False)
        if cycle8.success:
            break
    out: dict[str, Any] = {"slope": _SLOPE}
    for label, k, cycle in (("period_1", 1, cycle1), ("period_8", 8, cycle8)):
        if not cycle.success:
            out[label] = {"success": False, "message": cycle.message}
            continue
        start = {c: float(v) for c, v in cycle.fixed_point.items() if c in names}
        times = []
        for _ in range(repeats + 1):
            t0 = time.perf_counter()
            c = gaitopt.find_limit_cycle(model, start, steps=k, follow=False)
            times.append(time.perf_counter() - t0)
        out[label] = {
            "success": bool(c.success),
            "verified": bool(c.verified),
            "period": float(c.period),
            "max_abs_multiplier": float(np.max(np.abs(c.multipliers))),
            "median_s": _median(times[1:]),
        }
    ok = all(out[k].get("success") for k in ("period_1", "period_8"))
    out["ratio"] = out["period_8"]["median_s"] / out["period_1"]["median_s"] if ok else None
    return out


def run(repeats: int = 5, drake: bool = False) -> dict[str, Any]:
    """Whole processes and period-k (see the module docstring)."""
    return {"whole_process": _whole_process(repeats, drake), "period_k": _period_k(repeats)}


def goals(record: dict[str, Any]) -> dict[str, Any]:
    """Issue 12's goals as ratios of numbers measured in this run (``None`` where a number is
    missing, e.g. Drake not installed)."""
    models = record["models"]
    out: dict[str, Any] = {}

    def warm(name: str) -> float | None:
        e = models.get(name)
        return e["once_built"]["verify_true"]["median_s"] if e else None

    cg = warm("compass_gait")
    drake_runs = models.get("compass_gait", {}).get("drake", {}).get("runs", {})
    settle = drake_runs.get(f"settle to {_SETTLE:g}, accuracy 1e-4 (default)")
    if cg is not None:
        out["compass_verified_warm_s"] = cg
        if settle:
            out["drake_settle_s"] = settle["median_s"]
            out["compass_speedup_vs_drake"] = settle["median_s"] / cg
            out["compass_at_least_20x_drake"] = settle["median_s"] / cg >= 20
    kw = warm("kneed_walker")
    if kw is not None:
        out["kneed_verified_warm_s"] = kw
        out["kneed_at_most_5ms"] = kw <= 5e-3
    speed = record.get("speed", {})
    wp = speed.get("whole_process", {})
    if "drake" in wp:
        ratio = wp["gaitopt"]["median_s"] / wp["drake"]["median_s"]
        out["whole_process_ratio_vs_drake"] = ratio
        out["whole_process_at_most_half_drake"] = ratio <= 0.5
    pk = speed.get("period_k", {})
    if pk.get("ratio") is not None:
        out["period_8_over_period_1"] = pk["ratio"]
        out["period_8_at_most_10x"] = pk["ratio"] <= 10
    study = record.get("branches", {}).get("slope_study")
    if study:
        out["cascade_speedup_vs_orbit_diagram"] = study["speedup"]
        out["cascade_at_least_20x"] = study["speedup"] >= 20
    return out


def table(record: dict[str, Any]) -> str:
    """Issue 12's section of the printed report."""
    g = record.get("goals_issue_12", {})
    speed = record.get("speed", {})

    def ms(s: float | None) -> str:
        return "—" if s is None or not math.isfinite(s) else f"{1e3 * s:.3g} ms"

    def verdict(key: str) -> str:
        return "n/a" if key not in g else ("met" if g[key] else "NOT met")

    lines = ["Speed goals, ratios within this run:"]
    lines.append("  verified warm solve (find_limit_cycle(m), verify=True), every model:")
    for name, e in record["models"].items():
        b = e["once_built"]
        lines.append(
            f"    {name:22s} {ms(b['verify_true']['median_s']):>10s} verified, "
            f"{ms(b['verify_false']['median_s']):>10s} unverified"
        )
    if "compass_speedup_vs_drake" in g:
        lines.append(
            f"  compass gait verified warm {ms(g['compass_verified_warm_s'])} vs Drake settled to "
            f"{_SETTLE:g} {ms(g['drake_settle_s'])}: {g['compass_speedup_vs_drake']:.3g}× "
            f"(goal ≥ 20×) — {verdict('compass_at_least_20x_drake')}"
        )
    else:
        lines.append(
            f"  compass gait verified warm {ms(g.get('compass_verified_warm_s'))}; Drake not "
            f"measured (goal ≥ 20× Drake) — n/a"
        )
    wp = speed.get("whole_process", {})
    if wp:
        lines.append(
            f"  whole process `gaitopt solve compass_gait --json`: {ms(wp['gaitopt']['median_s'])}"
            f" (python -c pass {ms(wp['python_startup']['median_s'])}, python -c 'import "
            f"gaitopt' {ms(wp['import_gaitopt']['median_s'])})"
            + (
                f"; Drake's whole process {ms(wp['drake']['median_s'])}: ratio "
                f"{g['whole_process_ratio_vs_drake']:.2f} (goal ≤ 0.5) — "
                f"{verdict('whole_process_at_most_half_drake')}"
                if "drake" in wp
                else "; Drake not measured (goal ≤ 0.5× Drake) — n/a"
            )
        )
    if "kneed_verified_warm_s" in g:
        lines.append(
            f"  kneed walker verified warm {ms(g['kneed_verified_warm_s'])} (goal ≤ 5 ms) — "
            f"{verdict('kneed_at_most_5ms')}"
        )
    pk = speed.get("period_k", {})
    if pk:
        p1, p8 = pk["period_1"], pk["period_8"]
        lines.append(
            f"  compass gait at slope {pk['slope']}: period-8 verified {ms(p8.get('median_s'))} "
            f"vs period-1 {ms(p1.get('median_s'))}: "
            + (f"{pk['ratio']:.3g}×" if pk.get("ratio") is not None else "—")
            + f" (goal ≤ 10×) — {verdict('period_8_at_most_10x')}"
        )
    if "cascade_speedup_vs_orbit_diagram" in g:
        lines.append(
            f"  cascade study vs orbit diagram at equal slope resolution: "
            f"{g['cascade_speedup_vs_orbit_diagram']:.3g}× (goal ≥ 20×) — "
            f"{verdict('cascade_at_least_20x')}"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    print(json.dumps(run(repeats=2), indent=1, default=str))
