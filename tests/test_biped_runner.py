"""The biped runner (two alternating SLIP legs): its symmetric run is the SLIP run twice, energy
is conserved in every phase, an asymmetric limp is found, verified step by step against the SLIP
and classified, bad input is refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.errors import GuessError, ParameterError
from gaitopt.models.biped_runner import classify
from gaitopt.returnmap import return_map

#: A limp: leg B softer (7500 vs 8397.36 N/m) and placed flatter (0.56 vs 0.5236 rad).  Found by
#: continuation from the symmetric default (`find_limit_cycle` without a guess); the guess below
#: is that gait's apex height rounded to 1e-3 m.
LIMP = {"touchdown_angle_b": 0.56, "stiffness_b": 7500.0}


@pytest.fixture(scope="module")
def limp():
    return gaitopt.find_limit_cycle(gaitopt.model("biped_runner", **LIMP), {"z": 0.876})


def _slip_leg(model, leg):
    """The SLIP with the runner's mass, energy, gravity and leg ``leg``'s stiffness, rest
    length and nominal angle."""
    return gaitopt.model(
        "slip",
        mass=model.mass,
        stiffness=getattr(model, f"stiffness_{leg}"),
        rest_length=getattr(model, f"rest_length_{leg}"),
        touchdown_angle=getattr(model, f"touchdown_angle_{leg}"),
        energy=model.energy,
        gravity=model.gravity,
    )


@pytest.mark.parametrize("changes", [{}, {"touchdown_angle_a": 0.52, "touchdown_angle_b": 0.52}])
def test_symmetric_run_is_the_slip_run_twice(changes):
    # Exact reduction (module docstring): identical legs and angles make each step the SLIP
    # apex map S, so the stride map is P = S∘S: same apex height and speed, period 2 T_SLIP,
    # multiplier P'(z*) = S'(z*)² (one multiplier: a 1-D section).  Two independent shooting
    # problems (six phases here, three in gaitopt.models.slip), each solved to a residual and
    # discretisation error ≤ 3e-11; tolerance 1e-10 (the issue's).
    model = gaitopt.model("biped_runner", **changes)
    slip = gaitopt.find_limit_cycle(_slip_leg(model, "a"), {"z": 0.87})
    runner = gaitopt.find_limit_cycle(model, {"z": slip.fixed_point["z"] + 1e-3})
    for cycle in (runner, slip):
        assert cycle.success and cycle.verified, cycle.message
        assert cycle.residual <= 3e-11 and cycle.discretisation_error <= 3e-11
    assert runner.fixed_point["z"] == pytest.approx(slip.fixed_point["z"], abs=1e-10)
    assert runner.fixed_point["x_dot"] == pytest.approx(slip.fixed_point["x_dot"], abs=1e-10)
    assert runner.period == pytest.approx(2 * slip.period, abs=1e-10)
    assert len(runner.multipliers) == len(slip.multipliers) == 1
    assert runner.multipliers[0] == pytest.approx(slip.multipliers[0] ** 2, abs=1e-10)
    # The two steps are equal (the mid-stride apex is the SLIP apex too): 1e-10 m, 1e-10 s.
    steps = classify(runner)
    assert steps["gait"] == "symmetric run"
    assert steps["apex_b"] == pytest.approx(slip.fixed_point["z"], abs=1e-10)
    assert steps["stance_a"] == pytest.approx(steps["stance_b"], abs=1e-10)
    assert steps["step_a"] == pytest.approx(steps["step_b"], abs=1e-10)


@pytest.mark.parametrize("which", ["symmetric", "limp"])
def test_energy_is_conserved_in_every_phase(which, limp):
    # Invariant: E = ½ m |v|² + m g z (+ ½ k (l − r)² in stance) is constant along each phase's
    # flow and equals the `energy` parameter (the section's lift fixes it).  SciPy simulation at
    # the default rtol 1e-11, atol 1e-12 over two strides; tolerance 1e-10 relative to E.
    cycle = limp if which == "limp" else gaitopt.find_limit_cycle(gaitopt.model("biped_runner"))
    model = cycle.model
    sim = gaitopt.simulate(model, cycle.x, steps=2, inputs=cycle.inputs)
    assert sim.success, sim.message
    assert {arc.phase for arc in sim.arcs} == set(range(6))  # every phase visited
    for arc in sim.arcs:
        energy = model.phases[arc.phase].conserved["energy"]
        _, X = arc.sample(200)
        values = np.array([float(energy(X[:, j], model.p)) for j in range(X.shape[1])])
        assert np.max(np.abs(values - model.energy)) < 1e-10 * model.energy


def test_a_limp_is_found_verified_and_classified(limp):
    assert limp.success and limp.verified, limp.message
    model = limp.model
    steps = classify(limp)
    z_a, z_b = steps["apex_a"], steps["apex_b"]
    # The two steps differ: apex heights 0.87576 and 0.87633 m (README), 5.7e-4 m apart, far
    # above the solve's 3e-11 error.
    assert abs(z_a - z_b) > 1e-4
    assert steps["gait"] == "limp"  # aerial phases 0.1213 and 0.1218 s: comparable, not a skip
    # Independent check, step by step: each step of the stride is one step of the SLIP with that
    # leg (gaitopt.models.slip, SciPy event-located simulation, rtol 1e-11): S_A(z_a) = z_b and
    # S_B(z_b) = z_a, and the stride time is the sum of the two SLIP step times.  Error budget:
    # the shooting's 3e-11 plus the simulation's ~1e-10; tolerance 1e-9 m, 1e-9 s.
    times = []
    for leg, z0, z1 in (("a", z_a, z_b), ("b", z_b, z_a)):
        slip = _slip_leg(model, leg)
        sim = gaitopt.simulate(slip, {"z": z0}, steps=1)
        assert sim.success, sim.message
        assert sim.section_states[-1][1] == pytest.approx(z1, abs=1e-9)
        times.append(sim.section_times[-1] - sim.section_times[0])
    assert sum(times) == pytest.approx(limp.period, abs=1e-9)
    # Regression numbers of the first solve (README), 1e-6: multiplier 0.43740 (stable), period
    # 0.82127 s.  The AD multiplier against a central difference (h = 1e-5 m) of the SciPy
    # stride map: error budget h² P''' + rtol/h ~ 1e-6; tolerance 1e-5.
    assert len(limp.multipliers) == 1 and limp.stable
    assert limp.multipliers[0].real == pytest.approx(0.437404, abs=1e-6)
    assert limp.period == pytest.approx(0.821269, abs=1e-6)
    h = 1e-5
    fd = (return_map(model, [z_a + h])[0] - return_map(model, [z_a - h])[0]) / (2 * h)
    assert limp.multipliers[0].real == pytest.approx(fd, abs=1e-5)


def test_bad_input_is_refused_in_one_line():
    # Negative stiffness: outside the declared range (0, 1e7].
    with pytest.raises(ParameterError, match="stiffness_b"):
        gaitopt.model("biped_runner", stiffness_b=-8000.0)
    # A touchdown angle whose foot can never reach the ground from an apex: with θ_b = 0 the
    # touchdown height is l_b = 1 m, above E/(m g) = 0.956 m at E = 750 J (closed form).
    with pytest.raises(ParameterError, match="foot B never reaches the ground") as err:
        gaitopt.model("biped_runner", energy=750.0, touchdown_angle_b=0.0)
    assert "\n" not in str(err.value)
    # An apex below leg A's touchdown height l_a cos θ_a = 0.866 m: the foot is already below
    # the ground, it never "reaches" it: a named fall, and the search refuses the guess.
    model = gaitopt.model("biped_runner")
    sim = gaitopt.simulate(model, {"z": 0.8}, steps=1)
    assert sim.status == "fell" and "touchdown height" in sim.message
    with pytest.raises(GuessError) as err:
        gaitopt.find_limit_cycle(model, {"z": 0.8})
    assert "\n" not in str(err.value)
    # Leg B placed so flat (per-step input θ_b = 1.2 rad, touchdown height 0.36 m) that the
    # runner cannot vault over it: no gait, said honestly (success False, or a simulation fall).
    sim = gaitopt.simulate(model, {"z": 0.877}, steps=1, inputs=[model.touchdown_angle_a, 1.2])
    assert not sim.success and sim.status == "fell", sim.message
