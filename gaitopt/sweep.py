"""Sweeps: grids of solves or simulations, on Dask, saved as they finish, resumable.

:func:`sweep` runs a picklable task on every point of a grid — serially, on a local Dask cluster
(the default), or on a running Dask scheduler (``scheduler="tcp://host:8786"``).  Each finished
point is appended at once to a journal (JSON Lines, flushed and fsynced), so an interrupted sweep
loses nothing; run again with the same journal and it computes only the missing points.  The
result is ordered by point index whatever order the points finished in, so the output is
deterministic.

Points travel to Dask workers in chunks (``chunk`` points per task, by default about four tasks
per worker), so that Dask's per-task overhead does not dominate short tasks; each finished chunk
is journaled with one fsync, and resumption stays per point.  ``scheduler`` may also be a
connected ``dask.distributed.Client``, e.g. of a batch-system cluster from ``dask-jobqueue``::

    from dask.distributed import Client
    from dask_jobqueue import SLURMCluster

    cluster = SLURMCluster(cores=1, processes=1, memory="2GB", walltime="01:00:00")
    cluster.scale(jobs=32)
    result = sweep(solve_task, points, scheduler=Client(cluster), journal="map.jsonl")

The sweep knows nothing of models: the tasks live with what they run —
:func:`gaitopt.search.solve_task` (a limit cycle and its multipliers at given parameters —
stability maps, brute-force branches) and :func:`gaitopt.simulation.simulate_task` (many steps
from a state — orbit diagrams, basins of attraction).  :func:`dask_map` is the same cluster as a
plain ``map(func, iterable)``, the form in which the multi-starts take their parallelism
(``workers=``, :mod:`gaitopt.workers`).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .arguments import check_count, check_scheduler
from .errors import GaitoptInputError
from .files import jsonable

__all__ = ["sweep", "SweepResult", "grid", "dask_map"]

Task = Callable[[Mapping[str, Any]], Mapping[str, Any]]


@dataclass
class SweepResult:
    """The outcome of :func:`sweep`.

    Attributes
    ----------
    points : list of dict
        The grid, in index order.
    results : list of dict
        The task's result for each point, in index order.
    computed : list of int
        Indices computed in this run.
    reused : list of int
        Indices read back from the journal (finished by an earlier, interrupted run).
    journal : Path or None
        The journal file.
    """

    points: list[dict[str, Any]]
    results: list[dict[str, Any]]
    computed: list[int] = field(default_factory=list)
    reused: list[int] = field(default_factory=list)
    journal: Path | None = None

    def column(self, key: str) -> np.ndarray:
        """One result field over the grid (NaN where missing)."""
        return np.array([r.get(key, np.nan) if r is not None else np.nan for r in self.results])


def grid(**axes: Sequence[Any]) -> list[dict[str, Any]]:
    """The Cartesian product of named axes, last axis fastest: ``grid(a=[1, 2], b=[0, 1])``."""
    names = list(axes)
    mesh = np.meshgrid(*[np.asarray(axes[n]) for n in names], indexing="ij")
    flat = [m.ravel() for m in mesh]
    return [
        {n: _plain(f[i]) for n, f in zip(names, flat, strict=True)} for i in range(flat[0].size)
    ]


def sweep(
    task: Task,
    points: Sequence[Mapping[str, Any]],
    *,
    journal: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int = 2,
    chunk: int | None = None,
    progress: bool = True,
    description: str = "sweep",
) -> SweepResult:
    """Run ``task`` on every point, in parallel, saving each result as it finishes.

    Parameters
    ----------
    task : callable
        ``task(point) -> dict`` (JSON-able); a module-level function, so that it pickles.
    points : sequence of mappings
        The grid (JSON-able values).
    journal : path, optional
        JSON Lines file of finished points.  If it exists and belongs to the same grid, its points
        are not computed again (resume); a journal of another grid is an error.
    scheduler : str or dask.distributed.Client, optional
        ``"serial"`` (in this process), ``None``/``"local"`` (a local Dask cluster of ``workers``
        single-threaded processes), a Dask scheduler address (``"tcp://host:8786"``), or a
        connected ``dask.distributed.Client`` (e.g. of a ``dask_jobqueue.SLURMCluster``; it is
        used, not closed).
    workers : int
        Processes of the local cluster.
    chunk : int, optional
        Points per Dask task (each task runs its points one after another; the journal gets a
        chunk's points with one fsync).  Default: enough points that each of the cluster's
        workers gets about four tasks (at most :data:`MAX_CHUNK` points each), so that a task
        is long against Dask's per-task overhead (its guidance: ≥ ~100 ms) and the work still
        balances.  Resumption stays per point: a journal records each point.  A task with a
        ``batched`` attribute (``task.batched(points)``, equal to ``[task(p) for p in
        points]``: the basin's batch simulations) runs each chunk in one call, and serially
        every point in one call.
    progress : bool
        Show a progress bar (tqdm) on stderr.
    description : str
        Label of the progress bar.

    Returns
    -------
    SweepResult
    """
    points = [dict(p) for p in points]
    check_scheduler(scheduler, serial=True)
    if workers < 1:
        raise GaitoptInputError(f"`workers` must be at least 1, got {workers!r}")
    if chunk is not None:
        chunk = check_count("chunk", chunk, 1, MAX_CHUNK, "a chunk is one task's work")
    fingerprint = _fingerprint(task, points)
    results: list[dict[str, Any] | None] = [None] * len(points)
    reused: list[int] = []
    path = Path(journal) if journal is not None else None
    if path is not None:
        for index, result in _read_journal(path, fingerprint, len(points)).items():
            results[index] = result
            reused.append(index)
    todo = [i for i in range(len(points)) if results[i] is None]
    computed: list[int] = []
    with (
        _Journal(path, fingerprint) as log,
        _progress(len(points), len(reused), progress, description) as bar,
    ):
        for finished in _run(task, points, todo, scheduler, workers, chunk):
            finished = [(index, jsonable(result)) for index, result in finished]
            log.append([(index, points[index], result) for index, result in finished])
            for index, result in finished:
                results[index] = result
                computed.append(index)
            bar.update(len(finished))
    return SweepResult(points, results, computed, sorted(reused), path)  # type: ignore[arg-type]


# -- execution ---------------------------------------------------------------------------------
#: Most points in one Dask task.
MAX_CHUNK = 10_000


def run_chunk(task: Task, chunk: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """One Dask task: ``task`` on each point of ``chunk``, in order (all at once where the task
    has a ``batched`` version: ``task.batched(points)``, equal to ``[task(p) for p in
    points]``, e.g. a batch simulation of every point's starts together)."""
    batched = getattr(task, "batched", None)
    if callable(batched):
        return list(batched(list(chunk)))
    return [task(point) for point in chunk]


def _chunks(todo: list[int], size: int) -> list[list[int]]:
    return [todo[k : k + size] for k in range(0, len(todo), size)]


def _run(task: Task, points, todo, scheduler, workers, chunk):
    """Yield lists of ``(index, result)`` as points (serial) or chunks (Dask) finish."""
    if not todo:
        return
    if scheduler == "serial":
        if callable(getattr(task, "batched", None)):  # every point in one batch
            yield list(zip(todo, run_chunk(task, [points[i] for i in todo]), strict=True))
            return
        for i in todo:
            yield [(i, task(points[i]))]
        return
    from dask.distributed import as_completed

    with _client(scheduler, workers) as client:
        if chunk is None:
            n_workers = max(1, len(client.scheduler_info().get("workers", {})) or workers)
            chunk = min(MAX_CHUNK, max(1, -(-len(todo) // (4 * n_workers))))
        futures = {
            client.submit(run_chunk, task, [points[i] for i in part], pure=False): part
            for part in _chunks(todo, chunk)
        }
        for future in as_completed(futures):
            yield list(zip(futures[future], future.result(), strict=True))


@contextmanager
def _client(scheduler: Any, workers: int) -> Iterator[Any]:
    """A Dask client: of a local cluster of ``workers`` single-threaded processes (``None`` or
    ``"local"``), of the scheduler at an address, or the caller's connected client (left open);
    the ones made here are closed on exit."""
    from dask.distributed import Client, LocalCluster

    cluster, own = None, True
    if scheduler in (None, "local"):
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    elif isinstance(scheduler, str):
        client = Client(scheduler)
    else:  # a connected Client: the caller's, left open
        client, own = scheduler, False
    try:
        yield client
    finally:
        if own:
            client.close()
            if cluster is not None:
                cluster.close()


@contextmanager
def dask_map(scheduler: Any = "local", workers: int = 2) -> Iterator[Callable[..., list[Any]]]:
    """A Dask-backed map, the adapter behind the searches' ``scheduler=``
    (:func:`gaitopt.workers.worker_map`).

    Parameters
    ----------
    scheduler : str or dask.distributed.Client
        ``"local"`` (a local cluster of ``workers`` single-threaded processes), a scheduler
        address (``"tcp://host:8786"``) or a connected client (used, not closed).
    workers : int
        Processes of the local cluster.

    Yields
    ------
    callable
        ``run(func, iterable)``: one Dask task per item, the results in the iterable's order.
    """
    check_scheduler(scheduler)
    with _client(scheduler, workers) as client:

        def run(func: Callable[[Any], Any], items: Iterable[Any]) -> list[Any]:
            return list(client.gather(client.map(func, list(items), pure=False)))

        yield run


# -- the journal -------------------------------------------------------------------------------
class _Journal:
    """Append-only JSON Lines: a header with the grid's fingerprint, then one line per point."""

    def __init__(self, path: Path | None, fingerprint: str):
        self.path, self.fingerprint, self.handle = path, fingerprint, None

    def __enter__(self) -> _Journal:
        if self.path is not None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fresh = not self.path.exists() or self.path.stat().st_size == 0
            self.handle = open(self.path, "a", encoding="utf-8")
            if fresh:
                self._write({"sweep": self.fingerprint})
        return self

    def append(self, finished: Sequence[tuple[int, Mapping[str, Any], Mapping[str, Any]]]) -> None:
        """One line per finished point, written and synced to disk together."""
        if self.handle is not None:
            self._write(
                *({"index": i, "point": jsonable(point), "result": result}
                  for i, point, result in finished)
            )  # fmt: skip

    def _write(self, *records: Mapping[str, Any]) -> None:
        self.handle.write("".join(json.dumps(r, allow_nan=False) + "\n" for r in records))
        self.handle.flush()
        os.fsync(self.handle.fileno())

    def __exit__(self, *exc: object) -> None:
        if self.handle is not None:
            self.handle.close()


def _read_journal(path: Path, fingerprint: str, n: int) -> dict[int, dict[str, Any]]:
    """Finished points of an earlier run; a torn last line (an interrupted write) is ignored."""
    if not path.exists() or path.stat().st_size == 0:
        return {}
    done: dict[int, dict[str, Any]] = {}
    lines = path.read_text(encoding="utf-8").splitlines()
    try:
        header = json.loads(lines[0])
    except json.JSONDecodeError:
        header = {}
    if header.get("sweep") != fingerprint:
        raise GaitoptInputError(
            f"`journal` {str(path)!r} belongs to another sweep (other task or grid); "
            f"use a new journal file or delete this one"
        )
    clean = [lines[0]]
    for line in lines[1:]:
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            break  # torn by an interruption: that point was not finished
        index = int(record["index"])
        if 0 <= index < n:
            done[index] = record["result"]
            clean.append(line)
    if len(clean) < len(lines):  # drop the torn tail so appends stay parseable
        path.write_text("\n".join(clean) + "\n", encoding="utf-8")
    return done


def _fingerprint(task: Task, points: list[dict[str, Any]]) -> str:
    name = f"{getattr(task, '__module__', '')}.{getattr(task, '__qualname__', repr(task))}"
    text = json.dumps([name, jsonable(points)], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class _NoBar:
    def update(self, n: int) -> None:
        pass

    def __enter__(self) -> _NoBar:
        return self

    def __exit__(self, *exc: object) -> None:
        pass


def _progress(total: int, done: int, show: bool, description: str):
    if not show:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, initial=done, desc=description, unit="pt", leave=False)


def _plain(value: Any) -> Any:
    return value.item() if isinstance(value, np.generic) else value
