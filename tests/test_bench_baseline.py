"""The hand-written baseline of ``make bench`` is a valid comparison: it finds the published
gaits on its own (no gaitopt machinery), and the benchmark's record is well formed.  No timing
is asserted anywhere."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_json

# The benchmark lives outside the installed package, at the project's root (`python -m bench`).
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from bench import baselines  # noqa: E402
from bench import run as bench  # noqa: E402


def _solve(name: str, start=None) -> baselines.BaselineResult:
    m = gaitopt.model(name)
    hw = baselines.baseline(name, m.params)
    result = baselines.solve(hw, m.section_vector({}) if start is None else np.asarray(start))
    assert result.success, result.message
    return result


def test_compass_gait_baseline_reproduces_design_fixed_point():
    # Source: docs/design.md, reference numbers — compass gait at the defaults (agrees with Drake's
    # CompassGait simulated to convergence); given to 7 digits, so 1e-7.
    r = _solve("compass_gait")
    expected = [-0.2187746, 0.3237746, 1.0928668, 0.3761346]
    assert np.allclose(r.x, expected, rtol=0, atol=1e-7)
    assert math.isclose(r.period, 0.7344606, abs_tol=1e-7)
    assert max(abs(r.multipliers)) < 1  # the passive gait is stable


def test_rimless_wheel_baseline_reproduces_closed_form():
    # Source: Tedrake, Underactuated Robotics, §rimless wheel: ω* = cot 2α sqrt(4 g/l sin α sin γ)
    # (1.095462839648 rad/s at the defaults, docs/design.md); map slope cos² 2α = 0.5 for 8 spokes.
    m = gaitopt.model("rimless_wheel")
    r = _solve("rimless_wheel")
    assert math.isclose(r.fixed_point["theta_dot"], m.rolling_speed(), abs_tol=1e-9)
    assert math.isclose(r.fixed_point["theta_dot"], 1.095462839648, abs_tol=1e-9)
    assert math.isclose(r.multipliers[0].real, math.cos(2 * m.alpha) ** 2, abs_tol=1e-5)


def test_simplest_walker_baseline_reproduces_garcia():
    # Source: Garcia, Chatterjee, Ruina & Coleman 1998, γ = 0.009, long-step gait.
    r = _solve("simplest_walker")
    assert math.isclose(r.fixed_point["theta"], 0.20031090049483, abs_tol=1e-8)
    assert math.isclose(r.fixed_point["theta_dot"], -0.19983247291764, abs_tol=1e-8)


def test_vanderpol_baseline_period():
    # Source: Hairer, Nørsett & Wanner, Solving ODEs I: period 6.6632868593231301897 at μ = 1.
    r = _solve("vanderpol")
    assert math.isclose(r.period, 6.6632868593231301897, abs_tol=1e-8)


def test_models_without_a_baseline_are_skipped():
    assert baselines.baseline("no_such_model", {}) is None


def test_bench_record_and_table(tmp_path):
    # The record and its table; the control and continuation sections (minutes of work) are
    # exercised by `make bench` itself.
    record = bench.run(
        repeats=1,
        built_repeats=1,
        models=["rimless_wheel"],
        peers=False,
        control=False,
        branches=False,
        speed=False,
        basin=False,
        log=lambda s: None,
    )
    record["table"] = bench.rows(record)
    out = tmp_path / "bench.json"
    write_json(record, out)
    data = json.loads(out.read_text())
    entry = data["models"]["rimless_wheel"]
    assert entry["first_call"]["verify_false"]["runs"], entry["first_call"]
    assert entry["baseline"]["error_vs_gaitopt"] < 1e-8
    assert data["machine"]["cpu_count"] >= 1 and data["drake"]["available"] is False
    text = bench.format_table(record)
    assert "solve_ivp + fsolve" in text and "rimless_wheel" in text


def test_basin_throughput_record():
    """bench/basin.py at a tiny size (64 batched starts, 4 looped by the Python backend, 40 by
    the compiled arcs): the record's fields, and the looped starts', the NumPy batch's and the
    compiled batch's other drivers' outcomes equal the compiled batch's (the per-start simulation
    is the referee; no timing is asserted)."""
    from bench.basin import run as basin_run

    record = basin_run(batch=64, loop=4, rounds=1)
    assert record["outcomes_agree_on_loop_starts"] is True
    assert record["numpy_batch"]["outcomes_agree"] is True
    # the exact-math lanes and the scalar driver classify the same starts the same way
    assert all(record["drivers"][d]["outcomes_equal_batch"] for d in ("lanes_exact", "scalar"))
    assert sum(record["batch"]["outcomes"].values()) == 64
    anatomy = record["anatomy"]
    assert anatomy["tries_per_start"] >= 1 and anatomy["step_instructions"] > 0
    assert record["ratio"] > 0 and record["ratio_vs_compiled_loop"] > 0
    assert record["study_10_min"]["starts_one_process"] > 0


def test_optimal_gait_baseline_reaches_the_compass_optimum():
    # The hand-written Hermite–Simpson transcription (bench/optimize.py) against gaitopt's refined
    # optimum 6.668848535 N²·m²·s (README; discretisation error 1.5e-10): on 40 intervals its own
    # O(h⁴) error is 2e-6 relative (6.66886156), so 1e-5; halving h must cut the gap by ~16.
    from bench.optimize import hermite_simpson

    model = gaitopt.model("compass_gait", slope=0.0)
    swap = lambda x: x[[1, 0, 2, 3]]  # noqa: E731 — (stance, swing, rates): legs exchanged
    coarse = hermite_simpson(model, 0.8, 0.3, 40, end=swap)
    fine = hermite_simpson(model, 0.8, 0.3, 80, end=swap)
    reference = 6.668848535
    assert coarse["status"] == "Solve_Succeeded" and fine["status"] == "Solve_Succeeded"
    assert abs(coarse["cost"] - reference) <= 1e-5 * reference
    ratio = abs(coarse["cost"] - reference) / abs(fine["cost"] - reference)
    assert 10 < ratio < 24  # fourth order: 2⁴ = 16
