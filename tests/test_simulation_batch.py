"""The batch simulation (gaitopt.simulation.batch) against the per-start simulation
(gaitopt.simulate, the referee): the same events (times, states, names) and the same outcome for
every registered passive model's default start and perturbed starts, a Hypothesis property over
compass-gait starts, the basin's classification both ways, and bad input — for both backends of
the batch: the compiled one (every start run to its end in one C call, gaitopt.simulation
.batch_compiled) and the NumPy one (gaitopt.simulation.batch_phase).

Tolerance of the event agreement: 1e-10 (s, and state units, relative to 1 + |x|).  Both run
the same method (SciPy's DOP853 control and the same compiled step; Brent's method, the same
iteration, on the same dense output), so most starts agree bit for bit; where a crossing's last
bit differs, the error estimate of the next steps — at rtol 1e-11 a difference of nearly equal
numbers — turns it into step sizes that differ in their 5th digit, and the results then differ
at the integrator's tolerance (measured up to 2e-12 over 10 compass-gait steps)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gaitopt
from gaitopt.kernels.cache import compiler
from gaitopt.simulation.batch import simulate_batch

TOL = 1e-10
#: Models whose simulation takes seconds per start (the Strandbeest's linkage) are left to the
#: slow run.
_SLOW = {"strandbeest"}
PASSIVE = sorted(n for n, c in gaitopt.REGISTRY.items() if c.passive_gait and n not in _SLOW)


def _agree(model, starts: np.ndarray, steps: int, backend: str = "auto") -> None:
    """Every start's events and outcome agree between the batch and the per-start simulation."""
    batch = simulate_batch(model, starts, steps=steps, record_events=True, backend=backend)
    for i, start in enumerate(starts):
        try:
            ref = gaitopt.simulate(
                model, dict(zip(model.section.coordinates, start, strict=True)), steps=steps
            )
        except gaitopt.GaitoptInputError:
            assert batch.status[i] == "invalid start"
            continue
        assert batch.status[i] == ref.status, (i, ref.message, batch.message(i))
        assert batch.steps[i] == ref.steps
        events = batch.events_of(i)
        assert [e[2] for e in events] == [e.transition for e in ref.events]
        for mine, theirs in zip(events, ref.events, strict=True):
            assert abs(mine[0] - theirs.t) <= TOL * (1 + abs(theirs.t))
            assert mine[1] == theirs.phase
            np.testing.assert_allclose(mine[3], theirs.state_before, rtol=TOL, atol=TOL)
            if theirs.state_after is None:
                assert mine[4] is None
            else:
                np.testing.assert_allclose(mine[4], theirs.state_after, rtol=TOL, atol=TOL)
        if ref.status == "standing":
            assert batch.accumulation_time[i] == pytest.approx(ref.accumulation_time, abs=1e-9)
        n = ref.steps + 1
        np.testing.assert_allclose(batch.section_states[i, :n], ref.section_states, rtol=TOL,
                                   atol=TOL)  # fmt: skip


# The compiled batch is compared where there is a C compiler; without one the NumPy batch (the
# fallback) is what runs, and the tests of it below still run.
needs_compiler = pytest.mark.skipif(
    compiler() is None, reason="no C compiler ($GAITOPT_CC, default gcc; or GAITOPT_COMPILE=0)"
)


@pytest.mark.parametrize("backend", [pytest.param("compiled", marks=needs_compiler), "numpy"])
@pytest.mark.parametrize("name", PASSIVE)
def test_batch_events_agree_with_simulate_on_every_passive_model(name, backend):
    """Default start and five starts perturbed by up to 5 % (seeded), four returns each."""
    model = gaitopt.model(name)
    centre = model.section_vector(model.default_start())
    rng = np.random.default_rng(1)
    scale = np.where(np.abs(centre) > 0, np.abs(centre), 1.0)
    starts = centre + 0.05 * scale * (2 * rng.random((5, centre.size)) - 1)
    _agree(model, np.vstack([centre, starts]), steps=4, backend=backend)


@pytest.fixture(scope="module")
def compass():
    return gaitopt.model("compass_gait")


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.lists(st.floats(-0.3, 0.3), min_size=3, max_size=3))
def test_batch_agrees_with_simulate_over_compass_starts(compass, offset):
    """Hypothesis: any start within ±30 % of the default start (falls, trips, walking)."""
    centre = compass.section_vector(compass.default_start())
    start = centre * (1 + np.asarray(offset))
    _agree(compass, np.vstack([start, centre]), steps=6)


def test_basin_classification_batch_equals_per_start():
    """gaitopt.basin's batch classification (the compiled batch) and its per-start rule give the
    same outcome for 24 seeded compass-gait starts in x* ± 30 % |x*| (converged, fell, not
    converged)."""
    from gaitopt.basin.checks import check_setup
    from gaitopt.basin.classify import classify, classify_many, model_of

    gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    setup = check_setup(gait, 12, 3, 1e-4, None).__dict__
    model = model_of(setup)
    rng = np.random.default_rng(3)
    centre = np.asarray(setup["centre"])
    starts = centre * (1 + 0.3 * (2 * rng.random((24, centre.size)) - 1))
    per_start = [classify(setup, model, s) for s in starts]
    assert classify_many(setup, model, starts) == per_start
    assert len(set(per_start)) >= 2  # the sample is not all one outcome
    # the brute-force loop (SciPy's stepper from Python: an independent integration of the same
    # equations) classifies eight of them alike
    assert [classify(setup, model, s, backend="python") for s in starts[:8]] == per_start[:8]


def test_invalid_rows_and_bad_input(compass):
    """A row that is not a state (NaN) ends at once as "invalid start" while the others run; a
    start of the wrong width or an input of the wrong size is one line naming the argument."""
    centre = compass.section_vector(compass.default_start())
    out = simulate_batch(compass, [centre, [np.nan, 1.0, 0.5]], steps=1)
    assert out.status.tolist() == ["completed", "invalid start"]
    with pytest.raises(gaitopt.GaitoptInputError, match="`starts`"):
        simulate_batch(compass, [[1.0, 2.0]])
    with pytest.raises(gaitopt.GaitoptInputError, match="`inputs`"):
        simulate_batch(compass, [centre], inputs=[1.0, 2.0])


@pytest.mark.parametrize("backend", ["numpy", "auto"])
def test_rays_in_lockstep_equal_rays_one_by_one(backend, monkeypatch):
    """gaitopt.basin's 16 rays in a batch (the scans together; with the NumPy batch three
    halvings per round from every midpoint they can visit, with the compiled one a halving per
    round) give exactly the radii, first failures and flags of the rays bisected one by one with
    one simulation per start (no tolerance: the same midpoints, the same classifications)."""
    from gaitopt.basin import classify
    from gaitopt.basin.checks import check_setup
    from gaitopt.basin.rays import ray_directions, rays_batch, rays_task
    from gaitopt.simulation.batch import compiled_batch

    monkeypatch.setattr(classify, "BACKEND", backend)

    gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    setup = check_setup(gait, 12, 3, 1e-4, None)
    coordinates = ["stance", "stance_dot"]
    points = [
        setup.point(
            directions=[d], coordinates=coordinates, scan=4, bisections=6, max_radius=0.3
        )  # fmt: skip
        for d in ray_directions(16, 2, 0).tolist()  # enough rays to batch (basin.classify.SMALL)
    ]
    together = rays_batch(points)
    alone = [rays_task(point) for point in points]
    for a, b in zip(together, alone, strict=True):
        (ray_a,), (ray_b,) = a["rays"], b["rays"]
        assert ray_a["radius"] == ray_b["radius"]
        assert ray_a["first_failure"] == ray_b["first_failure"]
        assert ray_a["beyond"] == ray_b["beyond"]
    assert any(r["rays"][0]["first_failure"] is not None for r in alone)  # something bisected
    # the NumPy batch simulated every midpoint of its rounds (more starts than one by one): it
    # did take several halvings per round; the compiled batch simulates as many as one by one
    pairs = list(zip(together, alone, strict=True))
    if backend == "numpy" or not compiled_batch(gaitopt.model("compass_gait")):
        assert any(a["rays"][0]["runs"] > b["rays"][0]["runs"] for a, b in pairs)
    else:
        assert all(a["rays"][0]["runs"] == b["rays"][0]["runs"] for a, b in pairs)


def _exactly(model, starts: np.ndarray, steps: int, **options) -> list[str]:
    """The compiled batch against gaitopt.simulate's compiled backend, start by start: the same
    status, steps, event names and phases, and event times and states, section states and
    accumulation times equal to the last bit (both run the same C arc driver on the same
    compiled functions in the same order, so no tolerance is needed).  Returns the statuses."""
    batch = simulate_batch(model, starts, steps=steps, record_events=True, backend="compiled",
                           **options)  # fmt: skip
    for i, start in enumerate(starts):
        x0 = dict(zip(model.section.coordinates, start, strict=True))
        ref = gaitopt.simulate(model, x0, steps=steps, backend="compiled", **options)
        assert (batch.status[i], batch.steps[i]) == (ref.status, ref.steps)
        assert batch.t_end[i] == max([0.0] + [a.t1 for a in ref.arcs] + [e.t for e in ref.events])
        events = batch.events_of(i)
        assert [(e[2], e[1]) for e in events] == [(e.transition, e.phase) for e in ref.events]
        for mine, theirs in zip(events, ref.events, strict=True):
            assert mine[0] == theirs.t
            np.testing.assert_array_equal(mine[3], theirs.state_before)
            if theirs.state_after is not None:
                np.testing.assert_array_equal(mine[4], theirs.state_after)
        np.testing.assert_array_equal(batch.section_states[i, : ref.steps + 1],
                                      ref.section_states)  # fmt: skip
        if ref.status == "standing":
            assert batch.accumulation_time[i] == ref.accumulation_time
    return batch.status.tolist()


@needs_compiler
def test_compiled_batch_equals_simulate_to_the_bit(compass):
    """Compass-gait starts within ±30 % (seeded: walking, falls, trips), rimless-wheel starts that
    rock to rest (impacts accumulating: "standing"), compass starts with a phase time limit too
    short for a step ("timeout"), without the unilateral constraints, and with a hip torque per
    start."""
    centre = compass.section_vector(compass.default_start())
    rng = np.random.default_rng(5)
    starts = centre * (1 + 0.3 * (2 * rng.random((12, centre.size)) - 1))
    found = set(_exactly(compass, starts, steps=8))
    assert {"completed", "fell"} <= found
    wheel = gaitopt.model("rimless_wheel")
    assert set(_exactly(wheel, np.array([[0.5], [-0.5], [2.0]]), steps=40)) == {
        "standing", "completed"
    }  # fmt: skip
    assert _exactly(compass, starts[:2], steps=2, max_phase_time=0.05) == ["timeout"] * 2
    _exactly(compass, starts[:4], steps=3, constraints=False)
    # a hip torque per start (seeded): each row against gaitopt.simulate with its own input
    torques = rng.normal(0.0, 0.5, (4, 1))
    batch = simulate_batch(compass, starts[:4], steps=3, inputs=torques, backend="compiled")
    for i, (start, torque) in enumerate(zip(starts[:4], torques, strict=True)):
        x0 = dict(zip(compass.section.coordinates, start, strict=True))
        ref = gaitopt.simulate(compass, x0, steps=3, inputs=torque, backend="compiled")
        assert batch.status[i] == ref.status
        np.testing.assert_array_equal(batch.section_states[i, : ref.steps + 1],
                                      ref.section_states)  # fmt: skip


@needs_compiler
def test_without_a_compiler_the_numpy_batch_runs(compass, monkeypatch):
    """No compiled batch library (no C compiler, GAITOPT_COMPILE=0): backend "auto" falls back to
    the NumPy batch with the same outcomes; "compiled" is one line naming `backend`."""
    from gaitopt.kernels import batch_driver

    centre = compass.section_vector(compass.default_start())
    starts = centre * np.array([[1.0, 1.0, 1.0], [1.2, 0.9, 1.1]])
    compiled = simulate_batch(compass, starts, steps=3)
    assert compiled.settings["backend"] == "compiled"
    monkeypatch.setattr(batch_driver, "batch_library", lambda verbose=True: None)
    fallback = simulate_batch(compass, starts, steps=3)
    assert fallback.settings["backend"] == "numpy"
    assert fallback.status.tolist() == compiled.status.tolist()
    # the same method: the section states agree to the events' tolerance (module docstring)
    np.testing.assert_allclose(fallback.section_states, compiled.section_states, rtol=TOL,
                               atol=TOL)  # fmt: skip
    with pytest.raises(gaitopt.GaitoptInputError, match="`backend`"):
        simulate_batch(compass, starts, steps=3, backend="compiled")
    with pytest.raises(gaitopt.GaitoptInputError, match="`backend`"):
        simulate_batch(compass, starts, steps=3, backend="fast")


@needs_compiler
def test_compiled_batch_runs_again_the_starts_whose_events_overflow(compass, monkeypatch):
    """With room for only 8 events per start (EVENTS_PER_STEP = 0), the starts with more run
    again with four times the room: the same columns and events as with ample room (exact: the
    same simulation, run again)."""
    from gaitopt.simulation import batch_compiled

    centre = compass.section_vector(compass.default_start())
    starts = centre * np.array([[1.0, 1.0, 1.0], [1.2, 0.9, 1.1], [1.02, 1.0, 0.98]])
    ample = simulate_batch(compass, starts, steps=20, record_events=True, backend="compiled")
    monkeypatch.setattr(batch_compiled, "EVENTS_PER_STEP", 0)
    tight = simulate_batch(compass, starts, steps=20, record_events=True, backend="compiled")
    assert max(np.bincount(tight.events["start"])) > 8  # some start did overflow 8
    assert tight.status.tolist() == ample.status.tolist()
    np.testing.assert_array_equal(tight.section_states, ample.section_states)
    for key in ample.events:
        np.testing.assert_array_equal(tight.events[key], ample.events[key])
