"""The reduced folds ``foldx_i`` (:func:`gaitopt.kernels.symbolic.kernel_functions`): the fold
carrying only the state and duration columns of its derivatives, which the compiled Newton
iterates with (:mod:`gaitopt.kernels.newton`), against the full ``fold_i``; the compiled
Newton with them against the compiled Newton without them; the return map from the solve that
used them against finite differences of the simulated return map."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import simulated_return_map_fd

import gaitopt
from gaitopt.kernels import model_kernels
from gaitopt.kernels.cache import compiler
from gaitopt.kernels.newton import CompiledNewton
from gaitopt.kernels.symbolic import kernel_functions, reduced_fold
from gaitopt.shooting.newton import NEWTON_OPTIONS
from gaitopt.shooting.problem import MultipleShooting, shooting_problem
from gaitopt.shooting.transcription import ShootingTranscription

needs_compiler = pytest.mark.skipif(
    compiler() is None, reason="no C compiler ($GAITOPT_CC, default gcc; or GAITOPT_COMPILE=0)"
)

STOP = dict(max_iter=NEWTON_OPTIONS["max_iter"], abstol=NEWTON_OPTIONS["abstol"],
            abstol_step=NEWTON_OPTIONS["abstolStep"])  # fmt: skip


def test_which_phases_get_a_reduced_fold():
    # Source: the rule's definition (input and parameter columns at least the state and
    # duration columns), on the kneed walker's first phase (6 states, 3 inputs, 10
    # parameters: 7 of 20 columns) and the compass gait's (4 states, 1 input, 6 parameters)
    # against a phase with few parameters (6 states, 6 parameters).
    assert reduced_fold(6, 3, 10) and reduced_fold(4, 1, 6)
    assert not reduced_fold(6, 0, 6)


def test_no_reduced_fold_without_staging():
    # Source: kernel_functions' contract: the interpreted kernels (no compiler: staged=False)
    # and the inlined phases have no foldx (the Python Newton keeps the full fold).
    names = [f.name() for f in kernel_functions(type(gaitopt.model("compass_gait")), True)]
    assert not any(n.startswith("foldx_") for n in names)
    names = [f.name() for f in kernel_functions(type(gaitopt.model("kneed_walker")), False)]
    assert not any(n.startswith("foldx_") for n in names)


@needs_compiler
@pytest.mark.parametrize("name", ["kneed_walker", "three_link_walker"])
def test_reduced_fold_is_the_full_folds_state_and_duration_columns(name):
    # Source: fold_i itself (the compiled full kernel) at the same random point, with Dx its
    # D's state and duration columns: x⁺ and Dx⁺ are the same to the bit (tolerance 0: the
    # staged fold's derivative columns are computed column by column by the same stage
    # products and sums, so dropping the u and p columns changes no operation of the others).
    model = gaitopt.model(name)
    kern = model_kernels(type(model))
    rng = np.random.default_rng(3)
    checked = 0
    for i, (fold, foldx) in enumerate(zip(kern.fold, kern.foldx, strict=True)):
        if foldx is None:
            continue
        n, nu, np_ = kern.n[i], kern.n_u, kern.n_p
        x, u = 0.1 * rng.normal(size=n), rng.normal(size=nu)
        p = np.asarray(model.p, float)
        D = rng.normal(size=(n, n + nu + np_ + 1))
        Dx = np.hstack([D[:, :n], D[:, -1:]])
        x1, D1 = (np.array(a) for a in fold(x, D, u, p, 0.37, 7))
        x1x, D1x = (np.array(a) for a in foldx(x, Dx, u, p, 0.37, 7))
        assert np.array_equal(x1, x1x)
        assert np.array_equal(np.hstack([D1[:, :n], D1[:, -1:]]), D1x)
        checked += 1
    assert checked == len(kern.fold)  # every phase of these models has one


def _solvers(name: str):
    model = gaitopt.model(name)
    problem = shooting_problem(type(model), MultipleShooting(*type(model).mesh), 1)
    t = ShootingTranscription(model, problem=problem)
    asm = problem.assembly()
    reduced, full = CompiledNewton.build(asm), CompiledNewton.build(asm, reduced=False)
    assert reduced is not None and full is not None
    return model, t, reduced, full, np.asarray(model.nominal_input(), float), np.asarray(model.p)


@needs_compiler
@pytest.mark.parametrize("name", ["kneed_walker", "three_link_walker"])
def test_newton_with_reduced_folds_is_the_previous_path(name):
    # Source: the compiled Newton iterating with the full folds (reduced=False, the previous
    # path) from the same guess: the same number of Jacobians, the same root to 1e-12 of
    # (1 + max |w|), and at the root the same ∂F/∂w, ∂F/∂u, ∂F/∂p and return map to 1e-12 of
    # (1 + max |·|) (the same operations: measured identical to the bit).
    model, t, reduced, full, u, p = _solvers(name)
    w0 = t.guess()
    code_r, w_r, it_r, ev_r = reduced.solve(w0, u, p, **STOP)
    code_f, w_f, it_f, ev_f = full.solve(w0, u, p, **STOP)
    assert code_r in (1, 2) and code_r == code_f and it_r == it_f
    assert np.max(np.abs(w_r - w_f)) <= 1e-12 * (1 + np.max(np.abs(w_f)))
    pairs = [(ev_r.F, ev_f.F), (ev_r.F_w, ev_f.F_w), (ev_r.F_u, ev_f.F_u), (ev_r.F_p, ev_f.F_p)]
    pairs += list(zip(ev_r.return_map, ev_f.return_map, strict=True))
    for a, b in pairs:
        assert np.max(np.abs(a - b), initial=0.0) <= 1e-12 * (1 + np.max(np.abs(b), initial=0.0))


@needs_compiler
def test_newton_with_reduced_folds_stops_as_the_previous_path():
    # Source: the previous path (reduced=False) from a hopeless start (the kneed walker's
    # guess with its phase durations 50× too long): the same return code and number of
    # Jacobians.
    model, t, reduced, full, u, p = _solvers("kneed_walker")
    w0 = t.guess()
    w0[t.problem.duration_index()] *= 50
    with np.errstate(all="ignore"):
        code_r, _, it_r, _ = reduced.solve(w0, u, p, **STOP)
        code_f, _, it_f, _ = full.solve(w0, u, p, **STOP)
    assert code_r == code_f and it_r == it_f


@needs_compiler
def test_kneed_return_map_against_finite_differences_of_the_simulated_map():
    # Source: central differences (h = 1e-6) of the kneed walker's return map simulated by
    # DOP853 at rtol 1e-12 with located events (an independent method: no shooting, no
    # fixed-step RK8): truncation O(h²) ~ 1e-12 and the simulation's error ~1e-12 / h, so
    # agreement to 1e-6 of (1 + max |A|) (tests/test_newton_compiled.py's check on the compass
    # gait, here on the solve that iterated with the reduced folds).
    model, t, reduced, _, u, p = _solvers("kneed_walker")
    code, w, _, ev = reduced.solve(t.guess(), u, p, **STOP)
    assert code in (1, 2)
    A = ev.return_map[0]
    s = w[: t.problem.m]

    A_fd = simulated_return_map_fd(model, s, u)
    assert np.max(np.abs(A - A_fd)) <= 1e-6 * (1 + np.max(np.abs(A_fd)))
