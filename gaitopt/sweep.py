"""Sweeps: grids of solves or simulations, on Dask, saved as they finish, resumable.

:func:`sweep` runs a picklable task on every point of a grid — serially, on a local Dask cluster
(the default), or on a running Dask scheduler (``scheduler="tcp://host:8786"``).  Each finished
point is appended at once to a journal (JSON Lines, flushed and fsynced), so an interrupted sweep
loses nothing; run again with the same journal and it computes only the missing points.  The
result is ordered by point index whatever order the points finished in, so the output is
deterministic.

The sweep knows nothing of models: the tasks live with what they run —
:func:`gaitopt.shooting.solve_task` (a limit cycle and its multipliers at given parameters —
stability maps, brute-force branches) and :func:`gaitopt.simulation.simulate_task` (many steps
from a state — orbit diagrams, basins of attraction).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .arguments import check_scheduler
from .errors import GaitoptInputError
from .files import jsonable

__all__ = ["sweep", "SweepResult", "grid"]

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
    scheduler: str | None = None,
    workers: int = 2,
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
    scheduler : str, optional
        ``"serial"`` (in this process), ``None``/``"local"`` (a local Dask cluster of ``workers``
        single-threaded processes), or a Dask scheduler address (``"tcp://host:8786"``).
    workers : int
        Processes of the local cluster.
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
        for index, result in _run(task, points, todo, scheduler, workers):
            result = jsonable(result)
            log.append(index, points[index], result)
            results[index] = result
            computed.append(index)
            bar.update(1)
    return SweepResult(points, results, computed, sorted(reused), path)  # type: ignore[arg-type]


# -- execution ---------------------------------------------------------------------------------
def _run(task: Task, points, todo, scheduler, workers):
    """Yield ``(index, result)`` as points finish."""
    if not todo:
        return
    if scheduler == "serial":
        for i in todo:
            yield i, task(points[i])
        return
    from dask.distributed import Client, LocalCluster, as_completed

    if scheduler in (None, "local"):
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    else:
        cluster, client = None, Client(scheduler)
    try:
        futures = {client.submit(task, points[i], pure=False): i for i in todo}
        for future in as_completed(futures):
            yield futures[future], future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


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

    def append(self, index: int, point: Mapping[str, Any], result: Mapping[str, Any]) -> None:
        if self.handle is not None:
            self._write({"index": index, "point": jsonable(point), "result": result})

    def _write(self, record: Mapping[str, Any]) -> None:
        self.handle.write(json.dumps(record, allow_nan=False) + "\n")
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
