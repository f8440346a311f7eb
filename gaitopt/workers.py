"""Parallelism as a map: the ``workers=`` of the multi-starts.

A search that runs many independent solves (the multi-start of :func:`gaitopt.find_limit_cycle`,
the starts of :func:`gaitopt.optimize_gait`, a gait library's cold checks) takes its parallelism
as an argument, as SciPy's ``differential_evolution(workers=...)`` does: ``workers=1`` runs the
solves one after another in this process, an integer ``n > 1`` on a local pool of ``n``
processes (``-1``: one per CPU), and any callable ``map(func, iterable)`` — e.g.
``multiprocessing.Pool(4).map`` or a Dask client's map — is used as given.  The older
``scheduler=`` (``"local"`` or a Dask scheduler address) is a thin adapter onto a Dask-backed
map (:func:`gaitopt.sweep.dask_map`).

:func:`worker_map` resolves the two into one map-like callable, a context manager so that a pool
or cluster it starts is shut down when the search ends.  The searches only ever call that map:
none of them knows which runs their tasks.

A pool's processes are spawned (each imports gaitopt afresh), so a script that passes
``workers=n`` runs its work under ``if __name__ == "__main__":``, as with any spawned pool.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import Any

from .arguments import check_scheduler
from .errors import GaitoptInputError

__all__ = ["Map", "check_workers", "serial_map", "worker_map"]

#: A map-like callable: ``run(func, iterable)`` → the results of ``func`` on each item, in order.
Map = Callable[[Callable[[Any], Any], Iterable[Any]], Iterable[Any]]


def serial_map(func: Callable[[Any], Any], items: Iterable[Any]) -> list[Any]:
    """``func`` on each item, one after another in this process (``workers=1``)."""
    return [func(item) for item in items]


def check_workers(workers: object, scheduler: object = None) -> None:
    """Refuse a ``workers`` that is not ``1``, a positive integer, ``-1`` or a map-like
    callable, and ``workers`` other than 1 together with a ``scheduler`` (one or the other)."""
    check_scheduler(scheduler)
    if callable(workers):
        pass
    elif (
        isinstance(workers, bool)
        or not isinstance(workers, int)
        or not (workers >= 1 or workers == -1)
    ):
        raise GaitoptInputError(
            f"`workers` must be 1 (serial), a number of processes (-1: one per CPU) or a "
            f"map-like callable map(func, iterable), got {workers!r:.80}; e.g. workers=4"
        )
    if scheduler is not None and workers != 1:
        raise GaitoptInputError(
            f"`workers` ({workers!r:.80}) and `scheduler` ({scheduler!r:.80}) both given: "
            f"choose one (a Dask scheduler is a kind of workers)"
        )


@contextmanager
def worker_map(workers: int | Map = 1, scheduler: Any = None) -> Iterator[Map]:
    """The map that runs a search's tasks (see the module docstring).

    Parameters
    ----------
    workers : int or callable
        ``1``: serial in this process; ``n > 1``: a pool of ``n`` spawned processes (``-1``: one
        per CPU); a callable: used as ``workers(func, iterable)``.
    scheduler : str or dask.distributed.Client, optional
        A Dask scheduler instead (``"local"``, an address, or a connected client):
        :func:`gaitopt.sweep.dask_map`.

    Yields
    ------
    callable
        ``run(func, iterable)`` returning the results in the iterable's order.  Tasks sent to a
        pool or cluster must pickle (module-level functions, plain data).
    """
    check_workers(workers, scheduler)
    if scheduler is not None:
        from .sweep import dask_map

        with dask_map(scheduler) as run:
            yield run
    elif callable(workers):
        yield lambda func, items: list(workers(func, items))
    elif workers == 1:
        yield serial_map
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        count = (os.cpu_count() or 1) if workers == -1 else workers
        # Spawned, not forked: a fork of a process with CasADi's and BLAS's threads may hang.
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=count, mp_context=context) as pool:
            yield lambda func, items: list(pool.map(func, items))
