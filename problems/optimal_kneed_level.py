"""The kneed walker on level ground, powered by a hip torque and Kuo's push-off, across speeds.

On level ground (slope 0) gravity supplies no work; the walker (leg length 1 m, M = 1.6 kg,
the knee passive: its torque switched off, it locks by its own knee strike) is powered by a hip
torque τ(t), |τ| ≤ :data:`HIP` N·m, and Kuo's (2002) push-off: an impulse P ≥ 0 along the
trailing leg just before heel strike (``push_off``, an impulsive input of the heel strike; its
work is the walker's kinetic-energy gain, :meth:`KneedWalker.impulse_work`).  At each speed v
the least cost of transport — positive work per step (hip torque and push-off) over M·g·L — is
found with the step length L and period free (L/T = v), by
:func:`gaitopt.optimize.library.library_both_ends`: a cold start (the model's default start) at
every speed and warm-start chains from both ends, the lowest certified optimum kept and a speed
whose certified attempts reached different local minima flagged.

A point is reported only if certified like every optimum (IPOPT converged on the exact
switching-time transcription, discretisation error of cost and orbit ≤ 1e-8 under mesh doubling,
the dense checks of the polynomials — the swing foot above the ground, the stance foot pushing,
the positive work between the nodes — and the independent simulation with the optimal torque
and push-off as feedforward returning to the fixed point with the same cost).  Floquet
multipliers by AD through the collocation (and central differences of the simulated map).  The
heel strike's contact impulse must press the new foot into the ground (its normal component,
:func:`heel_strike_impulse`, is checked and reported).

    python problems/optimal_kneed_level.py --out results [--fast]

``--fast`` (for CI): :data:`FAST_SPEEDS` only.  Writes results/optimal_kneed_level/: level.json,
level.csv.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import casadi as ca
import numpy as np

import gaitopt
from gaitopt.files import write_csv, write_json
from gaitopt.optimize import GaitProblem
from gaitopt.optimize.library import disagreement, library_both_ends, lowest

SLOPE = 0.0  # rad: level ground
HIP = 1.0  # N·m: |τ_hip| ≤ HIP
PUSH = 2.0  # N·s: 0 ≤ P ≤ PUSH (never reached)
BOUNDS = {"hip_torque": HIP, "knee_torque": 0.0, "push_off": (0.0, PUSH)}
SPEEDS = np.array([0.70, 0.80, 0.90])  # m/s
FAST_SPEEDS = np.array([0.80, 0.90])
MAX_PASSES = 2  # chain passes in all: one from each end
SAME = 1e-6  # relative: certified attempts differing by more reached different local minima
COLUMNS = [
    "speed_m_per_s", "step_length_m", "period_s", "cost_of_transport", "push_off_N_s",
    "max_abs_multiplier", "stable", "verified", "discretisation_error", "heel_strike_impulse_N_s",
    "start", "different_minima", "attempts", "failed_starts",
]  # fmt: skip


def problem_at(speed: float) -> GaitProblem:
    """The least-cost-of-transport statement at ``speed`` (m/s), step length free."""
    model = gaitopt.model("kneed_walker", slope=SLOPE)
    return GaitProblem(model, "cot", speed=float(speed), bounds=BOUNDS)


def heel_strike_impulse(gait) -> float:
    """The normal component (N·s, along the slope normal) of the ground's impulse on the new
    stance foot at heel strike, with the push-off: positive when it presses the foot into the
    ground (the model's floating-base impact, :func:`gaitopt.mechanics.impact_velocity`)."""
    from gaitopt.hybrid import Symbols
    from gaitopt.mechanics import impact_velocity
    from gaitopt.models.kneed_walker import _masses, _unit, _walker

    model = gait.model
    col, w = gait.transcription
    sol = col.unpack(w, model.p)
    k = 1  # the two-link phase ends in the heel strike
    x = sol["X"][k][:, -1]
    push = float(sol["U"][k][model.inputs.index("push_off"), -1])
    sym = Symbols(model.parameter_specs(), model.inputs)
    xs, (p1, p2, p1d, p2d) = sym.states("q1", "q2", "q1_dot", "q2_dot")
    geo = _walker(sym, p1, p2, p2)
    _, impulse = impact_velocity(
        _masses(sym, geo), ca.vertcat(p1, p2), ca.vertcat(p1d, p2d), geo["swing_contact"],
        contact_slip=-sym.foot_radius * p2d * geo["tangent"],
        impulse=(geo["hip"], sym.input("push_off") * _unit(p1)), contact_impulse=True,
    )  # fmt: skip
    f = ca.Function("impulse", [xs, sym.u, sym.p], [ca.dot(geo["normal"], impulse)])
    u = np.zeros(len(model.inputs))
    u[model.inputs.index("push_off")] = push
    return float(f(x, u, model.p))


def row_of(v: float, attempts: list[dict]) -> tuple[list, dict]:
    """The table row and the JSON record of speed ``v``."""
    i = lowest(attempts)
    flag = disagreement(attempts, SAME)
    listing = "; ".join(
        f"{a['start']}" + (f" (seed {a['seed']})" if a["seed"] else "")
        + (f" {a['cost']:.10g}" if a["success"] else " failed")
        for a in attempts
    )  # fmt: skip
    failed = "; ".join(f"{a['start']}: {a['message']}" for a in attempts if not a["success"])
    if i is None:
        row = [v, None, None, None, None, None, None, False, None, None, "none", flag, listing,
               failed]  # fmt: skip
        return row, {
            "speed": v,
            "start": None,
            "different_minima": flag,
            "gait": None,
            "attempts": [{k: x for k, x in a.items() if k != "gait"} for a in attempts],
        }
    gait = attempts[i]["gait"]
    mu = float(np.max(np.abs(gait.multipliers))) if gait.multipliers is not None else None
    push = float(np.asarray(gait.inputs["push_off"])[-1])
    impulse = heel_strike_impulse(gait)
    row = [v, gait.step_length, gait.period, gait.cost, push, mu, gait.stable,
           bool(gait.verified) and impulse > 0, gait.discretisation_error, impulse,
           attempts[i]["start"], flag, listing, failed]  # fmt: skip
    record = {
        "speed": v, "start": attempts[i]["start"], "different_minima": flag,
        "heel_strike_impulse": impulse,
        "attempts": [{k: x for k, x in a.items() if k != "gait"} for a in attempts],
        "gait": gait.to_json(),
    }  # fmt: skip
    return row, record


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="two speeds only, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_kneed_level"
    folder.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    speeds = sorted(float(v) for v in (FAST_SPEEDS if args.fast else SPEEDS))
    points = library_both_ends(problem_at, speeds, max_passes=MAX_PASSES, same=SAME)
    rows, records = [], []
    for v in speeds:
        row, record = row_of(v, points[v])
        rows.append(row)
        records.append(record)
    statement = {"model": "kneed_walker", "slope": SLOPE, "bounds": BOUNDS, "step_length": "free",
                 "same_minimum_rel": SAME, "fast": bool(args.fast)}  # fmt: skip
    write_json({**statement, "points": records}, folder / "level.json")
    write_csv(COLUMNS, rows, folder / "level.csv")
    print(f"\n{'v (m/s)':>8} {'L (m)':>8} {'T (s)':>8} {'cot':>14} {'P (N·s)':>9} {'|μ|max':>8}")
    for r in rows:
        if r[3] is None:
            print(f"{r[0]:>8.3f}  no certified optimum: {r[13]}")
            continue
        print(f"{r[0]:>8.3f} {r[1]:>8.5f} {r[2]:>8.5f} {r[3]:>14.10g} {r[4]:>9.5f} {r[5]:>8.4g} "
              f"verified {r[7]} error {r[8]:.1e} {r[10]}"
              + (f" DIFFERENT MINIMA: {r[11]}" if r[11] else ""))  # fmt: skip
    print(f"{time.perf_counter() - t_start:.0f} s in all")
    return 0 if any(r[7] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
