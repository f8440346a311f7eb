"""The kneed walker's least cost of transport with hip AND knee torques (issue 24 item 5a).

The statement of ``problems/optimal_kneed_cot.py`` (kneed walker, leg length 1 m, M = 1.6 kg,
slope 0.03 rad, step length L = 0.47 m, speed v, hip |τ_h| ≤ 5 N·m) with the knee torque
switched on, |τ_k| ≤ 5 N·m, a clearance margin of 0.01 m for the swing foot
(``GaitProblem(clearance=0.01)``: ``h ≥ 0.01 sin(π t / T)``; without it the optimum skims the
slope, a boundary arc no simulation confirms) and the braking arcs regularised by
``braking_effort = 1e-3`` (``+ 1e-3 ∫u² dt`` over the arcs of negative power in the objective,
not in the reported cost: negative work is free, so a braking torque is otherwise not unique).

The optimum holds the swing knee straight with its torque for a while after heel strike: a
boundary arc of the knee strike's guard (:mod:`gaitopt.optimize.boundary_arcs`: the knee
flexion at 0 with zero rate, the torque given by its acceleration being zero, entry and exit
junctions), then lets it fold and swing passively; and the swing foot's height touches its
clearance margin once in mid-swing, a touch point made a junction
(:func:`gaitopt.optimize.state_arcs.clearance_functions`).  Each is a free mesh point, so the
refinement converges at the collocation's order.

At each speed: the passive-knee optimum (knee torque 0, a cold start, the statement of
``optimal_kneed_cot``), then the knee-powered optimum warm started from it.  The passive knee
is feasible for the knee-powered statement, so the knee-powered least cost must be no higher
(to the certificate's 1e-8): checked and written (``at_most_passive``).  Checked too, against
the independent simulation: the work–energy balance of the periodic orbit, cost of transport =
(heel- and knee-strike energy losses + negative actuator work) / (M g L)
(:func:`energy_balance`), to 1e-8.

    python problems/optimal_kneed_knee.py --out results [--fast]

``--fast`` (for CI): 0.84 m/s only (the full run adds 0.80 and 0.88 m/s).  Writes
results/optimal_kneed_knee/: knee.json, knee.csv.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_csv, write_json
from gaitopt.optimize import GaitProblem, solve_problem
from gaitopt.optimize.boundary_arcs import boundary_spans
from gaitopt.optimize.state_arcs import touch_times
from gaitopt.optimize.verify import profiles, simulate_gait

SLOPE = 0.03  # rad (optimal_kneed_cot's)
STEP = 0.47  # m
PASSIVE = {"hip_torque": 5.0, "knee_torque": 0.0}  # N·m: optimal_kneed_cot's statement
POWERED = {"hip_torque": 5.0, "knee_torque": 5.0}  # N·m: the knee torque switched on
CLEARANCE = 0.01  # m, the swing foot's margin at mid-step
BRAKING = 1e-3  # weight of ∫u² dt over the braking arcs (1 per N²·m²·s)
SPEEDS = (0.80, 0.84, 0.88)  # m/s
FAST_SPEEDS = (0.84,)
#: The knee-powered cost may exceed the passive knee's by this (relative): the certificate's
#: discretisation target.
SAME = 1e-8


def problems_at(speed: float) -> tuple[GaitProblem, GaitProblem]:
    """The passive-knee and the knee-powered statements at ``speed`` (m/s)."""
    model = gaitopt.model("kneed_walker", slope=SLOPE)
    passive = GaitProblem(model, "cot", step_length=STEP, speed=float(speed), bounds=PASSIVE)
    powered = GaitProblem(
        model, "cot", step_length=STEP, speed=float(speed), bounds=POWERED,
        clearance=CLEARANCE, braking_effort=BRAKING,
    )  # fmt: skip
    return passive, powered


def energy_balance(problem: GaitProblem, gait) -> float:
    """The cost of transport from the work–energy balance of the simulated orbit: along each
    phase ``dE/dt = Σ τᵢωᵢ`` (``E`` the phase's conserved energy in its stance-foot frame), so
    over a period the positive work is ``W⁺ = W⁻ + Σ (E(x⁻) − E(x⁺))`` over the knee and heel
    strikes (closed form from the simulated states), ``W⁻`` the negative work by composite
    Simpson on the dense simulated orbit (129 points per profile interval, split at its
    breakpoints, where the torque may jump); returns ``W⁺ / (M g L)``.  Independent of the
    collocation's quadrature (as ``tests/test_optimize_kneed_cot.py`` for the passive knee)."""
    model = gait.model
    col, w = gait.transcription
    sol = col.unpack(w, model.p)
    profs = profiles(col, sol)
    sim = simulate_gait(problem, model, model.lift(sol["s"]), profs, 1)
    if not sim.success:
        return float("nan")
    jumps = 0.0
    for event in sim.events:
        if event.state_after is None:
            continue
        before = model.phases[event.phase].conserved["energy"]
        after = model.phases[1 - event.phase].conserved["energy"]  # three-link ↔ two-link
        jumps += float(before(event.state_before, model.p)) - float(
            after(event.state_after, model.p)
        )
    negative = 0.0
    breaks = profs[0].breaks
    for arc in sim.arcs:
        rates = model.input_rates(arc.phase)
        inner = breaks[(breaks > arc.t0) & (breaks < arc.t1)]
        edges = np.concatenate([[arc.t0], inner, [arc.t1]])
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            ts = np.linspace(a, b, 129)
            xs = arc.solution(ts)
            us = np.column_stack([profs[0](min(max(t, a + 1e-13), b - 1e-13)) for t in ts])
            omega = np.asarray(rates.map(ts.size)(xs, model.p))
            f = np.maximum(0.0, -np.sum(us * omega, axis=0))
            h = (b - a) / (ts.size - 1)
            negative += h / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())
    weight = float(problem.total_mass(model.p)) * 9.81
    return (jumps + negative) / (weight * STEP)


def solve_speed(speed: float) -> dict:
    """The passive-knee and knee-powered optima at ``speed`` with their checks (a row)."""
    passive_problem, problem = problems_at(speed)
    t0 = time.perf_counter()
    passive = solve_problem(passive_problem)
    t1 = time.perf_counter()
    gait = solve_problem(problem, guess=passive if passive.transcription else None)
    t2 = time.perf_counter()
    ok = bool(gait.success and gait.verified)
    row = {
        "speed": float(speed),
        "cot_passive_knee": passive.cost if passive.success else None,
        "passive_certified": bool(passive.success),
        "cot": gait.cost if gait.cost is not None else None,
        "success": ok,
        "discretisation_error": gait.discretisation_error,
        **{k: (gait.discretisation or {}).get(k) for k in ("cost_error", "orbit_error")},
        "intervals": (gait.discretisation or {}).get("intervals"),
        "period_s": gait.period,
        "cost_simulated": (gait.verification or {}).get("cost_simulated"),
        "return_error": (gait.verification or {}).get("return_error"),
        "braking_effort_integral": None,
        "energy_balance_cot": None,
        "energy_balance_gap": None,
        "at_most_passive": None,
        "boundary_arcs": "",
        "touch_points": "",
        "max_abs_multiplier": (
            float(np.max(np.abs(gait.multipliers)))
            if gait.multipliers is not None and np.size(gait.multipliers)
            else None
        ),
        "time_passive_s": round(t1 - t0, 1),
        "time_s": round(t2 - t1, 1),
        "message": gait.message,
    }
    if gait.transcription is not None:
        col, w = gait.transcription
        sol = col.unpack(w, gait.model.p)
        row["braking_effort_integral"] = sol["braking_effort"]
        row["boundary_arcs"] = "; ".join(boundary_spans(col, w, gait.model.p))
        row["touch_points"] = "; ".join(touch_times(col, w, gait.model.p))
    if ok:
        balance = energy_balance(problem, gait)
        row["energy_balance_cot"] = balance
        row["energy_balance_gap"] = abs(balance - gait.cost) / gait.cost
        if passive.success:
            row["at_most_passive"] = bool(gait.cost <= passive.cost * (1 + SAME))
    row["_gait"] = gait
    return row


COLUMNS = [
    ("speed_m_per_s", "speed"), ("cost_of_transport", "cot"),
    ("cot_passive_knee", "cot_passive_knee"), ("passive_certified", "passive_certified"),
    ("success", "success"), ("discretisation_error", "discretisation_error"),
    ("cost_error", "cost_error"), ("orbit_error", "orbit_error"), ("intervals", "intervals"),
    ("period_s", "period_s"), ("cost_simulated", "cost_simulated"),
    ("return_error", "return_error"), ("braking_effort_integral", "braking_effort_integral"),
    ("energy_balance_cot", "energy_balance_cot"), ("energy_balance_gap", "energy_balance_gap"),
    ("at_most_passive", "at_most_passive"), ("boundary_arcs", "boundary_arcs"),
    ("touch_points", "touch_points"), ("max_abs_multiplier", "max_abs_multiplier"),
    ("time_passive_s", "time_passive_s"), ("time_s", "time_s"), ("message", "message"),
]  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="0.84 m/s only, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_kneed_knee"
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for v in FAST_SPEEDS if args.fast else SPEEDS:
        row = solve_speed(v)
        rows.append(row)
        cot = f"{row['cot']:.10g}" if row["success"] else "—"
        print(f"v = {v:.2f} m/s: cot {cot} (passive knee {row['cot_passive_knee']}), "
              f"error {row['discretisation_error']}, {row['time_s']} s: {row['message']}",
              flush=True)  # fmt: skip
    statement = {
        "model": "kneed_walker", "slope": SLOPE, "step_length": STEP, "bounds": POWERED,
        "passive_bounds": PASSIVE, "clearance": CLEARANCE, "braking_effort": BRAKING,
    }  # fmt: skip
    write_json(
        {**statement, "points": [
            {**{k: x for k, x in r.items() if k != "_gait"},
             "gait": r["_gait"].to_json() if r["success"] else None}
            for r in rows
        ]},
        folder / "knee.json",
    )  # fmt: skip
    write_csv([c for c, _ in COLUMNS], [[r[k] for _, k in COLUMNS] for r in rows],
              folder / "knee.csv")  # fmt: skip
    # A speed without a certified optimum is reported as such (its message in the CSV); every
    # certified one must pass both checks.
    certified = [r for r in rows if r["success"]]
    good = bool(certified) and all(
        r["at_most_passive"] and r["energy_balance_gap"] <= 1e-8 for r in certified
    )
    return 0 if good else 1


if __name__ == "__main__":
    raise SystemExit(main())
