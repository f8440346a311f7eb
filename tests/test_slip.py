"""The SLIP runner: the textbook's apex map and its fixed points, the map's limits, energy."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gaitopt
from gaitopt.errors import ParameterError
from gaitopt.models.slip import Slip, SlipSwingLeg
from gaitopt.returnmap import fixed_points_1d, return_map


@pytest.fixture(scope="module")
def slip() -> Slip:
    return gaitopt.model("slip")


@pytest.fixture(scope="module")
def gaits(slip):
    return {z: gaitopt.find_limit_cycle(slip, {"z": z}) for z in (0.87, 0.92)}


def test_defaults_are_the_textbook_dimensionless_numbers(slip):
    # Source: Tedrake, Underactuated Robotics, SLIP apex map (after Geyer 2005): k̃ = 10.7,
    # θ_td = 30°, Ẽ = 1.61.  Tolerance 1e-12 (the SI defaults are exact multiples).
    assert slip.relative_stiffness == pytest.approx(10.7, abs=1e-12)
    assert slip.relative_energy == pytest.approx(1.61, abs=1e-12)
    assert slip.touchdown_angle == pytest.approx(math.pi / 6, abs=1e-15)
    assert slip.nominal_input().tolist() == [slip.touchdown_angle]


def test_textbook_fixed_points_and_their_stability(gaits):
    # Source: docs/design.md "Reference numbers" / Tedrake's apex-map figure: a stable fixed point
    # near z = 0.87 m and an unstable one near 0.92 m.  "Near": within 1 cm (the figure's
    # resolution); the multiplier excludes the trivial one of energy conservation (one only).
    stable, unstable = gaits[0.87], gaits[0.92]
    for cycle in (stable, unstable):
        assert cycle.success and cycle.verified, cycle.message
        assert len(cycle.multipliers) == 1
        assert cycle.residual <= 1e-10 and cycle.discretisation_error <= 1e-10
    assert abs(stable.fixed_point["z"] - 0.87) < 0.01 and stable.stable
    assert abs(unstable.fixed_point["z"] - 0.92) < 0.01 and not unstable.stable
    assert 0 < stable.multipliers[0].real < 1 < unstable.multipliers[0].real


def test_multiplier_matches_finite_differences_of_the_simulated_apex_map(gaits, slip):
    # AD through the shooting equations vs central differences (h = 1e-5) of the event-located
    # SciPy map; error budget h² P''' + rtol/h ~ 1e-6; tolerance 1e-5.
    for cycle in gaits.values():
        z = cycle.fixed_point["z"]
        h = 1e-5
        fd = (return_map(slip, z + h)[0] - return_map(slip, z - h)[0]) / (2 * h)
        assert cycle.multipliers[0].real == pytest.approx(fd, abs=1e-5)
        # ∂P/∂θ_td by AD vs finite differences of the simulated map in the input.
        fd_u = (
            return_map(slip, z, inputs=[slip.touchdown_angle + h])[0]
            - return_map(slip, z, inputs=[slip.touchdown_angle - h])[0]
        ) / (2 * h)
        assert cycle.input_jacobian[0, 0] == pytest.approx(fd_u, abs=1e-5)


def test_every_fixed_point_on_the_domain(slip, gaits):
    # The map on (touchdown height, 1.0]: exactly the two textbook fixed points, each verified;
    # they agree with find_limit_cycle's to 1e-8 (brentq on the simulated map, xtol 1e-12).
    found = fixed_points_1d(slip, (slip.touchdown_height() + 1e-4, 1.0), samples=40)
    assert len(found.cycles) == 2
    assert [c.stable for c in found.cycles] == [True, False]
    expected = [gaits[0.87].fixed_point["z"], gaits[0.92].fixed_point["z"]]
    np.testing.assert_allclose(found.points, expected, atol=1e-8)


def test_the_map_limits_are_named_falls_not_crashes(slip):
    lo, hi = slip.apex_domain()
    # Below the touchdown height l0 cos θ_td the leg cannot be placed: undefined (NaN).
    assert lo == pytest.approx(math.cos(math.pi / 6), abs=1e-15)
    sim = gaitopt.simulate(slip, {"z": lo - 0.01}, steps=1)
    assert sim.status == "fell" and "below touchdown height" in sim.message
    assert np.isnan(return_map(slip, lo - 0.01)[0])
    # With too little forward energy (apex near E/(m g)) the runner falls back.
    assert hi == pytest.approx(1.61, abs=1e-12)
    sim = gaitopt.simulate(slip, {"z": 1.5}, steps=1)
    assert sim.status == "fell" and "falls back" in sim.message
    assert np.isnan(return_map(slip, 1.5)[0])
    # The note of a failed search states the domain.
    assert "between the touchdown height" in slip.existence_note()


def test_energy_is_conserved_through_every_phase_and_reset(slip, gaits):
    # Invariant: the SLIP is conservative (docs/design.md, invariants). Along each simulated arc and
    # across touchdown, liftoff and apex the energy stays at the parameter E; tolerance 1e-8
    # relative (rtol 1e-11 over a few steps).
    x0 = gaits[0.92].x + np.array([0.0, 0.01, 0.0, 0.0])
    x0[2] = slip.apex_speed(x0[1])  # stay on the energy level set
    sim = gaitopt.simulate(slip, x0, steps=3)
    assert sim.success
    p = slip.p
    for arc in sim.arcs:
        energy = slip.phases[arc.phase].conserved["energy"]
        _, X = arc.sample(25)
        values = np.array([float(energy(X[:, j], p)) for j in range(X.shape[1])])
        np.testing.assert_allclose(values, slip.energy, rtol=1e-8)
    for event in sim.events:
        phase = slip.phases[event.phase]
        target = next(t.target for t in phase.transitions if t.name == event.transition)
        before = float(phase.conserved["energy"](event.state_before, p))
        after = float(slip.phases[target].conserved["energy"](event.state_after, p))
        assert after == pytest.approx(before, rel=1e-12)


def test_touchdown_and_liftoff_geometry(slip, gaits):
    # Touchdown at z = h + l0 cos θ_td with the hip at r = l0, θ = −θ_td about the foot; liftoff
    # at r = l0.  Tolerance 1e-12 (located events, exact resets).
    sim = gaitopt.simulate(slip, gaits[0.87].x, steps=1)
    touchdown, liftoff, apex = sim.events
    assert touchdown.state_before[1] == pytest.approx(math.cos(math.pi / 6), abs=1e-12)
    assert touchdown.state_after[0] == pytest.approx(1.0, abs=1e-12)
    assert touchdown.state_after[1] == pytest.approx(-math.pi / 6, abs=1e-12)
    assert liftoff.state_before[0] == pytest.approx(1.0, abs=1e-12)
    assert apex.state_after[0] == 0.0 and abs(apex.state_after[3]) < 1e-12


def test_touchdown_angle_is_the_per_step_input(slip):
    # The parameter is only the default input: a model with θ_td = 0.5 rad and the default
    # model driven by the input 0.5 rad have the same gait (same floats: exact).
    by_parameter = gaitopt.find_limit_cycle(slip.replace(touchdown_angle=0.5), {"z": 1.0})
    by_input = gaitopt.find_limit_cycle(slip, {"z": 1.0}, inputs=[0.5])
    assert by_parameter.success and by_input.success
    assert by_parameter.fixed_point["z"] == pytest.approx(by_input.fixed_point["z"], abs=1e-12)


def test_ground_height_shifts_the_map(slip):
    # Raising the ground by h lowers the touchdown: the apex map with ground h from z equals
    # h + the map of a runner with energy E − m g h from z − h (translation invariance).
    # Tolerance 1e-9 (two simulations at rtol 1e-11).
    h = 0.03
    raised = slip.replace(ground_height=h)
    shifted = slip.replace(energy=slip.energy - slip.mass * slip.gravity * h)
    assert return_map(raised, 0.95)[0] == pytest.approx(h + return_map(shifted, 0.95 - h)[0], 1e-9)


def test_a_runner_without_enough_energy_is_refused():
    with pytest.raises(ParameterError, match=r"`energy`.*touchdown height"):
        gaitopt.model("slip", energy=600.0)


def test_swing_leg_model_with_a_constant_law_is_the_slip(slip):
    # SlipSwingLeg with only c0 = θ_td is the SLIP (same guard, same reset): same apex map.
    swing = SlipSwingLeg(**slip.params)
    assert return_map(swing, 0.9, inputs=swing.nominal_input())[0] == pytest.approx(
        return_map(slip, 0.9)[0], abs=1e-12
    )
