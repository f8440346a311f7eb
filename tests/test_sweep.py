"""Sweeps: Dask and serial agree; an interrupted sweep resumes without losing or repeating."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from gaitopt import GaitoptInputError
from gaitopt.shooting import solve_task
from gaitopt.simulation import simulate_task
from gaitopt.sweep import grid, sweep

POINTS = [
    {
        "model": "compass_gait",
        "params": {"slope": s},
        "x0": {"stance_dot": v},
        "steps": 6,
        "record": 2,
    }
    for s, v in [(0.05, 1.0), (0.06, 1.1), (0.07, 0.9), (0.05, 2.5), (0.06, 0.3), (0.08, 1.2)]
]


def test_grid_is_a_cartesian_product_last_axis_fastest():
    assert grid(a=[1, 2], b=[0.5, 0.25]) == [
        {"a": 1, "b": 0.5},
        {"a": 1, "b": 0.25},
        {"a": 2, "b": 0.5},
        {"a": 2, "b": 0.25},
    ]


def test_dask_and_serial_give_identical_results(tmp_path):
    serial = sweep(simulate_task, POINTS, scheduler="serial", progress=False)
    dask = sweep(
        simulate_task,
        POINTS,
        scheduler="local",
        workers=2,
        progress=False,
        journal=tmp_path / "dask.jsonl",
    )
    assert dask.results == serial.results  # deterministic, in index order
    assert sorted(dask.computed) == list(range(len(POINTS)))
    # the walker falls from some starts and walks from others: not a trivial grid
    assert {r["status"] for r in serial.results} == {"completed", "fell"}


def test_resume_after_a_kill_loses_and_repeats_nothing(tmp_path):
    journal = tmp_path / "sweep.jsonl"
    # Enough points that the kill lands mid-sweep even with the compiled simulator (a few ms a
    # point): the poll below sees three saved points 50 ms apart at most.
    points = [dict(p, steps=40) for p in POINTS] * 30
    script = (
        "import json, sys; from gaitopt.simulation import simulate_task; "
        "from gaitopt.sweep import sweep; "
        f"sweep(simulate_task, json.loads(sys.argv[1]), journal={str(journal)!r}, "
        "scheduler='serial', progress=False)"
    )
    proc = subprocess.Popen([sys.executable, "-c", script, json.dumps(points)])
    try:
        deadline = time.time() + 120
        while time.time() < deadline:
            if journal.exists() and len(journal.read_text().splitlines()) >= 4:  # header + 3
                break
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGKILL)  # an interruption at an arbitrary moment
    finally:
        proc.wait()
    before = {json.loads(line)["index"] for line in journal.read_text().splitlines()[1:]}
    assert 3 <= len(before) < len(points)
    resumed = sweep(simulate_task, points, journal=journal, scheduler="serial", progress=False)
    assert set(resumed.reused) == before
    assert set(resumed.computed).isdisjoint(before)
    assert sorted(resumed.reused + resumed.computed) == list(range(len(points)))
    fresh = sweep(simulate_task, points, scheduler="serial", progress=False)
    assert resumed.results == fresh.results
    indices = [json.loads(line)["index"] for line in journal.read_text().splitlines()[1:]]
    assert sorted(indices) == list(range(len(points)))  # each point saved exactly once


def test_a_torn_last_line_is_ignored_and_recomputed(tmp_path):
    journal = tmp_path / "sweep.jsonl"
    first = sweep(simulate_task, POINTS[:3], journal=journal, scheduler="serial", progress=False)
    with open(journal, "a") as fh:
        fh.write('{"index": 2, "point": {"mod')  # a write cut short
    again = sweep(simulate_task, POINTS[:3], journal=journal, scheduler="serial", progress=False)
    assert again.computed == [] and again.results == first.results
    for line in journal.read_text().splitlines():
        json.loads(line)  # the torn tail was dropped


def test_a_journal_of_another_grid_is_refused(tmp_path):
    journal = tmp_path / "sweep.jsonl"
    sweep(simulate_task, POINTS[:2], journal=journal, scheduler="serial", progress=False)
    with pytest.raises(GaitoptInputError, match="belongs to another sweep"):
        sweep(simulate_task, POINTS[:3], journal=journal, scheduler="serial", progress=False)


def test_solve_task_reports_failures_as_data():
    ok = solve_task({"model": "rimless_wheel", "params": {"slope": 0.08}})
    assert ok["success"] and ok["stable"]
    none = solve_task({"model": "rimless_wheel", "params": {"slope": 0.03}})
    assert not none["success"] and none["stable"] is None


def test_chunked_tasks_give_the_serial_results_and_journal_every_point(tmp_path):
    """Points go to Dask in chunks (issue 23: one task per point made Dask's overhead and a
    fsync per point dominate); the results, their order and the per-point journal are the same
    as serially, whatever the chunk size, and a journal written in chunks resumes per point."""
    serial = sweep(simulate_task, POINTS, scheduler="serial", progress=False)
    journal = tmp_path / "chunked.jsonl"
    chunked = sweep(
        simulate_task,
        POINTS,
        scheduler="local",
        workers=2,
        chunk=4,
        progress=False,
        journal=journal,
    )
    assert chunked.results == serial.results
    lines = journal.read_text().splitlines()
    assert len(lines) == 1 + len(POINTS)  # the header, then one line per point
    assert sorted(json.loads(line)["index"] for line in lines[1:]) == list(range(len(POINTS)))
    # Resume after losing the last chunk's lines: only those points are computed again.
    journal.write_text("\n".join(lines[:-2]) + "\n")
    again = sweep(simulate_task, POINTS, scheduler="serial", progress=False, journal=journal)
    assert again.results == serial.results and len(again.computed) == 2


def test_a_connected_client_is_used_and_left_open(tmp_path):
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster, Client(cluster) as client:  # fmt: skip
        result = sweep(simulate_task, POINTS[:3], scheduler=client, progress=False)
        assert client.status == "running"  # not closed by the sweep
    serial = sweep(simulate_task, POINTS[:3], scheduler="serial", progress=False)
    assert result.results == serial.results


def test_chunk_out_of_range_is_refused():
    with pytest.raises(GaitoptInputError, match="`chunk`"):
        sweep(simulate_task, POINTS, scheduler="serial", chunk=0, progress=False)
