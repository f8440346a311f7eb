"""Compass-gait step-to-step LQR with hip torque: pushes, slope changes, and the unstable
period-1 gait past the period doubling.

Sources: Goswami, Thuilot & Espiau 1996 (the compass gait, its period doubling near slope 0.06–0.09)
and Drake's ``CompassGait`` (conventions, defaults, hip torque ``B = [−1, 1]ᵀ``); Tedrake,
*Underactuated Robotics*, "Simple models of walking" (Poincaré-map linearisation and step-to-step
control); python-control's ``dlqr`` for the gains.

The per-step input is a hip torque held constant over a step, chosen at each heel strike by
``u = −K (s − s*)`` on the section coordinates ``s = (stance, stance_dot, swing_dot)``, with ``K``
from ``dlqr`` on the return map linearised by AD (``A = ∂P/∂s``, ``B = ∂P/∂u``).

(a) The passive gait at slope 0.0525 (stable, |λ| = 0.58):
    * pushes — an instantaneous change of ``swing_dot`` (or ``stance_dot``) just after a heel
      strike: the largest push survived for 20 steps, found by bisection, passive vs LQR;
    * slope changes — the walker steps onto a different slope and stays on it (sustained), or
      the slope under each step is random within ±A (seeded): steps survived of 40.
(b) The period-1 gait at slope 0.09, passively unstable (multiplier ≈ −1.67; the passive walker
    drifts to the period-2 gait): LQR stabilises it; the closed-loop multipliers eig(A − BK) are
    compared with the per-step contraction of the error seen in simulation.

Writes ``OUT/compass_gait_lqr/``: ``pushes.csv``, ``slope_changes.csv``, ``convergence.csv``,
``summary.json``, ``convergence.png``, ``steep_gait.png``, ``pushes.png``.  ``--fast``: coarser
bisection, fewer seeds and steps.

Usage::

    python problems/compass_gait_lqr.py --out results [--fast]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt import control as gc
from gaitopt import terrain as gt
from gaitopt.files import write_csv, write_json

STUDY = "compass_gait_lqr"


def largest_push(model, x_star, policy, state: int, sign: float, steps: int, iterations: int):
    """Bisection on the push size (rad/s) the walker survives for ``steps`` steps."""

    def survives(push: float) -> bool:
        x0 = x_star.copy()
        x0[state] += sign * push
        return gaitopt.simulate(model, x0, steps=steps, inputs=policy).success

    lo, hi = 0.0, 4.0
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if survives(mid) else (lo, mid)
    return lo


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="coarser, fewer runs (CI)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    from gaitopt.plotting import save_figure

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    iterations = 6 if args.fast else 12
    seeds = range(2) if args.fast else range(8)
    long_run = 15 if args.fast else 40

    # -- (a) the passive gait ---------------------------------------------------------------------
    walker = gaitopt.model("compass_gait")
    lin = gc.linearise(walker)
    x_star = lin.cycle.x
    designs = {
        "passive": None,
        "lqr Q=1 R=1": gc.lqr(lin, Q=1.0, R=1.0),
        "lqr Q=100 R=1": gc.lqr(lin, Q=100.0, R=1.0),
    }
    push_rows = []
    for name, policy in designs.items():
        for state, label in ((3, "swing_dot"), (2, "stance_dot")):
            for sign in (+1.0, -1.0):
                push = largest_push(walker, x_star, policy, state, sign, 20, iterations)
                push_rows.append([name, label, "+" if sign > 0 else "-", push])
    write_csv(
        ["controller", "pushed_state", "direction", "largest_push_rad_s"],
        push_rows,
        out / "pushes.csv",
    )
    for row in push_rows:
        print(f"push {row[1]} {row[2]}: {row[0]:<14} survives up to {row[3]:.3f} rad/s")

    slope_rows = []
    for slope in (0.02, 0.035, 0.07, 0.08):
        for name, policy in designs.items():
            sim = gaitopt.simulate(
                walker,
                x_star,
                steps=long_run,
                inputs=policy,
                terrain=lambda k, s=slope: {"slope": s},
            )
            torques = [abs(float(a.u[0])) for a in sim.arcs]
            slope_rows.append(
                [
                    "sustained",
                    slope,
                    "",
                    name,
                    sim.steps,
                    max(torques),
                    "" if sim.success else sim.message,
                ]
            )
    for amplitude in (0.005, 0.01, 0.02):
        for seed in seeds:
            terrain = gt.random_terrain(walker, seed, amplitude)
            for name, policy in designs.items():
                sim = gaitopt.simulate(
                    walker, x_star, steps=long_run, inputs=policy, terrain=terrain
                )
                torques = [abs(float(a.u[0])) for a in sim.arcs]
                slope_rows.append(
                    [
                        "random ±",
                        amplitude,
                        seed,
                        name,
                        sim.steps,
                        max(torques),
                        "" if sim.success else sim.message,
                    ]
                )
    write_csv(
        [
            "kind",
            "slope_or_amplitude",
            "seed",
            "controller",
            "steps_survived",
            "max_torque_Nm",
            "ended_by",
        ],
        slope_rows,
        out / "slope_changes.csv",
    )

    # -- (b) the unstable period-1 gait at slope 0.09 ----------------------------------------------
    steep = gc.linearise(gaitopt.model("compass_gait", slope=0.09))
    steep_lqr = gc.lqr(steep, Q=1.0, R=1.0)
    rho = float(np.abs(steep_lqr.closed_loop_multipliers).max())
    x0 = steep.cycle.x + np.array([1e-4, -1e-4, 0.0, 0.0])
    steps_b = 20 if args.fast else 30
    passive_run = gc.closed_loop(None, steep.model, x0, steps=steps_b, target=steep_lqr.target)
    lqr_run = gc.closed_loop(steep_lqr, steep.model, x0, steps=steps_b)
    fit = slice(5, min(steps_b, 25))
    tail = np.log(lqr_run.errors[fit])
    contraction = float(np.exp(np.polyfit(np.arange(tail.size), tail, 1)[0]))
    conv_rows = [
        [
            k,
            float(passive_run.errors[k]) if k < len(passive_run.errors) else None,
            float(lqr_run.errors[k]),
            1e-4 * rho**k,
        ]
        for k in range(len(lqr_run.errors))
    ]
    write_csv(
        ["step", "passive_error", "lqr_error", "predicted_rho_pow_n"],
        conv_rows,
        out / "convergence.csv",
    )

    # -- figures -----------------------------------------------------------------------------------
    fig, ax = plt.subplots(figsize=(6.0, 4.0), layout="constrained")
    ax.semilogy(passive_run.errors, "o-", ms=3, label="passive (drifts to the period-2 gait)")
    ax.semilogy(lqr_run.errors, "s-", ms=3, label="LQR (hip torque per step)")
    k = np.arange(len(lqr_run.errors))
    ax.semilogy(
        k, lqr_run.errors[0] * rho**k, "k--", lw=0.8, label=f"max |eig(A − BK)|ⁿ = {rho:.4f}ⁿ"
    )
    ax.set_xlabel("step")
    ax.set_ylabel("max-norm distance to the period-1 gait")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(
        f"Compass gait, slope 0.09: open-loop multiplier "
        f"{steep.open_loop_multipliers[0].real:.3f}; fitted contraction "
        f"{contraction:.4f}",
        fontsize=9,
    )
    save_figure(fig, out / "convergence.png")

    fig, ax = plt.subplots(figsize=(6.0, 3.6), layout="constrained")
    ax.plot(passive_run.section[:, 0], "o-", ms=3, label="passive")
    ax.plot(lqr_run.section[:, 0], "s-", ms=3, label="LQR")
    ax.set_xlabel("step")
    ax.set_ylabel("stance angle after heel strike (rad)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(
        "Slope 0.09: the passive walker alternates (period 2), LQR holds period 1", fontsize=9
    )
    save_figure(fig, out / "steep_gait.png")

    fig, ax = plt.subplots(figsize=(6.4, 3.8), layout="constrained")
    labels = sorted({(r[1], r[2]) for r in push_rows})
    width = 0.8 / len(designs)
    for j, name in enumerate(designs):
        values = [
            next(r[3] for r in push_rows if r[0] == name and (r[1], r[2]) == lab) for lab in labels
        ]
        ax.bar(np.arange(len(labels)) + (j - 1) * width, values, width, label=name)
    ax.set_xticks(range(len(labels)), [f"{a} {b}" for a, b in labels])
    ax.set_ylabel("largest push survived (rad/s)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    ax.set_title("Compass gait, slope 0.0525: pushes just after heel strike (20 steps)", fontsize=9)
    save_figure(fig, out / "pushes.png")

    summary = {
        "study": STUDY,
        "passive_gait": {
            "fixed_point": lin.cycle.fixed_point,
            "multipliers": lin.open_loop_multipliers,
        },
        "designs": {
            name: None
            if c is None
            else {
                "gain": c.gain,
                "closed_loop_multipliers": c.closed_loop_multipliers,
                "Q": c.weights["Q"],
                "R": c.weights["R"],
            }
            for name, c in designs.items()
        },
        "pushes": [
            dict(zip(("controller", "state", "direction", "largest"), r, strict=True))
            for r in push_rows
        ],
        "slope_changes": [
            dict(
                zip(
                    ("kind", "value", "seed", "controller", "steps", "max_torque", "ended_by"),
                    r,
                    strict=True,
                )
            )
            for r in slope_rows
        ],
        "steep": {
            "slope": 0.09,
            "open_loop_multipliers": steep.open_loop_multipliers,
            "gain": steep_lqr.gain,
            "closed_loop_multipliers": steep_lqr.closed_loop_multipliers,
            "largest_closed_loop_modulus": rho,
            "simulated_contraction": contraction,
            "steps_survived_lqr": lqr_run.survived,
            "passive_final_error": float(passive_run.errors[-1]),
        },
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - started,
    }
    write_json(summary, out / "summary.json")
    print(
        f"slope 0.09: open loop {steep.open_loop_multipliers[0].real:.4f}; closed loop max "
        f"|λ| = {rho:.4f}, simulated contraction {contraction:.4f}"
    )
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
