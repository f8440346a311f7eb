"""Where a warm verified solve spends its time: ``python -m bench.anatomy``.

A warm :func:`gaitopt.find_limit_cycle` (the model at its defaults, default start, ``verify=True``,
after one untimed call) is timed ``repeats`` times with each stage of the one sequence wrapped by
a timer: the argument checks, the guess's simulation and its nodes, Newton (the one call of the
compiled Newton, :mod:`gaitopt.kernels.newton`, which evaluates the Jacobians inside; or, where
it does not run, the number and time of its Jacobian evaluations from Python: the residual, the
compiled kernels and the assembly, one CasADi call each), the discretisation-error estimate, the
pre-check, the certificate (with the dense samples it reads), the multipliers, the referee's
simulation and the result.  Each stage's CPU time (``time.process_time``: on a shared machine
wall time includes waiting for a core) is the median over the repeats; ``other`` is the median
total less the stages' medians (the Python between them).  The machine's load is recorded beside
the numbers.

With Drake installed, the compass gait's warm verified solve is also set against Drake's
``CompassGait`` simulated from the same start until consecutive post-impact states agree to 1e-8
(default accuracy; the simulation run without its monitor to the settle time, as
:mod:`bench.drake` times it), in rounds of ten solves and one Drake run (``repeats / 10``
rounds) in this process, each in CPU and wall time: the issue's goal of 20×, measured with both
sides under the same load.

``--compare`` also times each model with the compiled Newton iterating on the full folds (as
before the reduced ``foldx`` kernels) and without the compiled Newton (Newton in Python on the
one-call CasADi assembly, the solve as before :mod:`gaitopt.kernels.newton`), in alternation
with it.  Writes ``results/bench_anatomy.json`` (``--out``); ``--quick``: 5 repeats.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import importlib
import json
import statistics
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

__all__ = ["STAGES", "anatomy", "main"]

#: (label, module, attribute path) of each timed stage, in the order a solve runs them; labels
#: starting with two spaces are parts of the stage above them (the compiled Newton's one call,
#: or the Jacobian evaluations from Python where it does not run: the calls with
#: ``jacobian=True``; the residual-only ones count in their stage).
STAGES = (
    ("arguments", "gaitopt.search", "check_arguments"),
    ("guess simulation", "gaitopt.shooting.gait", "simulate"),
    ("guess nodes", "gaitopt.shooting.problem", "ShootingProblem.unknowns_from_simulation"),
    ("Newton", "gaitopt.shooting.problem", "ShootingProblem.solve"),
    ("  compiled Newton (one call)", "gaitopt.kernels.newton", "CompiledNewton.solve"),
    ("  Jacobian evaluations (F, ∂F/∂w)", "gaitopt.kernels.assemble", "Assembly.__call__"),
    ("error estimate", "gaitopt.shooting.transcription", "ShootingTranscription.error_estimate"),
    ("pre-check", "gaitopt.shooting.transcription", "ShootingTranscription.precheck"),
    ("certificate", "gaitopt.orbit.solve", "certificate"),
    ("  dense samples", "gaitopt.shooting.problem", "ShootingProblem.sample_numeric"),
    ("multipliers", "gaitopt.shooting.transcription", "ShootingTranscription.return_map_jacobians"),
    ("referee", "gaitopt.shooting.transcription", "ShootingTranscription.referee"),
    ("result", "gaitopt.shooting.gait", "limit_cycle"),
)


@contextlib.contextmanager
def _timed(spent: dict[str, float], calls: dict[str, int]) -> Iterator[None]:
    """Wrap every stage of :data:`STAGES` with a CPU timer adding to ``spent`` (s) and
    ``calls``; the originals are put back on exit."""
    undo = []
    for label, module_name, path in STAGES:
        owner: Any = importlib.import_module(module_name)
        *parents, name = path.split(".")
        for parent in parents:
            owner = getattr(owner, parent)
        original = owner.__dict__[name] if isinstance(owner, type) else getattr(owner, name)

        def timer(*args: Any, _f: Any = original, _label: str = label, **kwargs: Any) -> Any:
            if _label.startswith("  Jacobian") and not kwargs.get("jacobian", True):
                return _f(*args, **kwargs)
            t0 = time.process_time()
            try:
                return _f(*args, **kwargs)
            finally:
                spent[_label] = spent.get(_label, 0.0) + time.process_time() - t0
                calls[_label] = calls.get(_label, 0) + 1

        setattr(owner, name, functools.wraps(original)(timer))
        undo.append((owner, name, original))
    try:
        yield
    finally:
        for owner, name, original in reversed(undo):
            setattr(owner, name, original)


@contextlib.contextmanager
def _without_compiled_newton() -> Iterator[None]:
    """The solve as before the compiled Newton (:mod:`gaitopt.kernels.newton`): every shooting
    system without it, so Newton runs in Python on the one-call CasADi assembly (put back on
    exit)."""
    from gaitopt.kernels.assemble import Assembly

    original = Assembly.__dict__["compiled_newton"]
    Assembly.compiled_newton = lambda self: None
    try:
        yield
    finally:
        Assembly.compiled_newton = original


@contextlib.contextmanager
def _without_reduced_folds() -> Iterator[None]:
    """The compiled Newton as before the reduced folds (``foldx``,
    :func:`gaitopt.kernels.symbolic.kernel_functions`): every iteration evaluates the full
    ``fold`` (``CompiledNewton.build(asm, reduced=False)``, kept per assembly beside the other;
    put back on exit)."""
    from gaitopt.kernels.assemble import Assembly
    from gaitopt.kernels.newton import CompiledNewton

    original = Assembly.__dict__["compiled_newton"]

    def full(self):
        if "_compiled_newton_full" not in self.__dict__:
            self.__dict__["_compiled_newton_full"] = CompiledNewton.build(self, reduced=False)
        return self.__dict__["_compiled_newton_full"]

    Assembly.compiled_newton = full
    try:
        yield
    finally:
        Assembly.compiled_newton = original


def anatomy(name: str, repeats: int, *, compiled: bool | str = True) -> dict[str, Any]:
    """The stages of ``repeats`` warm verified solves of model ``name`` (see the module
    docstring): medians in ms, calls per solve, the total's median CPU and wall time; with
    ``compiled=False`` as before the compiled Newton (:func:`_without_compiled_newton`), with
    ``compiled="full"`` the compiled Newton without the reduced folds
    (:func:`_without_reduced_folds`)."""
    if compiled is False:
        with _without_compiled_newton():
            return anatomy(name, repeats)
    if compiled == "full":
        with _without_reduced_folds():
            return anatomy(name, repeats)
    import gaitopt

    model = gaitopt.model(name)
    cycle = gaitopt.find_limit_cycle(model)  # warm: kernels loaded, functions built
    per_stage: dict[str, list[float]] = {label: [] for label, _, _ in STAGES}
    calls: dict[str, int] = {}
    cpu, wall = [], []
    with _timed(spent := {}, calls):
        for _ in range(repeats):
            spent.clear()
            t0, c0 = time.perf_counter(), time.process_time()
            cycle = gaitopt.find_limit_cycle(model)
            cpu.append(time.process_time() - c0)
            iterations = cycle.iterations
            wall.append(time.perf_counter() - t0)
            for label in per_stage:
                per_stage[label].append(spent.get(label, 0.0))
    stages = {label: 1e3 * statistics.median(v) for label, v in per_stage.items()}
    top = sum(v for label, v in stages.items() if not label.startswith(" "))
    total = 1e3 * statistics.median(cpu)
    return {
        "success": bool(cycle.success),
        "verified": bool(cycle.verified),
        "repeats": repeats,
        "cpu_ms": total,
        "cpu_min_ms": 1e3 * min(cpu),
        "wall_ms": 1e3 * statistics.median(wall),
        "stages_ms": {**stages, "other": total - top},
        "calls_per_solve": {label: calls.get(label, 0) / repeats for label in per_stage},
        "newton_iterations": iterations,  # Jacobians evaluated (in the compiled call or not)
    }


def compare(name: str, repeats: int, rounds: int = 3) -> dict[str, Any]:
    """:func:`anatomy` with the compiled Newton (``compiled``), with it iterating on the full
    folds (``full``: as before the reduced folds) and without it (``python``) in alternation
    (``rounds`` of each, ``repeats`` solves per round): the medians of the rounds' medians (CPU
    ms), so every side sees the same load."""
    keys = {"cpu": None, "newton": "Newton", "error": "error estimate",
            "multipliers": "multipliers", "certificate": "certificate"}  # fmt: skip
    sides = {"compiled": True, "full": "full", "python": False}
    found: dict[str, list[float]] = {f"{side}_{k}_ms": [] for side in sides
                                     for k in keys}  # fmt: skip
    for _ in range(rounds):
        for side, how in sides.items():
            entry = anatomy(name, repeats, compiled=how)
            for k, label in keys.items():
                value = entry["cpu_ms"] if label is None else entry["stages_ms"][label]
                found[f"{side}_{k}_ms"].append(value)
    return {"rounds": rounds, **{k: statistics.median(v) for k, v in found.items()}}


def versus_drake(repeats: int) -> dict[str, Any] | None:
    """The compass gait's warm verified solve against Drake settling toward 1e-8 (see the
    module docstring), in rounds; None without Drake."""
    import gaitopt

    from .drake import _drake_plain, _drake_settle, _import_drake

    drake, _ = _import_drake()
    if drake is None:
        return None
    model = gaitopt.model("compass_gait")
    x0 = model.lift(model.section_vector({}))
    settle = _drake_settle(drake, model, x0, 1e-4, 1e-8, 200)  # the settle time, untimed
    t_end = settle["simulated_time"]
    gaitopt.find_limit_cycle(model)
    _drake_plain(drake, model, x0, 1e-4, t_end)
    times: dict[str, list[float]] = {"gaitopt_cpu": [], "gaitopt_wall": [], "drake_cpu": [],
                                     "drake_wall": []}  # fmt: skip
    # In rounds of ten solves and one Drake run, each side after an untimed run of its own: a
    # Drake run evicts the solve's data from the caches and ten solves evict Drake's, and each
    # side is timed warm, as bench.run times each in a block of its own.
    for _ in range(max(1, repeats // 10)):
        gaitopt.find_limit_cycle(model)
        for _ in range(10):
            c0, t0 = time.process_time(), time.perf_counter()
            gaitopt.find_limit_cycle(model)
            times["gaitopt_cpu"].append(time.process_time() - c0)
            times["gaitopt_wall"].append(time.perf_counter() - t0)
        _drake_plain(drake, model, x0, 1e-4, t_end)
        c0, t0 = time.process_time(), time.perf_counter()
        _drake_plain(drake, model, x0, 1e-4, t_end)
        times["drake_cpu"].append(time.process_time() - c0)
        times["drake_wall"].append(time.perf_counter() - t0)
    med = {k: 1e3 * statistics.median(v) for k, v in times.items()}
    return {
        "drake_steps": settle["steps"], "drake_settled": settle["settled"],
        "simulated_time_s": t_end, **{f"{k}_ms": v for k, v in med.items()},
        "ratio_cpu": med["drake_cpu"] / med["gaitopt_cpu"],
        "ratio_wall": med["drake_wall"] / med["gaitopt_wall"],
    }  # fmt: skip


def kernel_steps(name: str, calls: int = 2000) -> list[dict[str, float]]:
    """Per phase of model ``name``, the CPU µs of one shooting RK step carrying its derivatives
    (``fold``) and of the same step without them (``step``), each evaluated in its
    ``Function.buffer`` with the arguments in place (no Python per call but the trigger) at the
    default start, median of ``calls``: the arithmetic under a Jacobian evaluation and under the
    dense samples."""
    import numpy as np

    import gaitopt
    from gaitopt.kernels import model_kernels, step_kernels

    model = gaitopt.model(name)
    kern, steps = model_kernels(type(model)), step_kernels(type(model))
    u, p = np.asarray(model.nominal_input(), dtype=float), model.p
    x0 = model.lift({})
    out = []
    for i, fold in enumerate(kern.fold):
        n = kern.n[i]
        x = x0[:n] if i == 0 else np.full(n, 0.1)
        D = np.hstack([np.eye(n), np.zeros((n, fold.size2_in(1) - n))])
        entry = {"states": n, "derivative_columns": int(fold.size2_in(1))}
        timed = [("fold_us", fold, (x, D, u, p, 0.01, 5)),
                 ("step_us", steps[i], (x, u, p, 0.01, 5))]  # fmt: skip
        if kern.foldx[i] is not None:  # the reduced fold Newton iterates with
            Dx = np.hstack([np.eye(n), np.zeros((n, 1))])
            timed.append(("foldx_us", kern.foldx[i], (x, Dx, u, p, 0.01, 5)))
        for label, f, args in timed:
            buffer, trigger = f.buffer()
            keep = [np.array(a, dtype=float).ravel(order="F") for a in args]
            keep += [np.zeros(f.nnz_out(j)) for j in range(f.n_out())]
            for j in range(f.n_in()):
                buffer.set_arg(j, memoryview(keep[j]))
            for j in range(f.n_out()):
                buffer.set_res(j, memoryview(keep[f.n_in() + j]))
            trigger()
            spent = []
            for _ in range(max(1, calls // 20)):  # 20 triggers per reading of the clock
                c0 = time.process_time()
                for _ in range(20):
                    trigger()
                spent.append((time.process_time() - c0) / 20)
            entry[label] = 1e6 * statistics.median(spent)
        out.append(entry)
    return out


def _load() -> list[float]:
    try:
        import os

        return [round(v, 2) for v in os.getloadavg()]
    except OSError:
        return []


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.anatomy", description=__doc__)
    parser.add_argument("--models", nargs="+", default=["compass_gait", "kneed_walker"])
    parser.add_argument("--repeats", type=int, default=60)
    parser.add_argument("--quick", action="store_true", help="5 repeats")
    parser.add_argument("--compare", action="store_true",
                        help="also with the compiled Newton on the full folds (as before the "
                        "reduced ones) and without the compiled Newton (Newton in Python, as "
                        "before it), in alternation with it: three rounds of each")  # fmt: skip
    parser.add_argument("--out", type=Path, default=Path("results/bench_anatomy.json"))
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be ≥ 1, got {args.repeats}")
    repeats = 5 if args.quick else args.repeats
    record: dict[str, Any] = {"load_start": _load(), "repeats": repeats, "models": {}}
    for name in args.models:
        entry = record["models"][name] = anatomy(name, repeats)
        entry["kernel_steps"] = kernel_steps(name)
        print(f"{name}: CPU {entry['cpu_ms']:.2f} ms median (min {entry['cpu_min_ms']:.2f}), "
              f"wall {entry['wall_ms']:.2f} ms, {entry['newton_iterations']} Newton "
              f"iterations")  # fmt: skip
        for label, ms in entry["stages_ms"].items():
            n = entry["calls_per_solve"].get(label)
            print(f"  {label:34s} {ms:7.3f} ms" + (f"  ×{n:g}" if n else ""))
        if args.compare:
            entry["compare"] = compare(name, repeats)
            c = entry["compare"]
            print(f"  compiled Newton vs Newton in Python (medians of {c['rounds']} alternating "
                  f"rounds): whole solve {c['compiled_cpu_ms']:.2f} vs "
                  f"{c['python_cpu_ms']:.2f} ms, Newton {c['compiled_newton_ms']:.3f} vs "
                  f"{c['python_newton_ms']:.3f} ms, error estimate "
                  f"{c['compiled_error_ms']:.3f} vs {c['python_error_ms']:.3f} ms, multipliers "
                  f"{c['compiled_multipliers_ms']:.3f} vs {c['python_multipliers_ms']:.3f} ms, "
                  f"certificate {c['compiled_certificate_ms']:.3f} vs "
                  f"{c['python_certificate_ms']:.3f} ms")  # fmt: skip
            print(
                f"  reduced folds vs full folds in the compiled Newton (the same rounds): "
                f"whole solve {c['compiled_cpu_ms']:.2f} vs {c['full_cpu_ms']:.2f} ms, "
                f"Newton {c['compiled_newton_ms']:.3f} vs {c['full_newton_ms']:.3f} ms"
            )
        for i, k in enumerate(entry["kernel_steps"]):
            reduced = f", Newton's (foldx) {k['foldx_us']:.2f} µs" if "foldx_us" in k else ""
            print(f"  phase {i}: RK step with derivatives {k['fold_us']:.2f} µs{reduced}, "
                  f"without {k['step_us']:.2f} µs")  # fmt: skip
    if "compass_gait" in args.models:
        vs = record["compass_vs_drake"] = versus_drake(repeats)
        if vs is not None:
            print(f"compass gait vs Drake settling toward 1e-8: CPU {vs['gaitopt_cpu_ms']:.2f} "
                  f"vs {vs['drake_cpu_ms']:.1f} ms ({vs['ratio_cpu']:.1f}×), wall "
                  f"{vs['gaitopt_wall_ms']:.2f} vs {vs['drake_wall_ms']:.1f} ms "
                  f"({vs['ratio_wall']:.1f}×)")  # fmt: skip
    record["load_end"] = _load()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=1) + "\n")
    print(f"load {record['load_start']} → {record['load_end']}; wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
