"""The five-link biped (issue 11): equations, torques, heel strike, section, declared limits.

The model's equations come from Lagrange's equations by AD, each link as its two-point
equimomental system (:func:`gaitopt.mechanics.rigid_link`).  They are checked here against an
independent derivation written in NumPy: OptimTraj's own method (``Derive_Equations.m``), angular
momentum balances of the rigid links about the stance foot, the stance knee, the hip (twice) and the
swing knee, with the inertias as ``I q̈`` terms.  The heel strike is checked against the five
momentum balances ``heelStrikeMap.m`` solves, computed with the same NumPy rigid-body kinematics.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from helpers import cross

import gaitopt
from gaitopt import gaits
from gaitopt.errors import GaitoptInputError, ParameterError
from gaitopt.models.five_link_biped import LINK_NAMES, POINT_NAMES, STATE_NAMES, FiveLinkBiped

RNG = np.random.default_rng(20241111)


@pytest.fixture(scope="module")
def model() -> FiveLinkBiped:
    return gaitopt.model("five_link_biped")


# -- an independent rigid-body reference (NumPy), in OptimTraj's conventions --------------------


def _e(q):
    """Upward unit vectors (−sin q, cos q) of the links, 2×5 (OptimTraj's e1; e4 = −e(q4))."""
    return np.array([-np.sin(q), np.cos(q)])


def _e_dot(q):
    """∂e/∂q = (−cos q, −sin q), 2×5."""
    return np.array([-np.cos(q), -np.sin(q)])


def _coefficients(m: FiveLinkBiped) -> dict[str, np.ndarray]:
    """Each point as Σ_j a_j e(q_j) (OptimTraj's P and G, Derive_Equations.m)."""
    ls, lt, lT = m.length_shank, m.length_thigh, m.length_torso
    cs, ct, cT = m.com_shank, m.com_thigh, m.com_torso
    return {
        "P0": np.zeros(5),
        "P1": np.array([ls, 0, 0, 0, 0]),
        "P2": np.array([ls, lt, 0, 0, 0]),
        "P3": np.array([ls, lt, lT, 0, 0]),
        "P4": np.array([ls, lt, 0, -lt, 0]),
        "P5": np.array([ls, lt, 0, -lt, -ls]),
        "G1": np.array([ls - cs, 0, 0, 0, 0]),
        "G2": np.array([ls, lt - ct, 0, 0, 0]),
        "G3": np.array([ls, lt, lT - cT, 0, 0]),
        "G4": np.array([ls, lt, 0, -ct, 0]),
        "G5": np.array([ls, lt, 0, -lt, -cs]),
    }


def _kinematics(m, q, qd):
    """Positions, velocities and the q̈-independent part of the accelerations of every point."""
    e, ed = _e(q), _e_dot(q)
    out = {}
    for name, a in _coefficients(m).items():
        pos = e @ a
        vel = ed @ (a * qd)
        acc0 = -e @ (a * qd**2)  # ë = ė' q̈ − e q̇²; the q̈ part is ed @ (a q̈)
        jac = ed * a  # ∂r/∂q (2×5)
        out[name] = (pos, vel, acc0, jac)
    return out


def _masses(m):
    return np.array([m.mass_shank, m.mass_thigh, m.mass_torso, m.mass_thigh, m.mass_shank])


def _inertias(m):
    return np.array(
        [m.inertia_shank, m.inertia_thigh, m.inertia_torso, m.inertia_thigh, m.inertia_shank]
    )


# The angular-momentum balances of Derive_Equations.m: (links, pivot, torque index in u1…u5).
_BALANCES = (
    ((0, 1, 2, 3, 4), "P0", 0),
    ((1, 2, 3, 4), "P1", 1),
    ((2, 3, 4), "P2", 2),
    ((3, 4), "P2", 3),
    ((4,), "P4", 4),
)


def _newton_euler_acceleration(m, q, qd, u4):
    """q̈ from OptimTraj's five angular-momentum balances (u1 = 0: the ankle is unactuated).

    About pivot P for the links S: Σ_S (G_k − P) × (−m_k g ĵ) + u = Σ_S [(G_k − P) × m_k G̈_k
    + I_k q̈_k], linear in q̈.
    """
    kin = _kinematics(m, q, qd)
    mass, inertia = _masses(m), _inertias(m)
    u = np.concatenate([[0.0], u4])
    A, b = np.zeros((5, 5)), np.zeros(5)
    for row, (links, pivot, k) in enumerate(_BALANCES):
        P = kin[pivot][0]
        b[row] = u[k]
        for j in links:
            G, _, acc0, jac = kin[f"G{j + 1}"]
            r = G - P
            b[row] += cross(r, np.array([0.0, -mass[j] * m.gravity]))
            b[row] -= cross(r, mass[j] * acc0)
            for i in range(5):
                A[row, i] += cross(r, mass[j] * jac[:, i])
            A[row, j] += inertia[j]
    return np.linalg.solve(A, b)


def _rigid_momentum(m, q, qd, pivot, links) -> float:
    """Σ_links m_k (G_k − pivot) × Ġ_k + I_k q̇_k (kg·m²/s)."""
    kin = _kinematics(m, q, qd)
    mass, inertia = _masses(m), _inertias(m)
    P = kin[pivot][0] if isinstance(pivot, str) else np.asarray(pivot)
    total = 0.0
    for j in links:
        G, V, _, _ = kin[f"G{j + 1}"]
        total += mass[j] * cross(G - P, V) + inertia[j] * qd[j]
    return total


def _random_state(scale=1.0):
    q = RNG.uniform(-1.2, 1.2, 5) * scale
    qd = RNG.uniform(-4.0, 4.0, 5) * scale
    return np.concatenate([q, qd])


def _on_guard(model, q1, q2, q3, q4, qd) -> np.ndarray:
    """A pre-impact state: the swing foot on the ground ahead of its knee (h = 0 solved for q5
    on the foot-ahead branch, q5 = −γ + arccos(·))."""
    g, ls, lt = model.slope, model.length_shank, model.length_thigh
    reach = (ls * math.cos(q1 + g) + lt * math.cos(q2 + g) - lt * math.cos(q4 + g)) / ls
    q5 = -g + math.acos(reach)
    return np.array([q1, q2, q3, q4, q5, *qd])


def _guard_rate(model, x) -> float:
    """ḣ = ∇h · ẋ, the swing foot's velocity along the ground normal (m/s); h depends on q only,
    so ẋ's q̇ part and no input are needed."""
    guard = model.phases[0].transitions[0].guard
    xs = ca.SX.sym("x", 10)
    grad = ca.Function("grad", [xs], [ca.jacobian(guard(xs, np.zeros(4), model.p), xs)])
    return float(np.asarray(grad(x)).ravel()[:5] @ x[5:])


# -- parameters, names, limits -------------------------------------------------------------------


def test_defaults_are_optimtrajs_parameters(model):
    # Source: OptimTraj demo/fiveLinkBiped/getPhysicalParameters.m (exact values).
    assert (model.mass_shank, model.mass_thigh, model.mass_torso) == (3.2, 6.8, 20.0)
    assert (model.inertia_shank, model.inertia_thigh, model.inertia_torso) == (0.93, 1.08, 2.22)
    assert (model.length_shank, model.length_thigh, model.length_torso) == (0.4, 0.4, 0.625)
    assert (model.com_shank, model.com_thigh, model.com_torso) == (0.128, 0.163, 0.2)
    assert model.gravity == 9.81 and model.slope == 0.0


def test_states_inputs_and_declared_limits(model):
    # Source: OptimTraj MAIN.m bounds: |u| ≤ 100 N·m (ankle u1 fixed at 0), |q| ≤ π/2, |q̇| ≤ 10.
    assert model.state_names == STATE_NAMES
    assert STATE_NAMES[:5] == LINK_NAMES
    assert FiveLinkBiped.inputs == (
        "stance_knee_torque",
        "stance_hip_torque",
        "swing_hip_torque",
        "swing_knee_torque",
    )
    assert FiveLinkBiped.input_units == ("N*m",) * 4
    assert FiveLinkBiped.input_bounds == {n: (-100.0, 100.0) for n in FiveLinkBiped.inputs}
    assert set(FiveLinkBiped.state_bounds) == set(STATE_NAMES)
    for name in LINK_NAMES:
        assert FiveLinkBiped.state_bounds[name] == (-math.pi / 2, math.pi / 2)
        assert FiveLinkBiped.state_bounds[f"{name}_dot"] == (-10.0, 10.0)
    assert FiveLinkBiped.torque_limit == 100.0 and FiveLinkBiped.rate_limit == 10.0
    assert FiveLinkBiped.angle_limit == math.pi / 2
    assert set(FiveLinkBiped.step_points) <= set(model.phases[0].point_names)
    assert FiveLinkBiped.passive_gait is False
    assert model.existence_note() and "no passive gait" in model.existence_note()


@pytest.mark.parametrize(
    ("changes", "name"),
    [
        ({"mass_torso": -1.0}, "mass_torso"),
        ({"inertia_shank": -0.1}, "inertia_shank"),
        ({"length_thigh": 0.0}, "length_thigh"),
        ({"slope": 0.9}, "slope"),
        ({"com_shank": 0.5}, "com_shank"),  # beyond the 0.4 m shank
        ({"com_torso": 0.7}, "com_torso"),  # beyond the 0.625 m torso
        ({"mass_torso": float("nan")}, "mass_torso"),
    ],
)
def test_bad_parameters_name_the_argument(changes, name):
    with pytest.raises(ParameterError) as info:
        gaitopt.model("five_link_biped", **changes)
    assert isinstance(info.value, GaitoptInputError)
    message = str(info.value)
    assert name in message and "\n" not in message


# -- kinematics ----------------------------------------------------------------------------------


def test_standing_straight_kinematics(model):
    # Closed form (OptimTraj's geometry at q = 0): knee 0.4 m, hip 0.8 m, torso top 1.425 m,
    # swing knee 0.4 m, swing foot at the stance foot.  Exact up to rounding: 1e-15.
    points = np.asarray(model.phases[0].points(np.zeros(10), model.p))
    expected = {
        "stance_foot": (0, 0),
        "stance_knee": (0, 0.4),
        "hip": (0, 0.8),
        "torso_top": (0, 1.425),
        "swing_knee": (0, 0.4),
        "swing_foot": (0, 0),
    }
    for name, xy in expected.items():
        np.testing.assert_allclose(points[:, POINT_NAMES.index(name)], xy, atol=1e-15)


def test_points_match_optimtraj_geometry(model):
    # Independent: OptimTraj's P1…P5 (e1 = cos q j − sin q i, e4 = −e(q4)) in NumPy; 1e-14.
    names = {
        "stance_knee": "P1",
        "hip": "P2",
        "torso_top": "P3",
        "swing_knee": "P4",
        "swing_foot": "P5",
    }
    for _ in range(5):
        x = _random_state()
        points = np.asarray(model.phases[0].points(x, model.p))
        kin = _kinematics(model, x[:5], x[5:])
        for name, ref in names.items():
            np.testing.assert_allclose(points[:, POINT_NAMES.index(name)], kin[ref][0], atol=1e-14)


# -- dynamics ------------------------------------------------------------------------------------


def test_mass_matrix_is_the_rigid_body_one_and_positive_definite(model):
    # Independent: for rigid links T = Σ ½ m |Ġ|² + ½ I q̇², so M = Σ m J_Gᵀ J_G + diag(I);
    # the model's M (equimomental point masses) must equal it (1e-12 relative) and be symmetric
    # positive definite.
    manip = FiveLinkBiped.manipulator()
    mass, inertia = _masses(model), _inertias(model)
    for _ in range(10):
        x = _random_state(2.0)
        M, _ = (np.asarray(a) for a in manip(x[:5], x[5:], np.zeros(4), model.p))
        kin = _kinematics(model, x[:5], x[5:])
        ref = np.diag(inertia).astype(float)
        for j in range(5):
            J = kin[f"G{j + 1}"][3]
            ref += mass[j] * J.T @ J
        np.testing.assert_allclose(M, ref, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(M, M.T, atol=1e-14)
        assert np.linalg.eigvalsh(M).min() > 0


def test_dynamics_match_optimtrajs_momentum_balances(model):
    # Independent derivation: OptimTraj's Derive_Equations.m method (angular momentum balances
    # about P0, the stance knee, the hip twice and the swing knee, torques u2…u5 on link k from
    # link k − 1, u1 = 0) solved in NumPy, at random states and torques.  Tolerance 1e-9
    # relative to the accelerations' scale.
    flow = model.phases[0].flow
    for _ in range(20):
        x = _random_state()
        u = RNG.uniform(-100, 100, 4)
        qdd = np.asarray(flow(x, u, model.p)).ravel()[5:]
        ref = _newton_euler_acceleration(model, x[:5], x[5:], u)
        np.testing.assert_allclose(qdd, ref, rtol=0, atol=1e-9 * (1 + np.abs(ref).max()))
    # The manipulator form agrees with the flow: M q̈ = rhs.
    manip = FiveLinkBiped.manipulator()
    M, rhs = (np.asarray(a) for a in manip(x[:5], x[5:], u, model.p))
    np.testing.assert_allclose(M @ qdd, rhs.ravel(), atol=1e-9 * (1 + np.abs(rhs).max()))


def test_torque_power_is_the_rate_of_energy(model):
    # Power balance: dE/dt = ∇E · f(x, u) = Σ u_k (q̇_k − q̇_{k−1}) (each torque acts between
    # adjacent links; OptimTraj's u2…u5).  Identity at random states: 1e-9 relative.
    energy = model.phases[0].conserved["energy"]
    flow = model.phases[0].flow
    xs = ca.SX.sym("x", 10)
    grad = ca.Function("grad", [xs], [ca.jacobian(energy(xs, model.p), xs)])
    for _ in range(20):
        x = _random_state()
        u = RNG.uniform(-100, 100, 4)
        dE = float(np.asarray(grad(x)).ravel() @ np.asarray(flow(x, u, model.p)).ravel())
        qd = x[5:]
        power = sum(u[k] * (qd[k + 1] - qd[k]) for k in range(4))
        rates = np.asarray(model.input_rates(0)(x, model.p)).ravel()  # the declared ω
        assert float(u @ rates) == pytest.approx(power, rel=1e-14, abs=1e-12)
        assert dE == pytest.approx(power, abs=1e-9 * (1 + abs(power) + np.abs(u).max()))
        passive = float(np.asarray(grad(x)).ravel() @ np.asarray(flow(x, 0 * u, model.p)).ravel())
        assert abs(passive) < 1e-9 * (1 + np.abs(qd).max())


def test_energy_is_conserved_along_the_passive_flow(model):
    # Simulated with u = 0 (DOP853, rtol 1e-11) from the default start and two with perturbed
    # rates, through a heel strike until the torso falls: energy is constant along each arc
    # (the impact dissipates, between arcs) to 1e-9 relative to its scale.
    energy = model.phases[0].conserved["energy"]
    base = model.section_vector(model.default_start())
    rates = np.arange(base.size) >= 4  # section coordinates 4… are the five rates
    for k in range(3):
        s = base + (0 if k == 0 else rates * RNG.normal(0, 0.2, base.size))
        sim = gaitopt.simulate(model, model.lift(s), steps=3, max_phase_time=5.0)
        assert sim.arcs and sum(a.t1 - a.t0 for a in sim.arcs) > 0.2, sim.message
        for arc in sim.arcs:
            _, X = arc.sample(200)
            values = np.array([float(energy(X[:, j], model.p)) for j in range(X.shape[1])])
            assert np.ptp(values) < 1e-9 * (1 + np.abs(values).max())


def test_unilateral_constraints(model):
    # The swing foot's clearance is the guard h (m), zero at both ends of the step; the stance
    # foot's normal force standing straight at rest is the total weight, closed form
    # (2·3.2 + 2·6.8 + 20) kg · 9.81 m/s² = 392.4 N (1e-12 relative).
    phase = model.phases[0]
    clearance, push = phase.constraints
    assert (clearance.outcome, clearance.at_start, clearance.at_end) == ("trip", True, True)
    assert push.outcome == "stance foot lifts off" and push.unit == "N"
    x = _random_state()
    u = RNG.uniform(-100, 100, 4)
    guard = phase.transitions[0].guard
    assert float(clearance.function(x, u, model.p)) == float(guard(x, u, model.p))
    weight = float(push.function(np.zeros(10), np.zeros(4), model.p))
    assert weight == pytest.approx(40.0 * 9.81, rel=1e-12)


# -- heel strike ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def impact(model):
    """A typical heel strike: stance leg leaning forward, swing foot landing ahead (knee flexed
    0.03 rad), the stance leg rotating forward, the swing foot moving down."""
    x_minus = _on_guard(model, -0.35, -0.25, 0.05, 0.32, [-1.4, -1.2, 0.1, 0.8, -0.5])
    transition = model.phases[0].transitions[0]
    x_plus = np.asarray(transition.reset(x_minus, np.zeros(4), model.p)).ravel()
    return x_minus, x_plus


def test_impact_conserves_optimtrajs_five_momenta(model, impact):
    # Source: heelStrikeMap.m / Derive_Equations.m: the impulse acts only at the striking foot,
    # so these angular momenta are conserved (rigid-body NumPy formula, independent of the
    # model's point masses): the whole walker about the striking foot; links 1–4 (old labels)
    # about the old swing knee; links 1–3 about the hip; links 1–2 about the hip; link 1 about
    # the old stance knee; after the swap these are links 1–5, 2–5, 3–5, 4–5, 5 about the new
    # stance foot, stance knee, hip, hip, swing knee.  Tolerance 1e-12 relative.
    x_minus, x_plus = impact
    qm, qdm, qp, qdp = x_minus[:5], x_minus[5:], x_plus[:5], x_plus[5:]
    foot = _kinematics(model, qm, qdm)["P5"][0]
    pairs = (
        ((0, 1, 2, 3, 4), foot, (0, 1, 2, 3, 4), "P0"),
        ((0, 1, 2, 3), "P4", (1, 2, 3, 4), "P1"),
        ((0, 1, 2), "P2", (2, 3, 4), "P2"),
        ((0, 1), "P2", (3, 4), "P2"),
        ((0,), "P1", (4,), "P4"),
    )
    for before_links, before_pivot, after_links, after_pivot in pairs:
        before = _rigid_momentum(model, qm, qdm, before_pivot, before_links)
        after = _rigid_momentum(model, qp, qdp, after_pivot, after_links)
        assert after == pytest.approx(before, rel=1e-12, abs=1e-13), after_links
    # A plastic impact dissipates: kinetic energy falls (potential is unchanged by the swap).
    energy = model.phases[0].conserved["energy"]
    assert float(energy(x_plus, model.p)) < float(energy(x_minus, model.p))


def test_impact_relabels_the_legs(model, impact):
    # The configuration is unchanged; only the labels swap and the origin moves to the new
    # stance foot: new points = old points (legs swapped) − old swing foot.  Exact: 1e-14.
    x_minus, x_plus = impact
    np.testing.assert_array_equal(x_plus[:5], x_minus[4::-1][:5])
    before = np.asarray(model.phases[0].points(x_minus, model.p))
    after = np.asarray(model.phases[0].points(x_plus, model.p))
    idx = {n: i for i, n in enumerate(POINT_NAMES)}
    origin = before[:, idx["swing_foot"]]
    swapped = {
        "stance_foot": "swing_foot",
        "stance_knee": "swing_knee",
        "hip": "hip",
        "torso_top": "torso_top",
        "swing_knee": "stance_knee",
        "swing_foot": "stance_foot",
    }
    for new, old in swapped.items():
        np.testing.assert_allclose(after[:, idx[new]], before[:, idx[old]] - origin, atol=1e-14)


def test_swing_foot_comes_down_then_lifts_off(model, impact):
    # OptimTraj's autoGen_cst_footVel conditions, as the guard's rate ḣ = ∇h·q̇ (the swing foot's
    # velocity along the ground normal): down before heel strike, up after it, at this typical
    # impact.  The sign is checked against the foot velocity computed by the NumPy kinematics.
    x_minus, x_plus = impact
    down = _guard_rate(model, x_minus)
    up = _guard_rate(model, x_plus)
    assert down < 0 < up
    foot_velocity = [_kinematics(model, x[:5], x[5:])["P5"][1] for x in (x_minus, x_plus)]
    assert down == pytest.approx(foot_velocity[0][1], abs=1e-14)  # level ground: normal = y
    assert up == pytest.approx(foot_velocity[1][1], abs=1e-14)


@pytest.mark.parametrize("slope", [0.0, 0.08])
def test_reset_lands_on_the_section_lift(model, slope):
    # The section is the reset's image of the guard: after heel strike the new swing foot is on
    # the ground (guard 0) behind the stance foot (not admissible), and lifting the state's own
    # section coordinates gives the state back.  Exact up to rounding: 1e-12.
    m = model.replace(slope=slope)
    transition = m.phases[0].transitions[0]
    u = np.zeros(4)
    for _ in range(5):
        # The typical impact's legs, tilted with the ground normal (q + γ as on level ground).
        q = np.array([-0.35, -0.25, 0.05, 0.32]) + RNG.normal(0, 0.05, 4) - slope
        x_minus = _on_guard(m, *q, RNG.normal(0, 1.5, 5))
        assert abs(float(transition.guard(x_minus, u, m.p))) < 1e-12
        assert float(transition.admissible(x_minus, u, m.p)) > 0
        x_plus = np.asarray(transition.reset(x_minus, u, m.p)).ravel()
        assert abs(float(transition.guard(x_plus, u, m.p))) < 1e-12
        assert float(transition.admissible(x_plus, u, m.p)) < 0
        lifted = m.lift(m.section_coordinates_of(x_plus))
        np.testing.assert_allclose(lifted, x_plus, atol=1e-12)


def test_default_start_is_a_plausible_post_impact_state(model):
    # On the section (trailing foot on the ground behind), within OptimTraj's bounds, with the
    # trailing foot lifting off (ḣ > 0) and the stance leg rotating forward (clockwise).
    x = model.lift(model.default_start())
    transition = model.phases[0].transitions[0]
    assert abs(float(transition.guard(x, np.zeros(4), model.p))) < 1e-12
    assert float(transition.admissible(x, np.zeros(4), model.p)) < 0
    assert np.all(np.abs(x[:5]) <= math.pi / 2) and np.all(np.abs(x[5:]) <= 10)
    assert _guard_rate(model, x) > 0 and x[5] < 0


# -- no passive gait: the shared machinery skips it ---------------------------------------------


def test_make_gaits_skips_the_actuated_only_model(tmp_path, capsys):
    status = gaits.main(["--out", str(tmp_path), "--models", "five_link_biped"])
    out = capsys.readouterr().out
    assert status == 0
    assert "five_link_biped: skipped (actuated-only" in out
    assert not (tmp_path / "five_link_biped").exists()
