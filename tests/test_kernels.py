"""The compiled shooting kernels (gaitopt.kernels): the Jacobian assembled from per-segment
blocks against CasADi's AD of the whole shooting graph, the interpreted fallback without a C
compiler, and the disk cache."""

from __future__ import annotations

import numpy as np

import gaitopt
from gaitopt.kernels import ModelKernels
from gaitopt.kernels.assemble import Assembly
from gaitopt.shooting import MultipleShooting, shooting_problem


def _point(name: str, cycles: int = 1):
    model = gaitopt.model(name)
    problem = shooting_problem(type(model), MultipleShooting(*type(model).mesh), cycles)
    rng = np.random.default_rng(1)
    w = np.zeros(problem.size)
    w[: problem.m] = model.section_vector({})
    nodes = np.tile(model.lift(w[: problem.m]), problem.disc.segments * len(problem.chain))
    for kind, _, off, shape in problem.layout:  # a plausible point: the start state, short phases
        size = int(np.prod(shape)) if shape else 1
        w[off : off + size] = nodes[:size] if kind == "nodes" else 0.3
    w += 1e-3 * rng.standard_normal(problem.size)
    return model, problem, w


def _compare(evaluation, problem, w, u, p, tol):
    F, F_w, F_p, F_u = (np.asarray(v, dtype=float) for v in problem.residual_jacobians(w, u, p))
    # Independent method: CasADi's AD through the whole chain (the shooting graph).
    assert np.max(np.abs(evaluation.F - F.ravel())) <= tol
    assert np.max(np.abs(evaluation.F_w - F_w)) <= tol * (1 + np.max(np.abs(F_w)))
    assert np.max(np.abs(evaluation.F_p - F_p)) <= tol * (1 + np.max(np.abs(F_p)))
    if F_u.size:
        assert np.max(np.abs(evaluation.F_u - F_u)) <= tol * (1 + np.max(np.abs(F_u)))


def test_assembled_jacobian_matches_ad_of_the_whole_chain():
    # Two phases (kneed walker) and a period-2 chain (compass gait): the block assembly must give
    # CasADi's AD Jacobian to rounding (1e-10 relative; measured ~1e-13).
    for name, cycles in (("compass_gait", 2), ("kneed_walker", 1)):
        model, problem, w = _point(name, cycles)
        u = model.nominal_input()
        _compare(problem.evaluate(w, u, model.p), problem, w, u, model.p, 1e-10)


def test_interpreted_fallback_without_a_compiler(monkeypatch, tmp_path):
    # A missing compiler: the same SX functions run interpreted, with the same results (1e-12).
    monkeypatch.setenv("GAITOPT_CC", str(tmp_path / "no-such-compiler"))
    monkeypatch.setenv("GAITOPT_CACHE", str(tmp_path / "cache"))
    model, problem, w = _point("vanderpol")
    kern = ModelKernels(type(model), verbose=False)
    assert not kern.compiled
    assert not (tmp_path / "cache").exists()
    u, p = model.nominal_input(), model.p
    compiled = Assembly(problem)(w, u, p)
    import gaitopt.kernels as kernels

    monkeypatch.setattr(kernels, "model_kernels", lambda cls: kern)
    kernels.phase_function.cache_clear()
    try:
        interpreted = kernels.assemble.Assembly.__new__(kernels.assemble.Assembly)
        monkeypatch.setattr(kernels.assemble, "model_kernels", lambda cls: kern)
        interpreted.__init__(problem)
        assert not interpreted.compiled
        other = interpreted(w, u, p)
    finally:
        kernels.phase_function.cache_clear()
    assert np.max(np.abs(other.F - compiled.F)) <= 1e-12
    assert np.max(np.abs(other.F_w - compiled.F_w)) <= 1e-12 * (1 + np.max(np.abs(other.F_w)))


def test_cache_compiles_once_and_reuses(monkeypatch, tmp_path, capsys):
    # The first use compiles (and says so on stderr); the second finds the same library.
    monkeypatch.setenv("GAITOPT_CACHE", str(tmp_path))
    model = gaitopt.model("vanderpol")
    first = ModelKernels(type(model))
    libraries = sorted(tmp_path.glob("*.so"))
    if not first.compiled:  # no C compiler on this machine: nothing to cache
        assert not libraries
        return
    assert "compiling" in capsys.readouterr().err
    assert len(libraries) == 1 and not list(tmp_path.glob(".*"))  # no temporary files left
    second = ModelKernels(type(model))
    assert second.compiled and sorted(tmp_path.glob("*.so")) == libraries
    assert "compiling" not in capsys.readouterr().err


def test_index_loads_without_building_and_ignores_a_stale_entry(monkeypatch, tmp_path):
    # A warm start finds the library in the index under the source key and builds nothing; an
    # entry whose library is gone is ignored and rewritten (the library compiled again).
    monkeypatch.setenv("GAITOPT_CACHE", str(tmp_path))
    import gaitopt.kernels as kernels

    cls = type(gaitopt.model("vanderpol"))
    first = ModelKernels(cls, verbose=False)
    if not first.compiled:  # no C compiler on this machine: no index either
        assert not (tmp_path / "index").exists()
        return
    assert len(list((tmp_path / "index").glob("*.json"))) == 1

    def no_build(model_cls):
        raise AssertionError("the index was not used")

    monkeypatch.setattr(kernels, "kernel_functions", no_build)
    second = ModelKernels(cls, verbose=False)
    assert second.compiled and second.n == first.n
    x = np.array([1.0, 0.5])
    for a, b in zip(first.end[0](x, [], cls().p), second.end[0](x, [], cls().p), strict=True):
        assert np.array_equal(np.asarray(a), np.asarray(b))  # the same library: bit for bit
    monkeypatch.undo()
    monkeypatch.setenv("GAITOPT_CACHE", str(tmp_path))
    for library in tmp_path.glob("*.so"):
        library.unlink()
    third = ModelKernels(cls, verbose=False)
    assert third.compiled and len(list(tmp_path.glob("*.so"))) == 1


def test_compiled_verification_steps_equal_the_interpreted_ones():
    # The verification's DOP853 step (state, rate, error norm, dense coefficients, events),
    # compiled per model class, must give the interpreted CasADi function's numbers (same
    # expression graph; measured identical, tolerance 1e-14 relative for compiler reassociation).
    from gaitopt.dop853 import step_function
    from gaitopt.kernels.verify import CHECKS_PER_STEP, phase_events, verification_steps

    for name in ("compass_gait", "kneed_walker"):
        model = gaitopt.model(name)
        compiled = verification_steps(type(model))
        for i, phase in enumerate(model.phases):
            for constraints in (True, False):
                events = phase_events(phase, constraints)
                interpreted = step_function(phase.flow, events, CHECKS_PER_STEP)
                x = model.lift(model.section_vector({})) if i == 0 else np.full(phase.n, 0.1)
                args = [x, np.asarray(phase.flow(x, model.nominal_input(), model.p)).ravel(),
                        0.01, np.array([0.25, 0.5, 0.75]), model.nominal_input(), model.p,
                        np.array([1e-10, 1e-12])]  # fmt: skip
                got = compiled[(i, constraints)](*args)
                want = interpreted(*args)
                for a, b in zip(got, want, strict=True):
                    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
                    assert a.shape == b.shape
                    assert np.allclose(a, b, rtol=1e-14, atol=1e-14)
