"""The one-dimensional hopper of Tedrake's exercise (gaitopt.models.one_d_hopper).

Source of every closed form: Tedrake, *Underactuated Robotics*, ch. "Simple Models of Walking
and Running", exercise "One-Dimensional Hopper", notebook
``exercises/simple_legs/one_d_hopper.ipynb`` (the energy E(t), the plastic touchdown and lift-off,
the preload law δ̄ at the bottom, reset at the apex); equation numbers refer to the module
docstring of :mod:`gaitopt.models.one_d_hopper`, which restates them.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import gaitopt
from gaitopt.cli import main
from gaitopt.errors import ParameterError
from gaitopt.models.one_d_hopper import OneDHopper
from gaitopt.returnmap import return_map

# An independent simulation (plain NumPy equations, SciPy DOP853 at rtol = atol = 1e-12, events
# located by SciPy's root finder to machine precision): the apex it reaches, 1e-10 m.
INDEPENDENT_TOL = 1e-10
# gaitopt.simulate at its default rtol 1e-11 (the referee the gait search uses): apex 1e-9 m.
SIM_TOL = 1e-9
# Shooting residual and discretisation-error estimate ≤ 1e-10: fixed point 1e-9 m, multiplier
# 1e-9, period 1e-9 s.
TOL = 1e-9


@pytest.fixture(scope="module")
def hopper() -> OneDHopper:
    return gaitopt.model("one_d_hopper")


def _independent_hop(hopper: OneDHopper, apex: float) -> dict[str, float]:
    """One hop from an apex at ``apex`` (m) by the notebook's equations, written here in NumPy
    (not the model's CasADi functions): the flights in closed form (ballistic), the two stance
    phases integrated by SciPy with the events bottom (ż_b = 0 rising) and lift-off (z_b = 0
    rising, i.e. l = −z_b = 0), the preload by the notebook's law at the simulated bottom."""
    mb, ml, k, g = hopper.body_mass, hopper.leg_mass, hopper.stiffness, hopper.gravity
    hd = hopper.desired_apex
    v_td = -math.sqrt(2 * g * apex)  # ballistic fall from the apex to z_b = z_l = 0

    def stance(delta):
        # foot on the ground (z_l = 0, l = −z_b): m_b z̈_b = −m_b g + k (l + δ)
        return lambda t, y: [y[1], -g + k * (-y[0] + delta) / mb]

    def bottom(t, y):
        return y[1]

    bottom.terminal, bottom.direction = True, 1

    def liftoff(t, y):
        return y[0]

    liftoff.terminal, liftoff.direction = True, 1
    opts = dict(method="DOP853", rtol=1e-12, atol=1e-12, max_step=0.05)
    # touchdown: the leg stops, the body keeps v_td (no impulse through the spring)
    first = solve_ivp(stance(0.0), (0, 5), [0.0, v_td], events=bottom, **opts)
    z_bt = float(first.y_events[0][0][0])
    delta_bar = z_bt / 2 + mb * g / k - (mb + ml) ** 2 * g * hd / (k * mb * z_bt)
    delta = max(delta_bar, 0.0)
    # start just off the bottom event (the body rests there): z_b(t_bt) = z_bt, ż_b = 0
    second = solve_ivp(stance(delta), (0, 5), [z_bt, 0.0], events=liftoff, **opts)
    v_minus = float(second.y_events[0][0][1])
    v_plus = mb * v_minus / (mb + ml)  # plastic lift-off, momentum conserved
    return {
        "bottom": z_bt,
        "delta_bar": delta_bar,
        "delta": delta,
        "v_liftoff_minus": v_minus,
        "v_liftoff_plus": v_plus,
        "apex": v_plus**2 / (2 * g),  # ballistic rise of body and leg together
        "t_compression": float(first.t_events[0][0]),
        "t_thrust": float(second.t_events[0][0]),
    }


# -- the deadbeat preload ------------------------------------------------------------------------


def test_deadbeat_preload_reaches_the_target_apex_in_an_independent_simulation(hopper):
    # Source: the notebook's law (eq. 3) for h = 1.0 m → h_d = 1.0 m: δ̄ = z/2 + m_b g/k −
    # (m_b + m_l)² g h_d / (k m_b z) with z = −0.5517778703 m (eq. 2); the next apex is h_d.
    # Tolerances: bottom and preload 1e-11 m (event location vs the closed form), apex
    # INDEPENDENT_TOL.
    hop = _independent_hop(hopper, 1.0)
    assert hop["bottom"] == pytest.approx(hopper.bottom(1.0), abs=1e-11)
    assert hopper.bottom(1.0) == pytest.approx(-0.0981 - math.sqrt(0.0981**2 + 0.1962), rel=1e-15)
    assert hop["delta"] == hop["delta_bar"] == pytest.approx(hopper.preload(1.0), abs=1e-11)
    assert hopper.preload(1.0) == pytest.approx(0.0373356763815, abs=1e-12)
    assert hop["apex"] == pytest.approx(1.0, abs=INDEPENDENT_TOL)
    # The same hop through the model (gaitopt.simulate, the model's own CasADi equations).
    sim = gaitopt.simulate(hopper, {"z_b": 1.0}, steps=1)
    assert sim.success, sim.message
    ev = {e.transition: e for e in sim.events}
    assert ev["bottom (preload)"].state_after[4] == pytest.approx(hopper.preload(1.0), abs=1e-11)
    assert sim.section_states[-1][0] == pytest.approx(1.0, abs=SIM_TOL)


@pytest.mark.parametrize("apex", [0.05, 0.4, 1.0, 1.2])
def test_one_hop_from_anywhere_in_the_deadbeat_region_reaches_the_target(hopper, apex):
    # Source: eqs. (3)–(5): from every apex 0 < h ≤ h_d/ρ = 1.21 m the law's δ̄ ≥ 0 and the next
    # apex is h_d = 1 m exactly.  Independent simulation, INDEPENDENT_TOL.
    hop = _independent_hop(hopper, apex)
    assert hop["delta_bar"] >= 0
    assert hop["apex"] == pytest.approx(hopper.desired_apex, abs=INDEPENDENT_TOL)


def test_deadbeat_region_edge_is_where_the_preload_vanishes(hopper):
    # Source: eq. (4) increases with δ and eq. (5) is the δ = 0 map, so δ̄(h) = 0 exactly at
    # ρ h = h_d: the region is (0, h_d/ρ] = (0, 1.21] m at the defaults.  Closed-form identity
    # to 1e-12 m (rounding); the map is continuous there (1e-12 m).
    lo, hi = hopper.deadbeat_region()
    assert (lo, hi) == (0.0, pytest.approx(1.21, abs=1e-12))
    assert hopper.preload_law(hi) == pytest.approx(0.0, abs=1e-12)
    assert hopper.preload_law(hi - 1e-3) > 0 > hopper.preload_law(hi + 1e-3)
    assert hopper.closed_form_map(hi) == pytest.approx(hopper.desired_apex, abs=1e-12)


# -- the passive hop: the apex ratio --------------------------------------------------------------


@pytest.mark.parametrize("apex, desired", [(1.5, 1.0), (2.0, 1.0), (0.5, 0.0), (2.1, 0.0)])
def test_passive_apex_ratio_matches_the_simulated_energy_loss(hopper, apex, desired):
    # Derivation (closed form, eq. 5).  Apex h: body and leg fall together to z_b = z_l = 0 at
    # speed v = sqrt(2 g h), energy E = (m_b + m_l) g h.  Touchdown stops the leg: it loses
    # ½ m_l v² = m_l g h.  Stance with δ = 0 conserves ½ m_b ż_b² + m_b g z_b + ½ k z_b², the same
    # on the way down and up, so the body reaches the stop (z_b = 0) again at speed v.  Lift-off
    # is plastic with no external impulse: (m_b + m_l) v⁺ = m_b v, losing ½ m_b v² · m_l/(m_b +
    # m_l) = m_b m_l g h/(m_b + m_l).  Next apex h' = v⁺²/(2g) = ρ h, ρ = (m_b/(m_b + m_l))² =
    # 100/121, and the energy after is ρ E: the two losses add up to (1 − ρ) E.
    # Where δ̄ clamps at 0 (ρ h > h_d, or h_d = 0 always) the hop is this passive one.
    # Tolerances: ratio and energies from gaitopt.simulate (rtol 1e-11) to 1e-10 relative; the
    # independent simulation's apex to INDEPENDENT_TOL.
    model = hopper.replace(desired_apex=desired)
    rho = model.apex_ratio
    assert rho == pytest.approx((10 / 11) ** 2, rel=1e-15)
    assert model.preload_law(apex) < 0  # the clamp is active: a passive hop
    sim = gaitopt.simulate(model, {"z_b": apex}, steps=1)
    assert sim.success, sim.message
    ev = {e.transition: e for e in sim.events}
    p, phases = model.p, model.phases
    energy = [phase.conserved["energy"] for phase in phases]
    total = model.body_mass + model.leg_mass
    e0 = total * model.gravity * apex
    td, lo = ev["touchdown"], ev["lift-off"]
    assert float(energy[0](td.state_before, p)) == pytest.approx(e0, rel=1e-10)
    td_loss = float(energy[0](td.state_before, p)) - float(energy[1](td.state_after, p))
    lo_loss = float(energy[2](lo.state_before, p)) - float(energy[3](lo.state_after, p))
    assert td_loss == pytest.approx(model.leg_mass * model.gravity * apex, rel=1e-10)
    assert lo_loss == pytest.approx(
        model.body_mass * model.leg_mass * model.gravity * apex / total, rel=1e-10
    )
    assert td_loss + lo_loss == pytest.approx((1 - rho) * e0, rel=1e-10)
    assert ev["bottom (preload)"].state_after[4] == 0.0  # δ = max(δ̄, 0) = 0 exactly
    assert sim.section_states[-1][0] / apex == pytest.approx(rho, rel=1e-10)
    assert _independent_hop(model, apex)["apex"] == pytest.approx(rho * apex, abs=INDEPENDENT_TOL)


# -- energy in each phase, momentum through the impacts -------------------------------------------


@pytest.mark.parametrize("apex", [1.0, 1.8])
def test_energy_is_conserved_in_each_phase_and_jumps_as_derived(hopper, apex):
    # Source: eq. (1) is constant along every phase's flow (gravity and the spring only; the
    # locked flights keep l = l̇ = 0).  Simulated at rtol 1e-12, atol 1e-13 over two hops (from
    # 1.8 m: a passive hop, then a deadbeat one); spread within a phase ≤ 1e-10 relative to
    # (1 + max |E|).  The jumps, closed form to 1e-9 relative: touchdown −½ m_l ż_b², bottom
    # +½ k δ² − k δ z (eq. 3's derivation), lift-off −½ m_b ż_b⁻² m_l/(m_b + m_l), apex −½ k δ²
    # (the preload reset withdraws the spring's stored energy).
    sim = gaitopt.simulate(hopper, {"z_b": apex}, steps=2, rtol=1e-12, atol=1e-13)
    assert sim.success, sim.message
    p = hopper.p
    for arc in sim.arcs:
        conserved = hopper.phases[arc.phase].conserved["energy"]
        _, X = arc.sample(200)
        values = np.array([float(conserved(X[:, j], p)) for j in range(X.shape[1])])
        assert np.ptp(values) <= 1e-10 * (1 + np.max(np.abs(values))), arc.phase
    mb, ml, k = hopper.body_mass, hopper.leg_mass, hopper.stiffness
    expected = {
        "touchdown": lambda x, y: -0.5 * ml * x[2] ** 2,
        "bottom (preload)": lambda x, y: 0.5 * k * y[4] ** 2 - k * y[4] * x[0],
        "lift-off": lambda x, y: -0.5 * mb * x[2] ** 2 * ml / (mb + ml),
        "apex": lambda x, y: -0.5 * k * x[4] ** 2,
    }
    for e in sim.events:
        target = (e.phase + 1) % 4
        before = float(hopper.phases[e.phase].conserved["energy"](e.state_before, p))
        after = float(hopper.phases[target].conserved["energy"](e.state_after, p))
        jump = expected[e.transition](e.state_before, e.state_after)
        assert after - before == pytest.approx(jump, rel=1e-9, abs=1e-9 * abs(before)), e.transition


def test_momentum_through_the_plastic_impacts(hopper):
    # Source: the notebook.  Touchdown: the spring passes no impulse, so the body's momentum
    # m_b ż_b is unchanged and the leg's, m_l ż_l, goes to 0 (the ground's impulse).  Lift-off:
    # no external impulse (the ground cannot pull), the total momentum m_b ż_b + m_l ż_l is
    # conserved and both move together (ż_l = ż_b + l̇).  Exact algebra of the resets: 1e-12
    # relative.
    sim = gaitopt.simulate(hopper, {"z_b": 1.0}, steps=1)
    ev = {e.transition: e for e in sim.events}
    mb, ml = hopper.body_mass, hopper.leg_mass

    def momenta(x):
        return mb * x[2], ml * (x[2] + x[3])  # body, leg (ż_l = ż_b + l̇)

    (b0, l0), (b1, l1) = momenta(ev["touchdown"].state_before), momenta(ev["touchdown"].state_after)
    assert b1 == pytest.approx(b0, rel=1e-12) and l1 == 0.0 and l0 < 0
    x_before, x_after = ev["lift-off"].state_before, ev["lift-off"].state_after
    assert sum(momenta(x_after)) == pytest.approx(sum(momenta(x_before)), rel=1e-12)
    assert momenta(x_before)[1] == pytest.approx(0.0, abs=1e-12)  # the leg rested on the ground
    assert x_after[3] == 0.0 and x_after[1] == 0.0  # together, on the stop


# -- the gait, its multiplier and period; continuation ---------------------------------------------


def _closed_form_period(hopper: OneDHopper, h: float) -> float:
    """Period (s) of the hop from ``h`` back to ``h = h_d``: ballistic descent ``sqrt(2h/g)``;
    the stance phases are harmonic at ``ω = sqrt(k/m_b)`` about ``δ − m_b g/k``; ballistic ascent
    ``v⁺/g``."""
    mb, ml, k, g = hopper.body_mass, hopper.leg_mass, hopper.stiffness, hopper.gravity
    w, a = math.sqrt(k / mb), mb * g / k
    v0 = math.sqrt(2 * g * h)
    t_compression = (math.pi - math.atan2(v0 / w, a)) / w  # y = z + a from (a, −v0) to its minimum
    z_bt, delta = hopper.bottom(h), hopper.preload(h)
    centre = delta - a
    amplitude = centre - z_bt  # z = centre − amplitude cos ω t from rest at z_bt
    t_thrust = math.acos(centre / amplitude) / w  # z = 0
    v_plus = mb * amplitude * w * math.sin(w * t_thrust) / (mb + ml)
    return math.sqrt(2 * h / g) + t_compression + t_thrust + v_plus / g


def test_gait_is_the_deadbeat_fixed_point(hopper):
    # Source: eqs. (3)–(5): h* = h_d = 1 m, P'(h*) = 0; period by the closed form above
    # (1.2514090635 s), the stance times also against the independent simulation (1e-10 s).
    # Tolerance TOL.
    cycle = gaitopt.find_limit_cycle(hopper)
    assert cycle.success and cycle.verified and cycle.stable, cycle.message
    assert cycle.fixed_point["z_b"] == pytest.approx(1.0, abs=TOL)
    assert cycle.fixed_point["l"] == cycle.fixed_point["l_dot"] == 0.0
    assert abs(cycle.multipliers[0]) < TOL
    period = _closed_form_period(hopper, 1.0)
    assert cycle.period == pytest.approx(period, abs=TOL)
    hop = _independent_hop(hopper, 1.0)
    assert cycle.durations[1] == pytest.approx(hop["t_compression"], abs=1e-10)
    assert cycle.durations[2] == pytest.approx(hop["t_thrust"], abs=1e-10)


def test_continuation_in_the_desired_apex_follows_h_d_to_the_stroke(hopper):
    # Source: h* = h_d with multiplier 0 along the branch; the branch ends where the stance's
    # deepest compression reaches the stroke s, h_max = k s²/(2 m_b g) − s = 2.18393476 m
    # (module docstring).  Tolerances: TOL on h* and λ; the boundary located within 1e-7 m
    # (continuation's bisection on a constraint's minimum over the orbit's samples; 1.2e-8 seen).
    branch = gaitopt.continuation(hopper, "desired_apex", to=2.5)
    assert branch.cycles
    for cycle in branch.cycles:
        assert cycle.success, cycle.message
        assert cycle.fixed_point["z_b"] == pytest.approx(cycle.model.desired_apex, abs=TOL)
        assert abs(cycle.multipliers[0]) < TOL
    assert hopper.highest_apex() == pytest.approx(0.5 * 1000 * 0.76**2 / 98.1 - 0.76, rel=1e-15)
    boundaries = [sp.param for sp in branch.special_points if sp.kind == "boundary"]
    assert boundaries and boundaries[0] == pytest.approx(hopper.highest_apex(), abs=1e-7)


def test_simulated_map_is_the_closed_form_map(hopper):
    # Source: eqs. (3)–(5): h_d in (0, h_d/ρ], ρ h above, NaN above h_max (the stroke).  The
    # simulated map (gaitopt.returnmap, rtol 1e-11) to SIM_TOL.
    for h in (0.1, 0.7, 1.1, 1.3, 1.9, 2.15):
        assert return_map(hopper, h)[0] == pytest.approx(hopper.closed_form_map(h), abs=SIM_TOL)
    assert math.isnan(hopper.closed_form_map(2.2)) and math.isnan(hopper.closed_form_map(0.0))
    sim = gaitopt.simulate(hopper, {"z_b": 2.2}, steps=1)
    assert not sim.success and "stroke" in sim.message


# -- bad input ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "params, match",
    [
        ({"stiffness": -1000.0}, "stiffness"),
        ({"body_mass": 0.0}, "body_mass"),
        ({"leg_mass": -1.0}, "leg_mass"),
        ({"desired_apex": -0.5}, "desired_apex"),
        ({"stroke": 0.1}, "stroke"),  # shorter than 2 m_b g/k = 0.1962 m: cannot carry the body
    ],
)
def test_bad_parameters_are_refused_clearly(params, match):
    with pytest.raises(ParameterError, match=match):
        gaitopt.model("one_d_hopper", **params)


def test_unreachable_desired_apex_is_an_honest_failure(hopper):
    # h_d = 2.5 m > h_max = 2.1839 m: the gait would compress the leg beyond its stroke.
    cycle = gaitopt.find_limit_cycle(hopper.replace(desired_apex=2.5))
    assert not cycle.success and cycle.status == "not_a_gait"
    assert "stroke exhausted" in cycle.message and "unreachable" in cycle.message


def test_passive_hopper_has_no_gait_and_says_why(hopper, capsys):
    # h_d = 0: the law never preloads, P(h) = ρ h has only the standing fixed point h = 0.
    model = hopper.replace(desired_apex=0.0)
    cycle = gaitopt.find_limit_cycle(model, follow=False)
    assert not cycle.success
    assert "no hopping gait" in cycle.message and "0.826446" in cycle.message
    assert main(["solve", "one_d_hopper", "--set", "desired_apex=0", "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["success"] is False and "no hopping gait" in out["message"]


def test_cli_solves_the_exercise(capsys):
    # The notebook's h = 1 m: the fixed point h* = 1 m, multiplier 0 (TOL).
    assert main(["solve", "one_d_hopper", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["success"] and out["fixed_point"]["z_b"] == pytest.approx(1.0, abs=TOL)
