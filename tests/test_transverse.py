"""Transverse linearisation and transverse LQR (gaitopt.transverse, issue 21).

Sources of the checks: the nontrivial Floquet multipliers of each gait, by the implicit function
theorem on the shooting equations (LimitCycle) or on the Radau collocation (OptimalGait), are an
independent computation of the eigenvalues the transverse monodromy must have (Manchester et al.
2011: a transverse linearisation's monodromy is the linearised Poincaré map on the moving
surface, conjugate to the return map on any other section)."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.transverse import transverse_linearisation


def _match(a: np.ndarray, b: np.ndarray) -> tuple[float, list[complex]]:
    """Largest distance pairing each of ``a`` with the nearest unused one of ``b``, and the
    unpaired rest of ``b``."""
    rest = list(np.asarray(b, complex))
    worst = 0.0
    for z in np.asarray(a, complex):
        j = int(np.argmin([abs(z - y) for y in rest]))
        worst = max(worst, abs(z - rest.pop(j)))
    return worst, rest


@pytest.mark.parametrize("name", ["compass_gait", "kneed_walker", "slip"])
def test_monodromy_has_the_floquet_multipliers(cycles, name):
    gait = cycles[name]
    lin = transverse_linearisation(gait)
    # the shooting's multipliers are accurate to its tol 1e-10; the re-integration's rtol 1e-12
    gap, rest = _match(gait.multipliers, lin.multipliers)
    assert gap < 1e-8
    # the transverse surface has n − 1 dimensions; the others are 0 (the reset's image has
    # lower dimension: the kneed walker's knee strike drops two) or 1 (the SLIP's energy)
    assert len(rest) == lin.dimensions[0] - len(gait.multipliers)
    assert all(min(abs(z), abs(z - 1)) < 1e-9 for z in rest)
    # the kneed walker changes dimension: 5 transverse states before the knee strike, 3 after
    if name == "kneed_walker":
        assert lin.dimensions == [5, 3]
        assert lin.jumps[0].shape == (3, 5) and lin.jumps[1].shape == (5, 3)
    # read on the clock instead of the phase, a constant input changes nothing (and the
    # clock, restarted at the section, adds a 0)
    gap, rest = _match(gait.multipliers, lin.clock_multipliers)
    assert gap < 1e-8


def test_reintegrated_orbit_closes(cycles):
    lin = transverse_linearisation(cycles["compass_gait"])
    # the DOP853 re-integration (rtol 1e-12) against the shooting's orbit (tol 1e-10)
    assert lin.orbit.closure < 1e-9


def test_simulate_with_a_state_feedback(cycles):
    gait = cycles["compass_gait"]
    model = gait.model
    calls = []

    def law(t, x, phase, step):
        calls.append(phase)
        return np.zeros(1)

    plain = gaitopt.simulate(model, gait.x, steps=3)
    fed = gaitopt.simulate(model, gait.x, steps=3, feedback=law)
    # the same passive flow through SciPy's stepper instead of the compiled one, both at
    # rtol 1e-11: the returns agree to the integrators' accuracy
    assert fed.success and calls
    assert np.max(np.abs(fed.section_states - plain.section_states)) < 1e-8
    with pytest.raises(gaitopt.GaitoptInputError, match="feedback"):
        gaitopt.simulate(model, gait.x, steps=1, feedback=law, feedforward=lambda t, k: [0.0])
