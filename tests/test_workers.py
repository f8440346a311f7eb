"""Parallelism injected as a map (``workers=``, :mod:`gaitopt.workers`): the multi-start finds the
same gaits, in the same order, whatever runs its solves — serially, on a process pool, or through
a caller's map — and a bad ``workers`` is refused before any work."""

from __future__ import annotations

import pytest

import gaitopt
from gaitopt.errors import GaitoptInputError
from gaitopt.workers import serial_map, worker_map


def _square(x: float) -> float:
    return x * x


def test_every_kind_of_workers_maps_in_order():
    # The map's contract (results in the items' order) by direct comparison with Python's map.
    items = [3.0, 1.0, 2.0]
    expected = list(map(_square, items))
    for workers in (1, map, 2):
        with worker_map(workers) as run:
            assert list(run(_square, items)) == expected
    assert serial_map(_square, items) == expected


def test_multi_start_is_the_same_on_a_pool_and_through_a_callers_map():
    # Independent runs of the same seeded search (Garcia et al. 1998, γ = 0.009: two gaits): a
    # pool of two spawned processes and a caller's map reach the same fixed points (bit for bit:
    # the same deterministic solves) and the same counts as the serial run.
    model = gaitopt.model("simplest_walker")
    serial = gaitopt.find_limit_cycle(model, starts=6, seed=0)
    calls = []

    def counting_map(func, items):
        items = list(items)
        calls.append(len(items))
        return map(func, items)

    mapped = gaitopt.find_limit_cycle(model, starts=6, seed=0, workers=counting_map)
    pooled = gaitopt.find_limit_cycle(model, starts=6, seed=0, workers=2)
    assert calls == [6]  # every start went through the caller's map, once
    assert serial.gaits and mapped.gaits == serial.gaits and pooled.gaits == serial.gaits


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({"workers": 0}, "`workers` must be 1"),
        ({"workers": 2.5}, "`workers` must be 1"),
        ({"workers": True}, "`workers` must be 1"),
        ({"workers": 2, "scheduler": "local"}, "choose one"),
    ],
)
def test_bad_workers_are_refused_before_any_work(kwargs, fragment):
    with pytest.raises(GaitoptInputError, match=fragment):
        gaitopt.find_limit_cycle(gaitopt.model("simplest_walker"), starts=2, **kwargs)


def test_optimize_starts_through_a_callers_map_find_the_serial_minima():
    # The same IPOPT runs, each start rebuilt from plain data and sent through the caller's map
    # (gaitopt.optimize.starts.mapped_starts): the serial run's minima to rounding (1e-12
    # relative), every start through the map once.
    level = gaitopt.model("compass_gait", slope=0.0)
    options = dict(period=0.8, step_length=0.3, starts=2, verify=False)
    serial = gaitopt.optimize_gait(level, **options)
    calls = []

    def counting_map(func, items):
        items = list(items)
        calls.append(len(items))
        return [func(item) for item in items]

    mapped = gaitopt.optimize_gait(level, workers=counting_map, **options)
    assert calls == [2]
    assert serial.success and mapped.success, (serial.message, mapped.message)
    assert len(mapped.minima) == len(serial.minima) >= 1
    for a, b in zip(serial.minima, mapped.minima, strict=True):
        assert b.cost == pytest.approx(a.cost, rel=1e-12) and b.starts == a.starts


def test_a_warm_start_is_not_sent_through_a_map():
    level = gaitopt.model("compass_gait", slope=0.0)
    options = dict(period=0.8, step_length=0.3, verify=False)
    gait = gaitopt.optimize_gait(level, **options)
    with pytest.raises(GaitoptInputError, match="warm start is not sent"):
        gaitopt.optimize_gait(level, guess=gait, workers=map, **options)


def test_scheduler_is_an_adapter_onto_a_dask_backed_map():
    # scheduler="local" (a local Dask cluster of two processes) through the same map contract:
    # the results of Python's map, in order.
    items = [3.0, 1.0, 2.0]
    with worker_map(scheduler="local") as run:
        assert list(run(_square, items)) == list(map(_square, items))
