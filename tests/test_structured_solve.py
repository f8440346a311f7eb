"""The structured (block-pattern, sparse LU) solve of period-k shooting systems
(:mod:`gaitopt.orbit.structured`, :mod:`gaitopt.shooting.pattern`): the pattern holds every
nonzero the assembly writes, and Newton takes the same iterates with it as with the dense solve."""

from __future__ import annotations

import numpy as np
import pytest

import gaitopt
from gaitopt.orbit import structured
from gaitopt.orbit.newton import newton
from gaitopt.orbit.structured import BlockPattern
from gaitopt.shooting import shooting_problem
from gaitopt.shooting.pattern import shooting_pattern


@pytest.fixture(scope="module")
def compass():
    return gaitopt.find_limit_cycle(gaitopt.model("compass_gait", slope=0.0525), verify=False)


def _period_k(cycle, k: int, seed: int = 0, scale: float = 1e-3):
    """The period-k problem and the period-1 orbit repeated k times, perturbed (so that Newton
    has work to do and no entry is zero by symmetry)."""
    one = cycle.problem
    problem = shooting_problem(one.model_cls, one.disc, k)
    s, nodes, durations = one.unpack(cycle.solution, cycle.model.p)
    w = problem.pack(s, nodes * k, list(durations) * k)
    return problem, w + scale * np.random.default_rng(seed).standard_normal(w.size)


@pytest.mark.parametrize(("name", "k"), [("compass_gait", 3), ("slip", 2), ("bouncing_ball", 4)])
def test_pattern_holds_every_nonzero_of_the_jacobian(name, k):
    # Source: the assembled dense Jacobian (gaitopt.kernels.assemble) at a perturbed orbit; every
    # nonzero must lie on the pattern derived from the layout alone (exact test), and the
    # pattern must be sparse (linear in k: under a third of the dense matrix at these k).
    cycle = gaitopt.find_limit_cycle(gaitopt.model(name), verify=False)
    problem, w = _period_k(cycle, k)
    F_w = problem.evaluate(w, cycle.inputs, cycle.model.p).F_w
    pattern = shooting_pattern(problem)
    assert pattern is not None and pattern.covers(F_w)
    assert pattern.nnz < problem.size**2 / 3
    assert np.count_nonzero(F_w) <= pattern.nnz


def test_pattern_grows_linearly_in_k(compass):
    # Source: the layout (stage k's rows touch stages k and k + 1 only): the pattern's nonzeros
    # per stage are the same for every k (exact; the first stage's lift counts once).
    nnz = [shooting_pattern(_period_k(compass, k)[0]).nnz for k in (2, 4, 8, 16)]
    per_stage = np.diff(nnz) / np.diff([2, 4, 8, 16])
    assert np.all(per_stage == per_stage[0])


@pytest.mark.parametrize("k", [2, 4, 8])
def test_structured_newton_takes_the_dense_iterates(compass, k, monkeypatch):
    # Source: the same Newton run twice, its steps solved densely (LAPACK) and on the pattern
    # (SuperLU); the iterates must agree to 1e-12 (both are backward stable: the difference is
    # rounding, amplified by the Jacobian's condition number, ~1e3 here) and converge alike.
    problem, w0 = _period_k(compass, k, scale=1e-2)
    asm = problem.assembly()
    u, p = compass.inputs, compass.model.p
    pattern = shooting_pattern(problem)

    def run(min_size: int):
        monkeypatch.setattr(structured, "STRUCTURED_MIN_SIZE", min_size)
        visited = []

        def evaluate(w):
            visited.append(np.array(w))
            return asm(w, u, p)

        def linear_solve(J, b):
            return structured.solve(J, b, pattern)

        w, converged, iterations, _ = newton(evaluate, w0, linear_solve=linear_solve)
        return visited, converged, iterations

    dense, conv_d, it_d = run(10**9)
    sparse, conv_s, it_s = run(0)
    assert conv_d and conv_s and it_d == it_s and len(dense) >= 3
    for a, b in zip(dense, sparse, strict=True):
        assert np.max(np.abs(a - b)) <= 1e-12 * (1 + np.max(np.abs(a)))


def test_shooting_solve_uses_the_pattern_above_the_threshold(compass, monkeypatch):
    # Source: the period-8 shooting system (ShootingProblem.solve, the solve find_limit_cycle
    # and the branch switch run) from a displaced period-1 orbit taken 8 times, solved with the
    # structured solve forced (threshold 0) and with the dense one: the structured path is
    # taken (counted), both converge, to the same point to what Newton's stopping test allows:
    # each stops at max |F| ≤ 1e-12, so the points differ by at most ‖F_w⁻¹‖∞ · 2e-12 (first
    # order in the residual).
    calls = {"n": 0}
    original = structured.solve

    def counting(matrix, rhs, pattern=None):
        if pattern is not None and matrix.shape[0] >= structured.STRUCTURED_MIN_SIZE:
            calls["n"] += 1
        return original(matrix, rhs, pattern)

    problem, w0 = _period_k(compass, 8, seed=1, scale=1e-2)
    u, p = compass.inputs, compass.model.p
    monkeypatch.setattr(structured, "solve", counting)
    monkeypatch.setattr(structured, "STRUCTURED_MIN_SIZE", 10**9)
    dense = problem.solve(w0, u, p)
    assert calls["n"] == 0
    monkeypatch.setattr(structured, "STRUCTURED_MIN_SIZE", 0)
    sparse = problem.solve(w0, u, p)
    assert calls["n"] >= sparse.iterations - 1 > 0
    assert dense.converged and sparse.converged
    F_w = problem.evaluate(dense.w, u, p).F_w
    bound = 2e-12 * np.linalg.norm(np.linalg.inv(F_w), np.inf)
    assert np.max(np.abs(sparse.w - dense.w)) <= bound


def test_singular_matrix_raises_like_numpy(monkeypatch):
    # Source: an exactly singular matrix (a zero column) must raise numpy's LinAlgError on both
    # paths, so that Newton falls back to least squares either way.
    monkeypatch.setattr(structured, "STRUCTURED_MIN_SIZE", 0)
    pattern = BlockPattern(4, [(range(4), range(4))])
    singular = np.diag([1.0, 2.0, 0.0, 3.0])
    with pytest.raises(np.linalg.LinAlgError):
        structured.solve(singular, np.ones(4), pattern)
    with pytest.raises(np.linalg.LinAlgError):
        structured.solve(singular, np.ones(4), None)


def test_bordered_pattern_adds_a_full_row_and_column(monkeypatch):
    # Source: construction — [[M, c], [rᵀ, d]] of a diagonal M: n + 2n + 1 entries; its sparse
    # solve against the dense one to 1e-15 (a 4 × 4 diagonal-plus-border system).
    monkeypatch.setattr(structured, "STRUCTURED_MIN_SIZE", 0)
    pattern = BlockPattern(3, [([i], [i]) for i in range(3)]).bordered()
    assert pattern.size == 4 and pattern.nnz == 3 + 2 * 3 + 1
    matrix = np.diag([2.0, 3.0, 4.0, 5.0])
    matrix[3, :3], matrix[:3, 3] = 1.0, -1.0
    assert pattern.covers(matrix)
    rhs = np.arange(1.0, 5.0)
    np.testing.assert_allclose(
        structured.solve(matrix, rhs, pattern), np.linalg.solve(matrix, rhs), atol=1e-15
    )
