"""The shooting Newton in one compiled call (:mod:`gaitopt.kernels.newton`): its evaluation
against the NumPy assembly, its iterations against the Python Newton, the return map's
Jacobians from its last Jacobian against the elimination in NumPy and against finite
differences of the simulated return map, the error estimate's correction, and the solve
without a C compiler (the Python Newton) giving the same gait."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from helpers import simulated_return_map_fd

import gaitopt
from gaitopt.kernels.cache import compiler
from gaitopt.orbit.sensitivity import section_jacobians
from gaitopt.shooting.newton import NEWTON_OPTIONS, newton
from gaitopt.shooting.problem import MultipleShooting, shooting_problem
from gaitopt.shooting.transcription import ShootingTranscription

needs_compiler = pytest.mark.skipif(
    compiler() is None, reason="no C compiler ($GAITOPT_CC, default gcc; or GAITOPT_COMPILE=0)"
)

STOP = dict(max_iter=NEWTON_OPTIONS["max_iter"], abstol=NEWTON_OPTIONS["abstol"],
            abstol_step=NEWTON_OPTIONS["abstolStep"])  # fmt: skip


def _setup(name: str, steps: int = 1):
    model = gaitopt.model(name)
    problem = shooting_problem(type(model), MultipleShooting(*type(model).mesh), steps)
    t = ShootingTranscription(model, problem=problem)
    compiled = problem.assembly().compiled_newton()
    assert compiled is not None
    return model, t, compiled, np.asarray(model.nominal_input(), float), np.asarray(model.p)


@needs_compiler
@pytest.mark.parametrize(("name", "steps"), [("compass_gait", 1), ("compass_gait", 2),
                                             ("kneed_walker", 1), ("slip", 1)])  # fmt: skip
def test_compiled_evaluation_is_the_numpy_assembly(name, steps):
    # Source: the shooting system assembled block by block in NumPy (Assembly._assemble), and
    # as one CasADi MX call (the evaluation without the C library), at a perturbed guess.  The
    # residual, the return state, the phase ends, rates and admissibility are bitwise the same
    # (the same compiled kernels, the same operations); the Jacobians agree to rounding, 1e-13
    # of (1 + max |J|) (sums of the same products in another order; measured ≤ 9e-16).
    model, t, compiled, u, p = _setup(name, steps)
    w = t.guess() + 1e-3 * np.cos(np.arange(t.problem.size))
    asm = t.problem.assembly()
    for jacobian, ref in [(j, asm._assemble(w, u, p, j)) for j in (True, False)] + [
        (j, asm._read(asm._assembled(j), w, u, p, j))
        for j in (True, False)  # the MX call
    ]:
        got = compiled.evaluate(w, u, p, jacobian=jacobian)
        for a, b in zip((got.F, got.x_return, got.rates, got.admissible, got.durations,
                         *got.ends), (ref.F, ref.x_return, ref.rates, ref.admissible,
                                      ref.durations, *ref.ends), strict=True):  # fmt: skip
            assert np.array_equal(a, b)
        if jacobian:
            for a, b in ((got.F_w, ref.F_w), (got.F_u, ref.F_u), (got.F_p, ref.F_p)):
                assert np.max(np.abs(a - b), initial=0.0) <= 1e-13 * (1 + np.max(np.abs(b)))


@needs_compiler
@pytest.mark.parametrize("name", ["compass_gait", "kneed_walker", "simplest_walker", "slip",
                                  "vanderpol"])  # fmt: skip
def test_compiled_newton_is_the_python_newton(name):
    # Source: the Python Newton (gaitopt.orbit.newton on the one-call assembly) from the same
    # guess with the same stopping tests: both converge after the same number of Jacobians, to
    # the same root within 1e-12 of (1 + max |w|) (the LU's rounding differs from LAPACK's;
    # the roots measured ≤ 2e-13 apart).  Where a rounding difference puts a residual on the
    # other side of abstol (1e-12), one more iteration is taken: the raibert hopper's 5 vs 6.
    model, t, compiled, u, p = _setup(name)
    w0 = t.guess()
    w_py, conv_py, it_py, ev_py = newton(t.problem, w0, u, p)
    code, w_c, it_c, ev_c = compiled.solve(w0, u, p, **STOP)
    assert conv_py and code in (1, 2) and it_c == it_py
    assert np.max(np.abs(w_c - w_py)) <= 1e-12 * (1 + np.max(np.abs(w_py)))
    assert np.max(np.abs(ev_c.F)) <= NEWTON_OPTIONS["abstol"]


@needs_compiler
def test_a_start_that_does_not_converge_stops_as_the_python_newton():
    # Source: the Python Newton's stopping tests from the same hopeless start (the compass
    # gait's guess with every phase duration 50× too long: the iterates leave the model's
    # range): both report not converged after the same number of Jacobians.
    model, t, compiled, u, p = _setup("compass_gait")
    w0 = t.guess()
    w0[t.problem.duration_index()] *= 50
    with np.errstate(all="ignore"):
        _, conv_py, it_py, _ = newton(t.problem, w0, u, p)
        code, _, it_c, _ = compiled.solve(w0, u, p, **STOP)
    assert not conv_py and code in (0, -1) and it_c == it_py


@needs_compiler
@pytest.mark.parametrize("name", ["compass_gait", "kneed_walker"])
def test_return_map_from_the_same_jacobian(name):
    # Source: eq. (1) in NumPy (orbit.sensitivity.section_jacobians, LAPACK) on the same
    # converged evaluation's Jacobians: A, B_u and B_p agree to 1e-12 of (1 + max |·|) (the same
    # elimination, another LU's rounding; measured ≤ 1e-14).
    model, t, compiled, u, p = _setup(name)
    code, w, _, ev = compiled.solve(t.guess(), u, p, **STOP)
    assert code in (1, 2) and ev.return_map is not None
    J_w = t.problem.map_jacobian(ev.F_w)
    A, B_u = section_jacobians(J_w, ev.F_u, t.problem.m, t.problem.n_g)
    _, B_p = section_jacobians(J_w, ev.F_p, t.problem.m, t.problem.n_g)
    for got, want in zip(ev.return_map, (A, B_u, B_p), strict=True):
        assert np.max(np.abs(got - want), initial=0.0) <= 1e-12 * (1 + np.max(np.abs(want)))
    # the error estimate's step from the same Jacobian: NumPy's solve on the finer residual
    # (rounding, 1e-12 of the step's scale plus 1e-20)
    step = compiled.correction(ev.F_w, w, u, p, 2 * t.problem.disc.rk_steps)
    want = t.problem.newton_step(ev.F_w, t.problem.fine_residual(w, u, p))
    assert np.max(np.abs(step - want)) <= 1e-12 * np.max(np.abs(want)) + 1e-20


@needs_compiler
def test_return_map_against_finite_differences_of_the_simulated_map():
    # Source: central differences (h = 1e-6) of the return map simulated by DOP853 at rtol
    # 1e-12 with located events (an independent method: no shooting, no fixed-step RK8):
    # truncation O(h²) ~ 1e-12 and the simulation's error ~1e-12 / h, so agreement to 1e-6 of
    # (1 + max |A|) (tests/test_sensitivity.py's check, here on the compiled Newton's A).
    model, t, compiled, u, p = _setup("compass_gait")
    code, w, _, ev = compiled.solve(t.guess(), u, p, **STOP)
    assert code in (1, 2)
    A = ev.return_map[0]
    s = w[: t.problem.m]

    A_fd = simulated_return_map_fd(model, s, u)
    assert np.max(np.abs(A - A_fd)) <= 1e-6 * (1 + np.max(np.abs(A_fd)))


def test_without_a_compiler_the_same_gait():
    # Source: the same solve in a process without a C compiler (GAITOPT_CC names none: the
    # kernels interpreted, Newton in Python): the same fixed point, period and multipliers to
    # 1e-10 (the LU and the kernels' rounding; measured ≤ 2e-13).
    here = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    code = ("import json, gaitopt; c = gaitopt.find_limit_cycle(gaitopt.model('compass_gait'));"
            "print(json.dumps([c.success, list(c.section_point), c.period,"
            " [[z.real, z.imag] for z in c.multipliers]]))")  # fmt: skip
    env = {**os.environ, "GAITOPT_CC": "no-such-cc"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True, timeout=300)  # fmt: skip
    success, s, period, mult = json.loads(out.stdout.strip().splitlines()[-1])
    assert success and here.success
    assert np.max(np.abs(np.asarray(s) - here.section_point)) <= 1e-10
    assert abs(period - here.period) <= 1e-10
    mine = np.array([[z.real, z.imag] for z in here.multipliers])
    assert np.max(np.abs(np.asarray(mult) - mine)) <= 1e-10


@needs_compiler
@pytest.mark.parametrize("name", ["compass_gait", "kneed_walker"])
def test_compiled_dense_samples_are_the_trajectory_function(name):
    # Source: the dense samples by the mapped CasADi trajectory function (the step kernels
    # from each segment start, the lift by the model's section function): bitwise the same
    # (tolerance 0: the same compiled steps on the same starts and step size).
    from gaitopt.fastcall import call1
    from gaitopt.kernels import trajectory_function

    model, t, compiled, u, p = _setup(name)
    pr = t.problem
    w = t.guess()
    S, q = pr.disc.segments, pr.disc.dense
    starts, durations = pr.segment_starts(w, p), pr.durations(w)
    want = [call1(trajectory_function(pr.model_cls, i, S, q), starts[k], u, p, durations[k] / S)
            for k, i in enumerate(pr.chain)]  # fmt: skip
    got = compiled.samples(w, u, p, q)
    assert len(got) == len(want)
    assert all(np.array_equal(a, b) for a, b in zip(got, want, strict=True))
