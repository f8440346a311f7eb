"""The kneed walker's least cost of transport across speeds (shallow slope, fixed step length).

The kneed walker (leg length 1 m, total mass M = 1.6 kg; its passive gait on its 0.0504 rad
slope takes 0.4727 m steps at 0.838 m/s) is powered by a hip torque τ(t), |τ| ≤ 5 N·m; its knee
is passive (the knee torque switched off, as in McGeer's 1990 kneed walker): it swings free and
locks by its own knee strike.  On a shallower slope (0.03 rad) gravity no longer pays for the
heel and knee strikes, and the torque makes up the difference.  For a fixed step length
L = 0.47 m and speeds v over a range (period T = L/v) the least cost of transport — positive
actuator work ∫max(0, τω) dt over a step divided by M·g·L — is found with
:func:`gaitopt.optimize.solve_problem` (exact switching-time transcription of bang, coasting and
held-hip arcs) from a cold start and, except at the first speed, warm started from its
neighbour's optimum, then in a second pass warm started from each certified neighbour; the
starts can reach different local minima, and the lowest certified one is reported (all are in
the CSV).  A biomechanics reader expects cost against speed to have a
minimum (Ralston 1958; Srinivasan & Ruina 2006, Nature 439:72, for simple walking models).

A point is reported as a gait only if it is certified: IPOPT converged on the exact
transcription, the discretisation error of cost and orbit under mesh doubling is below 1e-8, the
dense samples keep the knee from striking early and the swing foot above the slope, and the
independent simulator with the optimal torque as a feedforward returns to the fixed point with
the same cost.  Otherwise the speed is listed as a failure with the solver's reason.

    python problems/optimal_kneed_cot.py --out results [--fast | --redraw]

Writes results/optimal_kneed_cot/: cot.json, cot.csv, cot.png.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.optimize import GaitProblem, solve_problem  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

SLOPE = 0.03  # rad: a shallow slope (the passive gait's is 0.0504)
STEP = 0.47  # m, step length L (leg length 1 m)
BOUNDS = {"hip_torque": 5.0, "knee_torque": 0.0}  # N·m: hip |τ| ≤ 5, knee passive
ANCHOR = 0.84  # m/s: the first speed solved (near the passive gait's), then outwards
SPEEDS = np.round(np.arange(0.68, 0.9801, 0.04), 3)  # m/s
FAST_SPEEDS = np.array([0.84])


def problem_at(speed: float) -> GaitProblem:
    """The least-cost-of-transport statement at ``speed`` (m/s)."""
    model = gaitopt.model("kneed_walker", slope=SLOPE)
    return GaitProblem(model, "cot", step_length=STEP, speed=float(speed), bounds=BOUNDS)


def continuation_order(speeds: np.ndarray) -> list[tuple[float, float | None]]:
    """``(speed, neighbour)`` in the order solved: the speed nearest :data:`ANCHOR` first
    (no neighbour), then outwards on either side, each after its inner neighbour."""
    speeds = sorted(float(v) for v in speeds)
    first = min(range(len(speeds)), key=lambda j: abs(speeds[j] - ANCHOR))
    order = [(speeds[first], None)]
    order += [(speeds[j], speeds[j + 1]) for j in range(first - 1, -1, -1)]
    order += [(speeds[j], speeds[j - 1]) for j in range(first + 1, len(speeds))]
    return order


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="one speed, for CI")
    parser.add_argument(
        "--redraw", action="store_true", help="only redraw cot.png from the cot.csv written"
    )
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_kneed_cot"
    folder.mkdir(parents=True, exist_ok=True)
    if args.redraw:
        redraw(folder)
        return 0

    speeds = FAST_SPEEDS if args.fast else SPEEDS
    solved: dict[float, object] = {}
    results = {}
    for v, neighbour in continuation_order(speeds):
        t0 = time.perf_counter()
        # Cold start (the model's default start) and, away from the anchor, a warm start from
        # the neighbour's optimum: local minima differ, the lower certified one is reported.
        tries = {"cold": solve_problem(problem_at(v))}
        if neighbour in solved:
            tries["warm"] = solve_problem(problem_at(v), guess=solved[neighbour])
        elapsed = time.perf_counter() - t0
        good = {k: g for k, g in tries.items() if g.success}
        if good:
            how = min(good, key=lambda k: good[k].cost)
            gait = good[how]
            solved[v] = gait
        else:
            how = "none"
            gait = tries["cold"]
            gait.message = "; ".join(f"{k} start: {g.message}" for k, g in tries.items())
        costs = {k: (g.cost if g.success else None) for k, g in tries.items()}
        results[v] = (gait, how, elapsed, costs)
        print(
            f"v = {v:.3f} m/s: success {gait.success} ({how}), cot "
            f"{gait.cost if gait.success else None} (cold {costs['cold']}, warm "
            f"{costs.get('warm')}), discretisation error {gait.discretisation_error} "
            f"({elapsed:.1f} s)" + ("" if gait.success else f"\n    {gait.message}")
        )
    # Second pass: each speed warm started from its other neighbour too (the continuation
    # reached it from one side only), the lower certified cost kept.
    ordered = sorted(results)
    for j, v in enumerate(ordered):
        gait, how, elapsed, costs = results[v]
        for side, other in (("warm from below", j - 1), ("warm from above", j + 1)):
            if not 0 <= other < len(ordered) or ordered[other] not in solved:
                continue
            t0 = time.perf_counter()
            trial = solve_problem(problem_at(v), guess=solved[ordered[other]])
            elapsed += time.perf_counter() - t0
            costs[side] = trial.cost if trial.success else None
            if trial.success and (not gait.success or trial.cost < gait.cost * (1 - 1e-9)):
                gait, how = trial, side
                solved[v] = trial
        results[v] = (gait, how, elapsed, costs)
        print(f"v = {v:.3f} m/s, second pass: {costs} -> {how}")
    rows, records = [], []
    for v in sorted(results):
        gait, how, elapsed, costs = results[v]
        ok = bool(gait.success)
        mu = np.abs(gait.multipliers) if gait.multipliers is not None else np.array([])
        mu_max = float(np.max(mu)) if ok and mu.size else None
        rows.append(
            (v, gait.cost if ok else None, gait.period if ok else None,
             gait.step_length if ok else None, ok, bool(gait.verified),
             gait.discretisation_error if ok else None, mu_max, gait.stable if ok else None,
             how, costs["cold"], costs.get("warm"), costs.get("warm from below"),
             costs.get("warm from above"), round(elapsed, 1),
             "" if ok else gait.message)
        )  # fmt: skip
        records.append({"speed": v, "start": how, "costs": costs, "time_s": elapsed,
                        "gait": gait.to_json()})  # fmt: skip

    statement = {
        "model": "kneed_walker",
        "slope": SLOPE,
        "step_length": STEP,
        "bounds": BOUNDS,
    }
    write_json({**statement, "points": records}, folder / "cot.json")
    write_csv(
        ["speed_m_per_s", "cost_of_transport", "period_s", "step_length_m", "success", "verified",
         "discretisation_error", "max_abs_multiplier", "stable", "start", "cot_cold_start",
         "cot_warm_start", "cot_warm_from_below", "cot_warm_from_above", "time_s",
         "failure_reason"],
        rows,
        folder / "cot.csv",
    )  # fmt: skip

    good = draw([(r[0], r[1], bool(r[4])) for r in rows], folder)
    return 0 if good else 1


def draw(points: list[tuple[float, float | None, bool]], folder: Path) -> bool:
    """``cot.png``: the certified optima (speed, cot) and the speeds with none, at 0; returns
    whether any is certified."""
    fig, ax = plt.subplots(figsize=(6, 4.2))
    good = [(v, c) for v, c, ok in points if ok]
    if good:
        ax.plot(*zip(*good, strict=True), "o-", label="certified optimum")
    bad = [v for v, _, ok in points if not ok]
    if bad:
        ax.plot(bad, np.zeros(len(bad)), "rx", ms=9, label="no certified optimum (at 0)")
    ax.set_xlabel("speed v (m/s)")
    ax.set_ylabel(r"cost of transport $c_T = W^+/(M g d)$ (1)")
    ax.set_title(
        f"Kneed walker, slope {SLOPE} rad, step L = {STEP} m, hip |τ| ≤ "
        f"{BOUNDS['hip_torque']:g} N·m, passive knee",
        fontsize=10,
    )
    ax.legend()
    save_figure(fig, folder / "cot.png")
    return bool(good)


def redraw(folder: Path) -> None:
    """Redraw ``cot.png`` from the ``cot.csv`` a run wrote (no optimisation)."""
    import csv

    with open(folder / "cot.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    draw(
        [
            (float(r["speed_m_per_s"]), float(r["cost_of_transport"] or "nan"),
             r["success"] == "True")
            for r in rows
        ],
        folder,
    )  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
