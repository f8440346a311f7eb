"""One BLAS thread while gaitopt computes: its linear algebra is many small dense solves.

gaitopt's Newton steps, continuation correctors and Floquet eigenvalue problems factor matrices of
tens to a few hundred rows, thousands of times.  Multithreaded BLAS (OpenBLAS starts one thread per
core) does not speed those up, and on a loaded machine it slows them down badly: waking and
synchronising threads costs more than the work.  Measured on the 2-core development machine under
load, the compass gait's period-doubling cascade to period 8 (``continuation(compass_gait, "slope",
to=0.09)``) took 103 s wall / 38 s CPU with two BLAS threads and 32 s / 7 s with one.

:func:`single_blas_thread` wraps the public entry points (``find_limit_cycle``, ``continuation``,
``bifurcation_curve``, ``optimize_gait``, ``gait_library``, ``basin``): while one runs, the BLAS
libraries loaded in the process (NumPy's and SciPy's OpenBLAS, MKL, ...) use one thread, and the
caller's setting is restored when it returns, so a user's own large matrix products elsewhere in
the same process keep their threads.  Parallel work in gaitopt comes from processes (Dask
workers), never from BLAS threads.  ``GAITOPT_BLAS_THREADS=N`` sets another count, ``0`` leaves
BLAS alone.  Limits come from threadpoolctl (the library scikit-learn uses for the same purpose).

The ``gaitopt`` command is a process of its own: :func:`start_with_blas_threads` (called first
in :func:`gaitopt.cli.main`, whose module imports no NumPy) sets ``OPENBLAS_NUM_THREADS`` (and
MKL's and BLIS's variables) to that count, so the BLAS libraries start with it when they load:
no thread pool is started, and the entry points have nothing left to limit (threadpoolctl's scan
of the loaded libraries, about 10 ms, is skipped).  It does nothing where NumPy is already
imported or the user has set any of those variables.
"""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["single_blas_thread", "blas_threads"]

F = TypeVar("F", bound=Callable[..., Any])

_controller = None
#: The BLAS thread count the process's BLAS libraries were started with by
#: :func:`start_with_blas_threads`, or None.
_started_with: int | None = None
#: The variables BLAS libraries read their thread count from when they load.
_BLAS_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")


def blas_threads() -> int:
    """Threads BLAS may use inside gaitopt's entry points (``GAITOPT_BLAS_THREADS``, default 1;
    0: BLAS is left as it is)."""
    text = os.environ.get("GAITOPT_BLAS_THREADS", "1").strip()
    try:
        value = int(text)
    except ValueError:
        value = 1
    return max(value, 0)


def _load_scipy_blas() -> None:
    """Load SciPy's bundled BLAS library (a wheel's ``scipy.libs/*openblas*.so``) without
    importing :mod:`scipy.linalg` (0.2–0.5 s that a gait's solve may never need): the dynamic
    loader gives SciPy's extension modules this same library when they are imported later, so
    the limit set on it holds for them.  Where SciPy has no such bundled library (a system
    SciPy linked to the system's BLAS), :mod:`scipy.linalg` is imported instead."""
    import ctypes
    import importlib.util
    from pathlib import Path

    import numpy  # noqa: F401  (NumPy's BLAS, loaded by every caller anyway)

    try:
        spec = importlib.util.find_spec("scipy")
        libs = sorted((Path(spec.origin).parent.parent / "scipy.libs").glob("*openblas*.so*"))
        for lib in libs:
            ctypes.CDLL(str(lib))
    except (AttributeError, TypeError, OSError):
        libs = []
    if not libs:
        import scipy.linalg  # noqa: F401


def _limits(threads: int):
    """The threadpoolctl context limiting every loaded BLAS to ``threads`` threads."""
    global _controller
    if _controller is None:
        _load_scipy_blas()  # SciPy's own BLAS: loaded, so that it is limited too
        from threadpoolctl import ThreadpoolController

        _controller = ThreadpoolController()
    return _controller.limit(limits=threads, user_api="blas")


def start_with_blas_threads() -> None:
    """In a process whose BLAS is not loaded yet (no NumPy imported), have every BLAS library
    start with :func:`blas_threads` threads (its environment variable, read when it loads) and
    skip the limits of :func:`single_blas_thread`; nothing where NumPy is imported, the user set
    one of the variables, or ``GAITOPT_BLAS_THREADS=0``.  Meant for a process gaitopt runs
    itself (the ``gaitopt`` command): its children inherit the variables."""
    global _started_with
    threads = blas_threads()
    if threads == 0 or "numpy" in sys.modules or any(v in os.environ for v in _BLAS_VARIABLES):
        return
    for variable in _BLAS_VARIABLES:
        os.environ[variable] = str(threads)
    _started_with = threads


def single_blas_thread(function: F) -> F:
    """Decorate an entry point so that it runs with :func:`blas_threads` BLAS threads (nested
    calls cost one cheap re-limit, about 0.2 ms)."""

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        threads = blas_threads()
        if threads == 0 or threads == _started_with:
            return function(*args, **kwargs)
        with _limits(threads):
            return function(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
