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

``--fast`` (for the test): one start (0), knee-limited only, refinement target 1e-3.  Writes
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

STEP_LENGTH, PERIOD = 0.5, 0.7  # OptimTraj demo/fiveLinkBiped/MAIN.m (c8d1d91)
COLUMNS = [
    "case", "starts", "cost", "success", "verified", "discretisation_error",
    "min_stance_knee_flexion_rad", "min_swing_knee_flexion_rad", "active_constraints",
    "minima", "time_s", "message",
]  # fmt: skip


def knee_margins(gait) -> tuple[float, float]:
    """Least stance and swing knee flexion (rad) on the optimum's dense samples (the orbit's
    arcs: 8 per mesh interval of the collocation polynomials)."""
    x = np.hstack([arc.x for arc in gait.orbit])
    return float(np.min(x[1] - x[0])), float(np.min(x[3] - x[4]))


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
    stance, swing = knee_margins(gait) if gait.orbit else (float("nan"), float("nan"))
    row = {
        "case": "knee limit" if knee else "free knees",
        "starts": len(starts) if not isinstance(starts, int) else starts,
        "cost": gait.cost,
        "success": gait.success,
        "verified": gait.verified,
        "discretisation_error": gait.discretisation_error,
        "min_stance_knee_flexion_rad": stance,
        "min_swing_knee_flexion_rad": swing,
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
    tol = 1e-3 if args.fast else 1e-8
    rows, spans = [], {}
    for knee in cases:
        row, gait = solve(knee, starts, tol)
        rows.append(row)
        spans[row["case"]] = getattr(gait, "active_spans", {})
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
        "active_spans": spans,
    }
    write_json(json.loads(json.dumps(summary, default=float)), folder / "summary.json")
    return 0 if all(r["success"] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
