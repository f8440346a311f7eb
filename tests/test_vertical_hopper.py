"""The vertical hopper with the energy-based thrust controller (Raibert 1984/1986)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.models.vertical_hopper import VerticalHopper
from gaitopt.returnmap import return_map

# Shooting residual and discretisation-error estimate ≤ 1e-10: closed forms to 1e-9.
TOL = 1e-9
# Event-located SciPy simulation (rtol 1e-11) of one hop vs closed forms: 1e-9 m.
SIM_TOL = 1e-9


@pytest.fixture(scope="module")
def hopper() -> VerticalHopper:
    return gaitopt.model("vertical_hopper")


@pytest.fixture(scope="module")
def damped(hopper) -> gaitopt.LimitCycle:
    # ζ = b / (2 sqrt(k m)) = 0.05: the thrust-phase damper loss is not replaced by the controller.
    return gaitopt.find_limit_cycle(hopper.replace(damping=20.0))


def test_simulated_map_is_the_closed_form(hopper):
    # Source: module docstring, eq. (3): y' = y + K (h_d − y) for the undamped hopper, from any
    # apex above the leg; and eqs. (1)–(2) with a thrust offset u (energy injected
    # W = k δ c + ½ k δ² in closed form).  Tolerance SIM_TOL.
    for y in (0.52, 0.6, 0.7, 0.9, 1.5, 2.0):
        expected = y + hopper.gain * (hopper.desired_height - y)
        assert hopper.closed_form_map(y) == pytest.approx(expected, abs=1e-14)
        assert return_map(hopper, y)[0] == pytest.approx(expected, abs=SIM_TOL)
    for offset in (0.01, -0.002):
        assert return_map(hopper, 0.8, inputs=[offset])[0] == pytest.approx(
            hopper.closed_form_map(0.8, offset), abs=SIM_TOL
        )
    # Below the leg length the map is undefined: a named fall, NaN.
    assert np.isnan(return_map(hopper, 0.49)[0])
    sim = gaitopt.simulate(hopper, {"y": 0.49}, steps=1)
    assert sim.status == "fell" and "below the leg length" in sim.message


@pytest.mark.parametrize("gain", [0.3, 0.5, 1.0, 1.9, 2.2])
def test_fixed_point_and_multiplier_match_the_closed_form(hopper, gain):
    # Source: eq. (3): y* = h_d, P'(y*) = 1 − K; stable iff 0 < K < 2.  Tolerance TOL.
    model = hopper.replace(gain=gain)
    cycle = gaitopt.find_limit_cycle(model)
    assert cycle.success and cycle.verified, cycle.message
    assert cycle.fixed_point["y"] == pytest.approx(model.closed_form_fixed_point(), abs=TOL)
    assert cycle.multipliers[0].real == pytest.approx(1 - gain, abs=TOL)
    assert cycle.stable == (0 < gain < 2)


def _one_hop(model, apex: float):
    """One simulated hop from an apex at ``apex`` (m): the touchdown loss and the thrust's work
    (J, from the phases' energy functions across the two resets), and the bottom and lift-off
    events."""
    sim = gaitopt.simulate(model, {"y": apex}, steps=1)
    ev = {e.transition: e for e in sim.events}
    p = model.p
    energy = {i: model.phases[i].conserved["energy"] for i in range(4)}
    td, bottom, lo = ev["touchdown"], ev["bottom (thrust)"], ev["lift-off"]
    loss = float(energy[0](td.state_before, p)) - float(energy[1](td.state_after, p))
    work = float(energy[2](bottom.state_after, p)) - float(energy[1](bottom.state_before, p))
    return loss, work, bottom, lo


def test_thrust_balances_the_touchdown_loss_at_the_fixed_point(hopper):
    # Source: eqs. (1), (4): at y* = h_d the bottom compression is c* = 0.1216356 m, the thrust
    # δ* = 0.0039678 m and W* = k δ* c* + ½ k δ*² = ε m g (h_d − l0) = 1.962 J, the touchdown loss.
    # Measured in one simulated hop from the fixed point: tolerance SIM_TOL (lengths), 1e-8 J.
    c_star, delta_star, work = hopper.fixed_point_thrust()
    assert work == pytest.approx(0.1 * 10 * 9.81 * 0.2, rel=1e-14)
    assert hopper.thrust_work(delta_star, c_star) == pytest.approx(work, rel=1e-12)
    loss, gain, bottom, lo = _one_hop(hopper, hopper.desired_height)
    assert loss == pytest.approx(work, abs=1e-8)
    assert gain == pytest.approx(work, abs=1e-8)
    assert hopper.rest_length - bottom.state_before[0] == pytest.approx(c_star, abs=SIM_TOL)
    assert bottom.state_after[2] == pytest.approx(delta_star, abs=SIM_TOL)
    assert lo.state_before[0] == pytest.approx(hopper.rest_length + delta_star, abs=SIM_TOL)


def test_period_doubling_ends_the_stable_range(hopper):
    # Continuation in K locates the PD at the closed form K = 2 (eq. 3); tolerance 1e-6.
    branch = gaitopt.continuation(hopper, "gain", to=2.4, cascade=False)
    pds = [sp.param for sp in branch.special_points if sp.kind == "PD"]
    assert len(pds) == 1
    assert pds[0] == pytest.approx(hopper.stable_gains()[1], abs=1e-6)


@pytest.mark.parametrize("damping", [0.0, 20.0])
def test_energy_bookkeeping_through_each_phase(hopper, damping):
    # Invariants: in every phase the energy (+ the damper's ∫ b ẏ² dt in stance) is constant
    # (1e-9 relative); touchdown removes ε of the kinetic energy (1e-12 relative); lift-off and
    # apex are continuous (spring relaxed at lift-off; 1e-9 J).  Three hops from 1 m.
    model = hopper.replace(damping=damping)
    p = model.p
    sim = gaitopt.simulate(model, {"y": 1.0}, steps=3)
    assert sim.success
    for arc in sim.arcs:
        energy = model.phases[arc.phase].conserved["energy"]
        _, x = arc.sample(100)
        values = np.array([float(energy(x[:, j], p)) for j in range(x.shape[1])])
        assert np.ptp(values) < 1e-9 * (1 + np.max(np.abs(values)))
    targets = {"touchdown": 1, "bottom (thrust)": 2, "lift-off": 3, "apex": 0}
    for ev in sim.events:
        before = float(model.phases[ev.phase].conserved["energy"](ev.state_before, p))
        after = float(model.phases[targets[ev.transition]].conserved["energy"](ev.state_after, p))
        if ev.transition == "touchdown":
            kinetic = 0.5 * model.mass * ev.state_before[1] ** 2
            assert before - after == pytest.approx(model.touchdown_loss * kinetic, rel=1e-12)
            assert ev.state_after[2] == pytest.approx(before, rel=1e-15)  # E_a stored
        elif ev.transition in ("lift-off", "apex"):
            # The damper's account is dropped at lift-off: compare mechanical energies.
            dissipated = ev.state_before[3] if ev.transition == "lift-off" else 0.0
            assert after == pytest.approx(before - dissipated, abs=1e-9)


def test_damped_fixed_point_balances_thrust_against_all_losses(hopper, damped):
    # With damping the thrust-phase loss L2 is not replaced, so y* < h_d; the energy balance
    # still holds on the shooting orbit: thrust work W = touchdown loss + ∫ b ẏ² dt (1e-8 J,
    # shooting residual 1e-10).  y* ≈ h_d − L2 / (K m g) to first order (module docstring; 5 %).
    assert damped.success and damped.verified, damped.message
    model = damped.model
    y_star = damped.fixed_point["y"]
    assert y_star < model.desired_height
    touchdown_loss, work, bottom, lo = _one_hop(model, y_star)
    dissipated = lo.state_before[3]
    assert work == pytest.approx(touchdown_loss + dissipated, abs=1e-8)
    l2 = dissipated - bottom.state_before[3]
    offset = model.desired_height - y_star
    assert offset == pytest.approx(l2 / (model.gain * model.weight), rel=0.05)


def test_ad_multiplier_matches_finite_differences_of_the_simulated_map(damped):
    # AD multiplier (shooting) vs the central difference of the simulated apex map, h = 1e-5 m:
    # truncation O(h²) ~ 1e-10, roundoff ~ 1e-11 / h = 1e-6 → tolerance 1e-5.
    model = damped.model
    y = damped.fixed_point["y"]
    h = 1e-5
    fd = (return_map(model, y + h)[0] - return_map(model, y - h)[0]) / (2 * h)
    assert damped.multipliers[0].real == pytest.approx(fd, abs=1e-5)
    # The input Jacobian ∂P/∂u against the same difference in the thrust offset.
    fd_u = (return_map(model, y, inputs=[h])[0] - return_map(model, y, inputs=[-h])[0]) / (2 * h)
    assert damped.input_jacobian[0, 0] == pytest.approx(fd_u, rel=1e-5)


def test_convergence_from_other_heights_matches_the_multiplier(hopper, damped):
    # Undamped: the apex error shrinks by exactly 1 − K = 0.5 per hop (eq. 3); the simulated map
    # is exact to ~3e-11 m and the errors stay above 5e-4 m, so the ratios agree to 1e-6.
    # Damped: the ratio of successive errors tends to the AD multiplier (within 2e-3 once the
    # error is below 3 mm; the map's curvature gives the rest).
    for start in (0.55, 1.2):
        sim = gaitopt.simulate(hopper, {"y": start}, steps=8)
        err = sim.section_states[:, 0] - hopper.desired_height
        ratios = err[1:] / err[:-1]
        assert np.allclose(ratios, 1 - hopper.gain, rtol=0, atol=1e-6)
    model = damped.model
    y_star = damped.fixed_point["y"]
    for start in (0.55, 1.2):
        sim = gaitopt.simulate(model, {"y": start}, steps=14)
        err = sim.section_states[:, 0] - y_star
        assert abs(err[-1]) < 1e-4
        late = [b / a for a, b in zip(err[:-1], err[1:], strict=True) if abs(a) < 3e-3]
        assert late and all(abs(r - damped.multipliers[0].real) < 2e-3 for r in late)
    # Unstable gain (λ = −1.2): a 1 mm error grows past 5 mm in 12 hops.
    unstable = hopper.replace(gain=2.2)
    sim = gaitopt.simulate(unstable, {"y": hopper.desired_height + 1e-3}, steps=12)
    assert abs(sim.section_states[-1, 0] - hopper.desired_height) > 5e-3


def test_bad_desired_height_is_rejected(hopper):
    with pytest.raises(gaitopt.ParameterError, match="desired_height"):
        hopper.replace(desired_height=0.4)
    with pytest.raises(gaitopt.ParameterError, match="gain"):
        hopper.replace(gain=0.0)


def test_cli_solves_the_hopper(capsys):
    assert main(["solve", "vertical_hopper", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] and data["verified"] and data["stable"]
    # Source: eq. (3): y* = h_d = 0.7 m, multiplier 1 − K = 0.5.  Tolerance TOL.
    assert data["fixed_point"]["y"] == pytest.approx(0.7, abs=TOL)
    assert data["multipliers"][0][0] == pytest.approx(0.5, abs=TOL)


def test_old_name_of_the_closed_form_fixed_point_still_answers(hopper):
    # `fixed_point` names the found gait's section point; the closed form moved to
    # `closed_form_fixed_point` and the old method name warns (same value, exactly).
    with pytest.warns(DeprecationWarning, match="closed_form_fixed_point"):
        assert hopper.fixed_point() == hopper.closed_form_fixed_point() == hopper.desired_height
