"""Benchmarks of optimal gait synthesis run by ``make bench``.

* **compass gait, level ground, 0.3 m in 0.8 s, least effort** — :func:`gaitopt.optimize_gait`
  (Radau collocation, refined to a discretisation error below 1e-8, verified by simulation)
  against a hand-written baseline in the same run: a plain Hermite–Simpson transcription
  (Betts 2010, §4.5; Kelly 2017, SIAM Review 59, §4) written directly with CasADi ``Opti`` and
  IPOPT on 40 uniform intervals, using only the model's flow, guard, reset and foothold;
* **five-link biped, OptimTraj's problem** (0.4 m in 0.6 s, ``∫Σu² dt``, |u| ≤ 100 N·m, state
  bounds) — one start (start 4, which reaches OptimTraj's IPOPT minimum), verified, first call
  and once built; the seeded 8-start multi-start (its minima and the time per start); and the
  same hand-written Hermite–Simpson baseline on 40 intervals (with the model's unilateral
  constraints, input and state bounds).

Goals: the compass gait's optimum, verified, in ≤ 0.3 s once built; the five-link
biped ≤ 2 s per start.  Times are wall-clock on this machine; the first call includes building
the NLP, the second reuses the cached transcription and its NLP (the guess, IPOPT, refinement
and verification are all redone).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from gaitopt.hybrid import rate_along
from gaitopt.models import model as make_model
from gaitopt.optimize import optimize_gait
from gaitopt.optimize.problem import GaitProblem

__all__ = ["run", "hermite_simpson", "table"]

PERIOD, STEP = 0.8, 0.3  # s, m


def hermite_simpson(
    model: Any,
    period: float,
    step: float,
    intervals: int = 40,
    bounds: dict[str, float] | None = None,
    state_bounds: dict[str, tuple[float, float]] | None = None,
    end: Callable[[np.ndarray], np.ndarray] = lambda x: x,
) -> dict[str, Any]:
    """A one-phase model's least-effort step by Hermite–Simpson collocation, written by hand.

    Decision variables: the states at the ``intervals + 1`` knots and the midpoints, the inputs
    at the same points; constraints: the Simpson and Hermite defects, the guard at the last knot
    (crossed in its direction), the reset of the last state equal to the first (periodicity), the
    foothold's distance equal to the step length, the phase's unilateral constraints at the
    knots (a swing foot above the ground, a stance leg pushing) and the input and state bounds.
    Cost: Simpson quadrature of ``Σuᵢ²``.  The start: the model's default start moving
    linearly to ``end(x0)``, the same state with the legs exchanged.

    Returns
    -------
    dict
        ``cost`` (N²·m²·s), ``time`` (s, build and solve), ``status``, ``intervals``.
    """
    t0 = time.perf_counter()
    phase = model.phases[0]
    tr = phase.transitions[0]
    p = ca.DM(model.p)
    problem = GaitProblem(model, period=period, step_length=step)
    opti = ca.Opti()
    n, m, N = phase.n, len(model.inputs), intervals
    X, Xm = opti.variable(n, N + 1), opti.variable(n, N)
    U, Um = opti.variable(m, N + 1), opti.variable(m, N)
    h = period / N
    cost = 0
    for j in range(N):
        f0 = phase.flow(X[:, j], U[:, j], p)
        f1 = phase.flow(X[:, j + 1], U[:, j + 1], p)
        fm = phase.flow(Xm[:, j], Um[:, j], p)
        opti.subject_to(Xm[:, j] == (X[:, j] + X[:, j + 1]) / 2 + h / 8 * (f0 - f1))
        opti.subject_to(X[:, j + 1] - X[:, j] == h / 6 * (f0 + 4 * fm + f1))
        cost += h / 6 * (ca.sumsqr(U[:, j]) + 4 * ca.sumsqr(Um[:, j]) + ca.sumsqr(U[:, j + 1]))
    x_end, u_end = X[:, N], U[:, N]
    opti.subject_to(tr.guard(x_end, u_end, p) == 0)
    rate = rate_along(phase.flow, tr.guard)(x_end, u_end, p)  # ∇g · f
    opti.subject_to(tr.direction * rate >= 1e-2)
    opti.subject_to(tr.reset(x_end, u_end, p) == X[:, 0])
    opti.subject_to(ca.norm_2(problem.step_vector(0, x_end, p)) == step)
    opti.minimize(cost)
    for c in phase.constraints:
        knots = range(1, N) if c.at_start or c.at_end else range(N + 1)
        for j in knots:
            opti.subject_to(c.function(X[:, j], U[:, j], p) >= 0)
        if c.at_start:  # zero where the phase starts: it must rise
            opti.subject_to(rate_along(phase.flow, c.function)(X[:, 0], U[:, 0], p) >= 0)
    for r, name in enumerate(model.inputs):
        high = (bounds or {}).get(name)
        if high is not None:
            opti.subject_to(opti.bounded(-high, ca.vertcat(U[r, :].T, Um[r, :].T), high))
    for name, (low, high) in (state_bounds or {}).items():
        i = model.state_names.index(name)
        opti.subject_to(opti.bounded(low, ca.vertcat(X[i, :].T, Xm[i, :].T), high))
    # Start: the default post-impact state moving linearly to ``end(x0)`` (the pre-impact
    # state with the legs exchanged), no torque.
    x0 = np.asarray(model.lift(model.section_vector(model.default_start())), float)
    s = np.linspace(0, 1, 2 * N + 1)
    guess = np.outer(x0, 1 - s) + np.outer(end(x0), s)
    opti.set_initial(X, guess[:, ::2])
    opti.set_initial(Xm, guess[:, 1::2])
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
    # (stance, swing, rates) → the legs exchanged
    baseline = hermite_simpson(model, PERIOD, STEP, end=lambda x: x[[1, 0, 2, 3]])
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
    options = dict(
        period=0.6,
        step_length=0.4,
        bounds={name: high for name, (_, high) in model.input_bounds.items()},
        state_bounds=model.state_bounds,
    )
    times, gait = [], None
    for _ in range(2):  # start 4 (OptimTraj's IPOPT minimum), verified: first, then once built
        t0 = time.perf_counter()
        gait = optimize_gait(model, starts=[4], seed=0, **options)
        times.append(time.perf_counter() - t0)
    assert gait is not None
    t0 = time.perf_counter()
    multi = optimize_gait(model, starts=8, seed=0, **options)
    t_multi = time.perf_counter() - t0
    # absolute link angles (stance shank … swing shank) mirrored, rates kept
    baseline = hermite_simpson(
        model, 0.6, 0.4, 40, options["bounds"], model.state_bounds,
        end=lambda x: np.concatenate([x[4::-1], x[5:]]),
    )  # fmt: skip
    return {
        "cost": gait.cost,
        "verified": gait.verified,
        "discretisation_error": gait.discretisation_error,
        "time_first_s": times[0],
        "time_per_start_s": times[1],
        "multi_start": {
            "starts": 8,
            "time_s": t_multi,
            "time_per_start_s": t_multi / 8,
            "minima": [{"cost": m.cost, "starts": m.starts} for m in multi.minima],
        },
        "goal_s": 2.0,
        "baseline": baseline,
        "baseline_relative_difference": (
            abs(baseline["cost"] - gait.cost) / gait.cost
            if gait.cost is not None and baseline["cost"] is not None
            else None
        ),
    }


#: The other optimal gaits of the README, timed (first call and once built) without a baseline:
#: (label, model, model parameters, optimize_gait keywords).
OTHERS = (
    ("compass gait, least positive work, |τ| ≤ 20 N·m", "compass_gait", {"slope": 0.0},
     {"cost": "work", "period": 0.8, "step_length": 0.3, "bounds": {"hip_torque": 20.0}}),
    ("simplest walker, Kuo's push-off, least work", "simplest_walker", {"slope": 0.0},
     {"cost": "work", "step_length": 0.4, "bounds": {"hip_torque": 0}}),
    ("kneed walker, default slope, least effort", "kneed_walker", {},
     {"cost": "effort", "period": 0.5643, "step_length": 0.47}),
)  # fmt: skip


def _others() -> list[dict[str, Any]]:
    rows = []
    for label, name, params, options in OTHERS:
        model = make_model(name, **params)
        times, gait = [], None
        for _ in range(2):
            t0 = time.perf_counter()
            gait = optimize_gait(model, **options)
            times.append(time.perf_counter() - t0)
        assert gait is not None
        rows.append(
            {
                "label": label,
                "success": gait.success,
                "cost_kind": gait.cost_kind,
                "cost": gait.cost,
                "verified": gait.verified,
                "discretisation_error": gait.discretisation_error,
                "time_first_s": times[0],
                "time_second_s": times[1],
            }
        )
    return rows


def run(quick: bool = False) -> dict[str, Any]:
    """Both measurements (``quick``: the compass gait only)."""
    out: dict[str, Any] = {"compass_gait": _compass()}
    if not quick:
        out["five_link_biped"] = _five_link()
        out["others"] = _others()
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
        ms = f["multi_start"]
        fb = f["baseline"]
        minima = ", ".join(f"{m['cost']:.8f} ← starts {m['starts']}" for m in ms["minima"])
        lines += [
            f"  five-link biped effort {f['cost']:.10g} (verified {f['verified']}, "
            f"discretisation error {f['discretisation_error']:.2g}): one start, verified, "
            f"{f['time_first_s']:.2f} s first call, {f['time_per_start_s']:.2f} s once built "
            f"(goal 2 s)",
            f"  five-link biped, 8 starts: {ms['time_s']:.2f} s = {ms['time_per_start_s']:.2f} s "
            f"per start; minima {minima}",
            f"  Hermite–Simpson baseline ({fb['intervals']} intervals, CasADi Opti): "
            f"{fb['cost']} ({fb['status']}) in {fb['time']:.2f} s, relative difference "
            f"{f['baseline_relative_difference']}",
        ]
    for o in record.get("others", []):
        err = o["discretisation_error"]
        lines.append(
            f"  {o['label']}: {o['cost_kind']} {o['cost']:.10g} (success {o['success']}, "
            f"verified {o['verified']}, discretisation error "
            f"{'—' if err is None else f'{err:.2g}'}); {o['time_first_s']:.2f} s first call, "
            f"{o['time_second_s']:.2f} s once built"
        )
    return "\n".join(lines)
