"""Benchmarks of optimal gait synthesis run by ``make bench``.

* **compass gait, level ground, 0.3 m in 0.8 s, least effort** — :func:`gaitopt.optimize_gait`
  (Radau collocation, refined to a discretisation error below 1e-8, verified by simulation)
  against a hand-written baseline in the same run: a plain Hermite–Simpson transcription
  (Betts 2010, §4.5; Kelly 2017, SIAM Review 59, §4) written directly with CasADi ``Opti`` and
  IPOPT on 40 uniform intervals, using only the model's flow, guard, reset and foothold;
* **five-link biped, OptimTraj's problem** (0.4 m in 0.6 s, ``∫Σu² dt``) — the time of one start
  (start 0, verified), against the goal of 2 s per start.

Goals: the compass gait's optimum, verified, in ≤ 0.3 s once built; the five-link
biped ≤ 2 s per start.  Times are wall-clock on this machine; the first call includes building
and compiling the NLP, the second is measured again from scratch (the transcription is rebuilt
on every call).
"""

from __future__ import annotations

import time
from typing import Any

import casadi as ca
import numpy as np

from gaitopt.hybrid import rate_along
from gaitopt.models import model as make_model
from gaitopt.optimize import optimize_gait
from gaitopt.optimize.problem import GaitProblem

__all__ = ["run", "hermite_simpson_compass", "table"]

PERIOD, STEP = 0.8, 0.3  # s, m


def hermite_simpson_compass(intervals: int = 40) -> dict[str, Any]:
    """The level-ground compass gait's least-effort step by Hermite–Simpson collocation.

    Decision variables: the states at the ``intervals + 1`` knots and the midpoints, the hip
    torque at the same points; constraints: the Simpson and Hermite defects, the guard at the
    last knot (crossed downwards), the reset of the last state equal to the first (periodicity)
    and the foothold's distance equal to the step length.  Cost: Simpson quadrature of ``τ²``.

    Returns
    -------
    dict
        ``cost`` (N²·m²·s), ``time`` (s, build and solve), ``status``.
    """
    t0 = time.perf_counter()
    model = make_model("compass_gait", slope=0.0)
    phase = model.phases[0]
    tr = phase.transitions[0]
    p = ca.DM(model.p)
    problem = GaitProblem(model, period=PERIOD, step_length=STEP)
    opti = ca.Opti()
    n, N = phase.n, intervals
    X = opti.variable(n, N + 1)
    Xm = opti.variable(n, N)
    U = opti.variable(1, N + 1)
    Um = opti.variable(1, N)
    h = PERIOD / N
    cost = 0
    for j in range(N):
        f0 = phase.flow(X[:, j], U[:, j], p)
        f1 = phase.flow(X[:, j + 1], U[:, j + 1], p)
        fm = phase.flow(Xm[:, j], Um[:, j], p)
        opti.subject_to(Xm[:, j] == (X[:, j] + X[:, j + 1]) / 2 + h / 8 * (f0 - f1))
        opti.subject_to(X[:, j + 1] - X[:, j] == h / 6 * (f0 + 4 * fm + f1))
        cost += h / 6 * (U[:, j] ** 2 + 4 * Um[:, j] ** 2 + U[:, j + 1] ** 2)
    x_end, u_end = X[:, N], U[:, N]
    opti.subject_to(tr.guard(x_end, u_end, p) == 0)
    rate = rate_along(phase.flow, tr.guard)(x_end, u_end, p)  # ∇g · f
    opti.subject_to(tr.direction * rate >= 1e-2)
    opti.subject_to(tr.reset(x_end, u_end, p) == X[:, 0])
    opti.subject_to(ca.norm_2(problem.step_vector(0, x_end, p)) == STEP)
    opti.minimize(cost)
    # Start: the legs scissoring through the step, a small torque.
    x0 = np.asarray(model.lift(model.section_vector(model.default_start())), dtype=float)
    s = np.linspace(0, 1, N + 1)
    guess = np.outer(x0, 1 - s) + np.outer(np.array([x0[1], x0[0], x0[2], x0[3]]), s)
    opti.set_initial(X, guess)
    opti.set_initial(Xm, (guess[:, :-1] + guess[:, 1:]) / 2)
    opti.solver("ipopt", {"print_time": False, "expand": True}, {"print_level": 0, "sb": "yes"})
    try:
        sol = opti.solve()
        value, status = float(sol.value(cost)), "Solve_Succeeded"
    except RuntimeError:
        value, status = None, str(opti.stats().get("return_status"))
    return {"cost": value, "time": time.perf_counter() - t0, "status": status, "intervals": N}


def _compass() -> dict[str, Any]:
    model = make_model("compass_gait", slope=0.0)
    times, gait = [], None
    for _ in range(2):
        t0 = time.perf_counter()
        gait = optimize_gait(model, period=PERIOD, step_length=STEP)
        times.append(time.perf_counter() - t0)
    assert gait is not None
    baseline = hermite_simpson_compass()
    agree = (
        abs(baseline["cost"] - gait.cost) / gait.cost
        if gait.cost is not None and baseline["cost"] is not None
        else None
    )
    return {
        "cost": gait.cost,
        "verified": gait.verified,
        "discretisation_error": gait.discretisation_error,
        "time_first_s": times[0],
        "time_second_s": times[1],
        "goal_s": 0.3,
        "baseline": baseline,
        "baseline_relative_difference": agree,
    }


def _five_link() -> dict[str, Any]:
    model = make_model("five_link_biped")
    t0 = time.perf_counter()
    gait = optimize_gait(
        model,
        period=0.6,
        step_length=0.4,
        bounds={name: high for name, (_, high) in model.input_bounds.items()},
        state_bounds=model.state_bounds,
        starts=[0],
    )
    return {
        "cost": gait.cost,
        "verified": gait.verified,
        "time_per_start_s": time.perf_counter() - t0,
        "goal_s": 2.0,
    }


def run(quick: bool = False) -> dict[str, Any]:
    """Both measurements (``quick``: the compass gait only)."""
    out = {"compass_gait": _compass()}
    if not quick:
        out["five_link_biped"] = _five_link()
    return out


def table(record: dict[str, Any]) -> str:
    """Plain-text summary."""
    c = record["compass_gait"]
    b = c["baseline"]
    lines = [
        "optimal gaits:",
        f"  compass gait effort {c['cost']:.10g} N²·m²·s (verified {c['verified']}, "
        f"discretisation error {c['discretisation_error']:.2g}); "
        f"{c['time_first_s']:.2f} s first call, {c['time_second_s']:.2f} s second (goal 0.3 s)",
        f"  Hermite–Simpson baseline ({b['intervals']} intervals, CasADi Opti): "
        f"{b['cost']} in {b['time']:.2f} s, relative difference "
        f"{c['baseline_relative_difference']}",
    ]
    if "five_link_biped" in record:
        f = record["five_link_biped"]
        lines.append(
            f"  five-link biped effort {f['cost']:.10g} (verified {f['verified']}): "
            f"{f['time_per_start_s']:.2f} s per start (goal 2 s)"
        )
    return "\n".join(lines)
