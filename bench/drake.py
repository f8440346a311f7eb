"""Drake's ``CompassGait`` and ``RimlessWheel`` (only where ``pydrake`` imports) simulated from the
same start until the gait settles, and to convergence; timed without the monitor that watches
for the impacts (see :mod:`bench.run`)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .common import _median

__all__: list[str] = []


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
    """Drake's settle-by-simulation runs for ``model`` (see :mod:`bench.run`)."""
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
