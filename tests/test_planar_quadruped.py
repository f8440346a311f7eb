"""The planar quadruped (Scout II template): the pitch-free pronk is the SLIP of stiffness 2k,
energy is conserved in every phase and across every event, a passive bound exists and is
verified, bad input is refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.errors import GuessError, ParameterError


@pytest.fixture(scope="module")
def pronk():
    model = gaitopt.model("planar_quadruped_pronk")
    return gaitopt.find_limit_cycle(model)


@pytest.fixture(scope="module")
def bound():
    return gaitopt.find_limit_cycle(gaitopt.model("planar_quadruped"))


def _slip_twin(model):
    """The SLIP with stiffness 2k and the quadruped's mass, energy, rest length and angle."""
    return gaitopt.model(
        "slip",
        mass=model.mass,
        stiffness=2 * model.stiffness,
        rest_length=model.rest_length,
        energy=model.energy,
        touchdown_angle=model.touchdown_angle,
        gravity=model.gravity,
    )


@pytest.mark.parametrize("changes", [{}, {"touchdown_angle": 0.3, "energy": 95.0}])
def test_pitch_free_pronk_is_the_slip_of_twice_the_stiffness(changes):
    # Exact reduction (module docstring): with φ = φ̇ = 0 and equal touchdown angles the two leg
    # forces are equal, their pitch torques ±L F_z cancel, and the COM obeys the SLIP's
    # equations with stiffness 2k.  Two independent computations (Cartesian Newton–Euler in the
    # quadruped, polar coordinates about the foot in gaitopt.models.slip), each solved to a
    # residual and discretisation error ≤ 3e-11 (so that their sum stays below the tolerance):
    # fixed point, speed, period and the multiplier of the pitch-free direction agree to 1e-10
    # (the tolerance).
    model = gaitopt.model("planar_quadruped_pronk", **changes)
    quad = gaitopt.find_limit_cycle(model)
    slip = gaitopt.find_limit_cycle(_slip_twin(model), {"z": quad.fixed_point["z"]})
    for cycle in (quad, slip):
        assert cycle.success and cycle.verified, cycle.message
        assert cycle.residual <= 3e-11 and cycle.discretisation_error <= 3e-11
    assert quad.fixed_point["z"] == pytest.approx(slip.fixed_point["z"], abs=1e-10)
    assert quad.fixed_point["x_dot"] == pytest.approx(slip.fixed_point["x_dot"], abs=1e-10)
    assert quad.period == pytest.approx(slip.period, abs=1e-10)
    assert len(quad.multipliers) == len(slip.multipliers) == 1
    assert quad.multipliers[0] == pytest.approx(slip.multipliers[0], abs=1e-10)
    # The pitch stays zero along the simulated orbit (invariant set), to rounding 1e-12 rad.
    sim = gaitopt.simulate(model, quad.x, steps=1, inputs=quad.inputs)
    for arc in sim.arcs:
        _, X = arc.sample(50)
        assert np.max(np.abs(X[2])) < 1e-12 and np.max(np.abs(X[5])) < 1e-12


def _energies(model, cycle):
    sim = gaitopt.simulate(model, cycle.x, steps=2, inputs=cycle.inputs)
    assert sim.success, sim.message
    per_arc = []
    for arc in sim.arcs:
        energy = model.phases[arc.phase].conserved["energy"]
        _, X = arc.sample(200)
        per_arc.append(np.array([float(energy(X[:, j], model.p)) for j in range(X.shape[1])]))
    return sim, per_arc


@pytest.mark.parametrize("which", ["pronk", "bound"])
def test_energy_is_conserved_in_every_phase_and_across_events(which, pronk, bound):
    # Invariant: E = ½ m |v|² + ½ I φ̇² + m g z + Σ ½ k (l0 − r)² is constant along each phase's
    # flow and equals the `energy` parameter (the section's lift fixes it).  Simulated at the
    # default rtol 1e-11, atol 1e-12 over two strides; tolerance 1e-10 relative to E (≈ 90 J).
    cycle = {"pronk": pronk, "bound": bound}[which]
    model = cycle.model
    sim, per_arc = _energies(model, cycle)
    phases = {arc.phase for arc in sim.arcs}
    assert phases == set(range(len(model.phases)))  # every phase was visited
    for values in per_arc:
        assert np.max(np.abs(values - model.energy)) < 1e-10 * model.energy


def test_a_passive_bound_is_found_and_verified(bound):
    # The default gait of `planar_quadruped`: back stance, flight, front stance, flight, found by
    # multiple shooting and verified by the SciPy simulation (return error ≤ 1e-9).  Its numbers
    # (README): apex z = 0.31816 m, φ = 0, φ̇ = 5.5511 rad/s, ẋ = 0.68169 m/s, period 0.46672 s;
    # multipliers 4.1217 and a complex pair of modulus 1.0628 (unstable).  Checked here to 1e-4
    # against the values of the first solve (a regression check); the AD multipliers are
    # checked against finite differences of the simulated map by tests/test_model_contract.py.
    assert bound.success and bound.verified, bound.message
    fp = bound.fixed_point
    assert fp["z"] == pytest.approx(0.318159, abs=1e-4)
    assert abs(fp["phi"]) < 1e-8  # the bound's apex is level (time-reversal symmetric stride)
    assert fp["phi_dot"] == pytest.approx(5.55108, abs=1e-4)
    assert fp["x_dot"] == pytest.approx(0.681691, abs=1e-4)
    assert bound.period == pytest.approx(0.466724, abs=1e-5)
    moduli = np.sort(np.abs(bound.multipliers))
    np.testing.assert_allclose(moduli, [1.062792, 1.062792, 4.121725], atol=1e-4)
    assert len(bound.durations) == 5 and np.all(bound.durations > 0)
    # The stride is symmetric: descent = ascent, back stance = front stance (1e-8 s).
    d = bound.durations
    assert d[0] == pytest.approx(d[4], abs=1e-8) and d[1] == pytest.approx(d[3], abs=1e-8)


def test_the_pronk_multiplier_matches_the_simulated_map(pronk):
    # AD through the shooting equations vs a central difference (h = 1e-5 m) of the SciPy apex
    # map; error budget h² P''' + rtol/h ~ 1e-6; tolerance 1e-5.
    from gaitopt.returnmap import return_map

    z, h = pronk.fixed_point["z"], 1e-5
    fd = (return_map(pronk.model, [z + h])[0] - return_map(pronk.model, [z - h])[0]) / (2 * h)
    assert pronk.multipliers[0].real == pytest.approx(fd, abs=1e-5)


def test_bad_input_is_refused_in_one_line():
    # Negative stiffness: outside the declared range (0, 1e7].
    with pytest.raises(ParameterError, match="stiffness"):
        gaitopt.model("planar_quadruped", stiffness=-3520.0)
    # Too little energy for any foot to reach the ground from an apex: E/(m g) = 0.293 m below
    # l0 cos θ = 0.313 m (closed form), refused at construction.
    with pytest.raises(ParameterError, match="touchdown height") as err:
        gaitopt.model("planar_quadruped_pronk", energy=60.0)
    assert "\n" not in str(err.value)
    # An apex below the touchdown height: the foot is already below the ground, it never
    # "reaches" it: the simulation ends with a named fall and the search refuses the guess.
    model = gaitopt.model("planar_quadruped_pronk")
    sim = gaitopt.simulate(model, {"z": 0.25}, steps=1)
    assert sim.status == "fell" and "hip reaches the ground" in sim.message
    with pytest.raises(GuessError) as err:
        gaitopt.find_limit_cycle(model, {"z": 0.25})
    assert "\n" not in str(err.value)
    # A touchdown angle at which the front foot lands during back stance: no bound, said.
    quad = gaitopt.model("planar_quadruped")
    sim = gaitopt.simulate(quad, {"z": 0.36, "phi": 0.0, "phi_dot": 1.0}, steps=1)
    assert sim.status == "fell" and "double stance" in sim.message
