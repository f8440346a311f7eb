"""The kneed walker's push-off impulse (Kuo 2002) at heel strike: momentum, work, and the passive
gait unchanged (gaitopt/models/kneed_walker.py, gaitopt/mechanics.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import gaitopt

RESULTS = Path(__file__).resolve().parents[1] / "results"


@pytest.fixture(scope="module")
def model():
    return gaitopt.model("kneed_walker")


def _pre_impact(model):
    """A pre-heel-strike state of the two-link phase: q1 + q2 = 2γ, the swing foot ahead."""
    q1 = 0.27
    return np.array([q1, 2 * model.slope - q1, 1.1, -0.4])


def _cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def _momentum(model, phase, x, about, which=None):
    """Angular momentum Σ m (r − about) × v of the point masses ``which`` (all by default)."""
    m, r, v = (np.asarray(a, dtype=float) for a in model.phases[phase].bodies(x, model.p))
    m = m.ravel()
    idx = range(m.size) if which is None else which
    return sum(m[i] * _cross(r[:, i] - about, v[:, i]) for i in idx)


@pytest.mark.parametrize("push", [0.0, 0.15, 0.4])
def test_push_off_momentum(model, push):
    # Source: impulse–momentum about the new contact (closed form, independent of the
    # mechanics module's KKT solve): the heel strike's impulse acts at the new foot and the push
    # P ê at the hip, so H⁺ = H⁻ + (r_hip − r_c) × P ê about the new contact r_c (point feet); the
    # trailing leg's momentum about the hip is conserved (both impulses on it act at the hip).
    # Bodies: hip, stance shank, stance thigh, swing thigh, swing shank; the legs swap.
    # Tolerance 1e-12 (rounding).
    x = _pre_impact(model)
    u = np.array([0.0, 0.0, push])
    heel = model.phases[1].transitions[0]
    after = np.asarray(heel.reset(x, u, model.p), dtype=float).ravel()
    points = np.asarray(model.phases[1].points(x, model.p), dtype=float)
    names = model.phases[1].point_names
    contact, hip = points[:, names.index("swing_foot")], points[:, names.index("hip")]
    axis = np.array([np.sin(x[0]), np.cos(x[0])])  # stance leg, foot → hip
    before = _momentum(model, 1, x, contact)
    new = _momentum(model, 0, after, np.zeros(2))
    assert new == pytest.approx(before + push * _cross(hip - contact, axis), abs=1e-12)
    hip_after = np.asarray(model.phases[0].points(after, model.p), dtype=float)[:, 2]
    trailing = _momentum(model, 1, x, hip, which=(1, 2))
    assert _momentum(model, 0, after, hip_after, which=(3, 4)) == pytest.approx(trailing, abs=1e-12)


def test_push_off_work(model):
    # Source: an independent floating-base computation in NumPy (hip position and the two
    # absolute leg angles as coordinates, mass matrix Σ m Jᵀ J of the five point masses): the
    # push alone changes the velocities by M⁻¹ Q, Q = (P ê, 0, 0), and an impulse does the work
    # P ê · (v⁻ + v')/2 at its point (the mean of the velocities before and after it).
    # The model's impulse_work is the kinetic energy gained, to 1e-12 relative.
    x = _pre_impact(model)
    q1, q2, w1, w2 = x
    prm = model.params
    lt, ls = prm["a2"] + prm["b2"], prm["a1"] + prm["b1"]
    L = lt + ls

    def unit(a):
        return np.array([np.sin(a), np.cos(a)])

    def dunit(a):
        return np.array([np.cos(a), -np.sin(a)])

    # (mass, distance below the hip, leg): hip; stance shank, thigh; swing thigh, shank.
    masses = [
        (prm["mass_hip"], 0.0, 0),
        (prm["mass_shank"], lt + prm["b1"], 1),
        (prm["mass_thigh"], prm["b2"], 1),
        (prm["mass_thigh"], prm["b2"], 2),
        (prm["mass_shank"], lt + prm["b1"], 2),
    ]
    M = np.zeros((4, 4))
    for m, d, leg in masses:
        J = np.zeros((2, 4))
        J[:, :2] = np.eye(2)
        if leg:
            J[:, 1 + leg] = -d * dunit(q1 if leg == 1 else q2)
        M += m * J.T @ J
    v_hip = L * w1 * dunit(q1)  # stance foot pinned (point foot)
    qd = np.array([*v_hip, w1, w2])
    for push in (0.1, 0.3):
        Q = np.array([*(push * unit(q1)), 0.0, 0.0])
        qd_after = qd + np.linalg.solve(M, Q)
        expected = push * unit(q1) @ (qd[:2] + qd_after[:2]) / 2
        kinetic = 0.5 * qd_after @ M @ qd_after - 0.5 * qd @ M @ qd
        assert kinetic == pytest.approx(expected, rel=1e-12)  # the two routes agree
        u = np.array([0.0, 0.0, push])
        work = float(model.impulse_work(1)(x, u, model.p))
        assert work == pytest.approx(expected, rel=1e-12)
    assert model.impulse_work(0) is None


def test_passive_gait_unchanged(model):
    # Source: the committed passive gait (results/kneed_walker/cycle.json, written before the
    # push-off existed; stored to 10 digits): with P = 0 the heel strike is the passive one.
    stored = json.loads((RESULTS / "kneed_walker" / "cycle.json").read_text())
    gait = gaitopt.find_limit_cycle(model)
    assert gait.success and gait.verified
    assert gait.period == pytest.approx(stored["period"], abs=1e-10)
    for name, value in stored["fixed_point"].items():
        assert gait.fixed_point[name] == pytest.approx(value, abs=1e-10)


def test_push_off_is_off_unless_bounded(model):
    # The optional input: an optimisation leaves it at 0 unless its bounds name it.
    from gaitopt.optimize import GaitProblem

    off = GaitProblem(model, "effort", step_length=0.47, period=0.5643)
    on = GaitProblem(model, "effort", step_length=0.47, period=0.5643, bounds={"push_off": 1.0})
    j = model.inputs.index("push_off")
    assert off.input_bounds()[0][j] == off.input_bounds()[1][j] == 0.0
    assert on.input_bounds()[0][j] == 0.0 and on.input_bounds()[1][j] == 1.0
