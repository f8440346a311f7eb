"""The five-link biped's least-effort step with knees that may not hyperextend, against the same
step with free knees.

The problem is OptimTraj's later five-link example (Kelly's OptimTraj, ``demo/fiveLinkBiped``:
``MAIN.m`` at commit c8d1d91 sets ``param.stepLength = 0.5``, ``param.stepTime = 0.7`` and
``problem.func.pathCst = pathConstraint(x)``; ``pathConstraint.m`` at 867eeb3 keeps both knees
from hyperextending, ``q1 − q2 ≤ 0`` and ``q5 − q4 ≤ 0``; Kelly 2017, SIAM Review 59(4)): one step
of 0.5 m in 0.7 s on level ground, cost ∫Σu² dt, |u| ≤ 100 N·m, |q| ≤ π/2 rad, |q̇| ≤ 10 rad/s.
OptimTraj publishes no cost for it (no solver log is committed for this problem), so the numbers
here stand on their own checks: the knee limit at every collocation node and on dense samples
of the final polynomials (``c ≥ −1e-9 (1 + max|c|)``), the discretisation error under mesh
doubling, and the independent simulation.  The same step without the knee limit is solved too:
the limit must be active (its optimum hyperextends the stance knee), else the comparison says so.

    python problems/optimal_five_link_knee.py [--out results] [--starts 8] [--fast]

``--fast`` (for the test): one start (0), knee-limited only (the same target 1e-8).  Writes
results/optimal_five_link_knee/: table.csv (one row per case) and summary.json.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_csv, write_json
from gaitopt.optimize.state_arcs import touch_times
from gaitopt.optimize.verify import feedforward_of

STEP_LENGTH, PERIOD = 0.5, 0.7  # OptimTraj demo/fiveLinkBiped/MAIN.m (c8d1d91)
COLUMNS = [
    "case", "starts", "cost", "success", "verified", "discretisation_error",
    "min_stance_knee_flexion_rad", "min_swing_knee_flexion_rad", "dense_tolerance_rad",
    "min_stance_knee_flexion_simulated_rad", "touch_points", "active_constraints", "minima",
    "time_s", "message",
]  # fmt: skip
#: Uniform samples per mesh interval of the final polynomials for the knee margins: the
#: certificate's dense check of limits (gaitopt.optimize.collocation.LIMIT_SAMPLES).
SAMPLES = 64
#: Uniform samples of the simulated step for its knee margin.
SIM_SAMPLES = 20001


def knee_margins(gait) -> tuple[float, float, float]:
    """Least stance and swing knee flexion (rad) on :data:`SAMPLES` uniform samples per mesh
    interval of the optimum's collocation polynomials (each interval's, so the samples fall on
    the touch points, which are mesh points), and the certificate's tolerance
    ``1e-9 (1 + max |c|)`` of the stance knee's."""
    col, w = gait.transcription
    sol = col.unpack(w, col.model.p)
    (breaks,) = sol["breaks"]
    local = np.linspace(0.0, 1.0, SAMPLES + 1)
    tn = np.unique((breaks[:-1, None] + np.diff(breaks)[:, None] * local).ravel())
    x, _ = col.evaluate(sol["X"][0], sol["U"][0], tn, breaks)
    stance = x[1] - x[0]
    return float(np.min(stance)), float(np.min(x[3] - x[4])), 1e-9 * (1 + np.max(np.abs(stance)))


def simulated_margin(gait) -> float:
    """Least stance knee flexion (rad) of the independent simulation of one step from the
    optimum's fixed point with its torques as a feedforward (DOP853, rtol 1e-12), on
    :data:`SIM_SAMPLES` uniform samples and at its integrator's steps."""
    model = gait.model
    x0 = np.array([gait.fixed_point[n] for n in model.state_names])
    sim = gaitopt.simulate(model, x0, steps=1, feedforward=feedforward_of(gait.profiles),
                           rtol=1e-12, atol=1e-13)  # fmt: skip
    if not sim.success:
        return float("nan")
    least = np.inf
    for arc in sim.arcs:
        t = np.linspace(arc.t0, arc.t1, SIM_SAMPLES)
        x = arc.solution(t)
        least = min(least, float(np.min(x[1] - x[0])))
    return least


def solve(knee: bool, starts, tol: float) -> tuple[dict, object]:
    model = gaitopt.model("five_link_biped")
    t0 = time.perf_counter()
    gait = gaitopt.optimize_gait(
        model,
        period=PERIOD,
        step_length=STEP_LENGTH,
        bounds={name: high for name, (_, high) in model.input_bounds.items()},
        state_bounds=model.state_bounds,
        path_constraints=("knee_flexion",) if knee else (),
        starts=starts,
        seed=0,
        tol=tol,
    )
    elapsed = time.perf_counter() - t0
    nan = float("nan")
    stance, swing, tolerance = knee_margins(gait) if gait.orbit else (nan, nan, nan)
    simulated = simulated_margin(gait) if gait.orbit else nan
    col, w = gait.transcription if gait.orbit else (None, None)
    touches = touch_times(col, w, col.model.p) if col is not None else []
    row = {
        "case": "knee limit" if knee else "free knees",
        "starts": len(starts) if not isinstance(starts, int) else starts,
        "cost": gait.cost,
        "success": gait.success,
        "verified": gait.verified,
        "discretisation_error": gait.discretisation_error,
        "min_stance_knee_flexion_rad": stance,
        "min_swing_knee_flexion_rad": swing,
        "dense_tolerance_rad": tolerance,
        "min_stance_knee_flexion_simulated_rad": simulated,
        "touch_points": "; ".join(touches),
        "active_constraints": "; ".join(gait.active_constraints),
        "minima": " ".join(f"{m.cost:.10g}" for m in gait.minima),
        "time_s": elapsed,
        "message": gait.message,
    }
    return row, gait


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--starts", type=int, default=8, help="seeded starts (default 8)")
    parser.add_argument("--fast", action="store_true", help="one start, knee limit only")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_five_link_knee"
    folder.mkdir(parents=True, exist_ok=True)
    cases = [True] if args.fast else [True, False]
    starts = [0] if args.fast else args.starts
    tol = 1e-8
    rows, spans, active = [], {}, {}
    for knee in cases:
        row, gait = solve(knee, starts, tol)
        rows.append(row)
        spans[row["case"]] = getattr(gait, "active_spans", {})
        active[row["case"]] = list(gait.active_constraints)
        stance, swing = row["min_stance_knee_flexion_rad"], row["min_swing_knee_flexion_rad"]
        print(f"{row['case']}: cost {row['cost']}, success {row['success']}, disc. error "
              f"{row['discretisation_error']}, knee flexion min {stance:.3g}"
              f" / {swing:.3g} rad, {row['time_s']:.0f} s")  # fmt: skip
        print(f"  {row['message']}")
    if len(rows) == 2:
        limited, free = rows
        active = free["min_stance_knee_flexion_rad"] < 0 or free["min_swing_knee_flexion_rad"] < 0
        note = (
            "the knee limit is active: the free-knee optimum hyperextends a knee"
            if active
            else "the knee limit is NOT active: the free-knee optimum keeps both knees flexed"
        )
        print(note)
    write_csv(COLUMNS, [[r[c] for c in COLUMNS] for r in rows], folder / "table.csv")
    summary = {
        "problem": "OptimTraj demo/fiveLinkBiped MAIN.m (c8d1d91): 0.5 m in 0.7 s, knee limit "
        "pathConstraint.m (867eeb3); effort, |u| <= 100, |q| <= pi/2, |qdot| <= 10",
        "fast": args.fast,
        "rows": rows,
        "active_constraints": active,
        "active_spans": spans,
    }
    write_json(json.loads(json.dumps(summary, default=float)), folder / "summary.json")
    return 0 if all(r["success"] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
