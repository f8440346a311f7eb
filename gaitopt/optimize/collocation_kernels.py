"""The collocation's node kernels: the model's implicit dynamics where it declares them, each
phase's node function with its compiled kernels (:mod:`gaitopt.kernels.nodes`), their warm-up
(:func:`warm_kernels`), and the blocks of node outputs ``Y`` a
:class:`~gaitopt.optimize.collocation.Collocation` writes its equations in
(:func:`node_block`, :func:`defect_block`; :mod:`gaitopt.optimize.nodes` assembles their
derivatives)."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..kernels.nodes import defect_function, flow_jacobian, node_function, node_kernels
from .nodes import NodeBlock
from .radau import _derivative_matrix

__all__ = ["defect_block", "node_block", "phase_node_kernels", "warm_kernels"]


def _implicit_dynamics(model: Any) -> ca.Function | None:
    """The model's equations of motion in implicit form, if it declares them.

    A mechanical model whose states are ``(q, q̇)`` may provide the classmethod
    ``manipulator() -> Function(q, qd, u, p) -> (M, rhs)`` with ``M(q) q̈ = rhs(q, q̇, u)``
    (the five-link biped does).  Collocating ``M a = rhs`` with the accelerations ``a`` as
    unknowns keeps the NLP's expressions small (no symbolic inverse of ``M``); the flow is
    checked against it at a test point, and ignored if they differ."""
    factory = getattr(type(model), "manipulator", None)
    if factory is None:
        return None
    phase = model.phases[0]
    n = phase.n
    try:
        f = factory()
        if n % 2 or f.size1_in(0) != n // 2 or f.size1_in(1) != n // 2:
            return None
        x = np.linspace(0.1, 0.3, n)
        u = np.linspace(-0.2, 0.2, len(model.inputs))
        M, rhs = (np.asarray(v, dtype=float) for v in f(x[: n // 2], x[n // 2 :], u, model.p))
        explicit = np.asarray(phase.flow(x, u, model.p), dtype=float).ravel()
        if not np.allclose(np.linalg.solve(M, rhs).ravel(), explicit[n // 2 :], rtol=1e-9):
            return None
        if not np.allclose(explicit[: n // 2], x[n // 2 :]):
            return None
    except (RuntimeError, np.linalg.LinAlgError):
        return None
    return f


def phase_node_kernels(
    model: Any, i: int, implicit: ca.Function | None, free: bool = False
) -> tuple[ca.Function, Any] | None:
    """The node function of model phase ``i`` (with the implicit dynamics ``implicit``, if any)
    and its compiled kernels (:mod:`gaitopt.kernels.nodes`), differentiated in the parameters
    too where some are ``free``; None where the model's functions have no SX form."""
    phase = model.phases[i]
    constraints = tuple(c.function for c in getattr(phase, "constraints", ()))
    try:
        node = node_function(phase.flow, constraints, implicit)
    except (TypeError, RuntimeError, NotImplementedError):
        return None
    label = f"{type(model).__name__.lower()}_{i}{'i' if implicit is not None else 'e'}"
    nd = None if free else node.size1_in(0) - len(model.p)
    return node, node_kernels(node, label, nd)


def warm_kernels(model: Any, degree: int = 6) -> bool:
    """Compile (or find in the cache) the node kernels a transcription of ``model`` of Radau
    ``degree`` (default: the default mesh's) uses and the flow Jacobians of its Floquet check
    (``python -m gaitopt.kernels --warm``); whether every one is compiled."""
    phases = model.phases
    implicit = _implicit_dynamics(model) if len(phases) == 1 else None
    compiled = True
    if implicit is not None:  # the interval defects on the default mesh's degree
        n = phases[0].n
        tau = np.array([0.0, *ca.collocation_points(degree, "radau")])
        C = _derivative_matrix(tau, tau[1:]).T  # as Collocation.C
        compiled = node_kernels(defect_function(n, n // 2, C), f"defects_{n}_{degree}").compiled
    for i, phase in enumerate(phases):
        found = phase_node_kernels(model, i, implicit)
        compiled = compiled and found is not None and found[1].compiled
        try:
            flow_jacobian(phase.flow, f"{type(model).__name__.lower()}_{i}")
        except (TypeError, RuntimeError, NotImplementedError):
            compiled = False
    return compiled


def node_block(col, i: int, Xc: Any, Uk: Any, Ak: Any, p: Any) -> ca.MX | None:
    """The node outputs ``Y`` (dynamics rows, then one row per unilateral constraint) of a
    phase of model phase ``i`` at its ``N·d`` collocation points (``Xc``, ``Uk``, ``Ak``:
    their states, inputs, accelerations), a block of :mod:`gaitopt.optimize.nodes`; None
    where the node function cannot be built in SX or :attr:`use_node_kernels` is off."""
    if not col.use_node_kernels:
        return None
    found = phase_node_kernels(col.model, i, col.implicit, bool(col.problem.free))
    if found is None:
        return None
    node, kernels = found
    count = Xc.shape[1]
    parts = [Xc, Uk] + ([Ak] if Ak is not None else []) + [ca.repmat(p, 1, count)]
    Y = ca.MX.sym(f"Y{len(col.node_blocks)}", node.size1_out(0), count)
    col.node_blocks.append(NodeBlock(kernels, node, Y, ca.vertcat(*parts)))
    return Y


def defect_block(col, Xk: Any, Ak: Any, hs: list[Any]) -> ca.MX:
    """The collocation defects ``X_j C − h_j (q̇, a)`` of an implicit phase's intervals as
    the outputs ``Y`` (n·d × N) of a block of :mod:`gaitopt.optimize.nodes` whose inputs
    are each interval's states, accelerations and length (the interval kernel
    :func:`gaitopt.kernels.nodes.defect_function`)."""
    N, d = col.N, col.d
    n = Xk.shape[0]
    nq = n // 2
    fn = defect_function(n, nq, col.C)
    kernels = node_kernels(fn, f"defects_{n}_{d}")
    cols = [
        ca.vertcat(ca.vec(Xk[:, j * d : j * d + d + 1]), ca.vec(Ak[:, j * d : (j + 1) * d]), hs[j])
        for j in range(N)
    ]
    Y = ca.MX.sym(f"Y{len(col.node_blocks)}", n * d, N)
    col.node_blocks.append(NodeBlock(kernels, fn, Y, ca.horzcat(*cols)))
    return Y
