"""Newton's line search with a residual-only evaluation for its trial points
(:func:`gaitopt.orbit.newton.newton`, ``residual=``): the same iterates as evaluating the
Jacobian at every trial, with Jacobians only at the accepted points."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import gaitopt
from gaitopt.continuation.switching import doubled_unknowns
from gaitopt.orbit.newton import newton


def _system(F, F_w, calls):
    def evaluate(w):
        calls["jacobian"] += 1
        return SimpleNamespace(F=F(w), F_w=F_w(w))

    def residual(w):
        calls["residual"] += 1
        return SimpleNamespace(F=F(w))

    return evaluate, residual


# F(w) = (w₀² + 1, w₁ − 1): ‖F‖ has a minimum with F ≠ 0 at w₀ = 0 (no root: the line search
# backtracks at every iteration); F(w) = (atan w₀ − 0.5, w₁ − 1) from w₀ = 3: plain Newton
# overshoots (|atan| flattens), the line search converges to w₀ = tan 0.5.
SYSTEMS = {
    "no root": (
        lambda w: np.array([w[0] ** 2 + 1, w[1] - 1]),
        lambda w: np.array([[2 * w[0], 0.0], [0.0, 1.0]]),
        [1.3, 4.0],
    ),
    "root": (
        lambda w: np.array([np.arctan(w[0]) - 0.5, w[1] - 1]),
        lambda w: np.array([[1 / (1 + w[0] ** 2), 0.0], [0.0, 1.0]]),
        [3.0, 4.0],
    ),
}


@pytest.mark.parametrize("name", SYSTEMS)
def test_residual_trials_give_the_same_iterates(name):
    # Source: the same algorithm run twice (trial points by `evaluate` vs by `residual`); the
    # iterates must agree exactly (tolerance 0), the root where there is one to 1e-12 (abstol).
    F, F_w, w0 = SYSTEMS[name]
    plain, fast = {"jacobian": 0, "residual": 0}, {"jacobian": 0, "residual": 0}
    evaluate, _ = _system(F, F_w, plain)
    w_a, conv_a, it_a, ev_a = newton(evaluate, w0, line_search=True)
    evaluate, residual = _system(F, F_w, fast)
    w_b, conv_b, it_b, ev_b = newton(evaluate, w0, line_search=True, residual=residual)
    assert np.array_equal(w_a, w_b) and conv_a == conv_b and it_a == it_b
    assert np.array_equal(ev_a.F, ev_b.F) and ev_b.F_w is not None
    assert conv_a == (name == "root")
    if conv_a:
        assert abs(w_a[0] - np.tan(0.5)) <= 1e-12
    # Jacobians only at accepted points (plus the last one where it stops unconverged).
    assert fast["jacobian"] <= it_b + 1 < plain["jacobian"]


@pytest.mark.parametrize(("name", "steps"), [("compass_gait", 1), ("compass_gait", 2), ("slip", 1)])
def test_shooting_residual_alone_is_the_residual_with_jacobian(name, steps):
    # Source: the assembled shooting system evaluated with its Jacobian (the RK steps carrying
    # their derivatives) and without (kernels.step_kernels: the steps alone) at a perturbed
    # orbit: every output must be bitwise the same (tolerance 0), so that Newton's accept/reject
    # decisions do not depend on which evaluation computed them (SLIP: two phases per step; two
    # steps: the period-1 orbit repeated, as the branch switching at a period doubling has it).
    m = gaitopt.model(name)
    cycle = gaitopt.find_limit_cycle(m)
    assert cycle.success
    problem, w, _ = doubled_unknowns(cycle) if steps == 2 else (cycle.problem, cycle.solution, 0)
    asm = problem.assembly()
    w = w + 1e-3 * np.cos(np.arange(w.size))
    full = asm(w, cycle.inputs, m.p)
    alone = asm(w, cycle.inputs, m.p, jacobian=False)
    assert alone.F_w is None and asm._residual_chain() is not None  # the steps' own chain
    for a, b in zip(
        (full.F, full.x_return, full.rates, full.admissible, full.durations, *full.ends),
        (alone.F, alone.x_return, alone.rates, alone.admissible, alone.durations, *alone.ends),
        strict=True,
    ):
        assert np.array_equal(a, b)
