"""BLAS runs single-threaded inside gaitopt's entry points and as before outside them
(gaitopt.threads; measured there: the compass cascade 103 s → 32 s wall on 2 loaded cores)."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import gaitopt
from gaitopt.threads import blas_threads, single_blas_thread


def _blas_threads() -> set[int]:
    return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}


@pytest.mark.parametrize(
    "entry",
    [
        gaitopt.find_limit_cycle,
        gaitopt.continuation,
        gaitopt.optimize_gait,
        gaitopt.basin,
        gaitopt.bifurcation_curve,
        gaitopt.gait_library,
    ],
)
def test_entry_points_are_wrapped(entry):
    assert hasattr(entry, "__wrapped__")


def test_one_thread_inside_and_the_callers_setting_after(monkeypatch):
    monkeypatch.delenv("GAITOPT_BLAS_THREADS", raising=False)
    seen = []

    @single_blas_thread
    def work():
        seen.append(_blas_threads())
        return float(np.linalg.solve(np.eye(3), np.ones(3)).sum())

    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert work() == 3.0
        assert _blas_threads() == before  # restored
    assert seen == [{1}]


def test_environment_overrides(monkeypatch):
    monkeypatch.setenv("GAITOPT_BLAS_THREADS", "0")
    assert blas_threads() == 0
    monkeypatch.setenv("GAITOPT_BLAS_THREADS", "3")
    assert blas_threads() == 3
    monkeypatch.setenv("GAITOPT_BLAS_THREADS", "many")
    assert blas_threads() == 1
