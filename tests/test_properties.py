"""Property-based tests of the promise "never a false gait", over every registered model.

For parameters drawn inside each model's declared ranges and guesses drawn around its default
start (Hypothesis), whatever :func:`gaitopt.find_limit_cycle` reports must hold up:

* a reported gait is re-simulated independently (SciPy, event-located, at rtol 1e-12) and
  returns to its fixed point; every unilateral constraint its model declares holds along the
  simulated trajectory, sampled independently of the shooting's dense samples; and its reported
  multipliers agree with central finite differences of the simulated return map;
* a reported failure is well-formed JSON with ``null`` for every number that does not exist.

The CI profile runs a few examples per model (about two minutes on 2 cores); set
``GAITOPT_HYPOTHESIS_PROFILE=long`` for the long profile run before an issue is resolved.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gaitopt
from gaitopt.errors import GaitoptInputError
from gaitopt.returnmap import return_map

LONG = os.environ.get("GAITOPT_HYPOTHESIS_PROFILE") == "long"
EXAMPLES = 40 if LONG else 3

MODELS = [name for name, cls in gaitopt.REGISTRY.items() if cls.passive_gait]


def _value(spec, draw) -> float:
    """A value inside the declared range: near the default half the time (± 20 %, where most
    gaits live), anywhere in the range otherwise (log-uniform across decades)."""
    low, high = spec.low, spec.high
    if spec.integer:
        lo = int(math.ceil(low + (1 if spec.low_open else 0)))
        hi = int(math.floor(high - (1 if spec.high_open else 0)))
        near = int(spec.default)
        return float(draw(st.sampled_from([near, draw(st.integers(lo, hi))])))
    lo = low if not spec.low_open else low + 1e-9 * max(1.0, abs(high - low))
    hi = high if not spec.high_open else high - 1e-9 * max(1.0, abs(high - low))
    if draw(st.booleans()):
        d = spec.default
        x = draw(st.floats(d - 0.2 * abs(d), d + 0.2 * abs(d), allow_nan=False))
    elif lo > 0 and hi / lo > 100:
        x = math.exp(draw(st.floats(math.log(lo), math.log(hi), allow_nan=False)))
    else:
        x = draw(st.floats(lo, hi, allow_nan=False))
    return float(min(max(x, lo), hi))


@st.composite
def cases(draw, name: str):
    cls = gaitopt.REGISTRY[name]
    params = {}
    for spec in cls.parameter_specs():
        if draw(st.integers(0, 2)) == 0:  # change about a third of them at a time
            params[spec.name] = _value(spec, draw)
    guess = None
    if draw(st.booleans()):
        centre = cls().default_start()
        guess = {k: v + draw(st.floats(-0.1, 0.1)) * (abs(v) + 0.1) for k, v in centre.items()}
    return params, guess


def _model_or_skip(name, params):
    try:
        return gaitopt.model(name, **params)
    except GaitoptInputError:  # a combination the model's cross-parameter check refuses
        return None


def _fd_jacobian(model, s: np.ndarray, steps: int, h: float = 1e-6) -> np.ndarray:
    """Central differences of the simulated return map (SciPy, independent of the shooting)."""
    J = np.zeros((s.size, s.size))
    for j in range(s.size):
        e = np.zeros(s.size)
        e[j] = h * (1 + abs(s[j]))
        forward = return_map(model, s + e, steps=steps)
        backward = return_map(model, s - e, steps=steps)
        J[:, j] = (forward - backward) / (2 * e[j])
    return J


def _check_gait(cycle: gaitopt.LimitCycle) -> None:
    model = cycle.model
    # 1. Independent re-simulation returns to the fixed point.  Tolerance 1e-7 relative: the
    #    shooting is accurate to 1e-10, the simulation runs at rtol 1e-12 (certify's 1e3·tol).
    sim = gaitopt.simulate(model, cycle.x, steps=cycle.steps, rtol=1e-12, atol=1e-13)
    assert sim.success, sim.message
    scale = 1 + np.max(np.abs(cycle.x))
    assert np.max(np.abs(sim.section_states[-1] - cycle.x)) < 1e-7 * scale
    # 2. Every declared unilateral constraint holds along the simulated trajectory (1000
    #    samples per arc, not the shooting's).  Tolerance 1e-8 in the constraint's unit, relative
    #    to its size along the arc; an ``at_start`` one must rise where it starts at 0.
    p = model.p
    for arc in sim.arcs:
        phase = model.phases[arc.phase]
        _, X = arc.sample(1000)
        for c in phase.constraints:
            values = np.array([float(c.function(X[:, j], arc.u, p)) for j in range(X.shape[1])])
            tol = 1e-8 * (1 + np.max(np.abs(values)))
            inner = values[1 if c.at_start else 0 : -1 if c.at_end else None]
            assert np.min(inner) > -tol, f"{c.name} fails on a reported {model.name} gait"
    # 3. Multipliers: AD through the shooting equations vs finite differences of the simulated
    #    map.  Error budget (h = 1e-6 relative): truncation h² ~ 1e-12, rounding 1e-12 / h ~ 1e-6;
    #    tolerance 1e-4 on |λ| (sorted), absolute plus relative.
    s = cycle.section_point
    J_fd = _fd_jacobian(model, s, cycle.steps)
    if not np.all(np.isfinite(J_fd)):
        return  # a perturbation leaves the map's domain (a gait at the edge of existence)
    fd = np.sort(np.abs(np.linalg.eigvals(J_fd)))
    ad = np.sort(np.abs(cycle.multipliers))
    np.testing.assert_allclose(ad, fd, atol=1e-4, rtol=1e-4)


def _check_failure(cycle: gaitopt.LimitCycle) -> None:
    report = json.loads(json.dumps(cycle.as_dict(), allow_nan=False))  # strict JSON: no NaN/inf
    assert report["success"] is False and report["message"]
    assert report["stable"] is None and report["multipliers"] == []
    for key in ("period", "residual", "verification_error", "discretisation_error"):
        value = report.get(key)
        assert value is None or (isinstance(value, float) and math.isfinite(value))
    if report.get("period") is not None:  # a period is only reported if it exists
        assert report["period"] > 0


@pytest.mark.parametrize("name", MODELS)
def test_whatever_is_reported_holds_up(name):
    @settings(
        max_examples=EXAMPLES,
        deadline=None,
        derandomize=not LONG,  # CI: the same examples every run
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(cases(name))
    def check(case):
        params, guess = case
        model = _model_or_skip(name, params)
        if model is None:
            return
        try:
            cycle = gaitopt.find_limit_cycle(model, guess)
        except GaitoptInputError:  # an explicit guess that leads nowhere: bad input, said so
            assert guess is not None
            return
        json.dumps(cycle.as_dict(), allow_nan=False)
        if cycle.success:
            _check_gait(cycle)
        else:
            _check_failure(cycle)

    check()
