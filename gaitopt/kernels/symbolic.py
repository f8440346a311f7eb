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

from ..integrators import rk_step

__all__ = ["kernel_functions", "step_functions"]


def _fold(flow: ca.Function, name: str) -> ca.Function:
    n, nu, np_ = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", nu), ca.SX.sym("p", np_)
    hs, N = ca.SX.sym("hs"), ca.SX.sym("N")
    D = ca.SX.sym("D", n, n + nu + np_ + 1)
    h = ca.SX.sym("h")
    x1 = rk_step(flow, x, u, p, h)
    J = ca.jacobian(x1, ca.vertcat(x, u, p, h))
    A, B = J[:, :n], J[:, n:]
    # The step's own derivatives at h = hs / N, then the chain rule (dh/dhs = 1/N).
    step = ca.Function("step", [x, u, p, h], [x1, A, B])
    x1, A, B = step(x, u, p, hs / N)
    B = ca.horzcat(B[:, : nu + np_], B[:, nu + np_] / N)
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


def kernel_functions(model_cls) -> list[ca.Function]:
    """``[lift, fold_0, end_0, fold_1, end_1, ...]`` of a model class (SX functions).

    Raises
    ------
    TypeError, RuntimeError
        Where a model's functions cannot be evaluated on SX symbols (a model built from MX
        functions): the caller falls back to the shooting graph.
    """
    structure = model_cls.structure()
    functions = [_lift(structure.section, len(model_cls.parameter_specs()))]
    for i, phase in enumerate(structure.phases):
        functions += [_fold(phase.flow, f"fold_{i}"), _end(phase, f"end_{i}")]
    return functions
