"""Basin throughput: compass-gait starts classified per second by the compiled batch simulation
(:func:`gaitopt.simulation.batch.simulate_batch`, ``backend="compiled"``, what :mod:`gaitopt.basin`
uses: every start run to its end in one C call) against two per-start loops, one
:func:`gaitopt.simulate` per start, in the same run and at the same tolerances (rtol 1e-11,
atol 1e-12):

* ``loop_compiled``: :func:`gaitopt.simulate`'s default backend, each arc one compiled call
  (:mod:`gaitopt.simulation.compiled`) with Python per arc and per start;
* ``loop_python``: ``backend="python"``, SciPy's DOP853 stepper driven from Python, what a
  user's per-start ``solve_ivp`` loop does (the brute-force loop).

The starts are uniform in the box x* ± 0.3 |x*| of ``problems/compass_gait_basin.py`` (seeded),
each simulated for 40 + 5 steps and classified by :mod:`gaitopt.basin`'s rule; each loop
classifies the first of them, whose outcomes must equal the batch's.  The three alternate
``rounds`` times (CPU time of this process, since the machine is shared; the load is recorded)
and the median round is reported with every round's ratios.  The NumPy batch
(``backend="numpy"``, stepped from Python; the previous method) is timed once on a subset, with
its compiled step's share (the anatomy: step tries per start and µs per try).  The largest basin
study that fits in 10 minutes is extrapolated from the measured batch rate, or with ``--study N``
run: N starts in blocks, on ``--workers`` processes.

    python -m bench.basin [--quick] [--study N --workers 2] [--out results/bench_basin.json]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

__all__ = ["run", "study"]

_WINDOW = 0.3
_STUDY_S = 600.0


def _setup():
    import gaitopt
    from gaitopt.basin.checks import check_setup
    from gaitopt.basin.classify import model_of

    gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    setup = check_setup(gait, 40, 5, 1e-4, None).__dict__
    return setup, model_of(setup)


def _box(setup, count: int, seed: int = 0) -> np.ndarray:
    centre = np.asarray(setup["centre"])
    rng = np.random.default_rng(seed)
    return centre * (1 + _WINDOW * (2 * rng.random((count, centre.size)) - 1))


def run(
    *,
    quick: bool = False,
    batch: int | None = None,
    loop: int | None = None,
    rounds: int = 3,
) -> dict:
    """Measure (see the module docstring; ``rounds`` alternations of the two loops and the batch,
    the median round reported); the JSON-ready record."""
    from gaitopt.basin import classify as basin_classify
    from gaitopt.basin.classify import classify, classify_many

    batch = batch or (2048 if quick else 16384)
    loop = loop or (8 if quick else 40)
    setup, model = _setup()
    starts = _box(setup, batch)
    classify_many(setup, model, starts[:8])  # kernels built and loaded, untimed
    classify(setup, model, starts[0])
    classify(setup, model, starts[0], backend="python")
    loads = [os.getloadavg()[0]]

    def timed(f):
        t, cpu = time.perf_counter(), time.process_time()
        out = f()
        return time.process_time() - cpu, time.perf_counter() - t, out

    for lanes, math in _DRIVERS.values():  # every driver's kernels built and loaded, untimed
        with _driver(lanes, math):
            classify_many(setup, model, starts[:8])

    measured = []
    for _ in range(rounds):  # the loops and the batch alternate: all see the same load
        py = timed(lambda: [classify(setup, model, s, backend="python") for s in starts[:loop]])
        co = timed(lambda: [classify(setup, model, s) for s in starts[: 10 * loop]])
        ba = timed(lambda: classify_many(setup, model, starts))
        drivers: dict = {}
        for name, (lanes, math) in _DRIVERS.items():  # the batch's other drivers
            with _driver(lanes, math):
                got = timed(lambda: classify_many(setup, model, starts))
            drivers[name] = (got[0] / batch, got[2] == ba[2])
        loads.append(os.getloadavg()[0])
        per = (py[0] / loop, co[0] / (10 * loop), ba[0] / batch)
        agree = ba[2][:loop] == py[2] and ba[2][: 10 * loop] == co[2]
        measured.append({"python": per[0], "compiled": per[1], "batch": per[2],
                         "walls": (py[1] / loop, co[1] / (10 * loop), ba[1]),
                         "agree": agree, "outcomes": ba[2],
                         "drivers": {k: v[0] for k, v in drivers.items()},
                         "drivers_agree": {k: v[1] for k, v in drivers.items()}})  # fmt: skip
    ratios_py = [m["python"] / m["batch"] for m in measured]
    ratios_co = [m["compiled"] / m["batch"] for m in measured]
    median = sorted(measured, key=lambda m: m["python"] / m["batch"])[len(measured) // 2]
    outcomes = median["outcomes"]
    batch_s = median["batch"]
    # the NumPy batch, once, on a subset: its rate and anatomy (the compiled step's share)
    from gaitopt.simulation import batch_phase

    subset = starts[: min(batch, 2048)]
    kernel = {"calls": 0, "seconds": 0.0, "starts": 0}
    old = basin_classify.BACKEND
    basin_classify.BACKEND = "numpy"
    try:
        numpy_total, _, numpy_out = _timed_batch(batch_phase, kernel, setup, model, subset)
    finally:
        basin_classify.BACKEND = old
    tries = kernel["starts"] / len(subset)
    per_try = kernel["seconds"] / max(kernel["starts"], 1)
    ratio_py, ratio_co = median["python"] / batch_s, median["compiled"] / batch_s
    return {
        "model": "compass_gait",
        "criterion": "40 + 5 steps, within 1e-4 |x*| (gaitopt.basin's rule)",
        "window": f"x* ± {_WINDOW} |x*|, uniform, seed 0",
        "tolerances": "rtol 1e-11, atol 1e-12 (every method)",
        "timer": "CPU time of this process (time.process_time): the machine is shared, so wall "
        "time measures the other users too; wall times are given beside",
        "load_1min": loads,
        "loop_python": {
            "what": "gaitopt.simulate(backend='python') per start: SciPy's DOP853 stepper driven "
            "from Python (a user's per-start solve_ivp loop)",
            "starts": loop,
            "s_per_start": median["python"],
            "starts_per_s": 1 / median["python"],
            "wall_s_per_start": median["walls"][0],
        },
        "loop_compiled": {
            "what": "gaitopt.simulate() per start (default backend: each arc one compiled call)",
            "starts": 10 * loop,
            "s_per_start": median["compiled"],
            "starts_per_s": 1 / median["compiled"],
            "wall_s_per_start": median["walls"][1],
        },
        "batch": {
            "what": "classify_many: simulate_batch(backend='compiled'), blocks of "
            "gaitopt.basin.classify.BLOCK starts per C call",
            "starts": batch,
            "s_total": batch_s * batch,
            "wall_s_total": median["walls"][2],
            "s_per_start": batch_s,
            "starts_per_s": 1 / batch_s,
            "outcomes": {o: outcomes.count(o) for o in sorted(set(outcomes))},
        },
        "drivers": {
            "what": "the same batch through the compiled batch's drivers (median round): "
            "lanes_fast is what classify_many runs (gaitopt.kernels.lane_driver, "
            f"{_lanes()} starts per vector step call, libmvec sin/cos), lanes_exact the same with "
            "the C library's sin/cos per lane (the scalar step's bits), scalar the driver of one "
            "start at a time (gaitopt_batch)",
            "vector_isa_flags": _isa(),
            **{name: _driver_record(median, measured, name) for name in _DRIVERS},
        },
        "numpy_batch": {
            "what": "simulate_batch(backend='numpy') (stepped from NumPy), once, on a subset",
            "starts": len(subset),
            "s_per_start": numpy_total / len(subset),
            "starts_per_s": len(subset) / numpy_total,
            "outcomes_agree": numpy_out == outcomes[: len(subset)],
        },
        "ratio": ratio_py,
        "ratio_baseline": "loop_python (the brute-force per-start loop)",
        "ratio_vs_compiled_loop": ratio_co,
        "rounds": rounds,
        "ratios_per_round": ratios_py,
        "ratios_vs_compiled_loop_per_round": ratios_co,
        "goal": 50.0,
        "goal_met": ratio_py >= 50.0,
        "outcomes_agree_on_loop_starts": all(m["agree"] for m in measured),
        "anatomy": {
            "step_instructions": _instructions(model),
            "tries_per_start": tries,
            "compiled_step_us_per_try_mapped": 1e6 * per_try,
            "step_s_per_start_mapped": per_try * tries,
            "batch_s_per_start": batch_s,
            "how": "step tries counted and the compiled step timed in the NumPy batch on the "
            "subset (the same algorithm takes the same tries); the compiled batch calls the same "
            "step once per try",
        },
        "study_10_min": {
            "starts_one_process": int(_STUDY_S / batch_s),
            "starts_two_processes_at_most": int(2 * _STUDY_S / batch_s),
            "how": f"extrapolated from {batch} measured starts in one process at its CPU rate "
            f"(not run for 10 minutes; on a free core CPU and wall time agree); two worker "
            f"processes at most double it",
        },
    }


#: The batch's drivers timed beside classify_many's (lanes with libmvec sin/cos): name →
#: (GAITOPT_LANES, GAITOPT_VECTOR_MATH).
_DRIVERS = {"lanes_exact": ("1", "exact"), "scalar": ("0", "exact")}


@contextmanager
def _driver(lanes: str, math: str):
    """The compiled batch's driver chosen through its environment variables, restored after."""
    old = {k: os.environ.get(k) for k in ("GAITOPT_LANES", "GAITOPT_VECTOR_MATH")}
    os.environ["GAITOPT_LANES"], os.environ["GAITOPT_VECTOR_MATH"] = lanes, math
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _driver_record(median: dict, measured: list[dict], name: str) -> dict:
    per = median["drivers"][name]
    return {"starts_per_s": 1 / per, "s_per_start": per,
            "ratio_vs_loop_python": median["python"] / per,
            "outcomes_equal_batch": all(m["drivers_agree"][name] for m in measured)}  # fmt: skip


def _lanes() -> int:
    from gaitopt.kernels.vector_step import LANES

    return LANES


def _isa() -> list[str]:
    from gaitopt.kernels.vector_step import host_flags

    return list(host_flags())


def _study_block(args) -> tuple[dict, float]:
    """One worker's share of a study: ``(outcome counts, CPU s)``."""
    from gaitopt.basin.classify import classify_many

    first, count, block = args
    setup, model = _setup()
    cpu = time.process_time()
    counts: dict[str, int] = {}
    for k in range(first, first + count, block):
        n = min(block, first + count - k)
        for o in classify_many(setup, model, _box(setup, n, seed=1 + k // block)):
            counts[o] = counts.get(o, 0) + 1
    return counts, time.process_time() - cpu


def study(starts: int, workers: int = 2, block: int = 65536) -> dict:
    """A basin study of ``starts`` compass-gait starts (uniform in the box, seeded per block)
    classified by the compiled batch on ``workers`` processes: outcomes, wall and CPU time."""
    from concurrent.futures import ProcessPoolExecutor

    blocks = [(k, min(block, starts - k), block) for k in range(0, starts, block)]
    shares = [blocks[w::workers] for w in range(workers)]
    t = time.perf_counter()
    load = os.getloadavg()[0]
    with ProcessPoolExecutor(workers) as pool:
        done = list(pool.map(_study_share, shares))
    wall = time.perf_counter() - t
    counts: dict[str, int] = {}
    for c, _ in done:
        for o, v in c.items():
            counts[o] = counts.get(o, 0) + v
    cpu = sum(s for _, s in done)
    return {"starts": starts, "workers": workers, "wall_s": wall, "cpu_s": cpu,
            "starts_per_wall_s": starts / wall, "starts_per_cpu_s": starts / cpu,
            "load_1min_before": load, "load_1min_after": os.getloadavg()[0],
            "outcomes": dict(sorted(counts.items())),
            "fits_in_10_min": wall <= _STUDY_S}  # fmt: skip


def extrapolate(record: dict) -> None:
    """Add to ``record["study_10_min"]`` the starts 10 minutes hold at the study run's CPU rate,
    on one free core and on two (its worker processes share nothing but the machine)."""
    run_ = record["study_run"]
    rate = run_["starts_per_cpu_s"]
    record["study_10_min"]["from_study_run"] = {
        "starts_one_core": int(_STUDY_S * rate),
        "starts_two_cores": int(2 * _STUDY_S * rate),
        "wall_s_for_1e6_on_two_free_cores": 1e6 / (2 * rate),
        "how": f"the study run's CPU rate ({run_['starts']} starts, {run_['cpu_s']:.0f} s CPU) "
        f"on free cores (its wall time, {run_['wall_s']:.0f} s, was set by the shared machine's "
        f"load, {run_['load_1min_before']:.0f}–{run_['load_1min_after']:.0f})",
    }


def _study_share(blocks) -> tuple[dict, float]:
    counts: dict[str, int] = {}
    cpu = 0.0
    for b in blocks:
        c, s = _study_block(b)
        cpu += s
        for o, v in c.items():
            counts[o] = counts.get(o, 0) + v
    return counts, cpu


def _timed_batch(batch_phase, kernel: dict, setup, model, starts):
    """The batch classification of ``starts`` with the compiled step's calls timed in
    ``kernel``: ``(CPU s, wall s, outcomes)``."""
    from gaitopt.basin.classify import classify_many

    real = batch_phase.Mapped.__call__

    def timed(self, m, *args):  # the compiled step's share of the batch's time
        if self.shared == (3, 6):  # the DOP853 step (batch_phase._Phase.step)
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
    parser.add_argument("--quick", action="store_true", help="2048 batch starts, 8 looped")
    parser.add_argument("--batch", type=int, default=None, help="batch starts (default 16384)")
    parser.add_argument("--study", type=int, default=0, help="also run a study of N starts")
    parser.add_argument("--workers", type=int, default=2, help="the study's processes")
    parser.add_argument("--out", type=Path, default=Path("results/bench_basin.json"))
    args = parser.parse_args(argv)
    record = run(quick=args.quick, batch=args.batch, rounds=1 if args.quick else 3)
    if args.study:
        record["study_run"] = study(args.study, args.workers)
        extrapolate(record)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json(record, args.out)
    print(
        f"basin throughput: compiled batch {record['batch']['starts_per_s']:.0f} starts/s; "
        f"per-start loop, Python backend {record['loop_python']['starts_per_s']:.1f} starts/s "
        f"({record['ratio']:.1f}×, goal 50×), compiled arcs "
        f"{record['loop_compiled']['starts_per_s']:.0f} starts/s "
        f"({record['ratio_vs_compiled_loop']:.2f}×); exact-math lanes "
        f"{record['drivers']['lanes_exact']['starts_per_s']:.0f}, scalar driver "
        f"{record['drivers']['scalar']['starts_per_s']:.0f} starts/s; 10 min ≈ "
        f"{record['study_10_min']['starts_one_process']} starts in one process"
    )
    if args.study:
        s = record["study_run"]
        print(f"study: {s['starts']} starts in {s['wall_s']:.0f} s wall ({s['cpu_s']:.0f} s CPU, "
              f"{s['workers']} processes): {s['outcomes']}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
