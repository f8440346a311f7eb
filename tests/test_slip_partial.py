"""SLIP's partial stability: the (z, ẋ) apex map has the energy-level map's multiplier and a
neutral one (energy is conserved), so a disturbance that changes the energy is not rejected.

Sources: Tedrake, Underactuated Robotics, SLIP (the apex map on one energy level); energy
conservation (E = ½ m ẋ² + m g z at the apex), which makes 1 an exact multiplier of the 2-D map.
The 2-D Jacobian is computed by central differences of simulated steps (problems/
slip_partial_stability.py), independently of the shooting that gives the 1-D multiplier.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import load_study

import gaitopt


@pytest.fixture(scope="module")
def study():
    return load_study("slip_partial_stability")


@pytest.fixture(scope="module")
def gait() -> gaitopt.LimitCycle:
    cycle = gaitopt.find_limit_cycle(gaitopt.model("slip"))
    assert cycle.success, cycle.message
    return cycle


def test_apex_map_multipliers_are_the_level_maps_and_one(study, gait):
    model = gait.model
    z = float(gait.fixed_point["z"])
    v = model.apex_speed(z)
    eig = np.sort(np.linalg.eigvals(study.apex_jacobian(model, z, v)).real)
    lam = complex(gait.multipliers[0]).real
    # Neutral multiplier: exactly 1 by energy conservation; central differences with h = 1e-4 on
    # simulations at rtol 1e-11 are good to ~1e-7 (measured 3e-8): tolerance 1e-6.
    assert eig[1] == pytest.approx(1.0, abs=1e-6)
    # Stable multiplier: the 1-D map's (shooting); the difference quotient's O(h²) truncation is
    # ~1e-5 here (measured 7e-6): tolerance 1e-4.
    assert eig[0] == pytest.approx(lam, abs=1e-4)
    assert abs(eig[0]) < 1


def test_energy_disturbance_is_not_rejected(study, gait):
    model = gait.model
    z = float(gait.fixed_point["z"])
    v = model.apex_speed(z)
    pushed = study.run(model, z, 1.03 * v, 12)
    # Energy is conserved across steps (the push's energy stays): relative 1e-9 (rtol 1e-11).
    energy = study.energy_of(model, z, 1.03 * v)
    np.testing.assert_allclose(pushed[:, 2], energy, rtol=1e-9)
    # The apex converges to the fixed point of the new energy level, not the old one.
    new = gaitopt.find_limit_cycle(model.replace(energy=energy))
    assert new.success, new.message
    z_new = float(new.fixed_point["z"])
    assert abs(z_new - z) > 5e-3
    # 12 steps at |λ| ≈ 0.5 leave ~2e-4 of a 7e-3 offset: tolerance 1e-3 m.
    assert pushed[-1, 0] == pytest.approx(z_new, abs=1e-3)


def test_height_disturbance_at_the_same_energy_is_rejected(study, gait):
    model = gait.model
    z = float(gait.fixed_point["z"])
    v = model.apex_speed(z)
    dz = 0.02
    level = study.run(model, z + dz, math.sqrt(v**2 - 2 * model.gravity * dz), 12)
    # Converges back with the 1-D multiplier (|λ| ≈ 0.49 per step from 0.02 m): 12 steps bring
    # it within 1e-4 m (measured 2e-5).
    assert level[-1, 0] == pytest.approx(z, abs=1e-4)
