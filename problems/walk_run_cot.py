"""Walking or running? The minimal biped's least cost of transport across speed.

Srinivasan & Ruina 2006 (Nature 439:72) asked which gait a point mass on two massless
telescoping legs should use to travel at a given speed with the least positive leg work per unit
weight and distance, and found inverted-pendulum walking at low speed, running at high speed and
a "pendular run" in between.  Here the same question is put to gaitopt's optimiser for the two
phase sequences of :mod:`gaitopt.models.minimal_biped` — ``minimal_biped_walk`` (single stance,
instantaneous double-support transfer with a plastic heel strike) and ``minimal_biped_run``
(stance, flight) — at the step length ``d = STEP`` and speeds ``SPEEDS``.

Statement (both sequences): cost ``"cot"`` = positive leg work ``∫ max(0, F ṙ) dt / (M g d)``;
speed fixed; step length fixed at ``STEP`` (freed, the step shrinks without limit: with no cost
of swinging a massless leg ever shorter steps cost ever less, and a walk at 1 m/s went to 1 mm
steps, its phase's least duration);
``0 ≤ F ≤ F_MAX`` (the regularisation: Srinivasan & Ruina's impulsive push-off and impulsive
running stance become pushes at ``F_MAX``; their heel-strike collision stays impulsive and only
dissipates).  Each point: cold starts (a multi-start of ``STARTS`` starts on the first mesh of
``MESHES``, one start on the second), then the continuation in speed from below and from above
(each speed warm started from its neighbour's lowest certified optimum, or its lowest converged
one); the lowest certified optimum is kept, and
attempts that certify different costs are flagged (different local minima).  Certified means:
IPOPT converged on the exact positive-work transcription, the discretisation error is below
1e-8, the dense checks pass, and the independent simulation with the optimal force as a
feedforward returns to the fixed point with the same cost.

For every kept optimum the CSV also gives the **work–energy balance** of the simulated orbit:
positive work, negative work of the leg force, energy lost in the heel strikes (walking), and
the residual ``W⁺ + W⁻ + ΔE_impacts`` (zero for a periodic orbit), the structure of the force
(arcs of the power sign, e.g. ``[-hi held +hi]``: landing at ``F_MAX``, a rigid leg, a push at
``F_MAX``), and the smallest eigenvalue of the reduced Hessian (a sign change between
neighbouring speeds is a fold).  A run whose flight lasts the transcription's least phase
duration (1 ms) is the walk's limit, not a run: it is marked ``flight at floor``.

    python problems/walk_run_cot.py --out results [--fast | --redraw]

``--fast`` (for CI): one speed per sequence, one cold start only; ``--redraw``: only the
summary of cot.json and cot.png again from cot.csv.  Writes results/walk_run_cot/: cot.csv,
cot.json, cot.png, gaits.png.
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
from gaitopt.optimize import GaitProblem, solve_problem  # noqa: E402
from gaitopt.optimize.library.events import reduced_hessian  # noqa: E402
from gaitopt.optimize.radau import RadauMesh  # noqa: E402
from gaitopt.optimize.verify import simulate_gait  # noqa: E402
from gaitopt.optimize.work_check import simulated_work  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

STEP = 0.6  # m, step length d (leg length 1 m)
F_MAX = 30.0  # N: the leg force bound, about 3.06 M g (M = 1 kg)
GAITS = {"walk": "minimal_biped_walk", "run": "minimal_biped_run"}
#: Initial meshes (intervals, degree): the cold starts use each in turn, the continuations the
#: first (the exact-work stage of a walk converged from 12×4 where 6×6 found no arcs it could
#: solve at 1 m/s, and the other way round for runs at 4 m/s).
MESHES = {"walk": (RadauMesh(12, 4), RadauMesh(6, 6)), "run": (RadauMesh(6, 6), RadauMesh(12, 4))}
SPEEDS = (0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0)  # m/s
FAST = {"walk": (1.0,), "run": (4.0,)}
STARTS = 2
SAME = 1e-6  # relative: certified costs further apart are different local minima
FLOOR = 1.0001e-3  # s: a flight this short sits at the transcription's least phase duration
#: (sequence, speed in m/s) of the optimal gaits gaits.png draws (their samples go to cot.json).
DRAWN = (("walk", 1.0), ("walk", 2.0), ("run", 2.0), ("run", 3.0), ("run", 4.0))


def problem_at(gait: str, speed: float) -> GaitProblem:
    """The least-cost-of-transport statement of ``gait`` ("walk" or "run") at ``speed`` (m/s)."""
    model = gaitopt.model(GAITS[gait], step_length=STEP)
    return GaitProblem(
        model, "cot", step_length=STEP, speed=float(speed), bounds={"leg_force": (0.0, F_MAX)}
    )


def structure(message: str) -> str:
    """The arcs of the power sign from an optimum's message (``"[-hi held +hi]; [-]"``)."""
    found = re.search(r"arcs of the power signs (\[[^;]*\](?:; \[[^\]]*\])*)", message or "")
    return found.group(1) if found else ""


def energy_balance(gait) -> dict[str, float]:
    """The work–energy balance of one simulated period of a certified optimum.

    Positive and negative work of the leg force ``∫ max(0, F ṙ) dt``, ``∫ min(0, F ṙ) dt``
    (J; Gauss–Legendre, 8 points on 64 panels per phase, split at the profile's breakpoints),
    the change of kinetic energy in the cycle transitions (J; the heel strike's loss) and the
    residual ``W⁺ + W⁻ + ΔE_impacts`` (J), zero for a periodic orbit by the work–energy theorem.
    """
    model = gait.model
    problem = problem_at("walk" if len(model.phases) == 1 else "run", gait.speed)
    x0 = model.state_vector(gait.fixed_point)
    sim = simulate_gait(problem, model, x0, gait.profiles, 1)
    # F ṙ on the stance arcs (the leg force does no work in flight)
    pos, neg = simulated_work(sim, gait.profiles[0], 2)
    impacts = 0.0
    for event in sim.events:
        if event.state_after is None:
            continue
        before = _energy(model, event.phase, event.state_before)
        after = _energy(model, (event.phase + 1) % len(model.phases), event.state_after)
        impacts += after - before
    return {
        "positive_work": pos,
        "negative_work": neg,
        "impact_energy": impacts,
        "residual": pos + neg + impacts,
    }


def _energy(model, phase: int, x) -> float:
    """Kinetic plus potential energy (J) of the hip (the phase's ``bodies``)."""
    m, r, v = (np.asarray(a, dtype=float).ravel() for a in model.phases[phase].bodies(x, model.p))
    return float(0.5 * m[0] * v @ v + m[0] * model.gravity * r[1])


def _solve(
    gait: str, v: float, label: str, guess, points: dict, starts: int = 1, mesh: int = 0
) -> None:
    t0 = time.perf_counter()
    result = solve_problem(problem_at(gait, v), guess=guess, mesh=MESHES[gait][mesh], starts=starts)
    elapsed = time.perf_counter() - t0
    converged = bool(result.orbit) and result.cost is not None and np.isfinite(result.cost)
    points[v].append({
        "start": label,
        "success": bool(result.success),
        "cost": float(result.cost) if result.success else None,
        "converged_cost": float(result.cost) if converged else None,
        "time_s": round(elapsed, 1),
        "message": result.message or "(the solver gave no reason)",
        "gait": result,
    })  # fmt: skip
    what = f"certified, cot {result.cost:.10g}" if result.success else f"FAILED: {result.message}"
    print(f"{gait} v = {v:.2f} m/s {label}: {what[:300]} ({elapsed:.1f} s)", flush=True)


def _best(attempts: list[dict], key: str = "cost") -> dict | None:
    good = [a for a in attempts if a[key] is not None]
    return min(good, key=lambda a: a[key]) if good else None


def library(gait: str, speeds: list[float], fast: bool) -> dict[float, list[dict]]:
    """Every attempt of ``gait`` at every speed: multi-start cold starts, then one continuation
    from below and one from above (skipped in the fast mode)."""
    points: dict[float, list[dict]] = {v: [] for v in speeds}
    for v in speeds:
        _solve(gait, v, "cold", None, points, starts=1 if fast else STARTS)
    if fast:
        return points
    for v in speeds:
        _solve(gait, v, "cold, second mesh", None, points, mesh=1)
    for direction, order in (("from below", speeds), ("from above", speeds[::-1])):
        for prev, v in zip(order[:-1], order[1:], strict=True):
            seed = _best(points[prev]) or _best(points[prev], "converged_cost")
            if seed is not None:
                _solve(gait, v, direction, seed["gait"], points)
    return points


def summarise_kind(gait: str, g) -> str:
    """``walk``; for the running sequence ``run, flight at floor`` (the flight at the
    transcription's least phase duration: the walk's limit), ``pendular run`` (a held, rigid
    leg in stance: Srinivasan & Ruina's pendular run) or ``run``."""
    if gait == "walk":
        return "walk"
    if float(g.durations[1]) <= FLOOR:
        return "run, flight at floor"
    return "pendular run" if "held" in structure(g.message).split(";")[0] else "run"


def summarise(gait: str, v: float, attempts: list[dict]) -> dict:
    """One CSV row: the lowest certified optimum of ``gait`` at ``v`` and its checks."""
    best = _best(attempts)
    good = sorted(a["cost"] for a in attempts if a["success"])
    row = {
        "gait": gait,
        "speed_m_s": v,
        "froude_speed": round(v / np.sqrt(9.81), 6),
        "certified": best is not None,
        "cot": best["cost"] if best else None,
        "from": best["start"] if best else None,
        "different_minima": bool(good and good[-1] > good[0] * (1 + SAME)),
        "certified_costs": " ".join(f"{c:.10g}" for c in good),
        "failures": "" if best else " | ".join(f"{a['start']}: {a['message']}" for a in attempts),
    }
    if best is None:
        return row
    g = best["gait"]
    flight = float(g.durations[1]) if len(g.durations) > 1 else None
    arcs = structure(g.message)
    kind = summarise_kind(gait, g)
    balance = energy_balance(g)
    col, w = g.transcription
    lam_min, lam_max = reduced_hessian(col, w, col.model.p)
    row.update({
        "kind": kind,
        "period_s": g.period,
        "stance_s": float(g.durations[0]),
        "flight_s": flight,
        "arcs": arcs,
        "active": " | ".join(sorted(g.active_constraints)),
        "discretisation_error": g.discretisation_error,
        "return_error": g.verification.get("return_error"),
        "cost_simulated": g.verification.get("cost_simulated"),
        "positive_work_J": balance["positive_work"],
        "negative_work_J": balance["negative_work"],
        "impact_energy_J": balance["impact_energy"],
        "energy_residual_J": balance["residual"],
        "hessian_min": lam_min,
        "hessian_max": lam_max,
    })  # fmt: skip
    return row


def events(rows: list[dict]) -> list[str]:
    """Active-set (arc structure, active constraints) changes and folds (the reduced Hessian's
    smallest eigenvalue changing sign) between neighbouring certified speeds, per gait."""
    out = []
    for gait in GAITS:
        good = [r for r in rows if r["gait"] == gait and r["certified"]]
        for a, b in zip(good[:-1], good[1:], strict=True):
            span = f"{gait} between {a['speed_m_s']:g} and {b['speed_m_s']:g} m/s"
            if a["arcs"] != b["arcs"]:
                out.append(f"{span}: arcs {a['arcs']} -> {b['arcs']}")
            if a["active"] != b["active"]:
                gone = set(a["active"].split(" | ")) - set(b["active"].split(" | "))
                new = set(b["active"].split(" | ")) - set(a["active"].split(" | "))
                out.append(f"{span}: active set loses {sorted(gone)}, gains {sorted(new)}")
            ha, hb = a.get("hessian_min"), b.get("hessian_min")
            if ha is None or hb is None or not (np.isfinite(ha) and np.isfinite(hb)):
                continue  # no reduced Hessian: the active constraints leave no freedom
            if np.sign(ha) != np.sign(hb):
                out.append(
                    f"{span}: fold? reduced Hessian's smallest eigenvalue {ha:.3g} -> {hb:.3g}"
                )
    return out


def winners(rows: list[dict], speeds: list[float]) -> list[dict]:
    """At each speed, the kind of gait of least certified cost of transport, and the least
    certified cost of each sequence there (a run whose flight sits at the 1 ms floor counts with
    its cost, named for what it is: ``run, flight at floor``)."""
    out = []
    for v in speeds:
        here = [r for r in rows if r["speed_m_s"] == v and r["certified"]]
        entry = {"speed_m_s": v, "optimal": None, "cot": None}
        for gait in GAITS:
            mine = [r for r in here if r["gait"] == gait]
            entry[f"{gait}_cot"] = mine[0]["cot"] if mine else None
            entry[f"{gait}_kind"] = mine[0]["kind"] if mine else None
        if here:
            best = min(here, key=lambda r: r["cot"])
            entry.update(optimal=best["kind"], cot=best["cot"])
        out.append(entry)
    return out


def draw(rows: list[dict], folder: Path) -> None:
    """cot.png: the least cost of transport of each sequence against speed."""
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    styles = {"walk": ("o-", "C0"), "run": ("s-", "C3")}
    for gait, (fmt, colour) in styles.items():
        good = [r for r in rows if r["gait"] == gait and r["certified"]]
        ax.plot([r["speed_m_s"] for r in good], [r["cot"] for r in good], fmt, color=colour,
                label=GAITS[gait])  # fmt: skip
        for r in good:
            if r["kind"] in ("pendular run", "run, flight at floor"):
                ax.annotate("p" if r["kind"] == "pendular run" else "f",
                            (r["speed_m_s"], r["cot"]), textcoords="offset points",
                            xytext=(4, 4), fontsize=8, color=colour)  # fmt: skip
    ax.set_xlabel("speed v (m/s)")
    ax.set_ylabel("cost of transport W⁺/(M g d) (1)")
    ax.set_title(f"Minimal biped, d = {STEP} m, 0 ≤ F ≤ {F_MAX:g} N (p: pendular, f: flight 1 ms)")
    ax.legend()
    save_figure(fig, folder / "cot.png")
    plt.close(fig)


def samples(points: dict) -> list[dict]:
    """The drawn optima (:data:`DRAWN`) as plain data: the hip's path about the stance foot (m),
    the leg force against time (N, s) and the flight's time spans (s)."""
    out = []
    for gait, v in DRAWN:
        best = _best(points[gait].get(v, []))
        if best is None:
            continue
        g = best["gait"]
        path, flights = [], []
        for arc in g.orbit:
            x = np.asarray(arc.x)
            if arc.phase == 0:
                path.append([list(x[0] * np.sin(x[1])), list(x[0] * np.cos(x[1]))])
            else:
                path.append([list(x[0]), list(x[1])])
                flights.append([float(arc.t[0]), float(arc.t[-1])])
        out.append({
            "gait": gait,
            "speed_m_s": v,
            "kind": summarise_kind(gait, g),
            "cot": g.cost,
            "path": path,
            "phases": [int(arc.phase) for arc in g.orbit],
            "time": list(g.inputs["time"]),
            "leg_force": list(g.inputs["leg_force"]),
            "flights": flights,
        })  # fmt: skip
    return out


def draw_gaits(drawn: list[dict], folder: Path) -> None:
    """gaits.png: the hip's path with the stance leg at five instants (stance blue, flight red)
    over the leg force (flight shaded: the leg is off the ground, its force irrelevant)."""
    if not drawn:
        return
    fig, axes = plt.subplots(2, len(drawn), figsize=(3.0 * len(drawn), 5.0), squeeze=False)
    for j, d in enumerate(drawn):
        ax, axf = axes[0, j], axes[1, j]
        for phase, (hx, hz) in zip(d["phases"], d["path"], strict=True):
            hx, hz = np.asarray(hx), np.asarray(hz)
            ax.plot(hx, hz, "C0" if phase == 0 else "C3")
            if phase == 0:
                for k in np.linspace(0, hx.size - 1, 5).astype(int):
                    ax.plot([0, hx[k]], [0, hz[k]], color="0.6", lw=0.8)
        ax.set_aspect("equal")
        ax.tick_params(axis="x", labelsize=7)
        ax.set_xlabel("hip x from the foot (m)")
        ax.set_ylabel("hip height z (m)")
        ax.set_title(f"{d['kind']}, v = {d['speed_m_s']:g} m/s\ncot {d['cot']:.4g}", fontsize=9)
        t, f = np.asarray(d["time"]), np.asarray(d["leg_force"], dtype=float)
        for a, b in d["flights"]:
            f[(t > a) & (t < b)] = np.nan
            axf.axvspan(a, b, color="C3", alpha=0.15, lw=0)
        axf.plot(t, f, "k")
        axf.set_ylim(-1.0, 1.08 * F_MAX)
        axf.set_xlabel("time t (s)")
        axf.set_ylabel("leg force F (N)")
    fig.tight_layout()
    save_figure(fig, folder / "gaits.png")
    plt.close(fig)


def _cell(text: str):
    """A CSV cell back as a number, bool, None (empty) or text."""
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    try:
        return float(text)
    except ValueError:
        return text


def redraw(folder: Path) -> None:
    """The summary (``optimal``, ``events``) and cot.png again from the committed cot.csv."""
    import csv
    import json

    with open(folder / "cot.csv", encoding="utf-8") as f:
        rows = [{k: _cell(v) for k, v in r.items()} for r in csv.DictReader(f)]
    speeds = sorted({r["speed_m_s"] for r in rows})
    data = json.loads((folder / "cot.json").read_text(encoding="utf-8"))
    data["optimal"], data["events"] = winners(rows, speeds), events(rows)
    write_json(data, folder / "cot.json")
    draw(rows, folder)
    draw_gaits(data.get("drawn", []), folder)
    report(data["optimal"], data["events"])


def report(best: list[dict], changes: list[str]) -> None:
    for b in best:
        print(f"v = {b['speed_m_s']:g} m/s: optimal {b['optimal']} (cot {b['cot']})")
    for e in changes:
        print(e)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="one speed per gait, for CI")
    parser.add_argument(
        "--redraw",
        action="store_true",
        help="only recompute cot.json's summary and redraw cot.png from the cot.csv written",
    )
    args = parser.parse_args(argv)
    folder = Path(args.out) / "walk_run_cot"
    folder.mkdir(parents=True, exist_ok=True)
    if args.redraw:
        redraw(folder)
        return 0
    t_start = time.perf_counter()
    speeds = {g: list(FAST[g]) if args.fast else list(SPEEDS) for g in GAITS}
    points = {g: library(g, speeds[g], args.fast) for g in GAITS}
    rows = [summarise(g, v, points[g][v]) for g in GAITS for v in speeds[g]]
    all_speeds = sorted({v for g in GAITS for v in speeds[g]})
    best = winners(rows, all_speeds)
    changes = events(rows)
    drawn = samples(points)
    columns = list(dict.fromkeys(k for r in rows for k in r))
    write_csv(columns, [[r.get(k) for k in columns] for r in rows], folder / "cot.csv")
    write_json({
        "statement": {"step_length_m": STEP, "leg_force_bound_N": F_MAX, "mass_kg": 1.0,
                      "leg_length_m": 1.0, "gravity_m_s2": 9.81, "cost": "cot",
                      "starts": 1 if args.fast else STARTS},
        "rows": rows,
        "optimal": best,
        "events": changes,
        "drawn": drawn,
        "attempts": {g: {str(v): [{k: a[k] for k in a if k != "gait"} for a in points[g][v]]
                         for v in speeds[g]} for g in GAITS},
        "fast": args.fast,
        "time_s": round(time.perf_counter() - t_start, 1),
    }, folder / "cot.json")  # fmt: skip
    draw(rows, folder)
    draw_gaits(drawn, folder)
    report(best, changes)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
