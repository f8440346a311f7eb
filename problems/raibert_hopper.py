"""The planar Raibert hopper: the closed-loop hopping gait, speed tracking, pushes, neutral point.

Sources: Raibert 1986, *Legged Robots That Balance* (MIT Press), ch. 2–3: the three-part
controller — hopping height by a fixed thrust, forward speed by foot placement
``x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d)`` (the neutral point ``ẋ T_s/2`` plus a speed correction), body
attitude by the hip servo in stance; Raibert, Brown & Chepponis 1984, "Experiments in balance
with a 2D one-legged hopping machine" (ASME J. Dyn. Sys. Meas. Control 106).  The model is
``gaitopt.model("raibert_hopper")`` (its docstring states the phases, section and state order).

What it does, at the model's defaults:

1. finds the closed-loop gait (controller in the dynamics) with ``find_limit_cycle``: apex state,
   the four multipliers by AD, checked against central differences of the simulated apex map;
2. tracks a schedule of desired speeds (1.0 → 1.5 → 0.5 m/s, changed per hop through
   ``simulate``'s ``terrain=`` option) and compares each hop's speed with the closed-loop gait at
   that desired speed and the convergence with the speed multiplier;
3. pushes the hopper at an apex (forward speed, pitch rate) and records the distance to the gait
   hop by hop against the slowest multiplier;
4. compares Raibert's neutral-point estimate ``ẋ T_s/2`` (with the expected stance time
   ``π sqrt(M/k)`` and with the gait's actual one) with the actual neutral point — the foot
   placement of the periodic gait, which by definition gives zero net forward acceleration at its
   speed — over desired speeds 0–2 m/s.

Writes ``OUT/raibert_hopper_study/``: ``summary.json``, ``speed_tracking.csv``, ``push.csv``,
``neutral_point.csv``, ``speed_tracking.png``, ``push.png``, ``neutral_point.png``.
``--fast``: shorter schedules and fewer speeds (CI).

Usage::

    python problems/raibert_hopper.py --out results [--fast]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_csv, write_json
from gaitopt.plotting import save_figure

STUDY = "raibert_hopper_study"


def _section(model, sim) -> np.ndarray:
    return np.array([model.section_coordinates_of(x) for x in sim.section_states])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="shorter schedules (CI)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    hopper = gaitopt.model("raibert_hopper")
    coords = hopper.section.coordinates

    # 1. The closed-loop gait and its multipliers (AD vs finite differences of the simulation).
    gait = gaitopt.find_limit_cycle(hopper)
    if not gait.success:
        print(f"raibert_hopper: no gait: {gait.message}", file=sys.stderr)
        return 1
    s0, h = gait.section_point, 1e-6

    def apex_map(s):
        sim = gaitopt.simulate(hopper, hopper.lift(s), steps=1)
        return hopper.section_coordinates_of(sim.section_states[-1])

    fd = np.column_stack(
        [(apex_map(s0 + h * e) - apex_map(s0 - h * e)) / (2 * h) for e in np.eye(len(s0))]
    )
    values, vectors = np.linalg.eig(gait.jacobian)
    speed_mode = int(np.argmax(np.abs(vectors[coords.index("x_dot")])))
    v_gait = gait.fixed_point["x_dot"]

    # 2. Speed tracking: a per-hop schedule of desired speeds.
    hops = (8, 12, 12) if args.fast else (15, 25, 25)
    levels = (1.0, 1.5, 0.5)
    schedule = np.concatenate([np.full(n, v) for n, v in zip(hops, levels, strict=True)])
    sim = gaitopt.simulate(
        hopper,
        gait.x,
        steps=len(schedule),
        terrain=lambda step: {"desired_speed": float(schedule[step])},
    )
    if not sim.success:
        print(f"raibert_hopper: speed schedule failed: {sim.message}", file=sys.stderr)
        return 1
    track = _section(hopper, sim)
    gaits = {v: gaitopt.find_limit_cycle(hopper.replace(desired_speed=v), gait) for v in levels}
    steady = np.array([gaits[v].fixed_point["x_dot"] for v in schedule])
    track_rows = [
        [
            n,
            sim.section_times[n],
            schedule[min(n, len(schedule) - 1)],
            *track[n],
            steady[min(n, len(schedule) - 1)],
        ]
        for n in range(len(track))
    ]
    write_csv(
        ["hop", "t_s", "desired_speed", *coords, "gait_x_dot"],
        track_rows,
        out / "speed_tracking.csv",
    )
    # Observed contraction of the speed error after the 1.0 → 1.5 change (first three hops).
    n1 = hops[0]
    err = track[n1 : n1 + 4, coords.index("x_dot")] - gaits[1.5].fixed_point["x_dot"]
    observed = (err[1:] / err[:-1]).tolist()
    # The same in the modal coordinates of the new gait's Jacobian: each mode by its multiplier.
    new_values, new_vectors = np.linalg.eig(gaits[1.5].jacobian)
    modal = np.linalg.solve(new_vectors, (track[n1 : n1 + 5] - gaits[1.5].section_point).T).real
    new_speed_mode = int(np.argmax(np.abs(new_vectors[coords.index("x_dot")])))
    modal_ratios = (modal[new_speed_mode, 1:] / modal[new_speed_mode, :-1]).tolist()

    # 3. A push at the apex: forward speed +0.3 m/s and pitch rate +2 rad/s.
    push = np.array([0.0, 0.0, 0.3, 2.0])
    n_push = 25 if args.fast else 40
    psim = gaitopt.simulate(hopper, hopper.lift(s0 + push), steps=n_push)
    if not psim.success:
        print(f"raibert_hopper: push not survived: {psim.message}", file=sys.stderr)
        return 1
    dist = np.linalg.norm(_section(hopper, psim) - s0, axis=1)
    slowest = float(np.max(np.abs(values)))
    write_csv(
        ["hop", "distance", "slowest_multiplier_bound"],
        [[n, d, dist[0] * slowest**n] for n, d in enumerate(dist)],
        out / "push.csv",
    )

    # 4. The neutral point: estimate ẋ T_s/2 vs the gait's foot placement.
    speeds = [0.0, 0.5, 1.0, 2.0] if args.fast else list(np.linspace(0.0, 2.0, 9))
    neutral_rows, previous = [], gait
    for vd in speeds:
        model = hopper.replace(desired_speed=float(vd))
        cyc = gaitopt.find_limit_cycle(model, previous)
        if not cyc.success:
            neutral_rows.append([vd, *[float("nan")] * 7])
            continue
        previous = cyc
        v = cyc.fixed_point["x_dot"]
        stance = float(cyc.durations[1])
        x_f = model.foot_placement(v)
        est = model.neutral_point_estimate(v)
        est_actual = model.neutral_point_estimate(v, stance)
        neutral_rows.append(
            [
                vd,
                v,
                x_f,
                est,
                est_actual,
                stance,
                x_f / est if abs(v) > 1e-9 else float("nan"),
                cyc.stable,
            ]
        )
    write_csv(
        [
            "desired_speed",
            "gait_x_dot",
            "foot_placement",
            "estimate_expected_Ts",
            "estimate_actual_Ts",
            "stance_time",
            "placement_over_estimate",
            "stable",
        ],
        neutral_rows,
        out / "neutral_point.csv",
    )

    summary = {
        "model": hopper.name,
        "params": hopper.params,
        "sources": [
            "Raibert 1986, Legged Robots That Balance, ch. 2-3",
            "Raibert, Brown & Chepponis 1984, ASME J. Dyn. Sys. Meas. Control 106",
        ],
        "gait": {
            "fixed_point": gait.fixed_point,
            "period_s": gait.period,
            "durations_s": dict(
                zip(["descent", "stance", "ascent"], gait.durations.tolist(), strict=True)
            ),
            "multipliers": gait.multipliers,
            "stable": gait.stable,
            "verified": gait.verified,
            "ad_vs_fd_jacobian_max_error": float(np.max(np.abs(gait.jacobian - fd))),
            "speed_mode_multiplier": values[speed_mode],
        },
        "speed_tracking": {
            "schedule": {"hops": list(hops), "desired_speeds": list(levels)},
            "gait_speed_by_desired": {str(v): gaits[v].fixed_point["x_dot"] for v in levels},
            "final_speed_by_level": [
                float(track[sum(hops[: i + 1]), coords.index("x_dot")]) for i in range(3)
            ],
            "observed_error_ratios_after_1.0_to_1.5": observed,
            "speed_mode_ratios_after_1.0_to_1.5": modal_ratios,
            "speed_mode_multiplier_at_1.5": new_values[new_speed_mode],
        },
        "push": {
            "push": dict(zip(coords, push.tolist(), strict=True)),
            "hops": n_push,
            "final_distance": float(dist[-1]),
            "slowest_multiplier": slowest,
        },
        "neutral_point": {
            "expected_stance_time_s": hopper.expected_stance_time,
            "gait_stance_time_s": float(gait.durations[1]),
            "at_default": {
                "x_dot": v_gait,
                "foot_placement": hopper.foot_placement(v_gait),
                "estimate": hopper.neutral_point_estimate(v_gait),
            },
        },
        "runtime_s": time.perf_counter() - start,
        "fast": args.fast,
    }
    write_json(summary, out / "summary.json")

    # Figures.
    fig, ax = plt.subplots(figsize=(6.4, 3.6), layout="constrained")
    hop = np.arange(len(track))
    ax.step(hop[:-1], schedule, where="post", color="0.5", label="desired speed ẋ_d")
    ax.step(hop[:-1], steady, "--", where="post", color="C1", label="closed-loop gait's speed")
    ax.plot(hop, track[:, coords.index("x_dot")], "o-", ms=3, color="C0", label="apex speed")
    ax.set(
        xlabel="hop count n (dimensionless)",
        ylabel="forward speed ẋ (m/s)",
        title="Raibert hopper: speed tracking",
    )
    ax.legend(fontsize=8)
    save_figure(fig, out / "speed_tracking.png")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5.6, 3.6), layout="constrained")
    ax.semilogy(dist, "o-", ms=3, label="|apex state − gait|")
    ax.semilogy(dist[0] * slowest ** np.arange(len(dist)), "--", label=f"|λ|max = {slowest:.3f}")
    ax.set(
        xlabel="hop count n (dimensionless)",
        ylabel="distance to the gait (SI units, mixed)",
        title="Recovery from a push (ẋ +0.3 m/s, φ̇ +2 rad/s)",
    )
    ax.legend(fontsize=8)
    save_figure(fig, out / "push.png")
    plt.close(fig)

    rows = np.array([r[:5] for r in neutral_rows], dtype=float)
    fig, ax = plt.subplots(figsize=(5.6, 3.8), layout="constrained")
    ax.plot(rows[:, 1], rows[:, 2], "o-", label="actual neutral point (gait's foot placement)")
    ax.plot(rows[:, 1], rows[:, 3], "s--", label="ẋ T_s/2, T_s = π sqrt(M/k)")
    ax.plot(rows[:, 1], rows[:, 4], "^:", label="ẋ T_s/2, T_s of the gait")
    ax.set(xlabel="gait speed ẋ* (m/s)", ylabel="foot ahead of hip at touchdown (m)")
    ax.set_title("Neutral point: Raibert's estimate vs actual")
    ax.legend(fontsize=8)
    save_figure(fig, out / "neutral_point.png")
    plt.close(fig)

    print(
        f"{STUDY}: gait ẋ* = {v_gait:.4f} m/s, |λ| = "
        f"{', '.join(f'{abs(m):.4f}' for m in gait.multipliers)}; push distance "
        f"{dist[0]:.3g} → {dist[-1]:.3g} in {n_push} hops; written to {out} "
        f"({summary['runtime_s']:.1f} s)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
