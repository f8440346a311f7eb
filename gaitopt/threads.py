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
the same process keep their threads; an OpenBLAS first loaded during such a call (SciPy's, where
the call first imports ``scipy.linalg``) starts with the call's thread count
(``OPENBLAS_NUM_THREADS`` is set while the call runs) and keeps it.  Parallel work in gaitopt
comes from processes (Dask workers), never from BLAS threads.  ``GAITOPT_BLAS_THREADS=N`` sets
another count, ``0`` leaves BLAS alone.  Limits come from threadpoolctl (the library
scikit-learn uses for the same purpose).

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


class _Limited:
    """The limit of one entry point's call: every BLAS library loaded when it begins limited to
    ``threads`` (threadpoolctl; restored when it ends), and ``OPENBLAS_NUM_THREADS`` set to
    ``threads`` meanwhile, so that an OpenBLAS first loaded during the call (SciPy's, where the
    call first imports ``scipy.linalg``) starts with that many threads: it keeps them after the
    call (there was no caller's setting for it), and starts no idle worker threads.

    SciPy's bundled OpenBLAS is not loaded in advance to be limited: a loaded OpenBLAS starts a
    worker thread per further core, and each spins (``sched_yield``) for about 0.1 s before it
    sleeps, a tenth of a second of CPU that the compass gait's first optimisation, which needs
    no SciPy, would pay for nothing."""

    def __init__(self, controller, threads: int):
        self._controller, self._threads = controller, threads
        self._limiter = None
        self._environment: str | None = None

    def __enter__(self) -> _Limited:
        self._limiter = self._controller.limit(limits=self._threads, user_api="blas")
        self._environment = os.environ.get(_OPENBLAS)
        os.environ[_OPENBLAS] = str(self._threads)
        return self

    def __exit__(self, *exc: object) -> None:
        self._limiter.restore_original_limits()
        if self._environment is None:
            os.environ.pop(_OPENBLAS, None)
        else:
            os.environ[_OPENBLAS] = self._environment


_OPENBLAS = "OPENBLAS_NUM_THREADS"
_scanned = -1  # len(sys.modules) when the controller last listed the loaded libraries


def _limits(threads: int) -> _Limited:
    """The context limiting every loaded BLAS to ``threads`` threads (and any OpenBLAS loaded
    while it holds, :class:`_Limited`)."""
    global _controller, _scanned
    if _controller is None or _scanned != len(sys.modules):
        # libraries come with imported extension modules: list them again after an import
        # (about 0.3 ms), so that one loaded since (SciPy's) is limited and restored too
        from threadpoolctl import ThreadpoolController

        _controller = ThreadpoolController()
        _scanned = len(sys.modules)
    return _Limited(_controller, threads)


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
