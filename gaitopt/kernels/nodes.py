"""Compiled node kernels of the Radau collocation: one collocation point's equations with their
first and second derivatives, compiled once per model phase and kept in the kernel cache.

A collocation NLP repeats the same nonlinear equations at every one of its ``N·d`` nodes: the
dynamics there (``ẋ = f(x, u, p)``, or the implicit ``M(q) a − rhs(q, q̇, u, p)`` of a mechanical
model) and the phase's unilateral constraints (a foot's height, a contact force).  Their exact
Hessian, differentiated over the whole NLP, is the bulk of the first optimisation's time (the
five-link biped: an SX Hessian of about a million instructions, built per mesh).  Here the node
function ``y = node(z)``, ``z = [x; u; a; p]``, is differentiated once, symbolically:

* ``node(z) -> y``;
* ``node_jac(z) -> (y, ∂y/∂z)``;
* ``node_hess(z, μ) -> ((∂y/∂z)ᵀ μ, ∇²_z (μᵀ y))``;

and, for the Floquet sensitivities of an optimum, a phase's ``flow_jac(x, u, p) -> (f, f_x, f_u)``
(:func:`flow_jacobian`);

compiled into one shared library (:func:`gaitopt.kernels.cache.load`; interpreted where there is
no compiler), indexed by a hash of the node function's serialisation, this module's source, the
CasADi version, the compiler and the flags: everything that determines the code.  The functions
do not depend on the mesh, the bounds or the parameter values; :mod:`gaitopt.optimize.nodes`
maps them over the nodes of any mesh.
"""

from __future__ import annotations

import hashlib
import os
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from .cache import FLAGS, compiler, load

__all__ = ["NodeKernels", "node_function", "defect_function", "node_kernels", "flow_jacobian"]


def node_function(
    flow: ca.Function, constraints: tuple, implicit: ca.Function | None
) -> ca.Function:
    """``node(z) -> y`` of one phase at one collocation point (SX).

    ``z = [x; u; a; p]`` (``a``: the accelerations of an implicit model, else empty) and
    ``y = [dynamics; c₁; …]``: ``f(x, u, p)`` (explicit) or ``M(q) a − rhs(q, q̇, u, p)`` (implicit,
    ``x = (q, q̇)``), then each unilateral constraint's value ``c(x, u, p)``.

    Raises
    ------
    TypeError, RuntimeError, NotImplementedError
        Where a model function cannot be evaluated on SX symbols.
    """
    n, nu, np_ = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    nq = n // 2 if implicit is not None else 0
    x, u, a, p = ca.SX.sym("x", n), ca.SX.sym("u", nu), ca.SX.sym("a", nq), ca.SX.sym("p", np_)
    if implicit is not None:
        M, rhs = implicit(x[:nq], x[nq:], u, p)
        first = ca.mtimes(M, a) - rhs
    else:
        first = flow(x, u, p)
    values = [c(x, u, p) for c in constraints]
    y = ca.vertcat(first, *values)
    if not isinstance(y, ca.SX):
        raise TypeError("the node function is not an SX expression")
    return ca.Function("node", [ca.vertcat(x, u, a, p)], [y], ["z"], ["y"])


def defect_function(n: int, nq: int, C: np.ndarray) -> ca.Function:
    """``defects(z) -> y``: the collocation defects of one mesh interval of a mechanical model
    in implicit form, ``y = vec(X C − h [q̇; a])`` with ``z = [vec(X); vec(A); h]``: ``X`` the
    ``n × (d + 1)`` states at the interval's start and Radau points (``x = (q, q̇)``, ``nq``
    coordinates), ``A`` the ``nq × d`` accelerations at the points, ``C`` the
    ``(d + 1) × d`` differentiation matrix, ``h`` the interval's length (s)."""
    d = C.shape[1]
    X, A, h = ca.SX.sym("X", n, d + 1), ca.SX.sym("A", nq, d), ca.SX.sym("h")
    F = ca.vertcat(X[nq:, 1:], A)
    y = ca.vec(ca.mtimes(X, ca.DM(C)) - h * F)
    return ca.Function("node", [ca.vertcat(ca.vec(X), ca.vec(A), h)], [y], ["z"], ["y"])


class NodeKernels:
    """``node``, ``node_jac`` and ``node_hess`` of one node function (see the module docstring),
    compiled (``compiled``) or interpreted.

    ``nd``: the derivatives are taken with respect to the first ``nd`` entries of ``z`` only
    (default: all ``nz``): the decision variables, when the rest (the parameters) are constants
    of the NLP; the five-link biped's node Hessian is then 28 000 instructions instead of
    94 000."""

    def __init__(self, node: ca.Function, label: str, nd: int | None = None):
        self.nz, self.ny = node.size1_in(0), node.size1_out(0)
        self.nd = self.nz if nd is None else nd
        name = f"gaitopt_nodes_{label}" + ("" if self.nd == self.nz else f"_d{self.nd}")
        serial = node.serialize()
        self.key = _key(name, serial)
        loaded, self.compiled = load(name, lambda: _derivatives(node, self.nd), key=self.key)
        self.node, self.jac, self.hess = loaded


def _derivatives(node: ca.Function, nd: int) -> list[ca.Function]:
    z = ca.SX.sym("z", node.size1_in(0))
    mu = ca.SX.sym("mu", node.size1_out(0))
    y = node(z)
    J = ca.jacobian(y, z[:nd])
    H, grad = ca.hessian(ca.dot(mu, y), z[:nd])
    return [
        ca.Function("node", [z], [y], ["z"], ["y"]),
        ca.Function("node_jac", [z], [y, J], ["z"], ["y", "J"]),
        ca.Function("node_hess", [z, mu], [grad, H], ["z", "mu"], ["grad", "H"]),
    ]


def _key(name: str, serial: str) -> str | None:
    """Index key: the node function, this module, CasADi, the compiler and the flags."""
    cc = compiler()
    if cc is None:
        return None
    stat = os.stat(cc)
    ident = "\n".join(
        [name, serial, Path(__file__).read_text(), ca.__version__, cc, str(stat.st_size),
         str(stat.st_mtime_ns), " ".join(FLAGS)]
    )  # fmt: skip
    return hashlib.sha256(ident.encode()).hexdigest()[:24]


@lru_cache(maxsize=64)
def _kernels(serial: str, label: str, nd: int | None) -> NodeKernels:
    return NodeKernels(ca.Function.deserialize(serial), label, nd)


def node_kernels(node: ca.Function, label: str, nd: int | None = None) -> NodeKernels:
    """The (cached in-process and on disk) kernels of a node function, differentiated in the
    first ``nd`` entries of its input (default: all); ``label`` names the library
    (``gaitopt_nodes_<label>``)."""
    return _kernels(node.serialize(), label, nd)


@lru_cache(maxsize=64)
def _flow_jacobian(serial: str, label: str) -> ca.Function:
    flow = ca.Function.deserialize(serial)
    name = f"gaitopt_flowjac_{label}"

    def build() -> list[ca.Function]:
        n, nu, np_ = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
        x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", nu), ca.SX.sym("p", np_)
        f = flow(x, u, p)
        if not isinstance(f, ca.SX):
            raise TypeError("the flow is not an SX expression")
        J = [ca.densify(ca.jacobian(f, v)) for v in (x, u)]
        return [ca.Function("flow_jac", [x, u, p], [f, *J], ["x", "u", "p"], ["f", "f_x", "f_u"])]

    (function,), _ = load(name, build, key=_key(name, serial))
    return function


def flow_jacobian(flow: ca.Function, label: str) -> ca.Function:
    """``flow_jac(x, u, p) -> (f, f_x, f_u)`` of a phase's flow (dense Jacobians), compiled and
    cached like the node kernels (``label`` names the library)."""
    return _flow_jacobian(flow.serialize(), label)
