"""``python -m gaitopt.kernels --warm [MODEL ...]``: compile (or find in the cache) the shooting
kernels and the verification's DOP853 steps of the built-in models, so that no later call waits
for the compiler."""

from __future__ import annotations

import argparse
import sys
import time

from . import cache_dir, model_kernels
from .verify import verification_steps


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m gaitopt.kernels", description=__doc__)
    parser.add_argument("--warm", action="store_true", help="compile the kernels now")
    parser.add_argument("models", nargs="*", help="model names (default: every registered one)")
    args = parser.parse_args(argv)
    from ..models import REGISTRY

    names = args.models or list(REGISTRY)
    if not args.warm:
        print(f"kernel cache: {cache_dir()}")
        return 0
    for name in names:
        start = time.perf_counter()
        kern = model_kernels(REGISTRY[name])
        verification_steps(REGISTRY[name])  # the verification's DOP853 steps
        how = "none (SX unavailable)" if kern is None else (
            "compiled" if kern.compiled else "interpreted")  # fmt: skip
        print(f"{name:18s} {how:12s} {time.perf_counter() - start:6.2f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
