"""The vector DOP853 step (gaitopt.kernels.vector_step: the SX step's instructions emitted as C
on GCC vector types, 8 starts per call) against the scalar compiled step of the verification
(gaitopt.kernels.verify, CasADi's own generated C): every lane's every output equal to the bit
(tolerance 0: the same IEEE operations in the same order, no fused multiply-adds, the C library's
sin/cos per lane), on random inputs of the compass gait (sin and cos), the rimless wheel (no
inputs u) and both phases of the kneed walker, compiled for the host's vector unit and (the
compass gait) for the compiler's baseline target; and the emitter refusing a function that is not an
SX instruction list."""

from __future__ import annotations

import ctypes

import casadi as ca
import numpy as np
import pytest

import gaitopt
from gaitopt.kernels.cache import compiler
from gaitopt.kernels.vector_step import LANES, emit, vector_steps
from gaitopt.kernels.verify import verification_steps

pytestmark = pytest.mark.skipif(compiler() is None, reason="no C compiler")


def _inputs(f, rng):
    """Random step inputs (lanes in columns): states and rates N(0, 1), steps up to 0.01 s, the
    check fractions, rtol/atol 1e-11/1e-12, parameters in [0.5, 1.5)."""
    values = [rng.normal(size=(f.nnz_in(j), LANES)) for j in range(f.n_in())]
    values[2] = 0.01 * np.abs(values[2])
    values[3][:] = np.array([0.25, 0.5, 0.75])[:, None]
    values[5] = 0.5 + rng.random(values[5].shape)
    values[6][:] = np.array([1e-11, 1e-12])[:, None]
    return values


def _baseline(cls):
    """The vector steps compiled for the compiler's baseline target (no -mavx2/-mavx512f: what a
    host without them gets), bypassing the cache of the host's build."""
    from gaitopt.kernels import vector_step

    real = vector_step.host_flags
    vector_step.host_flags = lambda: ()
    try:
        return vector_step._vector_steps.__wrapped__(cls, "exact", False)
    finally:
        vector_step.host_flags = real


@pytest.mark.parametrize(
    "name, build",
    [("compass_gait", "host"), ("rimless_wheel", "host"), ("kneed_walker", "host"),
     ("compass_gait", "baseline")],
)  # fmt: skip
def test_vector_step_equals_the_scalar_step_to_the_bit(name, build):
    cls = type(gaitopt.model(name))
    vectors = vector_steps(cls, "exact") if build == "host" else _baseline(cls)
    scalars = verification_steps(cls)
    assert vectors is not None and scalars is not None
    rng = np.random.default_rng(7)
    for (phase, constraints), f in scalars.items():
        fn = vectors.function(phase, constraints)
        fn.restype, fn.argtypes = ctypes.c_int, [ctypes.c_void_p] * 2
        for _ in range(4):
            values = _inputs(f, rng)
            ins = [np.ascontiguousarray(v) if v.size else np.zeros(LANES) for v in values]
            outs = [np.full((max(f.nnz_out(j), 1), LANES), np.nan) for j in range(f.n_out())]
            arg = (ctypes.c_void_p * len(ins))(*(a.ctypes.data for a in ins))
            res = (ctypes.c_void_p * len(outs))(*(a.ctypes.data for a in outs))
            assert fn(arg, res) == 0
            for lane in range(LANES):
                ref = f(*(v[:, lane] for v in values))
                for j, r in enumerate(ref):
                    want = np.asarray(r.full()).ravel(order="F")
                    got = outs[j][: want.size, lane]
                    assert want.tobytes() == got.tobytes(), (name, phase, constraints, j, lane)


def test_emit_refuses_a_function_that_is_not_an_sx_instruction_list():
    x = ca.MX.sym("x")
    inner = ca.Function("inner", [x], [ca.sin(x)])
    outer = ca.Function("outer", [x], [inner(x) + 1])
    with pytest.raises(NotImplementedError, match="not an SX function"):
        emit(outer, "gaitopt_vstep_test")
