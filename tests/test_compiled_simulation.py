"""The compiled simulation (one C call per arc, :mod:`gaitopt.simulation.compiled`) against the
Python loop (:func:`gaitopt.simulation.phase.integrate_phase` driving SciPy's DOP853), on every
registered model.

Both run the same method, the same step-size control, the same event checks and the same root
location, so they take the same steps: their events must agree to 1e-12 (s, and in the states'
units, relative to 1 + |x|) — not to the integration tolerance (1e-11), which is what two
*different* integrators would agree to.  The remaining differences are rounding: the compiled
event functions and resets against CasADi's interpreter, and Brent's method in C against
SciPy's ``brentq`` (located to ~1e-15 either way).  The fallback where there is no C compiler
is the Python loop itself (forced with ``GAITOPT_COMPILE=0``).
"""

import numpy as np
import pytest

import gaitopt
from gaitopt.errors import GaitoptInputError
from gaitopt.kernels.cache import compiler
from gaitopt.models import model_names
from gaitopt.simulation import simulate

# Events agree to this (s; states: relative to 1 + |x|): see the module docstring.
TOL = 1e-12


def _agree(a, b) -> None:
    assert a.status == b.status, (a.message, b.message)
    assert len(a.events) == len(b.events) and len(a.arcs) == len(b.arcs)
    for ea, eb in zip(a.events, b.events, strict=True):
        assert ea.transition == eb.transition and ea.phase == eb.phase
        assert abs(ea.t - eb.t) <= TOL * (1 + abs(eb.t))
        scale = 1 + np.abs(eb.state_before)
        assert np.all(np.abs(ea.state_before - eb.state_before) <= TOL * scale)
        if eb.state_after is not None:
            scale = 1 + np.abs(eb.state_after)
            assert np.all(np.abs(ea.state_after - eb.state_after) <= TOL * scale)
    for aa, ab in zip(a.arcs, b.arcs, strict=True):
        # same steps: the dense output on the same pieces
        assert len(aa.solution.interpolants) == len(ab.solution.interpolants)
        t = np.linspace(ab.t0, ab.t1, 7)
        xa, xb = aa.solution(t), ab.solution(t)
        assert np.all(np.abs(xa - xb) <= TOL * (1 + np.abs(xb)))
    assert np.allclose(a.section_times, b.section_times, rtol=0, atol=TOL * 10)


# The Strandbeest's structure takes about 20 s to build in a fresh process (its linkage).
_MODELS = [
    pytest.param(name, marks=pytest.mark.slow) if name == "strandbeest" else name
    for name in model_names()
]


needs_compiler = pytest.mark.skipif(
    compiler() is None,
    reason="no C compiler ($GAITOPT_CC, default gcc; or GAITOPT_COMPILE=0): no compiled arcs to "
    "compare (the fallback is tested by test_without_a_compiler_the_python_loop_runs)",
)


@needs_compiler
@pytest.mark.parametrize("name", _MODELS)
def test_compiled_arcs_take_the_python_loops_steps_and_events(name):
    model = gaitopt.model(name)
    python = simulate(model, steps=3, backend="python")
    compiled = simulate(model, steps=3, backend="compiled")
    _agree(compiled, python)


@needs_compiler
@pytest.mark.parametrize("name", ["compass_gait", "slip", "rimless_wheel"])
def test_a_guess_simulation_agrees_too(name):
    # The shooting's guess: looser tolerances, no unilateral constraints (the "g" event set).
    model = gaitopt.model(name)
    options = dict(steps=2, rtol=1e-8, atol=1e-9, constraints=False)
    _agree(
        simulate(model, backend="compiled", **options),
        simulate(model, backend="python", **options),
    )


@needs_compiler
@pytest.mark.parametrize(
    "start, options, status",
    [
        (None, {"max_phase_time": 0.05}, "timeout"),  # a phase cut short
        # a heel strike, then the stance foot lifts off (a unilateral constraint's event)
        ({"stance": 0.2, "stance_dot": -0.1, "swing_dot": 0.0}, {}, "fell"),
    ],
)
def test_a_timeout_and_a_fall_agree(start, options, status):
    model = gaitopt.model("compass_gait")
    python = simulate(model, start, steps=2, backend="python", **options)
    assert python.status == status
    _agree(simulate(model, start, steps=2, backend="compiled", **options), python)


@needs_compiler
def test_an_arc_longer_than_the_step_buffers_resumes(monkeypatch):
    # The driver returns when its step buffers are full and the next call goes on from its
    # state: with room for 3 steps per call (an arc takes about 20), the same steps and events.
    from gaitopt.simulation import compiled

    monkeypatch.setattr(compiled, "_CAPACITY", 3)
    model = gaitopt.model("compass_gait")
    _agree(simulate(model, steps=2, backend="compiled"), simulate(model, steps=2, backend="python"))


def test_without_a_compiler_the_python_loop_runs(monkeypatch):
    from gaitopt.kernels.arcs import arc_library

    model = gaitopt.model("compass_gait")
    reference = simulate(model, steps=2, backend="python")
    monkeypatch.setenv("GAITOPT_COMPILE", "0")
    arc_library.cache_clear()
    try:
        assert arc_library(type(model)) is None
        fallback = simulate(model, steps=2)  # backend "auto": the Python loop
        # the same loop as the reference: bit for bit
        assert [e.t for e in fallback.events] == [e.t for e in reference.events]
        with pytest.raises(GaitoptInputError, match="backend"):
            simulate(model, steps=2, backend="compiled")
    finally:
        monkeypatch.delenv("GAITOPT_COMPILE")
        arc_library.cache_clear()


def test_bad_backend_is_refused():
    model = gaitopt.model("compass_gait")
    with pytest.raises(GaitoptInputError, match="backend"):
        simulate(model, steps=1, backend="fortran")
    with pytest.raises(GaitoptInputError, match="compiled"):
        simulate(model, steps=1, backend="compiled", method="RK45")


@needs_compiler
def test_bench_record_and_table(tmp_path):
    # The bench's fast mode on two models: a well-formed record whose two backends took the same
    # integrator steps and agree on every event time (1e-12 s, as above).  No timing asserted.
    import json
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from bench import simulate as bench

    out = tmp_path / "bench_simulate.json"
    assert bench.main(["compass_gait", "bouncing_ball", "--repeats", "1", "--steps", "2",
                       "--out", str(out)]) == 0  # fmt: skip
    record = json.loads(out.read_text())["simulate"]
    assert set(record) == {"compass_gait", "bouncing_ball"}
    for entry in record.values():
        assert entry["status"] == "completed" and entry["integrator_steps"] > 0
        assert entry["max_event_time_difference_s"] <= TOL
        assert entry["python_s"] > 0 and entry["compiled_s"] > 0
    assert "speed-up per simulation" in bench.table(record)


@needs_compiler
def test_the_shootings_guess_and_referee_run_compiled(monkeypatch):
    # find_limit_cycle simulates twice with a constant input (its guess, then the referee from the
    # fixed point): both through compiled arcs by default, none through the Python loop.
    import gaitopt.simulation as simulation
    from gaitopt.simulation import compiled

    calls = {"compiled": 0, "python": 0}
    arc, phase = compiled.integrate_arc, simulation.integrate_phase

    def counted_arc(*args, **kwargs):
        calls["compiled"] += 1
        return arc(*args, **kwargs)

    def counted_phase(*args, **kwargs):
        calls["python"] += 1
        return phase(*args, **kwargs)

    monkeypatch.setattr(compiled, "integrate_arc", counted_arc)
    monkeypatch.setattr(simulation, "integrate_phase", counted_phase)
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    assert cycle.success and cycle.verified
    assert calls["compiled"] >= 2 and calls["python"] == 0
