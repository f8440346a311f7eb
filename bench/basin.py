"""Basin throughput: compass-gait starts classified per second, the batch simulation
(:func:`gaitopt.simulation.batch.simulate_batch`, what :mod:`gaitopt.basin` uses) against the
per-start loop (one :func:`gaitopt.simulate` per start, the referee), in the same run.

The starts are uniform in the box x* ± 0.3 |x*| of ``problems/compass_gait_basin.py`` (seeded),
each simulated for 40 + 5 steps and classified by :mod:`gaitopt.basin`'s rule; the per-start
loop classifies the first ``loop`` of them, whose outcomes must equal the batch's.  Loop and batch
alternate ``rounds`` times (CPU time of this process, since the machine is shared) and the median
round is reported with every round's ratio.  The largest
basin study that fits in 10 minutes is extrapolated from the measured batch rate (one process;
a second worker process on the second core would at most double it — not measured here: the
machine is shared).  An anatomy of the batch's time (the compiled step's share) is recorded.

    python -m bench.basin [--quick] [--out results/bench_basin.json]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

__all__ = ["run"]

_WINDOW = 0.3
_STUDY_S = 600.0


def run(
    *, quick: bool = False, batch: int | None = None, loop: int | None = None, rounds: int = 3
) -> dict:
    """Measure (see the module docstring; ``rounds`` alternations of the loop and the batch, the
    median round reported); the JSON-ready record."""
    import gaitopt
    from gaitopt.basin.checks import check_setup
    from gaitopt.basin.classify import classify, classify_many, model_of
    from gaitopt.simulation import batch_phase

    batch = batch or (1024 if quick else 16384)
    loop = loop or (10 if quick else 40)
    gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    setup = check_setup(gait, 40, 5, 1e-4, None).__dict__
    model = model_of(setup)
    centre = np.asarray(setup["centre"])
    rng = np.random.default_rng(0)
    starts = centre * (1 + _WINDOW * (2 * rng.random((batch, centre.size)) - 1))
    classify_many(setup, model, starts[:8])  # kernels built and loaded, untimed
    classify(setup, model, starts[0])

    measured = []
    for _ in range(rounds):  # loop and batch alternate, so that both see the same load
        t, cpu = time.perf_counter(), time.process_time()
        referee = [classify(setup, model, s) for s in starts[:loop]]
        loop_s = (time.process_time() - cpu) / loop
        loop_wall = (time.perf_counter() - t) / loop
        kernel = {"calls": 0, "seconds": 0.0, "starts": 0}
        batch_total, batch_wall, outcomes = _timed_batch(batch_phase, kernel, setup, model, starts)
        batch_s = batch_total / batch
        measured.append((loop_s / batch_s, loop_s, loop_wall, batch_total, batch_wall, kernel,
                         outcomes[:loop] == referee, outcomes))  # fmt: skip
    ratios = [m[0] for m in measured]
    ratio, loop_s, loop_wall, batch_total, batch_wall, kernel, agree, outcomes = sorted(
        measured, key=lambda m: m[0]
    )[len(measured) // 2]  # the median round
    agree = all(m[6] for m in measured)
    batch_s = batch_total / batch
    per_try = kernel["seconds"] / max(kernel["starts"], 1)
    return {
        "model": "compass_gait",
        "criterion": "40 + 5 steps, within 1e-4 |x*| (gaitopt.basin's rule)",
        "window": f"x* ± {_WINDOW} |x*|, uniform, seed 0",
        "timer": "CPU time of this process (time.process_time): the machine is shared, so wall "
        "time measures the other users too; wall times are given beside",
        "loop": {
            "starts": loop,
            "s_per_start": loop_s,
            "starts_per_s": 1 / loop_s,
            "wall_s_per_start": loop_wall,
        },  # fmt: skip
        "batch": {
            "starts": batch,
            "s_total": batch_total,
            "wall_s_total": batch_wall,
            "s_per_start": batch_s,
            "starts_per_s": 1 / batch_s,
            "outcomes": {o: outcomes.count(o) for o in sorted(set(outcomes))},
        },
        "ratio": loop_s / batch_s,
        "rounds": rounds,
        "ratios_per_round": ratios,
        "goal": 50.0,
        "goal_met": loop_s / batch_s >= 50.0,
        "outcomes_agree_on_loop_starts": agree,
        "anatomy": {
            "step_instructions": _instructions(model),
            "step_tries": kernel["starts"],
            "tries_per_start": kernel["starts"] / batch,
            "compiled_step_s": kernel["seconds"],
            "compiled_step_share": kernel["seconds"] / batch_total,
            "compiled_step_us_per_try": 1e6 * per_try,
            "loop_us_per_try": 1e6 * loop_s / (kernel["starts"] / batch),
            "ratio_bound_by_step": loop_s / (per_try * kernel["starts"] / batch),
        },
        "study_10_min": {
            "starts_one_process": int(_STUDY_S / batch_s),
            "starts_two_processes_at_most": int(2 * _STUDY_S / batch_s),
            "how": f"extrapolated from {batch} measured starts in one process at its CPU rate "
            f"(not run for 10 minutes; on a free core CPU and wall time agree); two worker "
            f"processes at most double it",
        },
    }


def _timed_batch(batch_phase, kernel: dict, setup, model, starts):
    """The batch classification of ``starts`` with the compiled step's calls timed in
    ``kernel``: ``(CPU s, wall s, outcomes)``."""
    from gaitopt.basin.classify import classify_many

    real = batch_phase.Mapped.__call__

    def timed(self, m, *args):  # the compiled step's share of the batch's time
        if self.shared == (3, 5, 6):
            t0 = time.process_time()
            out = real(self, m, *args)
            kernel["seconds"] += time.process_time() - t0
            kernel["calls"] += 1
            kernel["starts"] += m
            return out
        return real(self, m, *args)

    batch_phase.Mapped.__call__ = timed
    try:
        t, cpu = time.perf_counter(), time.process_time()
        outcomes = classify_many(setup, model, starts)
        return time.process_time() - cpu, time.perf_counter() - t, outcomes
    finally:
        batch_phase.Mapped.__call__ = real


def _instructions(model) -> int:
    """Instructions of the compass gait's DOP853 step with its event functions (CasADi SX)."""
    from gaitopt.dop853 import step_function
    from gaitopt.kernels.verify import CHECKS_PER_STEP, phase_events

    phase = model.phases[0]
    return step_function(phase.flow, phase_events(phase, True), CHECKS_PER_STEP).n_instructions()


def main(argv: list[str] | None = None) -> int:
    from gaitopt.files import write_json

    parser = argparse.ArgumentParser(prog="python -m bench.basin", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="1024 batch starts, 10 looped")
    parser.add_argument("--batch", type=int, default=None, help="batch starts (default 16384)")
    parser.add_argument("--out", type=Path, default=Path("results/bench_basin.json"))
    args = parser.parse_args(argv)
    record = run(quick=args.quick, batch=args.batch, rounds=1 if args.quick else 3)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json(record, args.out)
    print(
        f"basin throughput: batch {record['batch']['starts_per_s']:.1f} starts/s, loop "
        f"{record['loop']['starts_per_s']:.2f} starts/s, ratio {record['ratio']:.1f}× "
        f"(goal 50×); compiled step {100 * record['anatomy']['compiled_step_share']:.0f} % of "
        f"the batch; 10 min ≈ {record['study_10_min']['starts_one_process']} starts"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
