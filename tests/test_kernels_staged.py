"""The staged fold (gaitopt.kernels.symbolic._staged_fold): one stage function called at each RK
stage, the code compiled for a large phase, against the inlined SX fold differentiated by CasADi's
AD (an independent derivation of the same derivatives) and the residual-only step."""

from __future__ import annotations

import numpy as np

from gaitopt.kernels import model_kernels
from gaitopt.kernels.symbolic import STAGED_ABOVE, _fold, _stage, _staged_fold, _step
from gaitopt.models import REGISTRY


def _arguments(fold, rng):
    n, m = fold.size1_in(0), fold.size2_in(1)
    x = 0.1 + 0.2 * rng.random(n)
    D = rng.standard_normal((n, m))
    u = 0.1 * rng.standard_normal(fold.size1_in(2))
    p = 0.5 + rng.random(fold.size1_in(3))
    return [x, D, u, p, 0.05, 7.0]


def test_staged_fold_equals_the_inlined_fold():
    # The kneed walker's two phases (stage functions of 2900 and 1500 instructions, both staged).
    # x⁺: the same operations in the same order, so equal to the bit (and to the step kernel's,
    # which the residual-only evaluation uses); D⁺: the chain rule through the stages against
    # CasADi's AD of the whole inlined step, equal to rounding (1e-13 relative; measured 3e-15).
    rng = np.random.default_rng(3)
    for phase in REGISTRY["kneed_walker"].structure().phases:
        stage = _stage(phase.flow, "fold")
        assert stage.n_instructions() > STAGED_ABOVE
        staged, inlined = _staged_fold(phase.flow, "fold", stage), _fold(phase.flow, "fold")
        step = _step(phase.flow, "step")
        for _ in range(3):
            args = _arguments(inlined, rng)
            x_s, D_s = (np.asarray(v) for v in staged(*args))
            x_i, D_i = (np.asarray(v) for v in inlined(*args))
            assert np.array_equal(x_s, x_i)
            assert np.array_equal(x_s, np.asarray(step(args[0], *args[2:])))
            assert np.max(np.abs(D_s - D_i)) <= 1e-13 * np.max(np.abs(D_i))


def test_compiled_staged_fold_equals_the_inlined_fold():
    # The compiled library (staged where the stage is large) against the interpreted inlined fold:
    # x⁺ to the bit, D⁺ to 1e-13 relative (measured 3e-15), both phases.
    kern = model_kernels(REGISTRY["kneed_walker"])
    rng = np.random.default_rng(4)
    for i, phase in enumerate(REGISTRY["kneed_walker"].structure().phases):
        inlined = _fold(phase.flow, "fold")
        args = _arguments(inlined, rng)
        x_c, D_c = (np.asarray(v) for v in kern.fold[i](*args))
        x_i, D_i = (np.asarray(v) for v in inlined(*args))
        assert np.array_equal(x_c, x_i)
        assert np.max(np.abs(D_c - D_i)) <= 1e-13 * np.max(np.abs(D_i))


def test_small_phases_keep_the_inlined_fold():
    # The compass gait's stage (840 instructions) is under the threshold: its fold stays inlined
    # (it runs faster so, 10 µs against 15 µs a step); the kneed walker's are staged (MX).
    from gaitopt.kernels.symbolic import kernel_functions

    compass = kernel_functions(REGISTRY["compass_gait"], staged=True)
    assert compass[1].is_a("SXFunction")
    kneed = kernel_functions(REGISTRY["kneed_walker"], staged=True)
    assert kneed[1].is_a("MXFunction") and kneed[3].is_a("MXFunction")
