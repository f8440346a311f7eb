"""The lane driver (gaitopt.kernels.lane_driver: 8 starts in flight, one vector step call per
round) against the scalar batch driver (gaitopt_batch, one start at a time; the reference,
itself tested against gaitopt.simulate in test_simulation_batch.py): with the vector steps'
exact math (the C library's sin/cos per lane) every column and every recorded event equal to the
last bit — the same scalar control code per lane and a vector step that gives each lane the
scalar step's bits (test_vector_step.py) — on compass-gait starts that walk, fall and trip,
invalid rows, phase time limits too short for a step (timeouts), rimless-wheel starts that rock
to rest (standing) or roll on, the kneed walker's two phases of different sizes, without the
unilateral constraints, with an input per start, with event buffers that overflow, with a
parameter vector per start (dims[8], p_stride), and on every registered passive model.

With libmvec's sin/cos (math "fast", at most 4 ulp from the correctly rounded value by glibc's
manual, against the C library's 1 ulp) the bits differ; the outcomes must not: the same status
and steps for every start, and the section states of the starts that complete within 1e-10
(absolute, state units; measured 1.2e-12 at most over these 45-step compass starts: a last-bit
difference changes the step sizes, and the integrator keeps each step's error near its rtol
1e-11 — test_simulation_batch.py's TOL for the same effect)."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.kernels.cache import compiler
from gaitopt.kernels.vector_step import vector_steps
from gaitopt.simulation import batch_compiled
from gaitopt.simulation.batch import simulate_batch

pytestmark = pytest.mark.skipif(compiler() is None, reason="no C compiler")

_COLUMNS = ("status", "outcome", "steps", "section_times", "section_states", "t_end",
            "phase_end", "accumulation_time")  # fmt: skip


def _run(model, starts, monkeypatch, lanes: bool, math: str = "exact", **options):
    monkeypatch.setenv("GAITOPT_LANES", "1" if lanes else "0")
    monkeypatch.setenv("GAITOPT_VECTOR_MATH", math)
    if lanes:  # the lane driver is what runs
        assert batch_compiled._lanes(type(model), options.get("constraints", True), model.p.size)
    return simulate_batch(model, starts, backend="compiled", **options)


def _bitwise(model, starts, monkeypatch, **options) -> list[str]:
    """Lanes and scalar driver: every column and event equal to the bit.  The statuses."""
    lanes = _run(model, starts, monkeypatch, True, **options)
    scalar = _run(model, starts, monkeypatch, False, **options)
    for column in _COLUMNS:
        a, b = np.asarray(getattr(lanes, column)), np.asarray(getattr(scalar, column))
        assert a.tobytes() == b.tobytes() if a.dtype.kind == "f" else np.array_equal(a, b), column
    if options.get("record_events"):
        for key in scalar.events:
            a, b = np.asarray(lanes.events[key]), np.asarray(scalar.events[key])
            assert a.tobytes() == b.tobytes() if a.dtype.kind == "f" else np.array_equal(a, b)
    return scalar.status.tolist()


def _compass_starts(model, count: int, seed: int) -> np.ndarray:
    centre = model.section_vector(model.default_start())
    rng = np.random.default_rng(seed)
    return centre * (1 + 0.3 * (2 * rng.random((count, centre.size)) - 1))


def test_lanes_equal_the_scalar_driver_on_compass_starts(monkeypatch):
    compass = gaitopt.model("compass_gait")
    starts = _compass_starts(compass, 90, seed=11)
    starts[[3, 40]] = np.nan  # invalid rows, in the middle of the lanes' intake
    found = set(_bitwise(compass, starts, monkeypatch, steps=12, record_events=True))
    assert {"completed", "fell", "invalid start"} <= found
    short = _bitwise(compass, starts[:20], monkeypatch, steps=2, max_phase_time=0.05)
    assert "timeout" in short
    _bitwise(compass, starts[:30], monkeypatch, steps=4, constraints=False, record_events=True)
    torques = np.random.default_rng(3).normal(0.0, 0.5, (30, 1))  # an input per start
    _bitwise(compass, starts[:30], monkeypatch, steps=4, inputs=torques)
    zero = _bitwise(compass, starts[:10], monkeypatch, steps=0)  # no step asked: ends at once
    assert set(zero) <= {"completed", "invalid start"}


def test_lanes_equal_the_scalar_driver_on_the_rimless_wheel_and_the_kneed_walker(monkeypatch):
    wheel = gaitopt.model("rimless_wheel")
    rows = np.array([[0.5], [-0.5], [2.0], [0.3], [1.0], [-0.2], [0.8], [1.5], [0.1], [0.6]])
    assert {"standing", "completed"} <= set(
        _bitwise(wheel, rows, monkeypatch, steps=40, record_events=True)
    )
    kneed = gaitopt.model("kneed_walker")
    centre = kneed.section_vector(kneed.default_start())
    rng = np.random.default_rng(2)
    starts = centre * (1 + 0.1 * (2 * rng.random((12, centre.size)) - 1))
    _bitwise(kneed, starts, monkeypatch, steps=3, record_events=True)


def test_lanes_run_again_the_starts_whose_events_overflow(monkeypatch):
    compass = gaitopt.model("compass_gait")
    starts = _compass_starts(compass, 12, seed=4)
    ample = _bitwise(compass, starts, monkeypatch, steps=20, record_events=True)
    monkeypatch.setattr(batch_compiled, "EVENTS_PER_STEP", 0)  # room for 8 events per start
    assert _bitwise(compass, starts, monkeypatch, steps=20, record_events=True) == ample


def test_fast_math_gives_the_same_outcomes(monkeypatch):
    compass = gaitopt.model("compass_gait")
    if vector_steps(type(compass), "fast").math != "fast":
        pytest.skip("no libmvec (glibc on x86-64)")
    starts = _compass_starts(compass, 64, seed=9)
    fast = _run(compass, starts, monkeypatch, True, "fast", steps=45)
    exact = _run(compass, starts, monkeypatch, False, steps=45)
    assert fast.status.tolist() == exact.status.tolist()
    assert fast.steps.tolist() == exact.steps.tolist()
    done = exact.status == "completed"
    assert done.any()
    assert fast.section_states[done].tobytes() != exact.section_states[done].tobytes()
    np.testing.assert_allclose(fast.section_states[done], exact.section_states[done], rtol=0,
                               atol=1e-10)  # fmt: skip


def test_vector_math_block_and_bad_math(monkeypatch):
    """vector_math chooses the math inside its block ($GAITOPT_VECTOR_MATH, where set, wins);
    a math that is neither is one line naming the argument."""
    from gaitopt.kernels.vector_step import vector_math

    cls = type(gaitopt.model("compass_gait"))
    monkeypatch.delenv("GAITOPT_VECTOR_MATH", raising=False)
    monkeypatch.delenv("GAITOPT_LANES", raising=False)
    fast = vector_steps(cls, "fast")
    with vector_math("fast"):
        assert vector_steps(cls) is fast
    assert vector_steps(cls) is vector_steps(cls, "exact")
    monkeypatch.setenv("GAITOPT_VECTOR_MATH", "exact")
    with vector_math("fast"):
        assert vector_steps(cls) is vector_steps(cls, "exact")
    with pytest.raises(gaitopt.GaitoptInputError, match="`math`"):
        with vector_math("approximate"):
            pass
    monkeypatch.setenv("GAITOPT_VECTOR_MATH", "approximate")
    with pytest.raises(gaitopt.GaitoptInputError, match="GAITOPT_VECTOR_MATH"):
        vector_steps(cls)


def test_lanes_honour_a_parameter_vector_per_start(monkeypatch):
    """dims[8] = p_stride = n_p: start s simulated with row s of p (its guards, flow, resets).
    The Python API for per-start parameters is not this module's, so the call's dims and p are
    set here: each start must end exactly (to the bit) as that start alone (the scalar driver)
    with a model of its own slope."""
    import ctypes

    monkeypatch.setenv("GAITOPT_LANES", "1")
    monkeypatch.setenv("GAITOPT_VECTOR_MATH", "exact")
    compass = gaitopt.model("compass_gait")
    slopes = np.linspace(0.035, 0.07, 12)
    models = [gaitopt.model("compass_gait", slope=float(s)) for s in slopes]
    per_start = np.ascontiguousarray([np.asarray(m.p, dtype=float).ravel() for m in models])
    centre = compass.section_vector(compass.default_start())
    rng = np.random.default_rng(8)
    rows = np.array([m.lift(centre * (1 + 0.05 * rng.standard_normal(centre.size)))
                     for m in models])  # fmt: skip
    real = batch_compiled._lanes
    calls = []

    def with_rows(model_cls, constraints, n_p):
        run, table, steps = real(model_cls, constraints, n_p)

        def call(*args):
            dims = (ctypes.c_int32 * 9).from_address(args[0])
            dims[8] = per_start.shape[1]  # p_stride: a row per start
            calls.append(dims[0])
            return run(*args[:9], per_start.ctypes.data, *args[10:])

        return call, table, steps

    monkeypatch.setattr(batch_compiled, "_lanes", with_rows)
    batch = simulate_batch(compass, rows, steps=8, full_state=True, backend="compiled")
    assert calls == [len(rows)]
    monkeypatch.setattr(batch_compiled, "_lanes", real)
    for i, m in enumerate(models):
        alone = simulate_batch(m, rows[i : i + 1], steps=8, full_state=True, backend="compiled")
        assert (batch.status[i], batch.steps[i]) == (alone.status[0], alone.steps[0])
        assert batch.section_states[i].tobytes() == alone.section_states[0].tobytes()
        assert batch.t_end[i] == alone.t_end[0]
    # and the rows did matter: with the one parameter vector (p_stride 0) the states differ
    shared = simulate_batch(compass, rows, steps=8, full_state=True, backend="compiled")
    assert shared.section_states.tobytes() != batch.section_states.tobytes()


_PASSIVE = sorted(n for n, c in gaitopt.REGISTRY.items() if c.passive_gait and n != "strandbeest")


@pytest.mark.parametrize("name", _PASSIVE)
def test_lanes_equal_the_scalar_driver_on_every_passive_model(name, monkeypatch):
    """16 starts within ±5 % of each passive model's default start (seeded), 4 steps, events
    recorded: the lanes' columns and events equal the scalar driver's to the bit (the
    Strandbeest, seconds per start, is left to test_simulation_batch's slow run)."""
    model = gaitopt.model(name)
    centre = model.section_vector(model.default_start())
    rng = np.random.default_rng(1)
    starts = centre * (1 + 0.05 * (2 * rng.random((16, centre.size)) - 1))
    _bitwise(model, starts, monkeypatch, steps=4, record_events=True)
