"""problems/slip_rough_terrain.py --fast: the Monte-Carlo survival study on seeded random ground,
its columnar results (survival.npz) against its CSV, its statistics recomputed from the columns,
and its own check of the batched runs against the per-seed closed loop."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from gaitopt.basin import wilson_interval
from tests.helpers import run_study


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    folder = run_study("slip_rough_terrain", tmp_path_factory.mktemp("rough"))
    summary = json.loads((folder / "summary.json").read_text())
    with open(folder / "survival.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    with np.load(folder / "survival.npz") as data:
        columns = {k: data[k] for k in data.files}
    return summary, rows, columns


def test_npz_columns_are_the_csv_rows(study):
    """The columnar file holds the CSV's runs, in order (exact: the CSV's floats are repr, an
    empty cell NaN), each with its controller's target apex."""
    summary, rows, col = study
    assert len(rows) == col["seed"].size
    for i, row in enumerate(rows):
        assert row["controller"] == col["controller"][i]
        assert float(row["amplitude_m"]) == col["amplitude_m"][i]
        assert int(row["seed"]) == col["seed"][i]
        assert int(row["steps_survived"]) == col["steps_survived"][i]
        assert row["ended_by"] == col["ended_by"][i]
        for key in ("rms_apex_error_m", "max_apex_error_m"):
            value = float(row[key]) if row[key] else np.nan
            np.testing.assert_array_equal(value, col[key][i])
        if col["steps_survived"][i] > 1:
            assert col["rms_apex_error_m"][i] <= col["max_apex_error_m"][i]
    passive = col["controller"] == "open loop, passive gait"
    assert np.all(col["target_apex_m"][~passive] == summary["target_apex_m"])
    assert np.all(col["target_apex_m"][passive] == summary["passive_gait"]["z"])


def test_statistics_from_the_columns(study):
    """The summary's survival statistics recomputed from survival.npz: the Wilson interval
    (gaitopt.basin.wilson_interval; its doctest checks the closed form) and the mean's normal
    interval, 1.96 standard errors (numpy's mean and std, to 1e-12)."""
    summary, _, col = study
    steps = summary["steps"]
    for name, by_amp in summary["survival"].items():
        for amp, got in by_amp.items():
            sel = (col["controller"] == name) & (col["amplitude_m"] == float(amp))
            n = col["steps_survived"][sel]
            assert got["runs"] == n.size == summary["seeds"][name]
            assert got["survived_all"] == int(np.sum(n == steps))
            assert got["fraction_ci95"] == pytest.approx(
                wilson_interval(int(np.sum(n == steps)), n.size), rel=1e-12
            )
            half = 1.96 * np.std(n, ddof=1) / np.sqrt(n.size)
            assert got["mean_steps_ci95"] == pytest.approx([n.mean() - half, n.mean() + half],
                                                           rel=1e-12, abs=1e-12)  # fmt: skip


def test_controllers_on_rough_ground(study):
    """Open loop at the unstable gait (multiplier ≈ 1.98, so 3 cm grows past the 0.9–1.25 m
    window within a few steps: Tedrake's SLIP chapter) falls on every ground; LQR, deadbeat and
    the blind swing-leg law keep every seed up at ±2 and ±5 cm; the blind law's apex error is
    the rootfinder's (< 1e-8 m: deadbeat whatever the ground, Ernst, Geyer & Blickhan 2009),
    the deadbeat's that of the ground it does not see (> 1 mm)."""
    summary, _, col = study
    s = summary["survival"]
    for amp in ("0.02", "0.05"):
        assert s["open loop"][amp]["survived_all"] == 0
        assert s["open loop"][amp]["mean_steps"] <= 4
        for name in ("lqr", "deadbeat", "blind"):
            assert s[name][amp]["all_seeds_survived"], (name, amp)
        assert s["blind"][amp]["rms_apex_error_m"] < 1e-8
        assert s["deadbeat"][amp]["median_rms_apex_error_m"] > 1e-3


def test_batch_equals_the_per_seed_loop(study):
    """The study's own check: on the compared seeds, the batched runs survive the same steps as
    gaitopt.control.closed_loop seed by seed, apex heights within 1e-9 m (the tolerance of
    tests/test_closed_loop_batch.py)."""
    summary, _, _ = study
    for name, got in summary["batch_vs_loop"].items():
        assert got["same_steps_survived"], name
        assert got["max_apex_gap_m"] <= 1e-9, name
        assert got["steps_survived_total"] > 0
