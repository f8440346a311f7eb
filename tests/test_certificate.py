"""One certificate and one referee for both front doors (issue 19 items 3 and 4).

The kneed walker's trailing foot starts on the slope after heel strike, so its clearance is a
unilateral constraint declared ``at_start``: zero where the swing phase begins, it must rise there
(``ċ > 1e-9`` m/s) or the foot does not lift off.  The optimisation half used to check only the
values between the nodes (to 1e-6) and would accept an orbit whose foot starts with zero rate; the
common certificate (:mod:`gaitopt.orbit.certificate`) refuses it by the rate rule.  Both halves'
dense samples (the shooting's RK samples, the collocation's polynomials) of the same orbit get the
same verdict.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

import gaitopt
from gaitopt.hybrid import rate_along
from gaitopt.optimize.certify import _certify
from gaitopt.optimize.collocation import RadauMesh
from gaitopt.optimize.verify import check_dense, feedforward_of, profiles
from gaitopt.optimize.verify import dense_arcs as collocation_arcs
from gaitopt.orbit import certify_orbit, referee
from gaitopt.orbit.certificate import CONSTRAINT_TOL
from gaitopt.orbit.referee import TIGHT
from gaitopt.shooting import shooting_problem
from gaitopt.shooting.certify import dense_arcs as shooting_arcs


@pytest.fixture(scope="module")
def passive() -> gaitopt.LimitCycle:
    """The kneed walker's passive gait at the defaults, by multiple shooting."""
    cycle = gaitopt.find_limit_cycle(gaitopt.model("kneed_walker"))
    assert cycle.success, cycle.message
    return cycle


@pytest.fixture(scope="module")
def optimum(passive) -> gaitopt.OptimalGait:
    """The least-effort gait with the passive gait's period and step length, by Radau
    collocation: the passive gait itself (zero torque), the same orbit in the other
    transcription.  The step length of the point-foot walker (legs of 1 m) is the chord
    2 sin((q2 − q1)/2) between the feet at heel strike."""
    x = passive.fixed_point
    legs = sum(passive.model.params[k] for k in ("a1", "b1", "a2", "b2"))
    step_length = 2 * legs * float(np.sin((x["q2"] - x["q1"]) / 2))
    # A coarse start mesh (4 intervals of degree 5, refined to 8) and tol 1e-6 keep the NLP
    # small: this optimum only has to be the same orbit, which it is to 2e-8 (8.1e-9 measured).
    gait = gaitopt.optimize_gait(
        passive.model, "effort", period=passive.period, step_length=step_length,
        mesh=RadauMesh(4, 5), tol=1e-6,
    )  # fmt: skip
    assert gait.success, gait.message
    return gait


def _without_lift_off(model, s: np.ndarray, u0: np.ndarray) -> np.ndarray:
    """Section coordinates with ``q2_dot`` changed so that the trailing foot's clearance starts
    with rate exactly 0 (it depends on the positions only, so its rate ∇c · q̇ is affine in
    ``q2_dot``: one secant step solves it)."""
    phase = model.phases[0]
    rate = rate_along(phase.flow, phase.constraints[0].function)
    j = model.section.coordinates.index("q2_dot")

    def start_rate(sc):
        return float(rate(model.lift(sc), u0, model.p))

    e = np.zeros_like(s)
    e[j] = 1.0
    r0, r1 = start_rate(s), start_rate(s + e)
    return s - r0 / (r1 - r0) * e


def _values_only_rule(col, sol) -> bool:
    """The rule the optimisation half applied to constraints before the common certificate
    (``optimize/verify.py`` until issue 19): every value between the nodes ≥ −1e-6·(1 + max|c|),
    the ``at_start`` sample skipped, no rate check."""
    model = col.model
    for arc in collocation_arcs(col, sol):
        for c in model.phases[arc.phase].constraints:
            values = np.asarray(
                c.function.map(arc.x.shape[1])(arc.x, arc.u, sol["p"]), dtype=float
            ).ravel()
            inner = values[1 if c.at_start else 0 : values.size - 1 if c.at_end else values.size]
            if inner.size and np.min(inner) < -1e-6 * (1 + np.max(np.abs(values))):
                return False
    return True


def test_an_optimum_whose_trailing_foot_does_not_lift_off_is_refused(optimum):
    # Source: the certificate's rate rule (ċ > 1e-9 m/s where an at_start constraint begins),
    # against the values-only rule it replaced.  The optimum's section velocity q2_dot is moved
    # so that the swing foot's clearance starts with rate 0 (|rate| < 1e-12, rounding); the
    # positions, hence every clearance value, are unchanged.
    col, w = optimum.transcription
    model, p = col.model, col.model.p
    sol = col.unpack(w, p)
    assert check_dense(col, sol) is None  # the optimum itself certifies
    clearance = model.phases[0].constraints[0]
    assert clearance.name == "swing foot above the slope" and clearance.at_start
    rate = rate_along(model.phases[0].flow, clearance.function)
    u0 = collocation_arcs(col, sol)[0].u[:, 0]
    assert float(rate(model.lift(sol["s"]), u0, p)) > 0.1  # the real foot lifts off (m/s)

    bad_w = np.array(w, dtype=float)
    col.blocks.put(bad_w, "s", _without_lift_off(model, sol["s"], u0))
    bad = col.unpack(bad_w, p)
    assert abs(float(rate(bad["X"][0][:, 0], u0, p))) < 1e-12
    # The values: unchanged from the certified optimum, within the one tolerance rule (so the
    # value rule does not refuse it), and the old values-only rule accepted the orbit.
    arc = collocation_arcs(col, bad)[0]
    h = np.asarray(clearance.function.map(arc.x.shape[1])(arc.x, arc.u, p)).ravel()
    h_ok = np.asarray(
        clearance.function.map(arc.x.shape[1])(collocation_arcs(col, sol)[0].x, arc.u, p)
    ).ravel()
    np.testing.assert_array_equal(h, h_ok)
    assert np.min(h[1:-1]) >= -CONSTRAINT_TOL * (1 + np.max(np.abs(h)))
    assert _values_only_rule(col, bad)
    # The common certificate refuses it, by the rate rule, naming the constraint.
    defect = check_dense(col, bad)
    assert defect is not None
    assert "'swing foot above the slope' starts at 0 and must rise, but its rate is" in defect
    assert defect.startswith("no gait: trip at the start of phase 'three-link swing'")
    # Through the optimisation half's certification step: no gait, and why.
    result = _certify(col.problem, col, bad_w, {}, verify=False)
    assert not result.success
    assert result.message.startswith("not a gait: trip at the start of")
    assert "'swing foot above the slope' starts at 0 and must rise" in result.message
    # The referee agrees, independently: the simulation with the optimal torques as feedforward
    # ends at once in the constraint's terminal event (the foot does not rise).
    verdict = referee(
        model, bad["X"][0][:, 0], bad["T"], 1, tol=1e-6,
        feedforward=feedforward_of(profiles(col, bad)), tolerances=(TIGHT,),
    )  # fmt: skip
    assert not verdict.ok and "does not rise" in verdict.message


def _shape(message: str | None) -> str | None:
    """A verdict without its numbers (times and values differ by the sampling)."""
    return None if message is None else re.sub(r"-?\d[\d.]*(e[+-]?\d+)?", "#", message)


def _verdicts(passive, optimum, change):
    """``certify_orbit`` on the shooting's RK samples and on the collocation's polynomials of
    the same orbit, after ``change(arcs, model) -> (arcs, p)``."""
    model = passive.model
    problem = shooting_problem(type(model), passive.discretisation, 1)
    col, w = optimum.transcription
    sol = col.unpack(w, col.model.p)
    out = []
    for arcs in (
        shooting_arcs(model, problem, passive.orbit, passive.inputs),
        collocation_arcs(col, sol),
    ):
        arcs, p = change(list(arcs), model)
        out.append(certify_orbit(model, arcs, p, steps=1, guard_tol=1e-6))
    return out


def _as_is(arcs, model):
    return arcs, model.p


def _steeper(arcs, model):
    # The orbit unchanged, the slope raised in the parameter vector only (as in test_trust):
    # the swing foot passes under the slope.
    return arcs, model.replace(slope=0.25).p


def _no_lift_off(arcs, model):
    first = arcs[0]
    x = first.x.copy()
    s = np.array([x[model.phases[0].states.index(c), 0] for c in model.section.coordinates])
    x[:, 0] = model.lift(_without_lift_off(model, s, first.u[:, 0]))
    return [dataclasses.replace(first, x=x), *arcs[1:]], model.p


@pytest.mark.parametrize(
    "change, expected",
    [
        (_as_is, None),
        (_steeper, "ends"),
        (_no_lift_off, "'swing foot above the slope' starts at 0 and must rise"),
    ],
)
def test_both_halves_give_the_same_verdict_on_the_same_orbit(passive, optimum, change, expected):
    # Source: two transcriptions of the kneed walker's passive gait (multiple shooting, RK4
    # samples; Radau collocation, its polynomials) whose fixed points agree to 2e-8 (8.1e-9
    # measured); the one certificate must accept both, and refuse both the same way after the
    # same change.
    x_opt = [optimum.fixed_point[k] for k in passive.state_names]
    np.testing.assert_allclose(x_opt, passive.x, atol=2e-8)
    assert optimum.cost < 1e-12  # the passive gait: no torque (N²·m²·s)
    shooting, collocation = _verdicts(passive, optimum, change)
    assert _shape(shooting) == _shape(collocation)
    if expected is None:
        assert shooting is None
    else:
        assert expected in shooting


def test_both_front_doors_return_gaits_with_one_status_table(passive, optimum):
    # Source: gaitopt.result.STATUS, the one table of codes and advice. A limit cycle and an
    # optimum are both gaitopt.Gait, with a status from it; a failed optimisation record too.
    from gaitopt.optimize import OptimalGait
    from gaitopt.result import STATUS

    for gait in (passive, optimum):
        assert isinstance(gait, gaitopt.Gait)
        assert gait.status == "success" and gait.advice == STATUS["success"]
    np.testing.assert_allclose(optimum.x, passive.x, atol=2e-8)  # same orbit (see above)
    failed = OptimalGait(False, "no gait", passive.model, "effort")
    assert failed.status == "not_converged" and failed.advice == STATUS["not_converged"]
    with pytest.raises(ValueError, match="status 'lost' is not one of"):
        OptimalGait(False, "", passive.model, "effort", status="lost")


def test_a_refused_optimum_has_the_status_of_the_certificate(optimum):
    # The trailing foot without lift-off (first test) through the optimiser's certification:
    # status not_a_gait, the same code a shooting orbit refused by the certificate gets.
    col, w = optimum.transcription
    model = col.model
    sol = col.unpack(w, model.p)
    bad_w = np.array(w, dtype=float)
    u0 = collocation_arcs(col, sol)[0].u[:, 0]
    col.blocks.put(bad_w, "s", _without_lift_off(model, sol["s"], u0))
    result = _certify(col.problem, col, bad_w, {}, verify=False)
    assert not result.success and result.status == "not_a_gait"


def test_both_halves_refuse_a_repeated_orbit_as_a_period_two_gait(passive, optimum):
    # The certificate's minimal-period rule, now for optimised gaits too: the passive orbit
    # twice (both transcriptions' samples) is the period-1 gait repeated, no period-2 gait
    # (states at the second return equal to 1e-6; here identical by construction).
    model = passive.model
    problem = shooting_problem(type(model), passive.discretisation, 1)
    col, w = optimum.transcription
    sol = col.unpack(w, col.model.p)
    verdicts = []
    for arcs in (
        shooting_arcs(model, problem, passive.orbit, passive.inputs),
        collocation_arcs(col, sol),
    ):
        verdicts.append(certify_orbit(model, [*arcs, *arcs], model.p, steps=2))
    assert verdicts[0] == verdicts[1]
    assert verdicts[0].startswith("no period-2 gait here: the orbit found is the period-1 gait")
