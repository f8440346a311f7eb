"""The one implementation of the return map's Jacobian (:mod:`gaitopt.orbit.sensitivity`)
against independent methods and closed forms.

* Rule 1 (implicit function theorem on the shooting equations, ``LimitCycle.jacobian`` and
  ``input_jacobian``) against central differences of the independent event-located simulator,
  on the compass gait and on the kneed walker, whose knee strike resets 6 states to 4.
* Rules 2–4 (collocated phase sensitivity, saltation, composition) on Radau arcs sampled from
  the simulated orbit: the kneed walker's ``A`` and ``B`` against rule 1 and the simulator; the
  rimless wheel's step-to-step slope ``cos² 2α`` and the bouncing ball's ``det = e²``,
  ``tr = 1 + e² − (1 + e)² Γ sin φ`` in closed form.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

import gaitopt
from gaitopt.optimize.radau import _derivative_matrix
from gaitopt.orbit.sensitivity import (
    CollocatedArc,
    collocated_return_map,
    defect_function,
    defect_jacobians,
    lift_jacobian,
    saltation,
    section_jacobians,
)

H_FD = 1e-6  # central-difference step (section and input units)


def simulated_map(model, s, u):
    """Section coordinates one return after ``s`` with the per-step input ``u``, simulated
    (DOP853, rtol 1e-12, located events): the independent return map."""
    sim = gaitopt.simulate(model, model.lift(s), steps=1, inputs=u, rtol=1e-12, atol=1e-13)
    assert sim.success, sim.message
    return model.section_coordinates_of(sim.section_states[-1])


def central_differences(f, x0, h=H_FD):
    cols = []
    for e in np.eye(x0.size) * h:
        cols.append((f(x0 + e) - f(x0 - e)) / (2 * h))
    return np.column_stack(cols)


@pytest.fixture(scope="module", params=["compass_gait", "kneed_walker"])
def cycle(request):
    model = gaitopt.model(request.param)
    c = gaitopt.find_limit_cycle(model)
    assert c.success, c.message
    return c


def test_rule_1_against_finite_differences_of_the_simulated_map(cycle):
    # Source: central differences (h = 1e-6) of the simulated map: truncation O(h²) ~ 1e-12,
    # rounding at most ~ rtol/h = 1e-6 of the entries; the shooting's own accuracy (tol 1e-10,
    # RK8 discretisation error below it) is far smaller.  Measured 3.5e-8 to 4.6e-8 of
    # (1 + max |entry|); asserted 1e-6.
    model, s, u = cycle.model, cycle.section_point, np.asarray(cycle.inputs, dtype=float)
    A_fd = central_differences(lambda z: simulated_map(model, z, u), s)
    B_fd = central_differences(lambda v: simulated_map(model, s, v), u)
    np.testing.assert_allclose(cycle.jacobian, A_fd, rtol=0, atol=1e-6 * (1 + np.abs(A_fd).max()))
    np.testing.assert_allclose(
        cycle.input_jacobian, B_fd, rtol=0, atol=1e-6 * (1 + np.abs(B_fd).max())
    )
    assert np.abs(B_fd).max() > 1e-2  # the input moves the map: not a vacuous check


def test_rule_1_is_the_same_for_numpy_and_casadi(cycle):
    # section_jacobians takes CasADi matrices too (the curves' symbolic conditions): the same
    # matrix to rounding (1e-12 relative: two LU solves of the same system).
    problem, ev = cycle.problem, cycle.evaluation
    J = problem.map_jacobian(ev.F_w)
    A, B = section_jacobians(J, ev.F_u, problem.m, problem.n_g)
    A_ca, B_ca = section_jacobians(ca.DM(J), ca.DM(ev.F_u), problem.m, problem.n_g)
    np.testing.assert_allclose(np.asarray(A_ca), A, rtol=0, atol=1e-12 * np.abs(A).max())
    np.testing.assert_allclose(np.asarray(B_ca), B, rtol=0, atol=1e-12 * np.abs(B).max())


# -- rules 2–4 on Radau arcs sampled from an exact orbit --------------------------------------
def radau_arcs(model, phases, starts, durations, states, u, N, d):
    """``CollocatedArc``s of the orbit's phases: node states from ``states(k, t)`` at the
    Radau points of ``N`` equal intervals of degree ``d``, the constant input ``u``."""
    tau = np.array([0.0, *ca.collocation_points(d, "radau")])
    C = _derivative_matrix(tau, tau[1:]).T
    arcs = []
    for k, (i, T) in enumerate(zip(phases, durations, strict=True)):
        phase = model.phases[i]
        tr = next(t for t in phase.transitions if t.target == phases[(k + 1) % len(phases)])
        h = T / N
        t = np.concatenate([[0.0], *[h * (j + tau[1:]) for j in range(N)]])
        X = np.column_stack([starts[k]] + [states(k, ti) for ti in t[1:]])
        U = np.tile(np.asarray(u, dtype=float)[:, None], (1, N * d))
        label = f"{type(model).__name__.lower()}_{i}"
        arcs.append(CollocatedArc(phase.flow, tr.guard, tr.reset, C, X, U, np.zeros_like(U),
                                  np.full(N, h), label, k == len(phases) - 1))  # fmt: skip
    return arcs


def test_rules_2_to_4_on_the_kneed_walker_knee_strike():
    # The passive kneed walker's orbit (6 states, then 4 after the knee strike) sampled from the
    # simulator at the Radau points of 10 intervals of degree 5 per phase: the collocated
    # sensitivities differ from the exact ones by the Radau IIA error of the variational
    # equations, O(h⁹) (measured 7e-9, 2e-11, 5e-13 of the entries at 5, 10, 20 intervals).
    # Sources: rule 1 on the shooting equations (RK8 multiple shooting, another transcription):
    # measured 6e-11, asserted 1e-9 of (1 + max |A|); and central differences of the simulated
    # map (measured 4e-8, asserted 1e-6, as above).  With u̇ = 0, an input offset held over the
    # orbit is a change of the per-step input: B = ∂P/∂u.
    model = gaitopt.model("kneed_walker")
    c = gaitopt.find_limit_cycle(model)
    assert c.success, c.message
    x0 = model.lift(c.section_point)
    u = np.asarray(c.inputs, dtype=float)
    sim = gaitopt.simulate(model, x0, steps=1, inputs=u, rtol=1e-12, atol=1e-13)
    assert sim.success and len(sim.arcs) == 2
    assert [model.phases[a.phase].n for a in sim.arcs] == [6, 4]
    arcs = radau_arcs(
        model, [a.phase for a in sim.arcs], [a.solution(a.t0) for a in sim.arcs],
        [a.t1 - a.t0 for a in sim.arcs],
        lambda k, t: sim.arcs[k].solution(sim.arcs[k].t0 + t), u, 10, 5,
    )  # fmt: skip
    L = np.asarray(lift_jacobian(model.section.lift)(c.section_point, model.p), dtype=float)
    index = [model.phases[0].states.index(q) for q in model.section.coordinates]
    A, B = collocated_return_map(arcs, L, index, model.p, offset=True)
    scale = 1 + np.abs(c.jacobian).max()
    np.testing.assert_allclose(A, c.jacobian, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(B, c.input_jacobian, rtol=0, atol=1e-9 * scale)
    B_fd = central_differences(lambda v: simulated_map(model, c.section_point, v), u)
    np.testing.assert_allclose(B, B_fd, rtol=0, atol=1e-6 * (1 + np.abs(B_fd).max()))
    # The defects' Jacobians assembled from the compiled flow kernel (with the offset's
    # columns) equal the symbolic Jacobians of the whole arc's defects: 1e-13 relative, rounding.
    a = arcs[1]
    args = (a.X, a.U, np.linspace(-1.0, 1.0, a.U.size).reshape(a.U.shape), a.hs, model.p)
    fast = defect_jacobians(a.flow, a.C, *args, label=a.label, offset=True)
    X, U, Ud, hs, p = args
    exact = defect_function(a.flow, hs.size, a.C.shape[1], a.C.tobytes(), True)(
        X[:, 1:], X[:, 0], 0.0, U, Ud, hs, p
    )
    for got, want in zip(fast, exact, strict=True):
        want = np.asarray(want, dtype=float)
        assert got.shape == want.shape
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * np.abs(want).max())


def test_rimless_wheel_slope_is_cos_squared_two_alpha():
    # Closed form (Tedrake, Underactuated Robotics, §rimless wheel): the rolling fixed point's
    # step-to-step map ω' = cos 2α sqrt(ω² + 4 g/l sin α sin γ) has slope cos² 2α there.  The
    # stance arc is sampled from the exact pendulum flow (the simulator, rtol 1e-12) at the
    # Radau points of 8 intervals of degree 5: O(h⁹) error, below the simulator's (measured
    # 3e-12 at 4 intervals, 2.6e-13 at 8 and 16); asserted 1e-11.
    model = gaitopt.model("rimless_wheel", slope=0.2)
    omega = model.rolling_speed()
    x0 = model.lift(np.array([omega]))
    sim = gaitopt.simulate(model, x0, steps=1, rtol=1e-12, atol=1e-13)
    assert sim.success
    arc = sim.arcs[0]
    arcs = radau_arcs(model, [0], [x0], [arc.t1 - arc.t0],
                      lambda k, t: arc.solution(arc.t0 + t), np.zeros(0), 8, 5)  # fmt: skip
    L = np.asarray(lift_jacobian(model.section.lift)([omega], model.p), dtype=float)
    A, _ = collocated_return_map(arcs, L, [1], model.p)
    assert A[0, 0] == pytest.approx(math.cos(2 * model.alpha) ** 2, abs=1e-11)


def test_bouncing_ball_trace_and_determinant_in_closed_form():
    # Closed form (gaitopt.models.bouncing_ball, from the exact impact-to-impact map): the
    # period-1 orbit with Γ cos φ = π (1 − e)/(1 + e) has det J = e² and
    # tr J = 1 + e² − (1 + e)² Γ sin φ.  The ballistic flight is a quadratic in t, which Radau
    # collocation of any degree ≥ 2 reproduces exactly, as it does the variational equations
    # (constant f_x): so only rounding remains (measured 7e-16; asserted 1e-12).
    model = gaitopt.model("bouncing_ball")
    e, g = model.restitution, model.gravity
    w = 2 * math.pi * model.frequency
    amp = model.acceleration * g / w**2
    phi = math.acos(math.pi * (1 - e) / (1 + e) / model.acceleration)  # sin φ > 0: stable
    T = 2 * math.pi / w
    v0 = g * T / 2
    x0 = np.array([phi, amp * math.sin(phi), v0])

    def states(k, t):
        return np.array([phi + w * t, amp * math.sin(phi) + v0 * t - g * t**2 / 2, v0 - g * t])

    arcs = radau_arcs(model, [0], [x0], [T], states, np.zeros(0), 3, 2)
    L = np.asarray(lift_jacobian(model.section.lift)([phi, v0], model.p), dtype=float)
    A, _ = collocated_return_map(arcs, L, [0, 2], model.p)
    Gamma = model.acceleration
    assert np.linalg.det(A) == pytest.approx(e**2, abs=1e-12)
    assert np.trace(A) == pytest.approx(1 + e**2 - (1 + e) ** 2 * Gamma * math.sin(phi), abs=1e-12)


def test_saltation_is_the_hand_derived_jump_of_a_falling_ball():
    # Rule 3 on the simplest reset: a ball (h, v) falling onto h = 0 with v⁺ = −e v⁻.  By hand,
    # δτ = −δh/v⁻, δx⁻ = (0, δv + g δh/v⁻), δx⁺ = (0, −e (δv + g δh/v⁻)); with a clock lead
    # δt₀ the input term is absent (no input).  Exact to rounding (1e-15).
    e, g, v = 0.7, 9.81, -3.0
    ends = [np.array([[v], [-g]]), np.array([[1.0, 0.0]]), np.zeros((1, 0)),
            np.array([[1.0, 0.0], [0.0, -e]]), np.zeros((2, 0))]  # fmt: skip
    dx = np.array([[1.0, 0.0], [0.0, 1.0]])
    dx_plus, dt_event = saltation(ends, np.zeros((0, 1)), dx, np.zeros((1, 2)))
    expected = np.array([[0.0, 0.0], [-e * g / v, -e]])
    np.testing.assert_allclose(dx_plus, expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(dt_event, [[-1 / v, 0.0]], rtol=0, atol=1e-15)
