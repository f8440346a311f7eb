"""The extended system of a two-parameter curve: the orbit's shooting equations plus one defining
condition, built as one CasADi function so that its Jacobian is exact (automatic
differentiation, second derivatives of the flow included).

Unknowns ``y = (w, ℓ₁, ℓ₂)``: the shooting unknowns ``w`` of :mod:`gaitopt.shooting` and the two
scaled curve parameters ``ℓᵢ = λᵢ / scaleᵢ``.  Equations ``H(y) = (F(w, u, p), g(w, u, p))``:

* ``F = 0`` — the orbit (multiple shooting, :class:`gaitopt.shooting.ShootingProblem`);
* ``g = 0`` — the defining condition, *minimally augmented* (Govaerts, "Numerical Methods for
  Bifurcations of Dynamical Equilibria", SIAM 2000, §4.3; Kuznetsov, "Elements of Applied
  Bifurcation Theory", 3rd ed., §10.2.2): with ``A = ∂P/∂s`` the return map's Jacobian in section
  coordinates (implicit function theorem on the shooting equations, :mod:`gaitopt.stability`)
  and ``M`` the matrix that is singular at the bifurcation,

      [ M   b ] [ v ]   [ 0 ]
      [ cᵀ  0 ] [ g ] = [ 1 ],

  ``g = 0`` exactly where ``M`` is singular, for bordering vectors ``b, c`` (the left and right
  singular vectors of the smallest singular value at the previous point) that keep the bordered
  matrix regular.  ``M = A + I`` for a period doubling (``PD``, a multiplier −1), ``A − I`` for a
  fold (``LP``, +1), ``A ⊙ A − I`` for a Neimark–Sacker point (``NS``, ``A ⊙ A`` the bialternate
  product whose eigenvalues are ``μᵢ μⱼ, i < j``: singular when ``μᵢ μⱼ = 1``);
* ``g = q(w, u, p)`` for a ``boundary``: the quantity of the shooting checks that vanishes where
  the gait stops existing — a phase duration (a phase shrinks to nothing), the guard's rate at a
  phase end (a grazing impact), or an admissibility function (a crossing becomes spurious);
* or a declared unilateral constraint ``c(x) ≥ 0`` (:class:`gaitopt.hybrid.Constraint`) becoming
  active: for one that starts at zero (``at_start``, a trailing foot on the ground) its lift-off
  rate ``g = ċ(x(0)) = ∇c · f`` at the phase start (``"lift_off"``); for an interior minimum of
  ``c`` touching zero (``"graze_min"``, a foot that scuffs the slope mid-swing) the grazing
  condition of Nordmark ("Non-periodic motion caused by grazing incidence in an impact
  oscillator", J. Sound Vib. 145(2), 1991) and di Bernardo et al. ("Piecewise-smooth Dynamical
  Systems", Springer 2008, §7.1), ``g = (c(x(t*)), ċ(x(t*))) = 0``, with the time ``t*`` of the
  minimum an extra unknown: ``y = (w, t*, ℓ₁, ℓ₂)``, ``x(t*)`` integrated from the phase start
  by ``S × steps`` RK steps of ``t*/(S × steps)`` (at least as fine as the mesh, smooth in
  ``t*``).

The parameters enter through :class:`ParameterPath`: each curve parameter sets one model
parameter, or several along an affine path (the compass gait's leg-mass position ``a`` with
``b = L − a``; the mass ratio with ``mass_hip = μ · mass_leg``).

Modules: this one (:class:`AugmentedSystem`, :func:`augmented_system`);
:mod:`~gaitopt.curves.paths` (:class:`ParameterPath`, :class:`Parametrisation`);
:mod:`~gaitopt.curves.matrices` (``A``, ``M``, the bialternate product, the bordering vectors);
:mod:`~gaitopt.curves.constraints` (the conditions of declared unilateral constraints).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..orbit.sensitivity import eliminate, map_blocks, section_jacobians
from ..shooting import MultipleShooting, ShootingProblem, shooting_problem
from .constraints import CONSTRAINT_QUANTITIES, constraint_condition, n_extra, phase_start
from .matrices import (
    bialternate,
    border_size,
    bordering,
    return_map_jacobian,
    singular_matrix,
)
from .paths import ParameterPath, Parametrisation

__all__ = [
    "CURVE_KINDS",
    "ParameterPath",
    "Parametrisation",
    "AugmentedSystem",
    "augmented_system",
    "bialternate",
    "bordering",
    "BOUNDARY_QUANTITIES",
    "CONSTRAINT_QUANTITIES",
    "constraint_condition",
    "n_extra",
    # also here, from the modules they live in:
    "border_size",
    "phase_start",
    "return_map_jacobian",
    "singular_matrix",
]

CURVE_KINDS = ("PD", "LP", "NS", "boundary")
BOUNDARY_QUANTITIES = ("duration", "grazing", "admissible", "lift_off", "graze_min")


# -- the CasADi function --------------------------------------------------------------------------
def _symbolic(f: ca.Function, sym) -> ca.Function:
    """``f`` callable on symbols of type ``sym`` (MX functions expanded for SX symbols)."""
    return f.expand() if sym is ca.SX and not f.is_a("SXFunction") else f


# SX (scalar graphs, about twice as fast to evaluate) while the graph stays small; MX beyond
# (refined meshes): the SX graph of the second derivatives grows with the RK steps per phase.
_SX_MAX_STEPS = 8


@dataclass(frozen=True)
class AugmentedSystem:
    """The compiled extended system of one model class, mesh, period, kind and condition.

    Attributes
    ----------
    problem : ShootingProblem
        The shooting equations.
    kind : str
        ``"PD"``, ``"LP"``, ``"NS"`` or ``"boundary"``.
    boundary : tuple or None
        For a boundary: the vanishing quantity (one of :data:`BOUNDARY_QUANTITIES`) and the
        phase (chain index) it belongs to, and for a constraint (:data:`CONSTRAINT_QUANTITIES`)
        its index in the phase's ``constraints``.
    function : casadi.Function
        ``(w, ℓ, b, c, p_base, K, u_base, D, scale) -> (g, ∂g/∂y, A)``: the condition, its
        exact gradient (reverse-mode AD) and the return map's Jacobian (``w`` followed by the
        extra unknowns, if any: ``t*`` of a ``graze_min`` boundary); built on first use.  ``PD``
        and ``LP`` curves of models with compiled shooting kernels do without it (see
        :meth:`evaluate`).
    """

    problem: ShootingProblem
    kind: str
    boundary: tuple | None
    builder: Any = field(repr=False, compare=False)

    @cached_property
    def function(self) -> ca.Function:
        """The CasADi function of the condition (built on first use)."""
        return self.builder()

    @property
    def kernel_path(self) -> bool:
        """Whether the condition comes from the compiled shooting kernels alone."""
        return self.kind in ("PD", "LP") and self.problem.assembly() is not None

    @property
    def border(self) -> int:
        """Length of the bordering vectors."""
        return border_size(self.kind, self.problem.m)

    @property
    def extra(self) -> int:
        """Unknowns beyond the shooting ones and the two parameters (``t*`` of a grazing)."""
        return n_extra(self.boundary)

    def evaluate(
        self,
        y: np.ndarray,
        b: np.ndarray,
        c: np.ndarray,
        par: Parametrisation,
        gradient: bool = True,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``H(y)``, ``∂H/∂y`` and the return map's Jacobian ``A`` at ``y``; with ``gradient``
        False the condition's row of ``∂H/∂y`` may be left as NaN where that saves work (the
        kernel path: two kernel evaluations fewer), for a corrector that reuses an older row.
        """
        N = self.problem.size
        wz, w, ell = y[:-2], y[:N], y[-2:]
        lam = ell * par.scale
        u, p = par.u(lam), par.p(lam)
        ev = self.problem.evaluate(w, u, p)  # compiled kernels where they exist
        F_ell = (ev.F_p @ par.K + ev.F_u @ par.D) * par.scale  # ∂F/∂ℓ = (F_p K + F_u D) diag(s)
        if self.kernel_path:
            g, grad, A = self._bordered_from_kernels(w, u, p, ev, F_ell, b, c, par, gradient)
        else:
            g, grad, A = self.function(wz, ell, b, c, *par.inputs().values())
        g = np.asarray(g, dtype=float).ravel()
        if self.kind == "boundary":  # A from the compiled shooting Jacobian (no 2nd derivatives)
            A = return_map_jacobian(self.problem, ev.F_w)
        F_block = np.hstack([ev.F_w, np.zeros((N, self.extra)), F_ell])
        H = np.concatenate([np.asarray(ev.F, dtype=float).ravel(), g])
        J = np.vstack([F_block, np.asarray(grad, dtype=float).reshape(g.size, y.size)])
        return H, J, np.asarray(A, dtype=float).reshape(self.problem.m, self.problem.m)

    def _bordered_from_kernels(self, w, u, p, ev, F_ell, b, c, par, gradient=True):
        """``g``, ``∂g/∂y`` and ``A`` of a PD or LP curve from the compiled shooting Jacobian.

        ``g`` from the bordered system ``[M b; cᵀ 0] [v; g] = [0; 1]`` with ``M = A ± I`` (``A``
        by the implicit function theorem), and its gradient by the minimally augmented formula
        ``g_y = −ωᵀ M_y v`` (Govaerts 2000, §4.3.2; ω from the transposed bordered system).
        ``ωᵀ A v`` is, by the adjoint of the section constraints, ``ψᵀ J(w) δw`` with
        ``δw = (v, −G_z⁻¹ G_s v)`` and ``ψ = (−G_z⁻ᵀ P_zᵀ ω, ω)`` held fixed, so its gradient is
        the directional derivative of ``ψᵀ ∂F/∂y`` along ``δw``: a central difference of two more
        kernel Jacobians (step ``ε``, truncation error ``O(ε²)`` ≈ 1e-10 relative, exact ``g``;
        the Newton corrector needs only the ``g`` to be exact).
        """
        problem, m, n_g = self.problem, self.problem.m, self.problem.n_g
        J = map_blocks(ev.F_w, m, n_g)  # ∂[G; P]/∂w
        A, GzGs = eliminate(J, None, m, n_g)  # A = P_s − P_z G_z⁻¹ G_s
        G_z, P_z = J[:n_g, m:], J[n_g:, m:]
        M = singular_matrix(self.kind, A)
        K = np.block([[M, b[:, None]], [c[None, :], np.zeros((1, 1))]])
        rhs = np.zeros(m + 1)
        rhs[-1] = 1.0
        vg = np.linalg.solve(K, rhs)
        omega_g = np.linalg.solve(K.T, rhs)
        v, g, omega = vg[:m], vg[m], omega_g[:m]
        if not gradient:
            return g, np.full(problem.size + self.extra + 2, np.nan), A
        dw = np.concatenate([v, -GzGs @ v])
        psi = np.concatenate([-np.linalg.solve(G_z.T, P_z.T @ omega) if n_g else [], omega])
        eps = 1e-5 * (1.0 + np.max(np.abs(w))) / max(np.max(np.abs(dw)), 1e-300)
        rows = []
        for sign in (1.0, -1.0):
            e = problem.evaluate(w + sign * eps * dw, u, p)
            F_ell_e = (e.F_p @ par.K + e.F_u @ par.D) * par.scale
            rows.append(psi @ np.hstack([e.F_w, np.zeros((problem.size, self.extra)), F_ell_e]))
        grad = -(rows[0] - rows[1]) / (2 * eps)
        return g, grad, A


def augmented_system(
    model_cls: type[HybridModel],
    disc: MultipleShooting,
    steps: int,
    kind: str,
    boundary: tuple | None = None,
) -> AugmentedSystem:
    """The cached :class:`AugmentedSystem` (built once per class, mesh, period and kind)."""
    return _augmented_system(model_cls, disc, steps, kind, boundary)


@lru_cache(maxsize=32)
def _augmented_system(model_cls, disc, steps, kind, boundary) -> AugmentedSystem:
    if kind not in CURVE_KINDS:
        raise GaitoptInputError(f"`kind` must be one of {', '.join(CURVE_KINDS)}, got {kind!r}")
    if kind == "boundary" and (boundary is None or boundary[0] not in BOUNDARY_QUANTITIES):
        raise GaitoptInputError(f"a boundary curve needs one of {BOUNDARY_QUANTITIES}")
    problem = shooting_problem(model_cls, disc, steps)
    if kind == "NS" and border_size(kind, problem.m) == 0:
        raise GaitoptInputError(
            f"{model_cls.name} has {problem.m} section coordinate(s): no complex pair of "
            f"multipliers, so no Neimark–Sacker curve; follow PD or LP"
        )
    return AugmentedSystem(
        problem, kind, boundary, lambda: _condition_function(model_cls, disc, steps, kind, boundary)
    )


def _condition_function(model_cls, disc, steps, kind, boundary) -> ca.Function:
    """The CasADi function of :attr:`AugmentedSystem.function`."""
    problem = shooting_problem(model_cls, disc, steps)
    m, n_g, n_p, n_u = (
        problem.m,
        problem.n_g,
        len(model_cls.parameter_specs()),
        len(model_cls.inputs),
    )
    nb = border_size(kind, m)
    sym = ca.SX if disc.rk_steps * len(problem.chain) <= _SX_MAX_STEPS else ca.MX
    w, ell = sym.sym("w", problem.size + n_extra(boundary)), sym.sym("ell", 2)
    b, c = sym.sym("b", nb), sym.sym("c", nb)
    p_base, K = sym.sym("p_base", n_p), sym.sym("K", n_p, 2)
    u_base, D = sym.sym("u_base", n_u), sym.sym("D", n_u, 2)
    scale = sym.sym("scale", 2)
    lam = scale * ell
    p = p_base + K @ lam
    u = u_base + D @ lam
    if kind == "boundary":
        A = sym(m, m)  # numerically, from the shooting kernels (AugmentedSystem.evaluate)
    else:
        J_w, _, _, _ = _symbolic(problem.linearisation, sym)(w[: problem.size], u, p)
        A, _ = section_jacobians(J_w, None, m, n_g)  # A = P_s − P_z G_z⁻¹ G_s, symbolically
    if kind == "boundary" and boundary[0] in CONSTRAINT_QUANTITIES:
        g = _symbolic(constraint_condition(model_cls, disc, steps, boundary), sym)(w, u, p)
    elif kind == "boundary":
        what, k = boundary[:2]
        _, dg, adm, durations = _symbolic(problem.checks, sym)(w, u, p)
        g = {"duration": durations, "grazing": dg, "admissible": adm}[what][k]
    else:
        M = singular_matrix(kind, A)
        bordered = ca.blockcat([[M, b], [c.T, sym(1, 1)]])
        rhs = ca.DM.zeros(nb + 1)
        rhs[nb] = 1
        g = ca.solve(bordered, rhs)[nb]
    y = ca.vertcat(w, ell)
    # The condition's gradient by reverse mode (one sweep per condition through the second
    # derivatives of the flow, not N forward directions); F's Jacobian comes from the compiled
    # shooting kernels (``ShootingProblem.evaluate``) and the chain rule through the affine
    # parameter map.
    return ca.Function(
        f"condition_{kind}",
        [w, ell, b, c, p_base, K, u_base, D, scale],
        [g, ca.jacobian(g, y), A],
        ["w", "ell", "b", "c", "p_base", "K", "u_base", "D", "scale"],
        ["g", "grad_g", "A"],
    )
