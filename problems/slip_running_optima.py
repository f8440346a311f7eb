"""Least cost of transport of the actuated SLIP across speed, the touchdown angle chosen.

The spring-mass runner of :mod:`gaitopt.models.slip` (Tedrake's k̃ = 10.7, m = 80 kg,
l0 = 1 m) with a leg force actuator ``F`` in parallel with its spring
(:mod:`gaitopt.models.slip_actuated`), at the SLIP's default energy ``E`` (Ẽ = 1.61) and stride
``d`` (the passive SLIP gait's at θ_td = 30°, 1.35576 m), run at speeds ``SPEEDS`` around the
passive SLIP gait's own speed ``V_PASSIVE`` = d / T (3.64678 m/s).

Statement: cost ``"cot"`` = positive actuator work ``∫ max(0, F ṙ) dt / (m g d)``; speed fixed;
energy and stride fixed (model parameters; the model declares the flight's energy equal to the
section's, so an orbit closes in every state); ``0 ≤ F ≤ F_MAX`` (an actuator that only pushes:
it still brakes, F > 0 while the leg shortens; the model's *leg pushes*, ``k (l0 − r) + F ≥ 0``,
then holds by itself: with ``F`` allowed to pull, optima pulled at the ends of stance, where
the spring force vanishes, and failed the dense check between the nodes).  The section is
touchdown, ``theta`` (minus the touchdown angle) and ``r_dot`` free: the optimiser chooses the
touchdown angle.  At ``V_PASSIVE`` the passive SLIP gait (F ≡ 0) is feasible and free, so the
least cost is 0 there; but the zero-cost optima are not isolated (a leg held at constant length,
``ṙ = 0``, does no work whatever its force), so the least cost of transport is also solved as
its well-posed companion, least effort ``∫ F² dt`` (N²·s), whose optimum at ``V_PASSIVE`` is the
passive gait (``F ≡ 0``, the only zero-effort orbit).

Each speed and cost: cold starts (``STARTS`` on each mesh of ``MESHES`` for the cost of
transport, on the first for the effort), the lowest certified optimum kept.  Certified: IPOPT
converged (for the cost of transport on the exact positive-work transcription), discretisation
error below 1e-8, dense checks pass, and the independent simulation with the optimal force as a
feedforward returns to the fixed point with the same cost (the optimiser's checks).  For every
kept optimum the CSV gives the touchdown angle, the work–energy balance of the simulated orbit
(positive and negative actuator work, their sum: zero for a periodic orbit at fixed energy, no
impacts) and the arcs of the power sign.

    python problems/slip_running_optima.py --out results [--fast]

``--fast`` (for CI): the passive speed only, one mesh, both costs.  Writes
results/slip_running_optima/: optima.csv, optima.json, optima.png.
"""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.models.slip_actuated import SLIP_STRIDE  # noqa: E402
from gaitopt.optimize import GaitProblem, solve_problem  # noqa: E402
from gaitopt.optimize.radau import RadauMesh  # noqa: E402
from gaitopt.optimize.verify import simulate_gait  # noqa: E402
from gaitopt.optimize.work_check import simulated_work  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

#: Speed (m/s) of the passive SLIP gait at the slip model's defaults: stride / period, with the
#: period 0.371770468 s of gaitopt.find_limit_cycle(gaitopt.model("slip"), {"z": 0.87}).
V_PASSIVE = 3.646778451636991
F_MAX = 1000.0  # N: the actuator bound, about 1.3 m g (m = 80 kg); it only pushes, F ≥ 0
BRAKING = 1e-9  # weight of the least-effort braking term (GaitProblem.braking_effort)
#: Initial meshes: "cot" tries each, "effort" the first.
MESHES = (RadauMesh(12, 4), RadauMesh(8, 6))
SPEEDS = (3.55, 3.6, 3.63, V_PASSIVE, 3.66, 3.7)  # m/s
FAST = (V_PASSIVE,)
COSTS = ("cot", "effort")
STARTS = 2


def problem_at(speed: float, cost: str = "cot") -> GaitProblem:
    """The statement at ``speed`` (m/s) with ``cost`` ("cot" or "effort")."""
    model = gaitopt.model("slip_actuated")
    return GaitProblem(
        model,
        cost,
        step_length=SLIP_STRIDE,
        speed=float(speed),
        bounds={"leg_force": (0.0, F_MAX)},
        braking_effort=BRAKING if cost == "cot" else 0.0,
    )


def structure(message: str) -> str:
    """The arcs of the power sign from an optimum's message."""
    found = re.search(r"arcs of the power signs (\[[^;]*\](?:; \[[^\]]*\])*)", message or "")
    return found.group(1) if found else ""


def energy_balance(gait) -> dict[str, float]:
    """Positive and negative actuator work (J) over one simulated period of ``gait`` and their
    sum, zero for a periodic orbit at fixed energy (no impacts: the leg is massless and touches
    down at rest length).  Gauss–Legendre, 8 points on 64 panels of the stance, split at the
    force profile's breakpoints."""
    model = gait.model
    x0 = model.state_vector(gait.fixed_point)
    sim = simulate_gait(problem_at(gait.speed, "effort"), model, x0, gait.profiles, 1)
    # F ṙ on the stance arcs (the actuator does no work in flight)
    pos, neg = simulated_work(sim, gait.profiles[0], 2)
    return {"positive_work": pos, "negative_work": neg, "residual": pos + neg}


def solve_speed(v: float, cost: str, fast: bool) -> list[dict]:
    """Every attempt at speed ``v`` with ``cost``: ``STARTS`` cold starts on each mesh ("cot")
    or the first ("effort"); one start on the first mesh in the fast mode."""
    attempts = []
    for j, mesh in enumerate(MESHES[:1] if fast or cost == "effort" else MESHES):
        t0 = time.perf_counter()
        result = solve_problem(problem_at(v, cost), mesh=mesh, starts=1 if fast else STARTS)
        elapsed = time.perf_counter() - t0
        attempts.append({
            "start": f"cold, mesh {j + 1}",
            "success": bool(result.success),
            "cost": float(result.cost) if result.success else None,
            "time_s": round(elapsed, 1),
            "message": result.message or "(the solver gave no reason)",
            "gait": result,
        })  # fmt: skip
        what = f"certified, cot {result.cost:.6g}" if result.success else "FAILED"
        print(
            f"{cost} v = {v:.4f} m/s mesh {j + 1}: {what}: {result.message[:240]} ({elapsed:.1f} s)"
        )
    return attempts


def summarise(v: float, cost: str, attempts: list[dict]) -> dict:
    """One CSV row: the lowest certified optimum at ``v`` with ``cost`` and its checks."""
    good = [a for a in attempts if a["success"]]
    best = min(good, key=lambda a: a["cost"]) if good else None
    row = {
        "cost": cost,
        "speed_m_s": v,
        "certified": best is not None,
        "optimal_cost": best["cost"] if best else None,
        "from": best["start"] if best else None,
        "failures": "" if best else " | ".join(f"{a['start']}: {a['message']}" for a in attempts),
    }
    if best is None:
        return row
    g = best["gait"]
    balance = energy_balance(g)
    weight_distance = g.model.mass * g.model.gravity * SLIP_STRIDE  # m g d (J)
    row.update({
        "touchdown_angle_deg": float(np.degrees(-g.fixed_point["theta"])),
        "touchdown_r_dot_m_s": float(g.fixed_point["r_dot"]),
        "period_s": g.period,
        "stance_s": float(g.durations[0]),
        "flight_s": float(g.durations[1]),
        "peak_force_N": float(np.max(np.abs(np.asarray(g.inputs["leg_force"], dtype=float)))),
        "arcs": structure(g.message),
        "discretisation_error": g.discretisation_error,
        "return_error": g.verification.get("return_error"),
        "cost_simulated": g.verification.get("cost_simulated"),
        "cot_simulated": balance["positive_work"] / weight_distance,
        "positive_work_J": balance["positive_work"],
        "negative_work_J": balance["negative_work"],
        "energy_residual_J": balance["residual"],
    })  # fmt: skip
    return row


def draw(rows: list[dict], folder: Path) -> None:
    """optima.png: the cost of transport of each certified optimum (least cost of transport,
    least effort) and its touchdown angle against speed."""
    fig, (ax, axa) = plt.subplots(2, 1, figsize=(6.4, 6.0), sharex=True)
    for cost, (fmt, colour) in {"cot": ("o-", "C3"), "effort": ("s--", "C0")}.items():
        good = [r for r in rows if r["cost"] == cost and r["certified"]]
        v = [r["speed_m_s"] for r in good]
        label = f"least {'cost of transport' if cost == 'cot' else 'effort ∫F² dt'}"
        ax.plot(v, [r["cot_simulated"] for r in good], fmt, color=colour, label=label)
        axa.plot(v, [r["touchdown_angle_deg"] for r in good], fmt, color=colour, label=label)
    for a in (ax, axa):
        a.axvline(V_PASSIVE, color="0.6", ls="--", lw=0.8)
    ax.set_ylabel("cost of transport W⁺/(m g d) (1)")
    ax.set_title(f"Actuated SLIP, Ẽ = 1.61, d = {SLIP_STRIDE:.4f} m, 0 ≤ F ≤ {F_MAX:g} N")
    ax.legend(fontsize=8)
    axa.set_xlabel("speed v (m/s) (dashed: the passive SLIP's)")
    axa.set_ylabel("touchdown angle θ_td (deg)")
    fig.tight_layout()
    save_figure(fig, folder / "optima.png")
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="the passive speed only, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "slip_running_optima"
    folder.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    speeds = FAST if args.fast else SPEEDS
    attempts = {(c, v): solve_speed(v, c, args.fast) for c in COSTS for v in speeds}
    rows = [summarise(v, c, attempts[c, v]) for c in COSTS for v in speeds]
    columns = list(dict.fromkeys(k for r in rows for k in r))
    write_csv(columns, [[r.get(k) for k in columns] for r in rows], folder / "optima.csv")
    write_json({
        "statement": {"model": "slip_actuated", "energy_J": 1263.528, "stride_m": SLIP_STRIDE,
                      "passive_speed_m_s": V_PASSIVE, "force_bounds_N": [0.0, F_MAX],
                      "braking_effort": BRAKING, "costs": list(COSTS),
                      "starts": 1 if args.fast else STARTS},
        "rows": rows,
        "attempts": {f"{c} {v}": [{k: a[k] for k in a if k != "gait"} for a in attempts[c, v]]
                     for c in COSTS for v in speeds},
        "fast": args.fast,
        "time_s": round(time.perf_counter() - t_start, 1),
    }, folder / "optima.json")  # fmt: skip
    draw(rows, folder)
    for r in rows:
        angle = r.get("touchdown_angle_deg")
        print(f"{r['cost']} v = {r['speed_m_s']:.4f} m/s: cost {r['optimal_cost']}, θ_td {angle}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
