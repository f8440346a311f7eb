"""The kneed walker (issue 5): equations, impacts, curved feet, the passive gait and its stability.

Every numeric check names its source and tolerance.  The point-foot walker is checked against the
closed-form Lagrange equations of the three-link and two-link chains written out by hand here (the
form Hsu Chen 2007 derives); the impacts against the momentum conservation laws they must obey,
which the floating-base derivation does not use explicitly; the gait against an independent
simulation and its multipliers against finite differences of the simulated map.
"""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.animation import walker_frames  # noqa: E402
from gaitopt.errors import ParameterError  # noqa: E402
from gaitopt.models.kneed_walker import BODY_NAMES  # noqa: E402
from gaitopt.plotting import plot_phase_portrait  # noqa: E402

CURVED = 0.2  # m: a curved-foot walker well inside the range with a gait at the default slope


@pytest.fixture(scope="module")
def point() -> gaitopt.LimitCycle:
    cycle = gaitopt.find_limit_cycle(gaitopt.model("kneed_walker"))
    assert cycle.success, cycle.message
    return cycle


@pytest.fixture(scope="module")
def curved(point) -> gaitopt.LimitCycle:
    cycle = gaitopt.find_limit_cycle(point.model.replace(foot_radius=CURVED), point)
    assert cycle.success, cycle.message
    return cycle


@pytest.fixture(params=["point", "curved"])
def gait(request) -> gaitopt.LimitCycle:
    return request.getfixturevalue(request.param)


def _momentum(phase, x, p, about, which=None) -> float:
    """Σ m_i (r_i − c) × v_i over the masses ``which`` (names in BODY_NAMES), planar (kg·m²/s)."""
    m, r, v = (np.asarray(a, dtype=float) for a in phase.bodies(x, p))
    m, r, v = m.ravel(), r.reshape(2, -1), v.reshape(2, -1)
    keep = [BODY_NAMES.index(n) for n in (which or BODY_NAMES)]
    d = r[:, keep] - np.asarray(about, dtype=float).reshape(2, 1)
    return float(np.sum(m[keep] * (d[0] * v[1, keep] - d[1] * v[0, keep])))


def _point(phase, x, p, name) -> np.ndarray:
    return np.asarray(phase.points(x, p), dtype=float)[:, phase.point_names.index(name)]


def _stance_contact(model, q1) -> np.ndarray:
    # Rolling without slipping: the contact is R (q1 − γ) down the slope from the origin.
    g = model.slope
    return model.foot_radius * (q1 - g) * np.array([math.cos(g), -math.sin(g)])


# -- the equations ------------------------------------------------------------------------------


def _closed_form_accelerations(model, q, qd, locked: bool) -> np.ndarray:
    """Hand-written Lagrange equations of the point-foot walker, M q̈ + h + G = 0.

    Absolute angles from vertical; M_ij = c_ij cos(q_i − q_j) off the diagonal, h_i = Σ_j c_ij
    sin(q_i − q_j) q̇_j², G_i = ∂V/∂q_i (the three-link form of Hsu Chen 2007, in the
    compass gait's sign convention; the knee-locked two-link chain sums the shank into the thigh).
    """
    mh, mt, ms, g = model.mass_hip, model.mass_thigh, model.mass_shank, model.gravity
    a1, b1, a2, b2 = model.a1, model.b1, model.a2, model.b2
    ls, lt = a1 + b1, a2 + b2
    L = ls + lt
    c11 = ms * a1**2 + mt * (ls + a2) ** 2 + (mh + mt + ms) * L**2
    g1 = -g * (ms * a1 + mt * (ls + a2) + (mh + mt + ms) * L)
    if locked:
        c = np.array(
            [[c11, -(mt * b2 + ms * (lt + b1)) * L], [0, mt * b2**2 + ms * (lt + b1) ** 2]]
        )
        gv = np.array([g1 * math.sin(q[0]), g * (mt * b2 + ms * (lt + b1)) * math.sin(q[1])])
    else:
        c = np.array(
            [
                [c11, -(mt * b2 + ms * lt) * L, -ms * b1 * L],
                [0, mt * b2**2 + ms * lt**2, ms * lt * b1],
                [0, 0, ms * b1**2],
            ]
        )
        gv = np.array(
            [
                g1 * math.sin(q[0]),
                g * (mt * b2 + ms * lt) * math.sin(q[1]),
                g * ms * b1 * math.sin(q[2]),
            ]
        )
    c = np.triu(c) + np.triu(c, 1).T
    n = len(q)
    M = np.array(
        [[c[i, j] * (math.cos(q[i] - q[j]) if i != j else 1) for j in range(n)] for i in range(n)]
    )
    h = np.array(
        [
            sum(c[i, j] * math.sin(q[i] - q[j]) * qd[j] ** 2 for j in range(n) if j != i)
            for i in range(n)
        ]
    )
    return np.linalg.solve(M, -h - gv)


def test_point_foot_flows_match_the_closed_form_lagrange_equations():
    # Source: the closed form above (hand-derived, independent of gaitopt.mechanics).  The AD
    # derivation with foot_radius = 0 must reproduce it term by term: tolerance 1e-12 relative.
    model = gaitopt.model("kneed_walker")
    rng = np.random.default_rng(5)
    for phase, locked in zip(model.phases, (False, True), strict=True):
        n = phase.n // 2
        for _ in range(5):
            q, qd = rng.uniform(-0.6, 0.6, n), rng.uniform(-3, 3, n)
            ad = np.asarray(phase.flow(np.r_[q, qd], [], model.p), dtype=float).ravel()
            np.testing.assert_allclose(ad[:n], qd, rtol=0, atol=0)
            expected = _closed_form_accelerations(model, q, qd, locked)
            np.testing.assert_allclose(ad[n:], expected, rtol=1e-12, atol=1e-12)


def test_curved_feet_reduce_to_point_feet_at_zero_radius(point, curved):
    # The rolling geometry has R as a factor of every extra term, so foot_radius = 0 is the point
    # foot exactly: (a) the functions tend to it continuously (at R = 1e-9 within 1e-8 relative of
    # R = 0 on random states: the extra terms are O(R)); (b) the curved-foot gait followed back to
    # R = 0 is the point-foot gait to the shooting's own accuracy (Newton stops at 1e-12 on the
    # equations; tolerance 5e-12 on the state and the period).
    model = point.model
    tiny = model.replace(foot_radius=1e-9)
    rng = np.random.default_rng(0)
    for k, phase in enumerate(model.phases):
        for _ in range(3):
            x = rng.uniform(-0.5, 0.5, phase.n)
            a = np.asarray(phase.flow(x, [], model.p), dtype=float)
            b = np.asarray(tiny.phases[k].flow(x, [], tiny.p), dtype=float)
            np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-12)
            tr, tr_tiny = phase.transitions[0], tiny.phases[k].transitions[0]
            a = np.asarray(tr.reset(x, [], model.p), dtype=float)
            b = np.asarray(tr_tiny.reset(x, [], tiny.p), dtype=float)
            np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-12)
    back = gaitopt.find_limit_cycle(curved.model.replace(foot_radius=0.0), curved)
    assert back.success, back.message
    np.testing.assert_allclose(back.x, point.x, rtol=0, atol=5e-12)
    assert back.period == pytest.approx(point.period, abs=5e-12)


def test_foot_radius_is_limited_to_the_shank_length():
    with pytest.raises(ParameterError, match="foot_radius"):
        gaitopt.model("kneed_walker", foot_radius=0.6)  # a1 + b1 = 0.5 m
    assert gaitopt.model("kneed_walker", foot_radius=0.5).foot_radius == 0.5


# -- the gait -----------------------------------------------------------------------------------


def test_passive_gait_at_the_defaults_is_verified_and_stable(point):
    # Two phases per step (knee strike, then heel strike), verified by simulation (rtol 1e-11,
    # accepted at 1e-7), discretisation error below 1e-10, three nontrivial multipliers inside the
    # unit circle.
    assert point.verified and point.stable
    assert [arc.transition for arc in point.orbit] == ["knee strike", "heel strike"]
    assert np.all(point.durations > 0) and point.steps == 1
    assert point.discretisation_error <= 1e-10 and point.residual <= 1e-10
    assert len(point.multipliers) == 3 and np.max(np.abs(point.multipliers)) < 1
    # Section: q2 = q3 = 2·slope − q1 and q3_dot = q2_dot just after heel strike.
    fp, slope = point.fixed_point, point.model.slope
    assert fp["q2"] == fp["q3"] == pytest.approx(2 * slope - fp["q1"], abs=1e-15)
    assert fp["q3_dot"] == fp["q2_dot"]


def test_simulation_from_the_fixed_point_repeats_the_orbit(gait):
    # Independent check (SciPy DOP853 with located events, rtol 1e-11): one step returns to the
    # fixed point and the phases last what the shooting says.  Tolerance 1e-9.
    model = gait.model
    sim = gaitopt.simulate(model, gait.x, steps=2)
    assert sim.success, sim.message
    assert [e.transition for e in sim.events] == ["knee strike", "heel strike"] * 2
    np.testing.assert_allclose(sim.section_states[1], gait.x, atol=1e-9)
    durations = [arc.t1 - arc.t0 for arc in sim.arcs[:2]]
    np.testing.assert_allclose(durations, gait.durations, atol=1e-9)


# -- invariants ---------------------------------------------------------------------------------


def test_energy_is_conserved_in_each_phase(gait):
    # The flows are conservative (rolling without slipping does no work): along the simulated
    # phases (rtol 1e-11) and the shooting orbit's samples; tolerance 1e-9 relative.
    model = gait.model
    sim = gaitopt.simulate(model, gait.x, steps=2)
    arcs = [(arc.phase, arc.sample(200)[1]) for arc in sim.arcs]
    arcs += [(arc.phase, arc.x) for arc in gait.orbit]
    for phase_index, X in arcs:
        energy = model.phases[phase_index].conserved["energy"]
        values = np.array([float(energy(X[:, j], model.p)) for j in range(X.shape[1])])
        assert np.ptp(values) < 1e-9 * (1 + np.max(np.abs(values)))


def _states_around(gait, transition: str) -> tuple[np.ndarray, np.ndarray]:
    """The states just before and just after ``transition`` in one simulated step of ``gait``."""
    sim = gaitopt.simulate(gait.model, gait.x, steps=1)
    (event,) = [e for e in sim.events if e.transition == transition]
    return event.state_before, event.state_after


def test_knee_strike_conserves_angular_momentum_and_locks_the_knee(gait):
    # Knee strike: the locking impulse is internal to the swing leg and the ground impulse acts
    # at the stance contact, so the whole walker's angular momentum about the stance contact and
    # the swing leg's (thigh + shank) about the hip are conserved (the laws behind Hsu Chen 2007's
    # knee-strike equations; the derivation used M Δq̇ = Jᵀ Λ instead).  Tolerance 1e-12
    # relative.  Geometry: the knee is straight at the strike (q2 = q3 to 1e-12) and was
    # extending (q̇3 < q̇2), flexed throughout the three-link phase.
    model, p = gait.model, gait.model.p
    before, after = _states_around(gait, "knee strike")
    three, two = model.phases
    assert before[1] == pytest.approx(before[2], abs=1e-12)
    assert before[5] < before[4]
    assert after[:2].tolist() == before[:2].tolist()
    contact = _stance_contact(model, before[0])
    for which, about_before, about_after in (
        (None, contact, contact),
        (("swing_thigh", "swing_shank"), _point(three, before, p, "hip"), None),
    ):
        about_after = _point(two, after, p, "hip") if about_after is None else about_after
        h0 = _momentum(three, before, p, about_before, which)
        h1 = _momentum(two, after, p, about_after, which)
        assert h1 == pytest.approx(h0, rel=1e-12, abs=1e-14)
    arc = gait.orbit[0]
    flexion = arc.x[2] - arc.x[1]
    assert np.all(flexion[1:-1] > 0)


def test_heel_strike_conserves_angular_momentum(gait):
    # Heel strike (knee locked): the only ground impulse acts at the striking foot's contact, so
    # the whole walker's angular momentum about that point is conserved; the trailing leg (the old
    # stance leg, the new swing leg) feels only the hip impulse, so its angular momentum about the
    # hip is conserved.  After the reset the legs have swapped roles: stance ↔ swing masses.
    # Tolerance 1e-12 relative.
    model, p = gait.model, gait.model.p
    before, after = _states_around(gait, "heel strike")
    three, two = model.phases
    strike = _point(two, before, p, "swing_centre") - model.foot_radius * np.array(
        [math.sin(model.slope), math.cos(model.slope)]
    )
    # The new contact, in the new stance leg's frame.
    contact_after = _stance_contact(model, after[0])
    h0 = _momentum(two, before, p, strike)
    h1 = _momentum(three, after, p, contact_after)
    assert h1 == pytest.approx(h0, rel=1e-12, abs=1e-14)
    h0 = _momentum(two, before, p, _point(two, before, p, "hip"), ("stance_shank", "stance_thigh"))
    h1 = _momentum(three, after, p, _point(three, after, p, "hip"), ("swing_thigh", "swing_shank"))
    assert h1 == pytest.approx(h0, rel=1e-12, abs=1e-14)
    # The released knee starts straight and moving with its thigh; energy is lost.
    assert after[1] == after[2] and after[4] == after[5]
    e0 = float(two.conserved["energy"](before, p))
    e1 = float(three.conserved["energy"](after, p)) + _height_drop(model, before)
    assert e1 < e0


def _height_drop(model, x_before) -> float:
    """Potential energy of the new frame's origin relative to the old one: the energies are
    measured from each stance phase's own origin on the slope."""
    two = model.phases[1]
    origin = _point(two, x_before, model.p, "swing_origin")
    mass = model.mass_hip + 2 * (model.mass_thigh + model.mass_shank)
    return mass * model.gravity * float(origin[1])


def test_heel_strike_geometry_and_the_scuff_rule(gait):
    # At heel strike the swing foot's arc touches the slope ahead of the stance foot: its lowest
    # point is on y = −x tan γ (1e-12) and the legs satisfy q1 + q2 = 2γ with q1 > q2.  The same
    # guard vanishes with the swing foot behind (the post-impact configuration, relabelled, and any
    # touchdown behind): the admissibility rule q1 − q2 > 0 excludes it, and the mid-swing scuff
    # (legs parallel, q1 = q2) is not a zero of the guard.
    model, p = gait.model, gait.model.p
    two = model.phases[1]
    tr = two.transitions[0]
    sim = gaitopt.simulate(model, gait.x, steps=1)
    before = sim.events[-1].state_before
    n = np.array([math.sin(model.slope), math.cos(model.slope)])
    lowest = _point(two, before, p, "swing_centre") - model.foot_radius * n
    assert float(n @ lowest) == pytest.approx(0.0, abs=1e-12)
    assert lowest[0] > _stance_contact(model, before[0])[0] + 0.3  # a step ahead (downhill)
    assert abs(float(tr.guard(before, [], p))) < 1e-12 and float(tr.admissible(before, [], p)) > 0
    behind = before[[1, 0, 3, 2]]  # the same feet, roles swapped: swing foot behind
    assert abs(float(tr.guard(behind, [], p))) < 1e-12
    assert float(tr.admissible(behind, [], p)) < 0
    parallel = np.array([0.3, 0.3, 1.0, -1.0])
    assert abs(float(tr.guard(parallel, [], p))) > 0.1


def test_swing_foot_clears_the_slope_until_the_knee_locks(gait):
    # The knee's purpose: the swing foot stays above the slope through the three-link phase (the
    # declared clearance constraint; a simulation would end in a trip otherwise); it starts on the
    # slope (the trailing foot), 1e-12, and rises at once.
    model, p = gait.model, gait.model.p
    three = model.phases[0]
    clearance = next(c for c in three.constraints if c.outcome == "trip")
    assert clearance.at_start
    arc = gait.orbit[0]
    height = np.array(
        [float(clearance.function(arc.x[:, j], [], p)) for j in range(arc.x.shape[1])]
    )
    assert height[0] == pytest.approx(0.0, abs=1e-12)
    assert np.all(height[1:] > 0)


# -- pictures -----------------------------------------------------------------------------------


def test_phase_portrait_marks_knee_and_heel_strikes(point):
    # The textbook's limit-cycle figure: q1, q2, q3 against their rates; the shank (q3) exists
    # only in the three-link phase.  Each kind of impact has its own legend entry and marker.
    fig, ax = plot_phase_portrait(point)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["q1", "q2", "q3", "knee strike (impact)", "heel strike (impact)"]
    solid = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-"]
    dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    assert len(solid) == 3 + 2  # q1, q2, q3 in the three-link phase; q1, q2 knee locked
    assert len(dashed) == 2 + 2  # q1, q2 jump at each impact
    # The shank's end at knee strike is marked where the three-link arc ends.
    arc = point.orbit[0]
    end = (arc.x[2, -1], arc.x[5, -1])
    offsets = np.vstack([c.get_offsets() for c in ax.collections if len(c.get_offsets())])
    assert np.min(np.hypot(*(offsets - np.array(end)).T)) < 1e-12
    plt.close(fig)


def test_curved_foot_walker_is_drawn_stepping_on_the_slope(curved):
    # The animation's contact for each step is the new stance leg's rolling origin on the slope
    # (y = −x tan γ, 1e-9) and the drawn stance arc touches the slope.
    model = curved.model
    sim = gaitopt.simulate(model, curved.x, steps=2)
    mids = [0.5 * (a.t0 + a.t1) for a in sim.arcs]
    frames = walker_frames(model, sim, mids)
    contacts = np.array([f["contact"] for f in frames])
    np.testing.assert_allclose(contacts[:, 1], -contacts[:, 0] * math.tan(model.slope), atol=1e-9)
    assert contacts[2, 0] > contacts[0, 0] + 0.3  # the second step starts a step further
    outline = frames[0]["outline"]
    height = outline[1] + outline[0] * math.tan(model.slope)
    assert np.nanmin(height) == pytest.approx(0.0, abs=5e-3)  # the arc is drawn in 13 samples


def test_a_period_one_gait_steeper_than_the_continued_family():
    """The README's slope bounds (0.1208445 rad with any stability) belong to the family
    continued from the default gait, not to the model: at slope 0.15 a multi-start finds another
    verified period-1 gait.  Numbers from `gaitopt solve kneed_walker --set slope=0.15 --starts
    16` (issue 25, confirmed independently there: it closes to 1.6e-12 and its trailing foot
    lifts off and clears the slope); period to 1e-8 s (the solve's residual is 1e-13, its
    discretisation error 1e-11), the multiplier to 1e-6."""
    gait = gaitopt.find_limit_cycle(gaitopt.model("kneed_walker", slope=0.15), starts=16)
    assert gait.success and gait.verified and not gait.stable
    assert gait.period == pytest.approx(0.4124066926, abs=1e-8)
    assert float(np.max(np.abs(gait.multipliers))) == pytest.approx(10.09965743, abs=1e-6)
