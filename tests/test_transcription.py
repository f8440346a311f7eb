"""The Transcription contract (gaitopt/orbit/transcription.py, rules 1-8), one test body run over
both transcriptions (rockit's style): multiple shooting and Radau collocation of the compass
gait's passive orbit (slope 0.0525, the README's gait; the collocation with the hip torque
switched off by its bound, so that both transcribe the same passive orbit)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gaitopt
from gaitopt.optimize import RadauMesh
from gaitopt.optimize.transcription import CollocationTranscription
from gaitopt.orbit import Layout, Transcription, solve_gait
from gaitopt.shooting import MultipleShooting
from gaitopt.shooting.transcription import ShootingTranscription

KINDS = ("shooting", "collocation")


def _model():
    return gaitopt.model("compass_gait", slope=0.0525)


def _transcription(kind: str, coarse: bool = False):
    model = _model()
    if kind == "shooting":
        disc = MultipleShooting(4, 1) if coarse else None
        return ShootingTranscription(model, disc=disc)
    mesh = RadauMesh(3, 3) if coarse else RadauMesh(6, 6)
    return CollocationTranscription(model, mesh, bounds={"hip_torque": 0})


_SOLVED: dict[str, object] = {}


def _solved(kind: str):
    """The passive orbit solved through ``kind`` by the generic solve → refine → certify →
    referee (cached: each test reads it)."""
    if kind not in _SOLVED:
        t = _transcription(kind)
        _SOLVED[kind] = solve_gait(t, t.guess(), tol=1e-8)
    return _SOLVED[kind]


@pytest.mark.parametrize("kind", KINDS)
def test_it_is_a_transcription_with_named_blocks_covering_w_and_f_once(kind):
    t = _transcription(kind)
    assert isinstance(t, Transcription)
    for layout in (t.columns, t.rows):
        assert isinstance(layout, Layout)
        owner = layout.owner()  # every entry in exactly one block, blocks in order
        assert owner.size == layout.size
        assert np.array_equal(np.sort(owner), owner)
        assert sum(b.size for b in layout) == layout.size
        assert len(set(layout.names)) == len(layout.names)
    assert t.columns.names[0] == "s" and "T0" in t.columns and "X0" in t.columns
    assert "periodicity" in t.rows
    w = t.guess()
    ev = t.evaluate(w)
    b = t.bounds()
    assert w.size == t.columns.size == b.lbw.size == ev.F_w.shape[1]
    assert ev.F.size == t.rows.size == b.lbg.size == ev.F_w.shape[0]
    # The named blocks read the same numbers as the transcription's own maps.
    assert np.array_equal(t.columns.take(w, "s"), w[: len(t.model.section.coordinates)])
    assert t.columns.take(w, "T0")[0] == pytest.approx(t.durations(w)[0], abs=0)


@pytest.mark.parametrize("kind", KINDS)
def test_evaluate_jacobian_matches_central_differences(kind):
    # Source: central differences of evaluate's own F (an independent method: AD / the
    # compiled kernels' Jacobian vs differences), step 1e-6: truncation ~1e-12·|F'''|, rounding
    # ~1e-10·|F|; tolerance 1e-6 relative to the Jacobian's largest entry.
    t = _transcription(kind)
    w = _solved(kind).w if kind == "shooting" else t.guess()
    J = np.asarray(t.evaluate(w).F_w, dtype=float)
    h = 1e-6
    fd = np.empty_like(J)
    for j in range(w.size):
        e = np.zeros(w.size)
        e[j] = h
        fd[:, j] = (t.evaluate(w + e).F - t.evaluate(w - e).F) / (2 * h)
    assert np.max(np.abs(J - fd)) <= 1e-6 * (1 + np.max(np.abs(J)))


def test_both_transcriptions_give_the_same_orbit():
    # Source: two independent discretisations of one passive orbit; they agree to the errors
    # they report (plus the solvers' tolerance 1e-10).
    shoot, col = _solved("shooting"), _solved("collocation")
    assert shoot.success and col.success, (shoot.message, col.message)
    bound = shoot.error + col.error + 1e-10
    ts, tc = shoot.transcription, col.transcription
    assert np.max(np.abs(ts.fixed_point(shoot.w) - tc.fixed_point(col.w))) <= bound
    assert abs(np.sum(ts.durations(shoot.w)) - np.sum(tc.durations(col.w))) <= bound
    # The README's period of this gait, 0.7344606213364 s (find_limit_cycle), to 1e-9.
    assert np.sum(tc.durations(col.w)) == pytest.approx(0.7344606213364, abs=1e-9)


@pytest.mark.parametrize("kind", KINDS)
def test_return_map_eigenvalues_are_find_limit_cycles_multipliers(kind):
    # Source: find_limit_cycle's multipliers (the shooting's implicit-function Jacobian, the
    # front door); the collocation's A is an independent derivation (its own equations).
    # Tolerance 1e-7: both orbits are within 1e-9 of each other and A is well conditioned.
    sol = _solved(kind)
    ref = gaitopt.find_limit_cycle(_model())
    rm = sol.transcription.return_map_jacobians(sol.w)
    m = len(_model().section.coordinates)
    assert rm.A.shape == (m, m)
    key = np.lexsort
    got, want = rm.multipliers, ref.multipliers
    order = lambda z: z[key((np.round(z.imag, 6), np.round(z.real, 6)))]  # noqa: E731
    assert np.max(np.abs(order(got) - order(want))) <= 1e-7
    assert np.array_equal(sol.multipliers, rm.multipliers)
    if kind == "shooting":  # B in the input and the parameters, as the LimitCycle's
        assert rm.B_u.shape == (m, 1) and rm.B_p.shape == (m, len(_model().p))
        assert np.max(np.abs(rm.B_u - ref.input_jacobian)) <= 1e-7 * (1 + np.max(np.abs(rm.B_u)))
    else:
        assert rm.B_u is None and rm.B_p is None


@pytest.mark.parametrize("kind", KINDS)
def test_refined_error_estimate_decreases(kind):
    # Source: the transcriptions' orders (RK8 per step; Radau IIA of degree 3, order 5): halving
    # the step must shrink the estimate, here by more than 4 (order ≥ 2 would do).
    t = _transcription(kind, coarse=True)
    coarse = solve_gait(t, t.guess(), tol=1e-6, max_refinements=0, verify=False)
    assert coarse.status in ("success", "discretisation"), coarse.message
    fine_t = t.refined()
    fine = solve_gait(fine_t, fine_t.carry(coarse.w, t), tol=1e-6, max_refinements=0,
                      verify=False)  # fmt: skip
    assert fine.status in ("success", "discretisation"), fine.message
    assert fine_t.columns.size >= t.columns.size
    assert 0 < fine.error < coarse.error / 4


@pytest.mark.parametrize("kind", KINDS)
def test_symbols_name_the_node_states_inputs_and_durations(kind):
    sol = _solved(kind)
    t = sol.transcription
    sym = t.symbols
    f = ca.Function(
        "f", [sym.w, sym.u, sym.p],
        [sym.state("swing", 0)[0], sym.input("hip_torque", 0), sym.period, sym.F],
    )  # fmt: skip
    swing0, torque, period, F = (np.asarray(v, float).ravel() for v in f(sol.w, t.u, t.p))
    names = t.model.state_names
    assert swing0[0] == pytest.approx(t.fixed_point(sol.w)[names.index("swing")], abs=1e-12)
    assert np.all(torque == 0.0)  # passive
    assert period[0] == pytest.approx(np.sum(t.durations(sol.w)), abs=1e-12)
    # The symbolic residual is evaluate's.
    assert np.max(np.abs(F - t.evaluate(sol.w).F)) <= 1e-9
    with pytest.raises(KeyError, match="no state 'knee'"):
        sym.state("knee", 0)


@pytest.mark.parametrize("kind", KINDS)
def test_orbit_arcs_carry_their_inputs(kind):
    sol = _solved(kind)
    for arc in sol.transcription.orbit(sol.w):
        assert arc.u.shape == (1, arc.t.size)  # one input (hip_torque) at every sample
        assert np.all(arc.u == 0.0)


def test_every_result_reads_the_one_status_table():
    # Source: gaitopt.result.STATUS, the one table of codes and advice; a branch that has no gait
    # to start from (the rimless wheel does not roll at slope 0.03, README) takes its start's
    # code, and a multi-start's per-start codes are entries of the same table.
    from gaitopt.optimize.result import START_STATUS, StartRecord
    from gaitopt.orbit.solve import OrbitSolution
    from gaitopt.result import STATUS

    wheel = gaitopt.model("rimless_wheel", slope=0.03)
    start = gaitopt.find_limit_cycle(wheel)
    branch = gaitopt.continuation(wheel, "slope", to=0.05, start=start)
    assert not branch.success and branch.status == start.status != "success"
    assert branch.advice == STATUS[start.status]
    assert all(START_STATUS[k] == STATUS[k] for k in START_STATUS)
    assert StartRecord(0, "no_start").advice == STATUS["no_start"]
    solved = _solved("shooting")
    assert isinstance(solved, OrbitSolution) and solved.advice == STATUS["success"]


def test_layout_refuses_gaps_overlaps_and_repeated_names():
    from gaitopt.orbit import Block

    assert Layout.from_sizes([("s", 3), ("X0", (4, 2)), ("T0", 1)]).size == 12
    with pytest.raises(ValueError, match="used twice"):
        Layout.from_sizes([("s", 2), ("s", 1)])
    with pytest.raises(ValueError, match="starts at 3, not at 2"):
        Layout((Block("s", slice(0, 2), (2,)), Block("T0", slice(3, 4), (1,))), 4)
    with pytest.raises(ValueError, match="cover 2 entries of 3"):
        Layout((Block("s", slice(0, 2), (2,)),), 3)
    with pytest.raises(KeyError, match="no block 'U0'"):
        Layout.from_sizes([("s", 2)])["U0"]


def test_ipopt_on_the_shooting_transcription_agrees_with_newton():
    # Source: two solvers of the same square system (orbit/newton.py, orbit/ipopt.py with no
    # objective: a feasibility problem); both stop at residuals ≤ 1e-12, the Jacobian is well
    # conditioned, so the solutions agree to 1e-9.
    t = _transcription("shooting")
    newton = _solved("shooting")
    ipopt = solve_gait(t, t.guess(), method="ipopt", tol=1e-8, verify=False)
    assert ipopt.status == "success", ipopt.message
    assert np.max(np.abs(ipopt.w - newton.w)) <= 1e-9
