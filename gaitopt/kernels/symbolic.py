"""The structured shooting kernels of a model class, as CasADi SX functions.

The shooting Jacobian is block-sparse: each segment's end depends only on its own start, the
phase duration, the inputs and the parameters.  So instead of differentiating the whole chain
(one large graph, minutes to compile), each phase gets

* ``fold_i(x, D, u, p, hs, N) -> (x⁺, D⁺)``: one fixed RK step of size ``hs / N`` (Dormand–Prince
  order 8, :func:`gaitopt.integrators.rk_step`) carrying its own derivatives ``D = ∂x/∂[x₀; u; p;
  hs]`` forward (``D⁺ = A·D + [0, B_u, B_p, c/N]``, the chain rule of the discrete map);
* ``end_i(x, u, p) -> (g, g_x, g_u, g_p, r, r_x, r_u, r_p, ġ, admissible)``: the cycle transition's
  guard and reset with their Jacobians, the guard's rate along the flow and the admissibility;

and the section gets ``lift(s, p) -> (x, x_s, x_p)``.  A segment is ``N`` folds from ``D = [I,
0]``; the shooting Jacobian is assembled from these blocks (:mod:`gaitopt.kernels.assemble`).
The functions do not depend on the mesh, so one compiled library serves every mesh and period.
"""

from __future__ import annotations

import casadi as ca

from ..integrators import _A, _B, _C, rk_step

__all__ = ["STAGED_ABOVE", "kernel_functions", "reduced_fold", "step_functions"]

#: A phase whose stage function (its flow with the flow's Jacobian times the stage state's
#: derivative, :func:`_stage`) is over this many SX instructions has its compiled ``fold``
#: generated from that function called at each of the 12 stages rather than from the
#: 12 stages inlined: gcc's register allocation on one function of 50 000–250 000 instructions
#: takes 15–60 s, the staged code 1–4 s and runs as fast.  Below it (the compass gait: 840) the
#: inlined code is compiled in a few seconds and runs faster (the MX glue between the stages
#: costs 5 µs of a 10 µs step).
STAGED_ABOVE = 1000


def _fold(flow: ca.Function, name: str, reduced: bool = False) -> ca.Function:
    n, nu, np_ = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", nu), ca.SX.sym("p", np_)
    hs, N = ca.SX.sym("hs"), ca.SX.sym("N")
    fixed = 0 if reduced else nu + np_  # the columns of u and p (none in foldx)
    D = ca.SX.sym("D", n, n + fixed + 1)
    h = ca.SX.sym("h")
    x1 = rk_step(flow, x, u, p, h)
    J = ca.jacobian(x1, ca.vertcat(x, h) if reduced else ca.vertcat(x, u, p, h))
    A, B = J[:, :n], J[:, n:]
    # The step's own derivatives at h = hs / N, then the chain rule (dh/dhs = 1/N).
    step = ca.Function("step", [x, u, p, h], [x1, A, B])
    x1, A, B = step(x, u, p, hs / N)
    B = ca.horzcat(B[:, :fixed], B[:, fixed] / N)
    D1 = A @ D + ca.horzcat(ca.SX.zeros(n, n), B)
    return ca.Function(name, [x, D, u, p, hs, N], [x1, D1], ["x", "D", "u", "p", "hs", "N"],
                       ["x1", "D1"])  # fmt: skip


def _step(flow: ca.Function, name: str) -> ca.Function:
    """``fold``'s step without its derivatives: ``x⁺`` by the same operations (so the same
    numbers), for evaluating the residual alone."""
    n, nu, np_ = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", nu), ca.SX.sym("p", np_)
    hs, N = ca.SX.sym("hs"), ca.SX.sym("N")
    h = ca.SX.sym("h")
    step = ca.Function("step", [x, u, p, h], [rk_step(flow, x, u, p, h)])
    return ca.Function(name, [x, u, p, hs, N], [step(x, u, p, hs / N)], ["x", "u", "p", "hs", "N"],
                       ["x1"])  # fmt: skip


def _stage(flow: ca.Function, name: str, reduced: bool = False) -> ca.Function:
    """``stage(x, dx, u, p) -> (k, dk)``: the flow ``k = f(x, u, p)`` and the derivative of a
    stage's rate, ``dk = f_x·dx + [0, f_u, f_p, 0]`` (SX, ``f_x`` sparse), ``dx`` the stage
    state's derivative with respect to ``[x₀; u; p; h]`` (``reduced``: ``[x₀; h]`` and ``dk =
    f_x·dx``, the same products for those columns)."""
    n, nu, np_ = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    m = n + 1 if reduced else n + nu + np_ + 1
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", nu), ca.SX.sym("p", np_)
    dx = ca.SX.sym("dx", n, m)
    k = flow(x, u, p)
    dk = ca.mtimes(ca.jacobian(k, x), dx)
    if not reduced:
        f_up = ca.jacobian(k, ca.vertcat(u, p))
        dk = dk + ca.horzcat(ca.SX(n, n), f_up, ca.SX(n, 1))
    return ca.Function(f"{name}_stage", [x, dx, u, p], [k, dk])


def _staged_fold(
    flow: ca.Function, name: str, stage: ca.Function, reduced: bool = False
) -> ca.Function:
    """:func:`_fold` generated from :func:`_stage` called at each of the 12 stages (MX).

    The step repeats :func:`rk_step`'s operations in its order, so ``x⁺`` is the same to the
    bit; ``D⁺`` is the derivative of the same discrete map by the chain rule through the stages
    (equal to rounding, 1e-15 relative): the generated C holds the stage function once instead
    of 12 copies inlined and differentiated together, 7–15× less code (the five-link biped:
    0.4 MB instead of 6.7 MB, gcc 4 s instead of 60 s) and no slower to run once the stage is
    large (:data:`STAGED_ABOVE`).
    """
    n, nu, np_ = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    fixed = 0 if reduced else nu + np_  # the columns of u and p (none in foldx)
    m = n + fixed + 1
    x, u, p = ca.MX.sym("x", n), ca.MX.sym("u", nu), ca.MX.sym("p", np_)
    hs, N = ca.MX.sym("hs"), ca.MX.sym("N")
    D = ca.MX.sym("D", n, m)
    h = hs / N
    start = ca.DM(ca.horzcat(ca.DM.eye(n), ca.DM(n, m - n)))  # ∂x₀/∂[x₀; u; p; h]
    ks, dks = [], []
    for i in range(len(_C)):
        xi, dxi, rates = x, start, None  # rates: Σⱼ aᵢⱼ kⱼ, the column ∂xᵢ/∂h
        for j in range(i):
            if _A[i, j] != 0.0:
                xi = xi + h * _A[i, j] * ks[j]  # as rk_step
                dxi = dxi + (h * _A[i, j]) * dks[j]
                rates = _A[i, j] * ks[j] if rates is None else rates + _A[i, j] * ks[j]
        if rates is not None:
            dxi = dxi + ca.horzcat(ca.MX(n, m - 1), rates)
        ki, dki = stage(xi, dxi, u, p)
        ks.append(ki)
        dks.append(dki)
    total = sum(float(_B[i]) * ks[i] for i in range(len(_B)) if _B[i] != 0.0)
    x1 = x + h * total  # as rk_step
    J = start + h * sum(float(_B[i]) * dks[i] for i in range(len(_B)) if _B[i] != 0.0)
    J = J + ca.horzcat(ca.MX(n, m - 1), total)
    A, B = J[:, :n], J[:, n:]
    B = ca.horzcat(B[:, :fixed], B[:, fixed] / N)  # dh/dhs = 1/N
    D1 = ca.mtimes(A, D) + ca.horzcat(ca.MX(n, n), B)
    return ca.Function(name, [x, D, u, p, hs, N], [x1, D1], ["x", "D", "u", "p", "hs", "N"],
                       ["x1", "D1"])  # fmt: skip


def step_functions(model_cls) -> list[ca.Function]:
    """``[step_0, step_1, ...]`` of a model class (SX functions; see :func:`_step`)."""
    return [_step(phase.flow, f"step_{i}") for i, phase in enumerate(model_cls.structure().phases)]


def _end(phase, name: str) -> ca.Function:
    from ..hybrid import rate_along

    tr = phase.transitions[0]
    flow = phase.flow
    n, nu, np_ = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", nu), ca.SX.sym("p", np_)
    g, r = tr.guard(x, u, p), tr.reset(x, u, p)
    rate = rate_along(flow, tr.guard)(x, u, p)
    adm = tr.admissible(x, u, p) if tr.admissible is not None else ca.SX(1)
    out = [g, ca.jacobian(g, x), ca.jacobian(g, u), ca.jacobian(g, p)]
    out += [r, ca.jacobian(r, x), ca.jacobian(r, u), ca.jacobian(r, p), rate, adm]
    names = ["g", "g_x", "g_u", "g_p", "r", "r_x", "r_u", "r_p", "rate", "adm"]
    return ca.Function(name, [x, u, p], out, ["x", "u", "p"], names)


def _lift(section, n_p: int) -> ca.Function:
    m = len(section.coordinates)
    s, p = ca.SX.sym("s", m), ca.SX.sym("p", n_p)
    x = section.lift(s, p)
    return ca.Function(
        "lift", [s, p], [x, ca.jacobian(x, s), ca.jacobian(x, p)], ["s", "p"], ["x", "x_s", "x_p"]
    )


def reduced_fold(n: int, n_u: int, n_p: int) -> bool:
    """Whether a staged phase of ``n`` states gets a ``foldx`` (:func:`kernel_functions`): where the
    inputs' and parameters' columns are at least as many as the state and duration columns
    Newton iterates with (so that it at least halves a fold's derivative work; the kneed walker:
    7 of 20 columns)."""
    return n_u + n_p >= n + 1


def kernel_functions(model_cls, staged: bool = False) -> list[ca.Function]:
    """``[lift, fold_0, end_0, fold_1, end_1, ..., foldx_i, ...]`` of a model class (SX
    functions; with ``staged`` the folds from a stage function called at each stage,
    :func:`_staged_fold`, the code to compile).

    ``foldx_i(x, Dx, u, p, hs, N) -> (x⁺, Dx⁺)`` is ``fold_i`` carrying only ``Dx = ∂x/∂[x₀;
    hs]`` (the columns of Newton's unknowns; ``u`` and ``p`` are fixed during a solve), after
    the others, for the staged phases (the large ones, where the fold's derivatives are the
    cost: the kneed walker's 11.7 µs step against 1.2 µs without derivatives) whose input and
    parameter columns are at least as many (:func:`reduced_fold`).  Its ``x⁺`` and ``Dx⁺`` are
    ``fold_i``'s state and duration columns to the bit: the same stage products column by
    column (``tests/test_kernels_foldx.py``).  An inlined phase (the compass gait's) gets none:
    its step differentiated with fewer inputs sums in another order (rounding, 7e-16) and the
    fold is cheap already (a compiled solve 4 % faster, measured).

    Raises
    ------
    TypeError, RuntimeError
        Where a model's functions cannot be evaluated on SX symbols (a model built from MX
        functions): the caller falls back to the shooting graph.
    """
    structure = model_cls.structure()
    functions = [_lift(structure.section, len(model_cls.parameter_specs()))]
    reduced = []
    for i, phase in enumerate(structure.phases):
        flow = phase.flow
        stage = _stage(flow, f"fold_{i}") if staged else None
        is_staged = stage is not None and stage.n_instructions() > STAGED_ABOVE
        if is_staged:
            fold = _staged_fold(flow, f"fold_{i}", stage)
        else:
            fold = _fold(flow, f"fold_{i}")
        functions += [fold, _end(phase, f"end_{i}")]
        if is_staged and reduced_fold(flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)):
            stagex = _stage(flow, f"foldx_{i}", reduced=True)
            reduced.append(_staged_fold(flow, f"foldx_{i}", stagex, reduced=True))
    return functions + reduced
