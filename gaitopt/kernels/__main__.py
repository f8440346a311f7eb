"""``python -m gaitopt.kernels --warm [--jobs N] [MODEL ...]``: compile (or find in the cache) the
shooting kernels (and their RK steps without derivatives; the compiled Newton's library), the
verification's DOP853 steps, the certificate's checks, the compiled simulation's arc libraries,
the batch simulation's driver and functions and, for a model with inputs, the optimiser's node
kernels and flow Jacobians (:func:`gaitopt.optimize.collocation.warm_kernels`) of the built-in
models, so that no later call waits for the compiler.  ``--jobs`` compiles that many models at
once (default: the number of CPUs); the cache is safe for concurrent compiles."""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time
from concurrent.futures import ProcessPoolExecutor


def _cpu() -> float:
    """CPU seconds of this process and its finished children (the compiler)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def _warm(name: str) -> tuple[str, str, float, float]:
    """Compile (or load) one registered model's kernels; ``(name, how, seconds, CPU
    seconds)``."""
    from ..models import REGISTRY
    from . import model_kernels, step_kernels
    from .verify import verification_steps

    start, cpu = time.perf_counter(), _cpu()
    kern = model_kernels(REGISTRY[name])
    if kern is not None:
        step_kernels(REGISTRY[name])  # the RK steps without derivatives (residual alone)
        from .newton import driver

        driver()  # the compiled Newton (one library for every model and mesh)
    verification_steps(REGISTRY[name])  # the verification's DOP853 steps
    from .checks import check_kernels

    check_kernels(REGISTRY[name])  # the certificate's guards, rules and constraints
    from .arcs import arc_library

    arc_library(REGISTRY[name])  # the compiled simulation's arcs
    from .batch_driver import batch_library

    batch_library()  # the compiled batch's driver (one library for every model)
    from ..simulation.batch_events import compiled_functions

    compiled_functions(REGISTRY[name])  # the batch simulation's guards, resets, locators
    if REGISTRY[name].inputs:  # the optimiser's node kernels and flow Jacobians
        from ..optimize.collocation import warm_kernels

        warm_kernels(REGISTRY[name]())
    how = "none (SX unavailable)" if kern is None else (
        "compiled" if kern.compiled else "interpreted")  # fmt: skip
    return name, how, time.perf_counter() - start, _cpu() - cpu


def main(argv: list[str] | None = None) -> int:
    from . import cache_dir

    parser = argparse.ArgumentParser(prog="python -m gaitopt.kernels", description=__doc__)
    parser.add_argument("--warm", action="store_true", help="compile the kernels now")
    parser.add_argument(
        "--jobs", type=int, default=os.cpu_count() or 1, help="models compiled at once"
    )
    parser.add_argument("models", nargs="*", help="model names (default: every registered one)")
    args = parser.parse_args(argv)
    from ..models import REGISTRY

    names = args.models or list(REGISTRY)
    unknown = [n for n in names if n not in REGISTRY]
    if unknown:
        parser.error(f"unknown model {unknown[0]!r}; models: {', '.join(REGISTRY)}")
    if not args.warm:
        print(f"kernel cache: {cache_dir()}")
        return 0
    if args.jobs <= 1 or len(names) == 1:
        for result in map(_warm, names):
            _report(*result)
        return 0
    # The slowest compiles first, so that the pool does not end waiting on one of them.
    slow = ("five_link_biped", "kneed_walker", "strandbeest")
    order = sorted(names, key=lambda n: n not in slow)
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for result in pool.map(_warm, order):
            _report(*result)
    return 0


def _report(name: str, how: str, seconds: float, cpu: float) -> None:
    print(f"{name:18s} {how:12s} {seconds:6.2f} s (CPU {cpu:6.2f} s)", flush=True)


if __name__ == "__main__":
    sys.exit(main())
