"""The collocation NLP split at its nodes: compiled node kernels mapped over the mesh, the rest
differentiated by CasADi, exact derivatives assembled by the chain rule.

The transcription (:class:`gaitopt.optimize.collocation.Collocation`) writes the equations it
repeats at every collocation node — the dynamics and the phase's unilateral constraints, the
node function ``y = node(z)`` of :mod:`gaitopt.kernels.nodes` — as symbols ``Y`` (one column per
node), with the node inputs ``Z(w, p)`` (the node's state, input, accelerations and the
parameters: a selection of the decision vector ``w``).  What remains, the *outer* NLP
``f(w, p, Y)``, ``g(w, p, Y)`` (the collocation defects, linear in the nodes; the guards,
resets, periodicity, cost quadrature, bounds), is small: CasADi expands and differentiates it in
a fraction of a second.  With ``Y = K(Z(w, p))`` (``K``: the node function on every node) and
the Lagrangian ``ℓ(w, Y) = σ f + λᵀ g``, the chain rule gives the derivatives IPOPT needs,
exactly (the same numbers as differentiating the whole NLP, up to rounding):

* ``∇f = f_w + Y_wᵀ f_Y`` and ``J_g = g_w + g_Y Y_w``, with ``Y_w = K_z Z_w`` (``K_z``
  block-diagonal, one block per node);
* ``∇²L = ℓ_ww + ℓ_wY Y_w + (ℓ_wY Y_w)ᵀ + Y_wᵀ ℓ_YY Y_w + Z_wᵀ [⊕ ∇²(μᵀ node)] Z_w +
  ∇²_w (νᵀ Z)``, ``μ = ∂ℓ/∂Y`` at each node, ``ν = K_zᵀ μ``.

The node kernels and their derivatives come compiled from the kernel cache, mapped over the
nodes with ``Function.map``; the assembly is a small MX graph of sparse products.  So a new
process builds the five-link biped's NLP in a fraction of a second instead of expanding and
differentiating the whole transcription (3–9 s per mesh), and IPOPT sees the same exact
Hessian (Griewank & Walther 2008, "Evaluating Derivatives", §3 and §8 for the chain rule and
the second-order adjoints used here).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca

__all__ = ["NodeBlock", "split_solver"]


@dataclass
class NodeBlock:
    """One phase's nodes: ``Y`` (ny × M symbols of the node outputs) stands for
    ``kernels.node`` mapped over ``Z`` (nz × M, an MX expression of ``w`` and ``p``)."""

    kernels: Any  # gaitopt.kernels.nodes.NodeKernels
    node: ca.Function  # the interpreted (differentiable) node function
    Y: ca.MX
    Z: ca.MX

    @property
    def count(self) -> int:
        return self.Y.shape[1]


def substitute(blocks: list[NodeBlock], exprs: list[ca.MX]) -> list[ca.MX]:
    """``exprs`` with each block's ``Y`` replaced by its interpreted node function mapped over
    ``Z``: an ordinary CasADi graph, differentiable as any other."""
    if not blocks:
        return exprs
    values = [b.node.map(b.count)(b.Z) for b in blocks]
    return ca.substitute(exprs, [b.Y for b in blocks], values)


def _block_diagonal(blocks: ca.MX, cols: int, count: int) -> ca.MX:
    """``count`` blocks side by side (each ``cols`` wide, a mapped function's output) as a
    block-diagonal matrix."""
    if count == 1:
        return blocks
    return ca.diagcat(*ca.horzsplit(blocks, cols))


def split_solver(
    name: str,
    w: ca.MX,
    p: ca.MX,
    f: ca.MX,
    g: ca.MX,
    blocks: list[NodeBlock],
    options: dict[str, Any],
) -> ca.Function:
    """IPOPT (``casadi.nlpsol``) on ``min f s.t. g`` whose node outputs ``Y`` are given by
    ``blocks``, with ``grad_f``, ``jac_g`` and ``hess_lag`` assembled by the chain rule (module
    docstring) from the compiled node kernels.  ``options`` are those of ``nlpsol`` (``expand``
    is set here: the outer parts are expanded, the kernels are compiled)."""
    nw, n_p = w.shape[0], p.shape[0]
    Ys = [b.Y for b in blocks]
    outer = ca.Function("outer", [w, p, *Ys], [f, g]).expand()
    ws, ps = ca.SX.sym("w", nw), ca.SX.sym("p", n_p)
    sizes = [b.Y.numel() for b in blocks]
    Yflat = ca.SX.sym("Y", sum(sizes))
    parts, at = [], 0
    for b, size in zip(blocks, sizes, strict=True):
        parts.append(ca.reshape(Yflat[at : at + size], b.Y.shape[0], b.count))
        at += size
    fs, gs = outer(ws, ps, *parts)
    ng = gs.shape[0]
    lam, sigma = ca.SX.sym("lam_g", ng), ca.SX.sym("lam_f")
    v = ca.vertcat(ws, Yflat)
    H, grad = ca.hessian(sigma * fs + ca.dot(lam, gs), v)
    H_ww, H_wY, H_YY = H[:nw, :nw], H[:nw, nw:], H[nw:, nw:]
    mu = grad[nw:]
    args = [ws, ps, Yflat]
    o_jac = ca.Function("o_jac", args, [gs, ca.jacobian(gs, ws), ca.jacobian(gs, Yflat)])
    o_grad = ca.Function("o_grad", args, [fs, ca.gradient(fs, ws), ca.gradient(fs, Yflat)])
    o_hess = ca.Function("o_hess", [*args, sigma, lam], [mu, H_ww, H_wY, H_YY])
    # The node inputs Z(w, p): a selection of w (and p), in general any function; the kernels
    # are differentiated in the first nd rows of each node's inputs (the rest: constants).
    Zs = ca.Function("Z", [w, p], [ca.vertcat(*[ca.vec(b.Z) for b in blocks])]).expand()
    Zflat = Zs(ws, ps)
    rows, at = [], 0
    for b in blocks:
        nz, nd = b.kernels.nz, b.kernels.nd
        rows += [at + c * nz + r for c in range(b.count) for r in range(nd)]
        constant = [at + c * nz + r for c in range(b.count) for r in range(nd, nz)]
        if constant and ca.jacobian(Zflat[constant], ws).nnz():
            raise ValueError("node inputs past nd depend on the decision variables")
        at += nz * b.count
    Zd = Zflat[rows]
    nu = ca.SX.sym("nu", Zd.shape[0])
    Z_w = ca.jacobian(Zd, ws)
    HZ = ca.hessian(ca.dot(nu, Zd), ws)[0]
    z_fun = ca.Function("z", [ws, ps], [Zflat, Z_w])
    z_hess = ca.Function("z_hess", [ws, ps, nu], [HZ]) if HZ.nnz() else None

    # -- the MX functions IPOPT calls -------------------------------------------------------
    wm, pm = ca.MX.sym("x", nw), ca.MX.sym("p", n_p)
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", ng)
    Zm, Z_wm = z_fun(wm, pm)

    def node_inputs() -> list[ca.MX]:
        out, at = [], 0
        for b in blocks:
            nz = b.kernels.nz
            out.append(ca.reshape(Zm[at : at + nz * b.count], nz, b.count))
            at += nz * b.count
        return out

    Zk = node_inputs()
    Y_vals, Y_w = [], []
    for b, z in zip(blocks, Zk, strict=True):
        y, J = b.kernels.jac.map(b.count)(z)
        Y_vals.append(ca.vec(y))
        Y_w.append(_block_diagonal(J, b.kernels.nd, b.count))
    Ym = ca.vertcat(*Y_vals)
    Y_wm = ca.mtimes(ca.diagcat(*Y_w), Z_wm)  # ∂Y/∂w

    y_only = ca.vertcat(
        *[ca.vec(b.kernels.node.map(b.count)(z)) for b, z in zip(blocks, Zk, strict=True)]
    )
    g_val, G_w, G_Y = o_jac(wm, pm, Ym)
    jac_g = ca.Function(
        "nlp_jac_g", [wm, pm], [g_val, G_w + ca.mtimes(G_Y, Y_wm)], ["x", "p"], ["g", "jac_g_x"]
    )
    f_val, f_w, f_Y = o_grad(wm, pm, Ym)
    grad_f = ca.Function(
        "nlp_grad_f",
        [wm, pm],
        [f_val, ca.densify(f_w + ca.mtimes(Y_wm.T, f_Y))],
        ["x", "p"],
        ["f", "grad_f_x"],
    )
    mu_m, Hww, HwY, HYY = o_hess(wm, pm, y_only, lam_f, lam_g)
    Hm = Hww
    if HwY.nnz():
        cross = ca.mtimes(HwY, Y_wm)
        Hm = Hm + cross + cross.T
    if HYY.nnz():
        Hm = Hm + ca.mtimes(Y_wm.T, ca.mtimes(HYY, Y_wm))
    H_nodes, nus, at = [], [], 0
    for b, z in zip(blocks, Zk, strict=True):
        size = b.kernels.ny * b.count
        mu_k = ca.reshape(mu_m[at : at + size], b.kernels.ny, b.count)
        at += size
        nu_k, Hb = b.kernels.hess.map(b.count)(z, mu_k)
        nus.append(ca.vec(nu_k))
        H_nodes.append(_block_diagonal(Hb, b.kernels.nd, b.count))
    Hm = Hm + ca.mtimes(Z_wm.T, ca.mtimes(ca.diagcat(*H_nodes), Z_wm))
    if z_hess is not None:
        Hm = Hm + z_hess(wm, pm, ca.vertcat(*nus))
    hess_lag = ca.Function(
        "nlp_hess_l",
        [wm, pm, lam_f, lam_g],
        [ca.triu(Hm)],
        ["x", "p", "lam_f", "lam_g"],
        ["triu_hess_gamma_x_x"],
    )
    # nlpsol builds the Lagrangian's gradient (for the multipliers it returns) by AD of the
    # NLP it is given, which cannot differentiate a compiled kernel: it is given the NLP with
    # the interpreted node function (differentiated in MX: the nodes' reverse mode is one
    # small SX function, mapped), which also gives IPOPT f and g.
    f_i, g_i = substitute(blocks, [f, g])
    opts = dict(options)
    opts.update(
        expand=False,
        grad_f=grad_f,
        jac_g=jac_g,
        hess_lag=hess_lag,
    )
    return ca.nlpsol(name, "ipopt", {"x": w, "p": p, "f": f_i, "g": g_i}, opts)
