"""Compiled shooting kernels: the structured residual and Jacobian of the shooting equations.

* :mod:`~gaitopt.kernels.symbolic` — per phase, one RK step carrying its derivatives and the
  transition's guard and reset with theirs (SX functions);
* :mod:`~gaitopt.kernels.cache` — generated C compiled once per model class, kept in a user cache
  directory, loaded with ``ca.external`` (interpreted where there is no C compiler);
* :mod:`~gaitopt.kernels.assemble` — the shooting residual and its Jacobians assembled in NumPy
  from per-segment blocks, for any mesh and period;
* :mod:`~gaitopt.kernels.arcs` — the simulation's arc library: per phase the event functions,
  admissibility, resets and constraint checks as C, and a hand-written C driver
  (:mod:`~gaitopt.kernels.arc_driver`) that integrates one phase per call around the
  verification's compiled DOP853 step (:mod:`~gaitopt.kernels.verify`);
* :mod:`~gaitopt.kernels.nodes` — the collocation's node and interval functions with their
  Jacobians and Hessians, and the flow Jacobians of the Floquet check (the optimiser's kernels,
  assembled by :mod:`gaitopt.optimize.nodes`).

``python -m gaitopt.kernels --warm`` compiles the kernels of every built-in model (``make
install`` runs it), so that no later call waits for the compiler.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from .cache import FLAGS, FLAGS_O2, cache_dir, compiler, load, source_key
from .symbolic import kernel_functions, step_functions

__all__ = [
    "ModelKernels",
    "model_kernels",
    "phase_function",
    "phase_residual_function",
    "step_kernels",
    "trajectory_function",
    "cache_dir",
]


class ModelKernels:
    """The kernels of one model class: ``lift`` and, per phase, ``fold``, ``end`` and
    ``foldx`` (None where the phase has none)."""

    def __init__(self, model_cls, *, verbose: bool = True):
        name = f"gaitopt_{model_cls.__name__.lower()}"
        loaded, self.compiled = load(
            name,
            lambda: kernel_functions(model_cls, staged=compiler() is not None),
            verbose=verbose,
            key=source_key(name, model_cls),
            flags=_flags,
        )
        names = [f.name() for f in loaded]
        self.lift = loaded[0]
        self.fold = [f for f in loaded if f.name().startswith("fold_")]
        self.end = [f for f in loaded if f.name().startswith("end_")]
        #: per phase its ``foldx`` (the fold carrying only the states' and duration's
        #: derivatives, :func:`~gaitopt.kernels.symbolic.kernel_functions`) or None
        self.foldx = [loaded[names.index(f"foldx_{i}")] if f"foldx_{i}" in names else None
                      for i in range(len(self.fold))]  # fmt: skip
        self.n = [f.size1_in(0) for f in self.fold]
        self.n_u = len(model_cls.inputs)
        self.n_p = len(model_cls.parameter_specs())


#: Below this much C (bytes), a library with a staged fold is compiled at -O2.
O2_BELOW = 1_000_000


def _flags(functions: list[ca.Function], source: str) -> tuple[str, ...]:
    """-O2 for a library with a staged fold (an MX function) of under :data:`O2_BELOW` bytes of
    C, else :data:`~gaitopt.kernels.cache.FLAGS` (-O1).  The staged fold's glue between its
    stages runs in loops over vectors: 40 % slower at -O1 than at -O2 for the kneed walker
    (0.4 MB, -O2 costs 1.6 s more); the five-link biped's library (1.3 MB, its reset's
    Jacobians 10 s of gcc at -O1 and 20 s at -O2) stays at -O1, where its staged fold already
    runs faster than the inlined one (69 against 77 µs a step)."""
    staged = any(f.is_a("MXFunction") for f in functions)
    return FLAGS_O2 if staged and len(source) < O2_BELOW else FLAGS


@lru_cache(maxsize=64)
def model_kernels(model_cls) -> ModelKernels | None:
    """The (cached) kernels of a model class, or None where the model's functions cannot be
    evaluated on SX symbols (the caller then uses the shooting graph)."""
    try:
        return ModelKernels(model_cls)
    except (RuntimeError, TypeError, NotImplementedError):
        return None


@lru_cache(maxsize=256)
def phase_function(model_cls, phase: int, segments: int, steps: int) -> ca.Function:
    """``phase(X, u, p, hs) -> (X_end, D, g, g_x, g_u, g_p, r, r_x, r_u, r_p, ġ, admissible)``.

    ``X`` (n × segments) holds the segment starts, ``hs`` the segment duration; ``X_end`` the
    segment ends after ``steps`` RK steps each and ``D`` (n × segments·(n + n_u + n_p + 1)) their
    derivatives ``∂x_end/∂[x_start; u; p; hs]`` side by side; the rest is the cycle transition
    at the last segment's end (see :func:`gaitopt.kernels.symbolic.kernel_functions`).
    """
    kern = model_kernels(model_cls)
    n, nu, np_ = kern.n[phase], kern.n_u, kern.n_p
    fold, end = kern.fold[phase], kern.end[phase]
    x0, u, p, hs = ca.MX.sym("x0", n), ca.MX.sym("u", nu), ca.MX.sym("p", np_), ca.MX.sym("hs")
    x, D = x0, ca.MX(ca.horzcat(ca.DM.eye(n), ca.DM.zeros(n, nu + np_ + 1)))
    for _ in range(steps):
        x, D = fold(x, D, u, p, hs, steps)
    segment = ca.Function("segment", [x0, u, p, hs], [x, D]).map(segments)
    X = ca.MX.sym("X", n, segments)
    X_end, Ds = segment(X, u, p, hs)
    return ca.Function(f"phase_{phase}", [X, u, p, hs], [X_end, Ds, *end(X_end[:, -1], u, p)])


@lru_cache(maxsize=64)
def step_kernels(model_cls) -> list[ca.Function] | None:
    """Per phase ``step_i(x, u, p, hs, N) -> x⁺``: ``fold_i``'s RK step without its derivatives
    (:func:`gaitopt.kernels.symbolic.step_functions`), in a library of their own compiled on the
    first residual-only evaluation; None where they cannot be built."""
    name = f"gaitopt_{model_cls.__name__.lower()}_step"
    try:
        return load(
            name, lambda: step_functions(model_cls), verbose=False,
            key=source_key(name, model_cls),
        )[0]  # fmt: skip
    except (RuntimeError, TypeError, NotImplementedError):
        return None


@lru_cache(maxsize=256)
def phase_residual_function(model_cls, phase: int, segments: int, steps: int) -> ca.Function | None:
    """``phase(X, u, p, hs) -> (X_end, g, g_x, g_u, g_p, r, r_x, r_u, r_p, ġ, admissible)``:
    :func:`phase_function` without the segments' derivatives ``D`` (the same numbers, the RK
    steps by :func:`step_kernels`), for the residual alone; None without step kernels."""
    kern, steppers = model_kernels(model_cls), step_kernels(model_cls)
    if kern is None or steppers is None:
        return None
    n, nu, np_ = kern.n[phase], kern.n_u, kern.n_p
    step, end = steppers[phase], kern.end[phase]
    x0, u, p, hs = ca.MX.sym("x0", n), ca.MX.sym("u", nu), ca.MX.sym("p", np_), ca.MX.sym("hs")
    x = x0
    for _ in range(steps):
        x = step(x, u, p, hs, steps)
    segment = ca.Function("segment", [x0, u, p, hs], [x]).map(segments)
    X = ca.MX.sym("X", n, segments)
    X_end = segment(X, u, p, hs)
    return ca.Function(f"residual_{phase}", [X, u, p, hs], [X_end, *end(X_end[:, -1], u, p)])


@lru_cache(maxsize=256)
def trajectory_function(model_cls, phase: int, segments: int, steps: int) -> ca.Function:
    """``trajectory(X, u, p, hs) -> samples`` (n × segments·(steps + 1)): the states at every one
    of ``steps`` RK steps of each segment (its start first), by the compiled ``fold``: the dense
    samples of the certification and the plotted orbit, the same numbers as
    :func:`gaitopt.integrators.segment_trajectory_function` (same RK step) without building its
    graph (0.1 s) or interpreting it.  The steps are :func:`step_kernels`' (``fold``'s step
    without its derivatives: the same numbers, a tenth of the work) where they exist."""
    kern, steppers = model_kernels(model_cls), step_kernels(model_cls)
    n, nu, np_ = kern.n[phase], kern.n_u, kern.n_p
    x0, u, p, hs = ca.MX.sym("x0", n), ca.MX.sym("u", nu), ca.MX.sym("p", np_), ca.MX.sym("hs")
    if steppers is not None:
        step = steppers[phase]

        def advance(x):
            return step(x, u, p, hs, steps)
    else:
        fold = kern.fold[phase]
        D = ca.MX(ca.DM.zeros(n, n + nu + np_ + 1))  # derivatives not needed here

        def advance(x):
            return fold(x, D, u, p, hs, steps)[0]

    cols, x = [x0], x0
    for _ in range(steps):
        x = advance(x)
        cols.append(x)
    segment = ca.Function("samples", [x0, u, p, hs], [ca.horzcat(*cols)]).map(segments)
    X = ca.MX.sym("X", n, segments)
    return ca.Function(f"trajectory_{phase}", [X, u, p, hs], [segment(X, u, p, hs)])
