"""Per-start parameters of the batch simulation (``simulate_batch(..., params=)``) against the
per-start simulation (``gaitopt.simulate`` of ``model.replace(**that start's parameters)``, the
referee).

Tolerances: the compiled batch runs the same C arc driver on the same compiled functions as
``gaitopt.simulate``'s compiled backend, start by start (the parameter vector is only read from
the start's own row), so it is compared to the last bit (tolerance 0, as
tests/test_simulation_batch.py's ``_exactly``); the NumPy batch runs the same method from NumPy,
compared at that file's 1e-10 (its docstring: where a crossing's last bit differs, the step
sizes differ after it, the results at the integrator's tolerance)."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.kernels.cache import compiler
from gaitopt.simulation.batch import simulate_batch

TOL = 1e-10
needs_compiler = pytest.mark.skipif(compiler() is None, reason="no C compiler")


def _referee(model, start, steps, params, **options):
    x0 = dict(zip(model.section.coordinates, start, strict=True))
    return gaitopt.simulate(model.replace(**params), x0, steps=steps, **options)


def _compare(batch, i, ref, tol: float) -> None:
    assert (batch.status[i], batch.steps[i]) == (ref.status, ref.steps), (i, ref.message)
    events = batch.events_of(i)
    assert [(e[2], e[1]) for e in events] == [(e.transition, e.phase) for e in ref.events]
    for mine, theirs in zip(events, ref.events, strict=True):
        assert abs(mine[0] - theirs.t) <= tol * (1 + abs(theirs.t))
        np.testing.assert_allclose(mine[3], theirs.state_before, rtol=tol, atol=tol)
    np.testing.assert_allclose(batch.section_states[i, : ref.steps + 1], ref.section_states,
                               rtol=tol, atol=tol)  # fmt: skip


def _cases():
    """(model, starts, params as given to simulate_batch, per-start parameter dicts, steps):
    compass-gait slopes per start (walking, and too steep or too shallow: falls), the SLIP's
    ground height per start (rough ground: lower ground, a longer descent) with its mass and
    stiffness per start given as N × n_p rows."""
    compass = gaitopt.model("compass_gait")
    centre = compass.section_vector(compass.default_start())
    slopes = compass.slope * np.array([1.0, 1.05, 0.9, 1.2, 0.5, 2.0])
    starts = np.tile(centre, (slopes.size, 1)) * (1 + 0.01 * np.arange(slopes.size))[:, None]
    yield compass, starts, {"slope": slopes}, [{"slope": s} for s in slopes], 4
    slip = gaitopt.model("slip")
    heights = np.array([0.0, 0.03, -0.05, 0.08, -0.1])
    z = np.array([[1.0], [1.03], [0.97], [1.05], [1.0]])
    rows = np.tile(slip.p, (heights.size, 1))
    names = [s.name for s in slip.parameter_specs()]
    rows[:, names.index("ground_height")] = heights
    rows[:, names.index("mass")] = [80.0, 70.0, 90.0, 80.0, 60.0]
    per = [dict(zip(names, r, strict=True)) for r in rows]
    yield slip, z, rows, per, 3


@needs_compiler
def test_per_start_params_equal_simulate_to_the_bit():
    """Compiled batch, each start with its own parameters: the same status, events and section
    states as gaitopt.simulate (compiled) of the model with those parameters (tolerance 0)."""
    found = set()
    for model, starts, params, per, steps in _cases():
        batch = simulate_batch(model, starts, steps=steps, params=params, record_events=True,
                               backend="compiled")  # fmt: skip
        for i, start in enumerate(starts):
            ref = _referee(model, start, steps, per[i], backend="compiled")
            _compare(batch, i, ref, 0.0)
            found.add(ref.status)
    assert {"completed", "fell"} <= found  # the slopes include falls


def test_per_start_params_numpy_backend():
    """The NumPy batch with per-start parameters against gaitopt.simulate (1e-10, see top)."""
    for model, starts, params, per, steps in _cases():
        batch = simulate_batch(model, starts, steps=steps, params=params, record_events=True,
                               backend="numpy")  # fmt: skip
        for i, start in enumerate(starts):
            _compare(batch, i, _referee(model, start, steps, per[i]), TOL)


@needs_compiler
def test_one_value_for_all_starts_is_the_shared_vector():
    """A mapping of scalars, or N equal rows, is the same run as the model with those values
    (exact: one parameter vector, stride 0)."""
    slip = gaitopt.model("slip")
    z = np.array([[1.0], [1.02]])
    a = simulate_batch(slip, z, steps=2, params={"ground_height": 0.02})
    b = simulate_batch(slip.replace(ground_height=0.02), z, steps=2)
    c = simulate_batch(slip, z, steps=2, params=np.tile(slip.replace(ground_height=0.02).p, (2, 1)))
    np.testing.assert_array_equal(a.section_states, b.section_states)
    np.testing.assert_array_equal(c.section_states, b.section_states)


@pytest.mark.parametrize(
    "params, match",
    [
        ({"height": 0.1}, "no parameter 'height'"),
        ({"ground_height": [0.0, 0.1, 0.2]}, r"\['ground_height'\] must be one number or 2"),
        (np.zeros((2, 3)), "`params` must be a mapping"),
        ({"mass": [80.0, -1.0]}, r"`mass` = -1 \(start 1\) is out of range"),
        ({"ground_height": [0.0, np.nan]}, "`ground_height` = nan"),
        ({"ground_height": "low"}, "`params` must be numbers"),
        ({"energy": [1263.0, 100.0]}, r"`params` \(start 1\): slip: `energy`"),
    ],
)
def test_bad_params_are_one_line(params, match):
    """Unknown names, wrong shapes, non-numbers, values out of the declared range and a start
    that breaks the model's own condition (the SLIP's energy below its touchdown height): one
    line naming `params`."""
    with pytest.raises(gaitopt.GaitoptInputError, match=match) as info:
        simulate_batch("slip", [[1.0], [1.02]], steps=1, params=params)
    assert "\n" not in str(info.value)
