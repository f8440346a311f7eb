"""The kneed walker's least cost of transport across speeds (shallow slope, fixed step length).

The kneed walker (leg length 1 m, total mass M = 1.6 kg; its passive gait on its 0.0504 rad
slope takes 0.4727 m steps at 0.838 m/s) is powered by a hip torque τ(t), |τ| ≤ 5 N·m; its knee
is passive (the knee torque switched off, as in McGeer's 1990 kneed walker): it swings free and
locks by its own knee strike.  On a shallower slope (0.03 rad) gravity no longer pays for the
heel and knee strikes, and the torque makes up the difference.  For a fixed step length
L = 0.47 m and speeds v over a range (period T = L/v) the least cost of transport — positive
actuator work ∫max(0, τω) dt over a step divided by M·g·L — is found with
:func:`gaitopt.optimize.solve_problem` (exact switching-time transcription of bang, coasting and
held-hip arcs) as a library across speed, built so that no single start decides a point:

* ``cold``: the model's default start (no warm start), at every speed;
* ``from above``: continuation down in speed from the fastest speed with a seed, each speed
  warm started from the lowest certified attempt at its faster neighbour — or, where none is
  certified, the lowest converged one that its checks rejected (an orbit is a start like any
  other; what it leads to is certified on its own) — or from the nearest faster speed that has
  one (the JSON and CSV name each seed, "(rejected)" for an uncertified one);
* ``from below``: continuation up in speed likewise, from the slowest speed with a seed.

The two chains alternate (from above first) and are repeated while a pass finds a lower
optimum at a seed speed (later passes re-solve only the speeds whose seed improved; labels
``from above, pass 2`` ...), at most :data:`MAX_PASSES` passes.  The lowest certified attempt is
reported.  Attempts whose certified costs differ by more than :data:`SAME` (relative) have
reached different local minima: the speed is flagged (``different_minima``, with every
certified cost) in the CSV, the JSON and the printed output.  The cost of transport has several
local minima in the gait and the optimiser returns whichever one its start leads to, as
"optimal gait found": a single start, or a continuation from one side, is not enough
(:func:`gaitopt.optimize.library.library_both_ends` runs it).  A
biomechanics reader expects cost against speed to have a minimum (Ralston 1958; Srinivasan &
Ruina 2006, Nature 439:72, for simple walking models).

A start is certified only if IPOPT converged on the exact transcription, the discretisation
error of cost and orbit under mesh doubling is below 1e-8, the dense samples keep the knee from
striking early and the swing foot above the slope, and the independent simulator with the
optimal torque as a feedforward returns to the fixed point with the same cost.  A speed with no
certified start is listed as a failure with every start's reason (``failed_starts`` also lists
the reasons of the starts that failed at a certified speed).

    python problems/optimal_kneed_cot.py --out results [--fast | --redraw]

``--fast`` (for CI): 0.80 and 0.84 m/s only.  Writes results/optimal_kneed_cot/: cot.json,
cot.csv, cot.png.
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
from gaitopt.optimize.library import disagreement as _disagreement  # noqa: E402
from gaitopt.optimize.library import library_both_ends, lowest, seed_of  # noqa: E402, F401
from gaitopt.plotting import save_figure  # noqa: E402

SLOPE = 0.03  # rad: a shallow slope (the passive gait's is 0.0504)
STEP = 0.47  # m, step length L (leg length 1 m)
BOUNDS = {"hip_torque": 5.0, "knee_torque": 0.0}  # N·m: hip |τ| ≤ 5, knee passive
SPEEDS = np.round(np.arange(0.68, 0.9801, 0.04), 3)  # m/s
FAST_SPEEDS = np.array([0.80, 0.84])
MAX_PASSES = 6  # chain passes in all (alternating); later passes re-solve only changed seeds
# Relative: certified starts whose costs differ by more reached different local minima (the
# same minimum from different starts agrees to the certificate's 1e-8 and better).
SAME = 1e-6


def problem_at(speed: float) -> GaitProblem:
    """The least-cost-of-transport statement at ``speed`` (m/s)."""
    model = gaitopt.model("kneed_walker", slope=SLOPE)
    return GaitProblem(model, "cot", step_length=STEP, speed=float(speed), bounds=BOUNDS)


def disagreement(attempts: list[dict]) -> str:
    """Empty where the certified attempts agree to :data:`SAME` (or fewer than two are
    certified); else every certified attempt's cost, lowest first, e.g.
    ``"from below 0.01942516336 < from above 0.04333637603"``
    (:func:`gaitopt.optimize.library.disagreement`)."""
    return _disagreement(attempts, SAME)


def library(speeds: list[float]) -> dict[float, list[dict]]:
    """Every attempt at every speed: a cold start, then the chains alternately until two
    passes in a row solve nothing or :data:`MAX_PASSES` are done
    (:func:`gaitopt.optimize.library.library_both_ends`)."""
    return library_both_ends(
        problem_at, speeds, max_passes=MAX_PASSES, same=SAME,
        solve=lambda problem, guess=None: solve_problem(problem, guess=guess),
        log=lambda text: print(f"v = {text}", flush=True),
    )  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="0.80 and 0.84 m/s only, for CI")
    parser.add_argument(
        "--redraw", action="store_true", help="only redraw cot.png from the cot.csv written"
    )
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_kneed_cot"
    folder.mkdir(parents=True, exist_ok=True)
    if args.redraw:
        redraw(folder)
        return 0

    t_start = time.perf_counter()
    speeds = sorted(float(v) for v in (FAST_SPEEDS if args.fast else SPEEDS))
    points = library(speeds)

    rows, records = [], []
    for v in speeds:
        attempts = points[v]
        i = lowest(attempts)
        ok = i is not None
        gait = attempts[i]["gait"] if ok else attempts[0]["gait"]
        flag = disagreement(attempts)
        mu = np.abs(gait.multipliers) if ok and gait.multipliers is not None else np.array([])

        def best_of(prefix: str, attempts: list[dict] = attempts) -> float | None:
            costs = [a["cost"] for a in attempts if a["success"] and a["start"].startswith(prefix)]
            return min(costs) if costs else None

        rows.append(
            (v, gait.cost if ok else None, gait.period if ok else None,
             gait.step_length if ok else None, ok, bool(gait.verified) if ok else False,
             gait.discretisation_error if ok else None, float(np.max(mu)) if mu.size else None,
             gait.stable if ok else None, attempts[i]["start"] if ok else "none",
             best_of("cold"), best_of("from below"), best_of("from above"), bool(flag), flag,
             "; ".join(f"{a['start']}" + (f" (seed {a['seed']})" if a["seed"] else "")
                       + (f" {a['cost']:.10g}" if a["success"] else " failed") for a in attempts),
             round(sum(a["time_s"] for a in attempts), 1),
             "; ".join(f"{a['start']}: {a['message']}" for a in attempts if not a["success"]))
        )  # fmt: skip
        records.append({
            "speed": v, "start": attempts[i]["start"] if ok else None,
            "different_minima": flag,
            "attempts": [{k: x for k, x in a.items() if k != "gait"} for a in attempts],
            "gait": gait.to_json() if ok else None,
        })  # fmt: skip

    statement = {"model": "kneed_walker", "slope": SLOPE, "step_length": STEP, "bounds": BOUNDS,
                 "same_minimum_rel": SAME}  # fmt: skip
    write_json({**statement, "points": records}, folder / "cot.json")
    write_csv(
        ["speed_m_per_s", "cost_of_transport", "period_s", "step_length_m", "success", "verified",
         "discretisation_error", "max_abs_multiplier", "stable", "start", "cot_cold_start",
         "cot_from_below", "cot_from_above", "different_minima", "minima", "attempts", "time_s",
         "failed_starts"],
        rows,
        folder / "cot.csv",
    )  # fmt: skip

    flagged = [r[0] for r in rows if r[13]]
    print(f"\n{'v (m/s)':>8} {'least cot':>14}  {'start':<22} flags")
    for r in rows:
        cot = f"{r[1]:.10g}" if r[4] else "—"
        note = f"DIFFERENT MINIMA: {r[14]}" if r[13] else ""
        if not r[4]:
            note = f"NO CERTIFIED OPTIMUM: {r[17]}"
        print(f"{r[0]:>8.3f} {cot:>14}  {r[9]:<22} {note}")
    print(f"{len(flagged)} speed(s) with different local minima: "
          f"{', '.join(f'{v:.2f}' for v in flagged) or 'none'}; "
          f"{time.perf_counter() - t_start:.0f} s in all")  # fmt: skip

    good = draw([(r[0], r[1], bool(r[4])) for r in rows], folder,
                _worse([(r[0], r[13], r[14]) for r in rows]))  # fmt: skip
    return 0 if good else 1


def _worse(rows: list[tuple]) -> list[tuple[float, float]]:
    """(speed, cost) of every certified local minimum above the least one at each flagged speed,
    from rows ``(speed, flagged, minima)`` (``minima``: "start cost < start cost ...", lowest
    first)."""
    return [
        (float(r[0]), float(part.rsplit(" ", 1)[1]))
        for r in rows
        if r[1]
        for part in r[2].split(" < ")[1:]
    ]


def draw(
    points: list[tuple[float, float | None, bool]],
    folder: Path,
    worse: list[tuple[float, float]] = (),
) -> bool:
    """``cot.png``: the certified optima (speed, cot), the worse certified local minima of the
    flagged speeds and the speeds with none, at 0; returns whether any is certified."""
    fig, ax = plt.subplots(figsize=(6, 4.2))
    good = [(v, c) for v, c, ok in points if ok]
    if good:
        ax.plot(*zip(*good, strict=True), "o-", label="certified optimum")
    bad = [v for v, _, ok in points if not ok]
    if bad:
        ax.plot(bad, np.zeros(len(bad)), "rx", ms=9, label="no certified optimum (at 0)")
    if worse:
        ax.plot(*zip(*worse, strict=True), "s", mfc="none", color="C1",
                label="worse local minimum (flagged)")  # fmt: skip
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
        _worse([(r["speed_m_per_s"], r["different_minima"] == "True", r["minima"])
                for r in rows]),
    )  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
