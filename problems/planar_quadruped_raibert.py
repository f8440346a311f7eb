"""The planar quadruped's bound under Raibert's controller per virtual leg, against desired speed.

Raibert, Chepponis & Brown 1986 ("Running on four legs as though they were one") run each virtual
leg of a bound with the one-legged hopper's three-part controller: thrust for the hop, foot
placement ẋ T_s/2 + k_ẋ (ẋ − ẋ_d) for the speed, a stance hip servo for the pitch
(gaitopt/models/planar_quadruped_raibert.py, on the Scout II template of Poulakakis,
Papadopoulos & Buehler 2006).  The passive bound of the same body is unstable everywhere the
passive study looked (problems/planar_quadruped.py; at its default, 90 J and 0.6817 m/s,
multipliers 4.12 and 0.616 ± 0.866i).  This study asks:

* **does the controller stabilise the bound at the same energy and speed?**  The controlled
  bound is solved with the thrust δ and the desired speed ẋ_d adjusted (Newton, finite-difference
  Jacobian) until its apex energy ½ m ẋ² + ½ I φ̇² + m g z and its forward speed equal the passive
  default bound's; the two gaits' multipliers are compared;
* **how do the controlled bound's speed, period and multipliers follow the desired speed?**
  Pseudo-arclength continuation in ẋ_d from the default gait (ẋ_d = 1 m/s) both ways, with the
  special points (LP, PD, NS, boundaries) the continuation reports;
* **the pronk** (`planar_quadruped_raibert_pronk`, pitch-free, = raibert_hopper on 2k and 2c):
  its two multipliers continued in the speed gain k_ẋ, where the speed loop period-doubles.

    python problems/planar_quadruped_raibert.py --out results [--fast]

Writes results/planar_quadruped_raibert_study/: speed.csv (one row a gait), branch.json/.csv (the
continuation), pronk_k_speed.json/.csv, summary.json and speed.png.
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
from gaitopt.plotting import save_figure  # noqa: E402


def apex_energy(cycle) -> float:
    """``½ m ẋ² + ½ I φ̇² + m g z`` (J) at the gait's apex (``ż = 0``, no leg on the ground)."""
    m, fp = cycle.model, cycle.fixed_point
    return float(
        0.5 * m.mass * fp["x_dot"] ** 2
        + 0.5 * m.inertia * fp["phi_dot"] ** 2
        + m.mass * m.gravity * fp["z"]
    )


def _moduli(cycle) -> list[float]:
    return sorted((float(abs(z)) for z in cycle.multipliers), reverse=True)


def match_passive(controlled, energy, speed, tol=1e-9, max_iter=12):
    """The controlled bound whose apex energy and forward speed are ``energy`` (J) and ``speed``
    (m/s): Newton on (desired_speed, thrust), Jacobian by forward differences (steps 1e-5 m/s,
    1e-6 m), each gait warm-started from the last.  Returns the gait and the iteration log."""
    target = np.array([energy, speed])

    def solve(p, guess):
        cycle = gaitopt.find_limit_cycle(
            guess.model.replace(desired_speed=p[0], thrust=p[1]), guess
        )
        if not (cycle.success and cycle.verified):
            raise RuntimeError(f"controlled bound lost at {p}: {cycle.message}")
        return np.array([apex_energy(cycle), cycle.fixed_point["x_dot"]]), cycle

    p = np.array([controlled.model.desired_speed, controlled.model.thrust])
    f, cycle = solve(p, controlled)
    log = []
    for _ in range(max_iter):
        err = f - target
        log.append({"desired_speed": p[0], "thrust": p[1], "error": err.tolist()})
        if np.max(np.abs(err)) < tol:
            return cycle, log
        steps = (1e-5, 1e-6)
        jac = np.column_stack(
            [(solve(p + h * e, cycle)[0] - f) / h for h, e in zip(steps, np.eye(2), strict=True)]
        )
        p = p - np.linalg.solve(jac, err)
        f, cycle = solve(p, cycle)
    raise RuntimeError(f"matching did not converge: {log[-1]}")


def _row(cycle, desired) -> list[float]:
    fp = cycle.fixed_point
    mods = _moduli(cycle)
    theta = cycle.model.touchdown_angle(fp["x_dot"])
    return [
        desired,
        fp["x_dot"],
        cycle.period,
        fp["z"],
        fp["phi"],
        fp["phi_dot"],
        apex_energy(cycle),
        theta,
        *mods,
        mods[0],
        int(bool(cycle.stable)),
    ]


HEADER = [
    "desired_speed_m_s",
    "speed_m_s",
    "period_s",
    "z_m",
    "phi_rad",
    "phi_dot_rad_s",
    "apex_energy_J",
    "touchdown_angle_rad",
    "abs_multiplier_0",
    "abs_multiplier_1",
    "abs_multiplier_2",
    "abs_multiplier_3",
    "max_abs_multiplier",
    "stable",
]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "planar_quadruped_raibert_study"
    folder.mkdir(parents=True, exist_ok=True)
    fast = args.fast
    t0 = time.perf_counter()

    model = gaitopt.model("planar_quadruped_raibert")
    gait = gaitopt.find_limit_cycle(model)
    passive = gaitopt.find_limit_cycle(gaitopt.model("planar_quadruped"))
    if not (gait.success and gait.verified and passive.success and passive.verified):
        print(f"no gait at the defaults: {gait.message} / {passive.message}")
        return 1

    # -- the same energy and speed as the passive default bound -------------------------------
    e_passive = float(passive.model.energy)
    v_passive = float(passive.fixed_point["x_dot"])
    matched, log = match_passive(gait, e_passive, v_passive)
    comparison = {
        "energy_J": e_passive,
        "speed_m_s": v_passive,
        "passive": {
            "touchdown_angles_rad": [
                passive.model.back_touchdown_angle,
                passive.model.front_touchdown_angle,
            ],
            "period_s": passive.period,
            "multipliers": [[float(z.real), float(z.imag)] for z in passive.multipliers],
            "abs_multipliers": _moduli(passive),
            "stable": bool(passive.stable),
        },
        "controlled": {
            "desired_speed_m_s": matched.model.desired_speed,
            "thrust_m": matched.model.thrust,
            "apex_energy_J": apex_energy(matched),
            "speed_m_s": float(matched.fixed_point["x_dot"]),
            "touchdown_angle_rad": matched.model.touchdown_angle(matched.fixed_point["x_dot"]),
            "period_s": matched.period,
            "multipliers": [[float(z.real), float(z.imag)] for z in matched.multipliers],
            "abs_multipliers": _moduli(matched),
            "stable": bool(matched.stable),
            "verified": bool(matched.verified),
        },
        "newton": log,
    }

    # -- follow the desired speed ---------------------------------------------------------------
    bounds = (0.5, 1.5) if fast else (-1.0, 8.0)
    t = time.perf_counter()
    branch = gaitopt.continuation(
        model,
        "desired_speed",
        start=gait,
        to=bounds[1],
        bounds=bounds,
        both_directions=True,
        cascade=False,
        options=gaitopt.PseudoArclength(max_step=0.5 if fast else 0.1),
    )
    t_branch = time.perf_counter() - t
    write_json(branch.as_dict(), folder / "branch.json")
    write_csv(*branch.csv_rows(), folder / "branch.csv")
    order = np.argsort(branch.params)
    # Only certified gaits enter the table (a boundary's cycle is the last certified one).
    kept = [i for i in order if branch.cycles[i].success and branch.cycles[i].verified]
    rows = [_row(branch.cycles[i], float(branch.params[i])) for i in kept]
    write_csv(HEADER, rows, folder / "speed.csv")
    table = np.array(rows)
    special = []
    for sp in branch.special_points:
        entry = {"kind": sp.kind, "desired_speed": float(sp.param), "message": sp.message}
        if sp.cycle is not None and sp.cycle.success:
            d = np.asarray(sp.cycle.durations)
            entry.update(
                speed=float(sp.cycle.fixed_point["x_dot"]),
                max_abs_multiplier=_moduli(sp.cycle)[0],
                shortest_phase=sp.cycle.model.phases[int(np.argmin(d))].name,
                shortest_phase_duration=float(d.min()),
            )
        special.append(entry)
    elapsed = time.perf_counter() - t0
    summary = {
        "fast": fast,
        "elapsed_s": elapsed,
        "continuation_s": t_branch,
        "default": {
            "desired_speed_m_s": model.desired_speed,
            "speed_m_s": float(gait.fixed_point["x_dot"]),
            "z_m": float(gait.fixed_point["z"]),
            "phi_dot_rad_s": float(gait.fixed_point["phi_dot"]),
            "period_s": gait.period,
            "apex_energy_J": apex_energy(gait),
            "abs_multipliers": _moduli(gait),
        },
        "matched_to_passive": comparison,
        "branch": {
            "bounds": list(bounds),
            "desired_speed_range": [float(table[0, 0]), float(table[-1, 0])],
            "speed_range": [float(table[:, 1].min()), float(table[:, 1].max())],
            "period_range": [float(table[:, 2].min()), float(table[:, 2].max())],
            "max_abs_multiplier_range": [float(table[:, -2].min()), float(table[:, -2].max())],
            "points": len(rows),
            "uncertified_points_left_out": len(order) - len(kept),
            "stable_points": int(table[:, -1].sum()),
            "special_points": special,
            "message": branch.message,
        },
    }
    write_json(summary, folder / "summary.json")

    # -- the pronk against the speed gain -------------------------------------------------------
    pronk_model = gaitopt.model("planar_quadruped_raibert_pronk")
    pronk = gaitopt.find_limit_cycle(pronk_model)
    if not (pronk.success and pronk.verified):
        print(f"no pronk at the defaults: {pronk.message}")
        return 1
    k_bounds = (0.02, 0.05) if fast else (0.005, 0.12)
    pronk_branch = gaitopt.continuation(
        pronk_model,
        "k_speed",
        start=pronk,
        to=k_bounds[1],
        bounds=k_bounds,
        both_directions=True,
        cascade=False,
        options=gaitopt.PseudoArclength(max_step=0.1 if fast else 0.02),
    )
    write_json(pronk_branch.as_dict(), folder / "pronk_k_speed.json")
    write_csv(*pronk_branch.csv_rows(), folder / "pronk_k_speed.csv")
    summary["pronk"] = {
        "default": {
            "k_speed_s": pronk_model.k_speed,
            "z_m": float(pronk.fixed_point["z"]),
            "speed_m_s": float(pronk.fixed_point["x_dot"]),
            "period_s": pronk.period,
            "multipliers": sorted(float(z.real) for z in pronk.multipliers),
        },
        "k_speed_range": [float(pronk_branch.params.min()), float(pronk_branch.params.max())],
        "special_points": [
            {
                "kind": sp.kind,
                "k_speed": float(sp.param),
                "message": sp.message,
                "multipliers": None
                if sp.cycle is None
                else sorted(float(z.real) for z in sp.cycle.multipliers),
            }
            for sp in pronk_branch.special_points
        ],
        "message": pronk_branch.message,
    }
    summary["elapsed_s"] = time.perf_counter() - t0
    write_json(summary, folder / "summary.json")

    # -- figure ---------------------------------------------------------------------------------
    fig, axes = plt.subplots(1, 5, figsize=(21, 4.2))
    vd = table[:, 0]
    axes[0].plot(vd, table[:, 1], "k-", label="controlled bound")
    axes[0].plot(vd, vd, color="0.6", ls="--", label="ẋ = ẋ_d")
    axes[0].set_ylabel("apex forward speed ẋ (m/s)")
    axes[1].plot(vd, table[:, 2], "k-")
    axes[1].set_ylabel("stride period T (s)")
    for j in range(4):
        axes[2].plot(vd, table[:, 8 + j], ".", ms=3, label=f"|λ_{j}|")
    axes[2].axhline(1.0, color="0.3", ls="--", lw=0.9, label="|λ| = 1")
    axes[2].set_ylabel("multiplier modulus |λ| (1)")
    for ax in axes[:3]:
        ax.set_xlabel("desired speed ẋ_d (m/s)")
        ax.grid(alpha=0.3)
    for sp in special:
        if "speed" in sp:
            axes[0].plot(
                [sp["desired_speed"]],
                [sp["speed"]],
                "ro",
                ms=5,
                label=f"{sp['kind']} ({sp.get('shortest_phase', '')} → 0 s)",
            )
    axes[0].legend(fontsize=8)
    axes[2].legend(fontsize=7)
    ring = np.linspace(0, 2 * np.pi, 200)
    ax = axes[3]
    ax.plot(np.cos(ring), np.sin(ring), color="0.5", lw=0.9)
    lam_p = np.array([complex(*z) for z in comparison["passive"]["multipliers"]])
    lam_c = np.array([complex(*z) for z in comparison["controlled"]["multipliers"]])
    ax.plot(lam_p.real, lam_p.imag, "rx", ms=8, label="passive bound")
    ax.plot(lam_c.real, lam_c.imag, "bo", ms=6, label="Raibert-controlled bound")
    ax.set_aspect("equal")
    ax.set_xlim(-1.5, 4.5)
    ax.set_xlabel("Re λ (1)")
    ax.set_ylabel("Im λ (1)")
    ax.set_title(f"multipliers at {e_passive:g} J, {v_passive:.4g} m/s", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    ax.grid(alpha=0.3)
    ax = axes[4]
    order_k = np.argsort(pronk_branch.params)
    ks = pronk_branch.params[order_k]
    lam = np.array([sorted(z.real for z in pronk_branch.cycles[i].multipliers) for i in order_k])
    ax.plot(ks, lam[:, 0], "k.-", ms=3, label="λ (speed loop)")
    ax.plot(ks, lam[:, 1], "b.-", ms=3, label="λ (height)")
    ax.axhline(-1.0, color="0.3", ls="--", lw=0.9, label="λ = ±1")
    ax.axhline(1.0, color="0.3", ls="--", lw=0.9)
    for sp in pronk_branch.special_points:
        ax.axvline(sp.param, color="r", lw=0.8, label=f"{sp.kind} at k_ẋ = {sp.param:.4g} s")
    ax.set_xlabel("speed gain k_ẋ (s)")
    ax.set_ylabel("pronk multiplier λ (1)")
    ax.set_title("pronk (pitch-free), ẋ_d = 1 m/s", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, folder / "speed.png")

    c = comparison["controlled"]
    print(
        f"matched ({e_passive:g} J, {v_passive:.6g} m/s): passive |λ| "
        f"{np.round(comparison['passive']['abs_multipliers'], 4).tolist()}, controlled |λ| "
        f"{np.round(c['abs_multipliers'], 4).tolist()} (ẋ_d = {c['desired_speed_m_s']:.6g} m/s, "
        f"δ = {c['thrust_m']:.6g} m)"
    )
    b = summary["branch"]
    print(
        f"branch: ẋ_d {b['desired_speed_range']}, ẋ {b['speed_range']}, T {b['period_range']}, "
        f"|λ|max {b['max_abs_multiplier_range']}, stable {b['stable_points']}/{b['points']}, "
        f"special {[(s['kind'], round(s['desired_speed'], 6)) for s in special]}; {b['message']}"
    )
    print(
        f"pronk: default λ {summary['pronk']['default']['multipliers']}, k_ẋ "
        f"{summary['pronk']['k_speed_range']}, special "
        f"{[(s['kind'], round(s['k_speed'], 6)) for s in summary['pronk']['special_points']]}"
    )
    print(f"wrote {folder} in {summary['elapsed_s']:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
