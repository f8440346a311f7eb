"""The solve's hot calls, made cheaper without changing their numbers: CasADi functions through
preallocated buffers (:mod:`gaitopt.fastcall`), the shooting residual and Jacobian assembled in
one CasADi call (:mod:`gaitopt.kernels.assemble`), the dense samples by the derivative-free RK
step, the certificate's checks compiled (:mod:`gaitopt.kernels.checks`), the simulation's
phase functions kept across calls and an arc's dense-output pieces built when first read.
Each is compared with the way it was computed before (an independent evaluation of the same
numbers)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gaitopt
from gaitopt.fastcall import call, call1
from gaitopt.kernels import model_kernels, trajectory_function
from gaitopt.kernels.cache import compiler
from gaitopt.orbit.certificate import (
    GUARD_TOL,
    DenseArc,
    _mapped,
    _Samples,
    _values,
    check_early_crossings,
)
from gaitopt.simulation.dense import Dop853Piece, PiecewiseSolution


def _functions():
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y", 2, 2)
    dense = ca.Function("dense", [x, y], [ca.sin(x) * ca.trace(y), ca.mtimes(y, x[:2])])
    sparse = ca.Function("sparse", [x], [ca.diag(x)])  # a structurally sparse output
    return dense, sparse


# Compiled checks and compiled arcs exist only where there is a C compiler.
needs_compiler = pytest.mark.skipif(
    compiler() is None, reason="no C compiler ($GAITOPT_CC, default gcc; or GAITOPT_COMPILE=0)"
)


def test_buffered_call_is_the_ordinary_call():
    # Source: CasADi's own call with NumPy arguments (DM conversion) on the same function and
    # inputs: every output must agree exactly (tolerance 0), dense and sparse outputs, an input
    # given as one column for a mapped function's repeated columns, and a size that does not fit
    # (the fallback, which raises as the ordinary call does).
    dense, sparse = _functions()
    xv, yv = np.array([0.3, -1.2, 2.5]), np.array([[1.0, 2.0], [-0.5, 4.0]])
    for got, want in zip(call(dense, xv, yv), dense(xv, yv), strict=True):
        assert got.shape == want.shape and np.array_equal(got, np.asarray(want))
    assert np.array_equal(call1(sparse, xv), np.asarray(ca.densify(sparse(xv))))
    mapped = dense.map(4)
    got = call(mapped, np.tile(xv[:, None], (1, 4)) * np.arange(1, 5), yv)  # y: one 2 × 2 block
    want = mapped(np.tile(xv[:, None], (1, 4)) * np.arange(1, 5), np.tile(yv, (1, 4)))
    assert all(np.array_equal(a, np.asarray(b)) for a, b in zip(got, want, strict=True))
    with pytest.raises(RuntimeError):
        call(dense, np.zeros(5), yv)  # neither the buffer nor CasADi takes 5 values for 3


@pytest.mark.parametrize("name", ["compass_gait", "kneed_walker", "slip"])
def test_one_call_assembly_is_the_numpy_assembly(name):
    # Source: the shooting system assembled block by block in NumPy (Assembly._assemble, the
    # previous code) at a perturbed orbit.  The residual, the phase ends, rates and
    # admissibility must be bitwise the same (the same compiled kernels; no arithmetic in the
    # assembly); the Jacobians agree to rounding, 1e-13 (sums of the same products in another
    # order).
    m = gaitopt.model(name)
    cycle = gaitopt.find_limit_cycle(m, verify=False)
    asm = cycle.problem.assembly()
    w = cycle.solution + 1e-3 * np.cos(np.arange(cycle.solution.size))
    for jacobian in (True, False):
        one = asm(w, cycle.inputs, m.p, jacobian=jacobian)
        with np.errstate(all="ignore"):
            ref = asm._assemble(w, cycle.inputs, m.p, jacobian)
        for a, b in zip(
            (one.F, one.x_return, one.rates, one.admissible, one.durations, *one.ends),
            (ref.F, ref.x_return, ref.rates, ref.admissible, ref.durations, *ref.ends),
            strict=True,
        ):
            assert np.array_equal(a, b)
        if jacobian:
            for a, b in ((one.F_w, ref.F_w), (one.F_u, ref.F_u), (one.F_p, ref.F_p)):
                assert np.max(np.abs(a - b), initial=0.0) <= 1e-13 * (1 + np.max(np.abs(b)))
        else:
            assert one.F_w is None


def test_dense_samples_by_the_step_alone_are_the_fold_samples():
    # Source: the samples by the RK step that carries its derivatives (the kernels' ``fold``
    # with zero derivatives, the previous trajectory function): bitwise the same (tolerance 0),
    # both phases of the kneed walker.
    m = gaitopt.model("kneed_walker")
    kern = model_kernels(type(m))
    rng = np.random.default_rng(3)
    for phase in range(len(m.phases)):
        n, nu, np_ = kern.n[phase], kern.n_u, kern.n_p
        X = rng.normal(size=(n, 4)) * 0.2 + (m.lift({})[:n, None] if phase == 0 else 0.0)
        u, p, hs = np.zeros(nu), m.p, 0.05
        fast = call1(trajectory_function(type(m), phase, 4, 8), X, u, p, hs)
        fold, cols = kern.fold[phase], []
        for j in range(4):
            x = X[:, j]
            cols.append(x)
            for _ in range(8):
                x = np.asarray(fold(x, np.zeros((n, n + nu + np_ + 1)), u, p, hs, 8)[0]).ravel()
                cols.append(x)
        assert np.array_equal(fast, np.column_stack(cols))


@needs_compiler
@pytest.mark.parametrize("name", ["kneed_walker", "slip", "three_link_walker"])
def test_compiled_checks_are_the_interpreted_checks(name):
    # Source: each guard, admissibility rule and constraint evaluated by itself (CasADi's
    # interpreter, mapped over the samples: the certificate's previous evaluation) at random
    # states around the default start: bitwise the same (tolerance 0).
    m = gaitopt.model(name)
    samples = _Samples(m, m.p)
    assert samples.kernels is not None  # a C compiler is present (needs_compiler)
    rng = np.random.default_rng(7)
    for i, phase in enumerate(m.phases):
        X = rng.normal(size=(phase.n, 33)) * 0.3
        U = np.tile(np.asarray(m.nominal_input(), float).reshape(-1, 1), (1, 33))
        arc = DenseArc(i, "x", 1.0, np.linspace(0, 1, 33), X, U)
        for j, tr in enumerate(phase.transitions):
            assert np.array_equal(samples.guard(arc, j), _values(tr.guard, arc, m.p))
            rule = samples.admissible(arc, j)
            assert (rule is None) == (tr.admissible is None)
            if rule is not None:
                assert np.array_equal(rule, _values(tr.admissible, arc, m.p))
        for j, c in enumerate(phase.constraints):
            assert np.array_equal(samples.constraint(arc, j), _values(c.function, arc, m.p))


def _early_crossing_loop(model, arcs, p):
    """The previous sample-by-sample loop of check_early_crossings: the first (phase, sample)."""
    for arc in arcs:
        K = arc.x.shape[1]
        for j, tr in enumerate(model.phases[arc.phase].transitions):
            g = tr.direction * _values(tr.guard, arc, p)
            a = _values(tr.admissible, arc, p) if tr.admissible is not None else np.ones(K)
            armed = np.maximum.accumulate(g < -GUARD_TOL * (1 + np.max(np.abs(g))))
            for idx in range(1, K - 1 if j == 0 else K):
                if armed[idx - 1] and g[idx - 1] < 0 <= g[idx] and (a[idx - 1] > 0 or a[idx] > 0):
                    return arc.label, idx
    return None


def test_vectorised_early_crossings_are_the_loop():
    # Source: the sample-by-sample loop the check had (written out above); on the kneed walker's
    # orbit (no crossing) and on samples whose knee angle is made to cross its guard at a chosen
    # sample, the verdict and the crossing's sample must be the same.
    m = gaitopt.model("kneed_walker")
    cycle = gaitopt.find_limit_cycle(m, verify=False)
    arcs = [
        DenseArc(a.phase, f"arc {k}", float(a.t[-1] - a.t[0]), a.t, a.x, np.zeros((0, a.t.size)))
        for k, a in enumerate(cycle.orbit)
    ]
    assert (
        check_early_crossings(m, arcs, m.p) is None and _early_crossing_loop(m, arcs, m.p) is None
    )
    rng = np.random.default_rng(11)
    crossings = 0
    for trial in range(12):
        k = trial % len(arcs)
        x = arcs[k].x + rng.normal(size=arcs[k].x.shape) * 0.05 * (trial % 3)
        broken = list(arcs)
        broken[k] = DenseArc(arcs[k].phase, arcs[k].label, arcs[k].duration, arcs[k].t, x,
                             arcs[k].u)  # fmt: skip
        loop = _early_crossing_loop(m, broken, m.p)
        words = check_early_crossings(m, broken, m.p)
        assert (words is None) == (loop is None)
        if loop is not None:
            crossings += 1
            assert loop[0] in words and f"t = {broken[k].t[loop[1]]:.4g} s" in words
    assert crossings >= 4  # the perturbed samples do cross (here 8 of 12, at samples 1 to 63)


@needs_compiler
def test_kept_phase_functions_and_lazy_pieces_simulate_the_same():
    # Source: a simulation in a fresh thread (no kept phase functions: built anew) against
    # the same simulation twice in this thread (the second with the kept ones), and every
    # piece of an arc against SciPy's formula built eagerly (Dop853Piece on the arc's stored
    # steps): identical times, states and dense output (tolerance 0).
    import threading

    m = gaitopt.model("compass_gait")
    x0 = m.lift({})

    def run():
        return gaitopt.simulate(m, x0, steps=3, rtol=1e-10, atol=1e-12)

    first, second = run(), run()
    fresh: list = []
    thread = threading.Thread(target=lambda: fresh.append(run()))
    thread.start()
    thread.join()
    for sim in (second, fresh[0]):
        assert np.array_equal(np.array(sim.section_times), np.array(first.section_times))
        assert np.array_equal(np.array(sim.section_states), np.array(first.section_states))
    arc = first.arcs[0].solution
    t = np.linspace(arc.t_min, arc.t_max, 23)
    ends, y_old, F = arc._steps
    eager = [Dop853Piece(a, b, y, f) for a, b, y, f in
             zip(arc.ts[:-1].tolist(), ends.tolist(), y_old, F, strict=True)]  # fmt: skip
    segments = np.clip(np.searchsorted(arc.ts, t, side="left") - 1, 0, len(eager) - 1)
    pieces = [eager[s](ti) for s, ti in zip(segments, t, strict=True)]
    assert np.array_equal(arc(t), np.column_stack(pieces))
    assert len(arc.interpolants) == len(eager)
    # all times at once (shuffled, on the stamps, outside the arc) as piece by piece (SciPy's
    # OdeSolution order: PiecewiseSolution.__call__), and a single time
    t = np.concatenate([np.linspace(arc.t_min - 0.01, arc.t_max + 0.01, 31), arc.ts])
    np.random.default_rng(5).shuffle(t)
    assert np.array_equal(arc(t), PiecewiseSolution.__call__(arc, t))
    assert np.array_equal(arc(t[3]), PiecewiseSolution.__call__(arc, t[3]))
    # another slope: another phase function (the kept one is not reused for other parameters)
    steep = gaitopt.simulate(m.replace(slope=0.06), x0, steps=1, rtol=1e-10, atol=1e-12)
    assert steep.section_times[-1] != first.section_times[1]


def test_mapped_checks_are_kept_per_size():
    # Source: the cache's contract — the same mapped function for one function and size, a
    # different one for another size.
    f = gaitopt.model("compass_gait").phases[0].transitions[0].guard
    assert _mapped(f, 9) is _mapped(f, 9) and _mapped(f, 9) is not _mapped(f, 10)
