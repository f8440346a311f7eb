"""SLIP running on rough terrain: open loop, discrete LQR, deadbeat and blind swing-leg control.

Sources: Tedrake, *Underactuated Robotics*, ch. "Simple models of walking and running", SLIP
section (apex map, deadbeat control of the touchdown angle, rough terrain); Ernst, Geyer &
Blickhan 2009, "Spring-legged locomotion on uneven ground: a control approach to keep the
running speed constant" (the swing-leg angle as a function of time since apex, so that touchdown
at any ground height gives the deadbeat angle); Seyfarth, Geyer & Herr 2003 (swing-leg
retraction); python-control's ``dlqr`` for the LQR gain.

Setup (``gaitopt.model("slip")`` at docs/design.md's defaults, k̃ = 10.7, Ẽ = 1.61): the runner is to
hold the apex height z* = 1.0 m (nominal touchdown angle solved so that z* is a fixed point; the
passive gait there is unstable, multiplier ≈ 1.98).  Every step the ground under the next
touchdown is drawn uniformly within ±A of level (seeded, :func:`gaitopt.terrain.random_terrain`);
no controller knows it.  Each run starts from a perturbed apex, z0 = z* + 3 cm, and lasts
``--steps`` steps or until the runner falls.  Controllers (input: the touchdown angle, kept in
[0, π/2]):

* ``open loop`` — the nominal angle every step;
* ``open loop, passive gait`` — the textbook's stable gait (z = 0.877 m at θ_td = 30°), for
  reference (its target is its own fixed point);
* ``lqr`` — python-control ``dlqr`` on the AD-linearised apex map, Q = R = 1;
* ``deadbeat`` — each step the angle that brings the next apex to z* *on level ground*
  (CasADi rootfinder on the shooting equations);
* ``blind`` — the Ernst/Geyer swing-leg law θ(t since apex), deadbeat for every ground height in
  ±(A + 1 cm) (:func:`gaitopt.terrain.blind_swing_law`).

Measured: steps survived (all seeds), the apex error |z − z*| per step (RMS over the steps after
the first), and, on level ground from z0 = z* + 5 cm, the convergence per step.

Writes ``OUT/slip_rough_terrain/``: ``survival.csv`` (controller, amplitude, seed, steps
survived, RMS error, max error, why it ended), ``convergence.csv`` (controller, step, apex error),
``summary.json``, ``apex_heights.png`` (one seed at A = 5 cm), ``survival.png``,
``convergence.png`` (the passive gait from 3 cm above its fixed point: 5 cm is beyond its
unstable neighbour at 0.917 m).  ``--fast``: 2 amplitudes, 2 seeds, 12 steps.

Usage::

    python problems/slip_rough_terrain.py --out results [--fast]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt import control as gc
from gaitopt import terrain as gt
from gaitopt.files import write_csv, write_json

STUDY = "slip_rough_terrain"
TARGET = 1.0  # m, apex height to hold
START_OFFSET = 0.03  # m, perturbed first apex
# Marker and line style per controller: overlapping curves (deadbeat and blind agree on level
# ground) stay visible.
_STYLES = ("o-", "s--", "^-.", "D:", "v-")
CONTROLLERS = ("open loop", "open loop, passive gait", "lqr", "deadbeat", "blind")


def build(slip):
    """Controller name → (model to simulate, policy, target apex height)."""
    deadbeat = gc.deadbeat(slip, target={"z": TARGET})
    lin = deadbeat.linearisation
    lqr = gc.lqr(lin, Q=1.0, R=1.0)
    passive = gaitopt.find_limit_cycle(slip, {"z": 0.87})
    return {
        "open loop": (slip, lin.nominal_input, TARGET),
        "open loop, passive gait": (slip, passive.inputs, passive.fixed_point["z"]),
        "lqr": (slip, lqr, TARGET),
        "deadbeat": (slip, deadbeat, TARGET),
        "blind": (None, deadbeat, TARGET),
    }, {"deadbeat": deadbeat, "lqr": lqr, "passive": passive}


def run(name, entry, amplitude, seed, steps, slip):
    model, policy, target = entry
    if name == "blind":
        policy = gt.BlindPolicy(policy, heights=(-amplitude - 0.01, amplitude + 0.01))
        model = policy.model()
    terrain = gt.random_terrain(slip, seed, amplitude) if amplitude > 0 else None
    start = {"z": target + START_OFFSET}
    result = gc.closed_loop(
        policy, model, start, steps=steps, terrain=terrain, target=np.array([target])
    )
    return result, terrain


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="2 amplitudes, 2 seeds, 12 steps")
    parser.add_argument("--steps", type=int, default=None, help="steps per run (default 40)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    from gaitopt.plotting import save_figure

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    slip = gaitopt.model("slip")
    amplitudes = (0.02, 0.05) if args.fast else (0.0, 0.02, 0.05, 0.1, 0.15)
    seeds = range(2) if args.fast else range(4)
    steps = args.steps or (12 if args.fast else 40)
    entries, design = build(slip)
    deadbeat = design["deadbeat"]

    # -- survival on random terrain ---------------------------------------------------------------
    rows, runs = [], {}
    for amplitude in amplitudes:
        for name in CONTROLLERS:
            for seed in seeds:
                result, _ = run(name, entries[name], amplitude, seed, steps, slip)
                errors = result.errors[1:]
                rms = float(np.sqrt(np.mean(errors**2))) if errors.size else math.nan
                peak = float(np.max(errors)) if errors.size else math.nan
                why = "" if result.simulation.success else result.simulation.message
                rows.append([name, amplitude, seed, result.survived, rms, peak, why])
                runs[(name, amplitude, seed)] = result
        done = [r for r in rows if r[1] == amplitude]
        print(
            f"A = {amplitude:g} m: "
            + ", ".join(
                f"{n}: {sum(r[3] for r in done if r[0] == n)}/{steps * len(seeds)}"
                for n in CONTROLLERS
            )
        )
    write_csv(
        [
            "controller",
            "amplitude_m",
            "seed",
            "steps_survived",
            "rms_apex_error_m",
            "max_apex_error_m",
            "ended_by",
        ],
        rows,
        out / "survival.csv",
    )

    # -- convergence per step on level ground from a larger perturbation ------------------------
    conv_rows, convergence = [], {}
    for name in CONTROLLERS:
        model, policy, target = entries[name]
        if name == "blind":
            policy = gt.BlindPolicy(policy, heights=(-0.02, 0.02))
            model = policy.model()
        # The passive gait's basin ends at its unstable neighbour (0.917 m): start inside it.
        offset = 0.03 if name == "open loop, passive gait" else 0.05
        result = gc.closed_loop(
            policy, model, {"z": target + offset}, steps=8, target=np.array([target])
        )
        convergence[name] = result.errors
        conv_rows += [[name, k, float(e)] for k, e in enumerate(result.errors)]
    write_csv(["controller", "step", "apex_error_m"], conv_rows, out / "convergence.csv")

    # -- figures ----------------------------------------------------------------------------------
    show_amp = 0.05 if 0.05 in amplitudes else amplitudes[-1]
    fig, (ax, axg) = plt.subplots(
        2,
        1,
        figsize=(7.5, 5.6),
        sharex=True,
        layout="constrained",
        gridspec_kw={"height_ratios": [3, 1]},
    )
    for k, name in enumerate(CONTROLLERS):
        result = runs[(name, show_amp, 0)]
        ax.plot(
            result.section[:, 0],
            _STYLES[k % len(_STYLES)],
            ms=6 - k,
            mfc="none",
            lw=1.0,
            zorder=5 - k,
            color=f"C{k}",
            label=f"{name} ({result.survived} steps)",
        )
    ax.axhline(TARGET, color="k", lw=0.8, ls=":")
    ax.set_ylabel("apex height z (m)")
    ax.set_ylim(0.8, 1.25)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title(
        f"SLIP on random terrain ±{100 * show_amp:g} cm (seed 0), target apex "
        f"{TARGET} m; no controller sees the ground",
        fontsize=9,
    )
    terrain = gt.random_terrain(slip, 0, show_amp)
    axg.step(range(steps), [terrain.value(k) for k in range(steps)], where="post", color="0.3")
    axg.set_ylabel("ground (m)")
    axg.set_xlabel("step count n (dimensionless)")
    axg.grid(alpha=0.3)
    save_figure(fig, out / "apex_heights.png")

    fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
    width = 0.8 / len(CONTROLLERS)
    for k, name in enumerate(CONTROLLERS):
        mean = [np.mean([r[3] for r in rows if r[0] == name and r[1] == a]) for a in amplitudes]
        ax.bar(np.arange(len(amplitudes)) + (k - 2) * width, mean, width, color=f"C{k}", label=name)
    ax.set_xticks(range(len(amplitudes)), [f"±{100 * a:g} cm" for a in amplitudes])
    ax.set_ylabel(f"steps survived (mean of {len(seeds)} seeds, max {steps})")
    ax.set_xlabel("ground height change per step, amplitude (m, shown in cm)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, axis="y")
    save_figure(fig, out / "survival.png")

    fig, ax = plt.subplots(figsize=(6.0, 4.0), layout="constrained")
    for k, name in enumerate(CONTROLLERS):
        e = np.maximum(convergence[name], 1e-13)
        note = " (from +3 cm, inside its basin)" if name == "open loop, passive gait" else ""
        # Distinct markers and dashes: the deadbeat and blind curves coincide where they agree.
        ax.semilogy(
            e,
            _STYLES[k % len(_STYLES)],
            ms=7 - k,
            mfc="none",
            zorder=5 - k,
            color=f"C{k}",
            label=name + note,
        )
    lam = abs(design["lqr"].closed_loop_multipliers[0])
    prediction = f"LQR prediction |λ_cl|ⁿ = {lam:.3f}ⁿ"
    ax.semilogy(0.05 * lam ** np.arange(9), "k--", lw=0.8, label=prediction)
    ax.set_xlabel("step count n (dimensionless)")
    ax.set_ylabel("apex height error |z − z*| (m)")
    ax.set_ylim(1e-13, 1)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("Level ground, first apex 5 cm above the target: convergence per step", fontsize=9)
    save_figure(fig, out / "convergence.png")

    table = {}
    for name in CONTROLLERS:
        for amplitude in amplitudes:
            sel = [r for r in rows if r[0] == name and r[1] == amplitude]
            survived_all = [r for r in sel if r[3] == steps]
            table.setdefault(name, {})[f"{amplitude:g}"] = {
                "steps_survived": [r[3] for r in sel],
                "all_seeds_survived": len(survived_all) == len(sel),
                "rms_apex_error_m": float(np.nanmax([r[4] for r in sel])) if sel else None,
            }
    summary = {
        "study": STUDY,
        "target_apex_m": TARGET,
        "nominal_touchdown_angle_rad": float(deadbeat.nominal_input[0]),
        "open_loop_multiplier": deadbeat.linearisation.open_loop_multipliers[0],
        "lqr_gain": design["lqr"].gain,
        "lqr_closed_loop_multiplier": design["lqr"].closed_loop_multipliers[0],
        "deadbeat_gain_linearised": deadbeat.gain,
        "deadbeat_feasible_range_m": deadbeat.deadbeat_solver.feasible_range(),
        "passive_gait": {
            "z": design["passive"].fixed_point["z"],
            "multiplier": design["passive"].multipliers[0],
        },
        "amplitudes_m": list(amplitudes),
        "seeds": list(seeds),
        "steps": steps,
        "start_offset_m": START_OFFSET,
        "survival": table,
        "convergence_level_ground": {k: list(v) for k, v in convergence.items()},
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - started,
    }
    write_json(summary, out / "summary.json")
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
