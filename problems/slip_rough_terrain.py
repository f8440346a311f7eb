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

Measured, as a Monte-Carlo over seeded grounds (:data:`SEEDS` per controller and amplitude: 1000
for the open loops and LQR, 100 for deadbeat, 16 for the blind law — each decision of those is
one and 17 Newton solves; level ground is one run): steps survived, the fraction that survive
every step with its 95 % Wilson interval and the mean steps survived with its 95 % interval, the
apex error |z − z*| per step (RMS over the steps after the first), and, on level ground from
z0 = z* + 5 cm, the convergence per step.  All the seeds of a controller and amplitude run
together (:func:`gaitopt.control.closed_loop_batch`: one batched simulation step for every
runner still up, each on its own ground); on the first :data:`COMPARE` seeds the study runs
them again one by one with :func:`gaitopt.control.closed_loop` and records both times and that
the steps survived are the same (``batch_vs_loop`` in the summary).

Writes ``OUT/slip_rough_terrain/``: ``survival.csv`` and ``survival.npz`` (per run, columnar:
controller, amplitude, seed, steps survived, RMS and max apex error, why it ended, the target
apex height), ``survival_stats.csv`` (per controller and amplitude, with the
intervals), ``convergence.csv`` (controller, step, apex error), ``summary.json``,
``apex_heights.png`` (seed 0 at A = 5 cm), ``survival.png``, ``convergence.png`` (the passive
gait from 3 cm above its fixed point: 5 cm is beyond its unstable neighbour at 0.917 m).
``--fast``: 2 amplitudes, 4 seeds, 12 steps, 2 compared seeds.

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
from gaitopt.basin import wilson_interval
from gaitopt.files import replaced_atomically, write_csv, write_json

STUDY = "slip_rough_terrain"
TARGET = 1.0  # m, apex height to hold
START_OFFSET = 0.03  # m, perturbed first apex
# Marker and line style per controller: overlapping curves (deadbeat and blind agree on level
# ground) stay visible.
_STYLES = ("o-", "s--", "^-.", "D:", "v-")
CONTROLLERS = ("open loop", "open loop, passive gait", "lqr", "deadbeat", "blind")
#: Seeds (random grounds) per controller and amplitude: as many as the study affords in a few
#: minutes — a linear policy costs nothing beside the batch simulation, a deadbeat decision one
#: Newton solve per run and step, the blind swing-leg law 17 of them.
SEEDS = {"open loop": 1000, "open loop, passive gait": 1000, "lqr": 1000, "deadbeat": 100,
         "blind": 16}  # fmt: skip
#: Seeds per controller on which the batch is run against the per-seed loop (timed).
COMPARE = {"open loop": 32, "open loop, passive gait": 32, "lqr": 32, "deadbeat": 8, "blind": 2}
FAST_SEEDS, FAST_COMPARE = 4, 2


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


def policy_for(name, entry, amplitude):
    """(model, policy, target) of a controller on ground within ±``amplitude`` (the blind law
    covers ±(A + 1 cm))."""
    model, policy, target = entry
    if name == "blind":
        policy = gt.BlindPolicy(policy, heights=(-amplitude - 0.01, amplitude + 0.01))
        model = policy.model()
    return model, policy, target


def run_batch(name, entry, amplitude, seeds, steps, slip):
    """Every seed's run on its own ground, stepped together (gaitopt.control.closed_loop_batch)."""
    model, policy, target = policy_for(name, entry, amplitude)
    terrain = [gt.random_terrain(slip, s, amplitude) for s in seeds] if amplitude > 0 else None
    starts = np.full((len(seeds), 1), target + START_OFFSET)
    return gc.closed_loop_batch(policy, model, starts, steps=steps, terrain=terrain,
                                target=[target])  # fmt: skip


def run_loop(name, entry, amplitude, seed, steps, slip):
    """One seed's run (gaitopt.control.closed_loop): the per-seed loop the batch replaces."""
    model, policy, target = policy_for(name, entry, amplitude)
    terrain = gt.random_terrain(slip, seed, amplitude) if amplitude > 0 else None
    return gc.closed_loop(policy, model, {"z": target + START_OFFSET}, steps=steps,
                          terrain=terrain, target=np.array([target]))  # fmt: skip


def statistics(survived: np.ndarray, rms: np.ndarray, steps: int) -> dict:
    """Survival statistics of one controller at one amplitude, with 95 % intervals: the fraction
    of runs that survive every step (Wilson score interval) and the mean steps survived (normal
    approximation, 1.96 standard errors; none for one run)."""
    n = int(survived.size)
    whole = int(np.sum(survived == steps))
    low, high = wilson_interval(whole, n)
    mean = float(np.mean(survived))
    half = 1.96 * float(np.std(survived, ddof=1)) / math.sqrt(n) if n > 1 else math.nan
    finite = rms[np.isfinite(rms)]
    return {
        "runs": n,
        "survived_all": whole,
        "fraction_survived_all": whole / n,
        "fraction_ci95": [low, high],
        "mean_steps": mean,
        "mean_steps_ci95": [mean - half, mean + half],
        "median_steps": float(np.median(survived)),
        "median_rms_apex_error_m": float(np.median(finite)) if finite.size else math.nan,
    }


def compare(name, entry, amplitudes, seeds, steps, slip) -> dict:
    """The batch against the per-seed loop on the same runs: the same steps survived, apex heights
    within 1e-9 m, and the time of each (s)."""
    batch_s = loop_s = 0.0
    same, worst, total = True, 0.0, 0
    for amplitude in amplitudes:
        clock = time.perf_counter()
        batch = run_batch(name, entry, amplitude, seeds, steps, slip)
        batch_s += time.perf_counter() - clock
        clock = time.perf_counter()
        loop = [run_loop(name, entry, amplitude, seed, steps, slip) for seed in seeds]
        loop_s += time.perf_counter() - clock
        for i, run in enumerate(loop):
            same &= bool(batch.survived[i] == run.survived)
            k = min(int(batch.survived[i]), run.survived)
            worst = max(
                worst, float(np.max(np.abs(batch.section[i, : k + 1] - run.section[: k + 1])))
            )
            total += run.survived
    return {
        "seeds": len(seeds),
        "amplitudes_m": list(amplitudes),
        "steps_survived_total": total,
        "same_steps_survived": same,
        "max_apex_gap_m": worst,
        "batch_seconds": batch_s,
        "loop_seconds": loop_s,
        "loop_over_batch_time": loop_s / batch_s,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results", help="results directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="2 amplitudes, 4 seeds, 12 steps")
    parser.add_argument("--steps", type=int, default=None, help="steps per run (default 40)")
    args = parser.parse_args(argv)
    import matplotlib.pyplot as plt

    from gaitopt.plotting import save_figure

    out = Path(args.out) / STUDY
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    slip = gaitopt.model("slip")
    amplitudes = (0.02, 0.05) if args.fast else (0.0, 0.02, 0.05, 0.1, 0.15)
    seeds = {name: range(FAST_SEEDS if args.fast else SEEDS[name]) for name in CONTROLLERS}
    steps = args.steps or (12 if args.fast else 40)
    entries, design = build(slip)
    deadbeat = design["deadbeat"]

    # -- survival on random terrain: every seed of a controller and amplitude in one batch -------
    rows, runs, stats, timing = [], {}, {}, {}
    for amplitude in amplitudes:
        for name in CONTROLLERS:
            # level ground is the same for every seed: one run
            chosen = seeds[name] if amplitude > 0 else range(1)
            clock = time.perf_counter()
            batch = run_batch(name, entries[name], amplitude, chosen, steps, slip)
            timing.setdefault(name, 0.0)
            timing[name] += time.perf_counter() - clock
            rms, peak = batch.apex_errors()
            for i, seed in enumerate(chosen):
                why = "" if batch.success[i] else batch.message(i)
                rows.append([name, amplitude, seed, int(batch.survived[i]), float(rms[i]),
                             float(peak[i]), why])  # fmt: skip
            runs[(name, amplitude)] = batch
            stats.setdefault(name, {})[f"{amplitude:g}"] = statistics(batch.survived, rms, steps)
        print(
            f"A = {amplitude:g} m: "
            + ", ".join(
                f"{n}: {stats[n][f'{amplitude:g}']['survived_all']}/"
                f"{stats[n][f'{amplitude:g}']['runs']} survive"
                for n in CONTROLLERS
            )
        )
    header = ["controller", "amplitude_m", "seed", "steps_survived", "rms_apex_error_m",
              "max_apex_error_m", "ended_by"]  # fmt: skip
    write_csv(header, rows, out / "survival.csv")
    columns = list(zip(*rows, strict=True))
    with replaced_atomically(out / "survival.npz") as tmp, open(tmp, "xb") as fh:
        np.savez_compressed(
            fh,
            controller=np.array(columns[0], dtype=str),
            amplitude_m=np.array(columns[1], dtype=float),
            seed=np.array(columns[2], dtype=int),
            steps_survived=np.array(columns[3], dtype=int),
            rms_apex_error_m=np.array(columns[4], dtype=float),
            max_apex_error_m=np.array(columns[5], dtype=float),
            ended_by=np.array(columns[6], dtype=str),
            target_apex_m=np.concatenate(
                [
                    np.full(len(runs[(n, a)]), runs[(n, a)].target[0])
                    for a in amplitudes
                    for n in CONTROLLERS
                ]
            ),  # fmt: skip
        )
    stat_rows = [
        [name, float(a), *(lambda d: [d["runs"], d["survived_all"], d["fraction_survived_all"],
                                       *d["fraction_ci95"], d["mean_steps"],
                                       *d["mean_steps_ci95"], d["median_steps"],
                                       d["median_rms_apex_error_m"]])(stats[name][a])]
        for name in CONTROLLERS for a in stats[name]
    ]  # fmt: skip
    write_csv(["controller", "amplitude_m", "runs", "survived_all", "fraction_survived_all",
               "fraction_ci95_low", "fraction_ci95_high", "mean_steps", "mean_steps_ci95_low",
               "mean_steps_ci95_high", "median_steps", "median_rms_apex_error_m"], stat_rows,
              out / "survival_stats.csv")  # fmt: skip

    # -- the batch against the per-seed loop, on the same runs ------------------------------------
    rough = [a for a in amplitudes if a > 0]
    speed = {}
    for name in CONTROLLERS:
        count = FAST_COMPARE if args.fast else COMPARE[name]
        speed[name] = compare(name, entries[name], rough, range(count), steps, slip)
        got = speed[name]
        print(
            f"{name}: batch {got['batch_seconds']:.2f} s, loop {got['loop_seconds']:.2f} s "
            f"({got['loop_over_batch_time']:.1f}×), same steps: {got['same_steps_survived']}"
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
        result = runs[(name, show_amp)]  # seed 0: row 0
        survived = int(result.survived[0])
        ax.plot(
            result.section[0, : survived + 1, 0],
            _STYLES[k % len(_STYLES)],
            ms=6 - k,
            mfc="none",
            lw=1.0,
            zorder=5 - k,
            color=f"C{k}",
            label=f"{name} ({survived} steps)",
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

    fig, (ax, axf) = plt.subplots(2, 1, figsize=(6.8, 6.4), sharex=True, layout="constrained")
    width = 0.8 / len(CONTROLLERS)
    for k, name in enumerate(CONTROLLERS):
        got = [stats[name][f"{a:g}"] for a in amplitudes]
        x = np.arange(len(amplitudes)) + (k - 2) * width
        mean = np.array([g["mean_steps"] for g in got])
        ci = np.array([g["mean_steps_ci95"] for g in got]).T
        frac = np.array([g["fraction_survived_all"] for g in got])
        wil = np.array([g["fraction_ci95"] for g in got]).T
        label = f"{name} ({len(seeds[name])} seeds)"
        ax.bar(
            x,
            mean,
            width,
            color=f"C{k}",
            label=label,
            yerr=np.nan_to_num(np.abs(ci - mean)),
            capsize=2,
            error_kw={"lw": 0.8},
        )
        axf.bar(x, frac, width, color=f"C{k}", yerr=np.abs(wil - frac), capsize=2,
                error_kw={"lw": 0.8})  # fmt: skip
    axf.set_xticks(range(len(amplitudes)), [f"±{100 * a:g} cm" for a in amplitudes])
    ax.set_ylabel(f"steps survived n (mean, max {steps})")
    axf.set_ylabel(f"fraction surviving all {steps} steps (1)")
    axf.set_xlabel("ground height change per step, amplitude A (m, shown in cm)")
    ax.set_title("95 % intervals: mean ± 1.96 s.e.; fraction: Wilson (level ground: one run)",
                 fontsize=8)  # fmt: skip
    fig.legend(fontsize=7, loc="outside lower center", ncol=3)
    ax.grid(alpha=0.3, axis="y")
    axf.grid(alpha=0.3, axis="y")
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
            got = stats[name][f"{amplitude:g}"]
            table.setdefault(name, {})[f"{amplitude:g}"] = {
                **got,
                "all_seeds_survived": got["survived_all"] == got["runs"],
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
        "seeds": {name: len(seeds[name]) for name in CONTROLLERS},
        "seeds_level_ground": 1,
        "steps": steps,
        "start_offset_m": START_OFFSET,
        "survival": table,
        "batch_seconds": timing,
        "batch_vs_loop": speed,
        "convergence_level_ground": {k: list(v) for k, v in convergence.items()},
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - started,
    }
    write_json(summary, out / "summary.json")
    print(f"wrote {out} in {summary['elapsed_s']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
