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
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError, ParameterError, did_you_mean
from ..hybrid import HybridModel
from ..shooting import MultipleShooting, ShootingProblem, shooting_problem

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
]

CURVE_KINDS = ("PD", "LP", "NS", "boundary")
BOUNDARY_QUANTITIES = ("duration", "grazing", "admissible", "lift_off", "graze_min")
#: Boundary quantities of a declared unilateral constraint: ``(what, chain index, constraint
#: index)``; the others are ``(what, chain index)``.
CONSTRAINT_QUANTITIES = ("lift_off", "graze_min")


@dataclass(frozen=True)
class ParameterPath:
    """A curve parameter: a scalar ``λ`` that sets model parameters along an affine path,
    ``parameter_k = offset_k + slope_k · λ``.

    A model parameter continued by itself is the path ``{name: (0, 1)}`` (see :meth:`of`).

    Attributes
    ----------
    name : str
        Name of the curve parameter (a key of the output points), e.g. ``"mass_ratio"``.
    coefficients : mapping of str to (float, float)
        ``parameter -> (offset, slope)``; at least one slope non-zero.
    unit : str
        Unit of ``λ`` (for plots), e.g. ``"1"`` or ``"m"``.
    doc : str
        What ``λ`` is.

    Examples
    --------
    The compass gait's leg-mass position with the leg length held at 1 m, ``b = 1 − a``::

        ParameterPath("a", {"a": (0.0, 1.0), "b": (1.0, -1.0)}, unit="m")
    """

    name: str
    coefficients: Mapping[str, tuple[float, float]]
    unit: str = ""
    doc: str = ""
    _items: tuple[tuple[str, float, float], ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise GaitoptInputError(f"ParameterPath: `name` must be a non-empty string, got "
                                    f"{self.name!r}")  # fmt: skip
        items = []
        for key, pair in dict(self.coefficients).items():
            try:
                offset, slope = (float(v) for v in pair)
            except (TypeError, ValueError):
                raise GaitoptInputError(
                    f"ParameterPath {self.name}: coefficients[{key!r}] must be (offset, slope), "
                    f"got {pair!r}"
                ) from None
            if not (math.isfinite(offset) and math.isfinite(slope)):
                raise GaitoptInputError(
                    f"ParameterPath {self.name}: coefficients[{key!r}] = {pair!r} is not finite"
                )
            items.append((str(key), offset, slope))
        if not any(s != 0 for _, _, s in items):
            raise GaitoptInputError(
                f"ParameterPath {self.name}: no coefficient has a non-zero slope; e.g. "
                f"{{'{self.name}': (0, 1)}}"
            )
        object.__setattr__(self, "_items", tuple(items))

    @classmethod
    def of(cls, model: HybridModel, name: str) -> ParameterPath:
        """The path of one model parameter ``name`` (checked: real-valued, known)."""
        specs = {s.name: s for s in model.parameter_specs()}
        if name not in specs:
            raise ParameterError(
                f"{model.name}: unknown parameter {name!r}; {did_you_mean(name, specs)}"
                f"parameters: {', '.join(specs)}"
            )
        if specs[name].integer:
            raise ParameterError(
                f"{model.name}: parameter `{name}` takes integer values and cannot be continued"
            )
        return cls(name, {name: (0.0, 1.0)}, unit=specs[name].unit, doc=specs[name].doc)

    @property
    def parameters(self) -> tuple[str, ...]:
        """The model parameters the path sets."""
        return tuple(k for k, _, _ in self._items)

    def values(self, value: float) -> dict[str, float]:
        """The model parameters at ``λ = value``."""
        return {k: offset + slope * float(value) for k, offset, slope in self._items}

    def value_of(self, model: HybridModel) -> float:
        """``λ`` of a model on the path; raises if the model is not on it."""
        key, offset, slope = next(it for it in self._items if it[2] != 0)
        value = (float(getattr(model, key)) - offset) / slope
        for k, v in self.values(value).items():
            have = float(getattr(model, k))
            if abs(have - v) > 1e-12 * (1 + abs(v)):
                raise GaitoptInputError(
                    f"ParameterPath {self.name}: the model's {k} = {have:g} is not on the path "
                    f"(expected {v:g} at {self.name} = {value:g}); set {k}={v:g}"
                )
        return value


@dataclass(frozen=True)
class Parametrisation:
    """How the two curve parameters set the parameter vector and the per-step input:
    ``p = p_base + K λ``, ``u = u_base + D λ`` (affine, exact), ``λ = scale ⊙ ℓ``."""

    model: HybridModel
    paths: tuple[ParameterPath, ParameterPath]
    p_base: np.ndarray
    K: np.ndarray
    u_base: np.ndarray
    D: np.ndarray
    scale: np.ndarray
    lam0: np.ndarray

    @classmethod
    def build(
        cls, model: HybridModel, paths: tuple[ParameterPath, ParameterPath], u0: np.ndarray
    ) -> Parametrisation:
        names = [s.name for s in model.parameter_specs()]
        touched = [k for path in paths for k in path.parameters]
        for k in touched:
            if k not in names:
                raise ParameterError(
                    f"{model.name}: unknown parameter {k!r} in a parameter path; "
                    f"{did_you_mean(k, names)}parameters: {', '.join(names)}"
                )
        if len(set(touched)) != len(touched):
            raise GaitoptInputError(
                f"the two curve parameters {paths[0].name!r} and {paths[1].name!r} set the same "
                f"model parameter; choose two independent parameters"
            )
        lam0 = np.array([path.value_of(model) for path in paths])
        p_base = model.p.copy()
        K = np.zeros((len(names), 2))
        for i, path in enumerate(paths):
            for k, offset, slope in path._items:
                p_base[names.index(k)] = offset
                K[names.index(k), i] = slope
        u0 = np.asarray(u0, dtype=float)
        D = np.zeros((u0.size, 2))
        nominal = model.nominal_input()
        if u0.size and np.allclose(u0, nominal, rtol=1e-9, atol=1e-12):
            # A nominal input that is a parameter (the SLIP's touchdown angle) moves with it;
            # nominal inputs are affine in the parameters (as in gaitopt.continuation), so a
            # large difference step is exact up to rounding.
            u0 = nominal
            for i, path in enumerate(paths):
                h = 1e-2 * max(abs(lam0[i]), 1e-3)
                try:
                    up = model.replace(**path.values(lam0[i] + h)).nominal_input()
                    D[:, i] = (up - nominal) / h
                except ParameterError:
                    down = model.replace(**path.values(lam0[i] - h)).nominal_input()
                    D[:, i] = (nominal - down) / h
        u_base = u0 - D @ lam0
        scale = np.maximum(np.abs(lam0), 1e-3)
        return cls(model, paths, p_base, K, u_base, D, scale, lam0)

    def p(self, lam: np.ndarray) -> np.ndarray:
        """Parameter vector at ``λ``."""
        return self.p_base + self.K @ np.asarray(lam, dtype=float)

    def u(self, lam: np.ndarray) -> np.ndarray:
        """Per-step input at ``λ``."""
        return self.u_base + self.D @ np.asarray(lam, dtype=float)

    def model_at(self, lam: np.ndarray) -> HybridModel | None:
        """The model at ``λ``, or None where a parameter leaves its valid range."""
        changes: dict[str, float] = {}
        for path, value in zip(self.paths, lam, strict=True):
            changes.update(path.values(value))
        try:
            return self.model.replace(**changes)
        except ParameterError:
            return None

    def inputs(self) -> dict[str, np.ndarray]:
        """The numeric inputs of the augmented function (everything but ``w, ℓ, b, c``)."""
        return {"p_base": self.p_base, "K": self.K, "u_base": self.u_base, "D": self.D,
                "scale": self.scale}  # fmt: skip


# -- bialternate product and bordering vectors ---------------------------------------------------
def _pairs(m: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(m) for j in range(i + 1, m)]


def bialternate(A: Any) -> Any:
    """``A ⊙ A``: the bialternate product, entries the 2 × 2 minors
    ``a_ik a_jl − a_il a_jk`` over index pairs ``i < j``, ``k < l``; its eigenvalues are
    ``μᵢ μⱼ, i < j`` (Kuznetsov, §10.2.2).  Works on NumPy arrays and CasADi matrices."""
    m = A.shape[0]
    pairs = _pairs(m)
    if isinstance(A, np.ndarray):
        out = np.zeros((len(pairs), len(pairs)), dtype=A.dtype)
        for r, (i, j) in enumerate(pairs):
            for s, (k, l_) in enumerate(pairs):
                out[r, s] = A[i, k] * A[j, l_] - A[i, l_] * A[j, k]
        return out
    rows = []
    for i, j in pairs:
        rows.append(ca.horzcat(*[A[i, k] * A[j, l_] - A[i, l_] * A[j, k] for k, l_ in pairs]))
    return ca.vertcat(*rows)


def singular_matrix(kind: str, A: Any) -> Any:
    """The matrix ``M`` that is singular on a curve of ``kind`` (NumPy or CasADi)."""
    eye = np.eye if isinstance(A, np.ndarray) else ca.DM.eye
    if kind == "PD":
        return A + eye(A.shape[0])
    if kind == "LP":
        return A - eye(A.shape[0])
    B = bialternate(A)
    return B - eye(B.shape[0])


def bordering(kind: str, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bordering vectors ``(b, c)``: left and right singular vectors of ``M``'s smallest
    singular value (the bordered matrix is then as far from singular as it can be)."""
    M = singular_matrix(kind, np.asarray(A, dtype=float))
    U, _, Vt = np.linalg.svd(M)
    return U[:, -1].copy(), Vt[-1].copy()


def border_size(kind: str, m: int) -> int:
    """Length of the bordering vectors."""
    if kind in ("PD", "LP"):
        return m
    if kind == "NS":
        return m * (m - 1) // 2
    return 1  # boundary: unused


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
        J = np.array(ev.F_w, dtype=float)
        J[n_g:, :m] += np.eye(m)  # ∂[G; P]/∂w
        G_s, G_z, P_s, P_z = J[:n_g, :m], J[:n_g, m:], J[n_g:, :m], J[n_g:, m:]
        GzGs = np.linalg.solve(G_z, G_s) if n_g else np.zeros((0, m))
        A = P_s - P_z @ GzGs
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
        # A = P_s − P_z G_z⁻¹ G_s (implicit function theorem; gaitopt.stability.section_jacobians)
        G_s, G_z, P_s, P_z = J_w[:n_g, :m], J_w[:n_g, m:], J_w[n_g:, :m], J_w[n_g:, m:]
        A = P_s - P_z @ ca.solve(G_z, G_s) if n_g else P_s
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


def return_map_jacobian(problem: ShootingProblem, F_w: np.ndarray) -> np.ndarray:
    """``A = ∂P/∂s`` from the shooting Jacobian ``∂F/∂w`` (``F = [G; P − s]``; the implicit
    function theorem, :func:`gaitopt.stability.section_jacobians`)."""
    J = np.array(F_w, dtype=float)
    J[problem.n_g :, : problem.m] += np.eye(problem.m)
    G_s, G_z, P_s, P_z = (
        J[: problem.n_g, : problem.m],
        J[: problem.n_g, problem.m :],
        J[problem.n_g :, : problem.m],
        J[problem.n_g :, problem.m :],
    )
    return P_s - P_z @ np.linalg.solve(G_z, G_s) if problem.n_g else P_s


# -- declared unilateral constraints becoming active ----------------------------------------------
def n_extra(boundary: tuple | None) -> int:
    """Extra unknowns of a boundary's extended system: ``t*`` for ``graze_min``, else none."""
    return 1 if boundary is not None and boundary[0] == "graze_min" else 0


def phase_start(problem: ShootingProblem, w: Any, p: Any, k: int) -> Any:
    """The state where chain phase ``k`` begins, from the shooting unknowns (symbolic or
    numeric): the lifted section point for ``k = 0``, else the phase's first node."""
    if k == 0:
        return problem.section.lift(w[: problem.m], p)
    _, _, off, (n, _) = next(item for item in problem.layout if item[0] == "nodes" and item[1] == k)
    return w[off : off + n]


def constraint_condition(
    model_cls: type[HybridModel], disc: MultipleShooting, steps: int, boundary: tuple
) -> ca.Function:
    """``g(w⁺, u, p)``: the defining condition of a constraint boundary ``(what, k, j)`` —
    constraint ``j`` of chain phase ``k`` — with ``w⁺ = (w, t*)`` for ``graze_min``.

    * ``lift_off``: ``ċ(x₀) = ∇c(x₀) · f(x₀)``, the rate at the phase start of a constraint that
      starts at zero (``at_start``): the trailing foot stops lifting off where it vanishes;
    * ``graze_min``: ``(c(x(t*)), ċ(x(t*)))``, an interior minimum of ``c`` touching zero,
      ``x(t*)`` by ``S × steps`` RK steps from the phase start (the grazing condition of
      Nordmark 1991; di Bernardo et al. 2008, §7.1).
    """
    return _constraint_condition(model_cls, disc, steps, tuple(boundary))


@lru_cache(maxsize=32)
def _constraint_condition(model_cls, disc, steps, boundary) -> ca.Function:
    from ..hybrid import rate_along
    from ..integrators import segment_function

    what, k, j = boundary
    if what not in CONSTRAINT_QUANTITIES:
        raise GaitoptInputError(f"`boundary` must be one of {CONSTRAINT_QUANTITIES}, got {what!r}")
    problem = shooting_problem(model_cls, disc, steps)
    phase = problem.phases[problem.chain[k]]
    if not 0 <= j < len(phase.constraints):
        raise GaitoptInputError(
            f"phase {phase.name!r} declares {len(phase.constraints)} constraint(s); no index {j}"
        )
    constraint = phase.constraints[j]
    rate = rate_along(phase.flow, constraint.function)
    n_p, n_u = len(model_cls.parameter_specs()), len(model_cls.inputs)
    w = ca.MX.sym("w", problem.size + n_extra(boundary))
    u, p = ca.MX.sym("u", n_u), ca.MX.sym("p", n_p)
    x0 = phase_start(problem, w, p, k)
    if what == "lift_off":
        if not constraint.at_start:
            raise GaitoptInputError(
                f"constraint {constraint.name!r} is not declared at_start: it has no lift-off rate"
            )
        g = rate(x0, u, p)
    else:
        t_star = w[problem.size]
        x_star = segment_function(phase.flow, disc.segments * disc.rk_steps)(x0, u, p, t_star)
        g = ca.vertcat(constraint.function(x_star, u, p), rate(x_star, u, p))
    return ca.Function(f"constraint_{what}", [w, u, p], [g], ["w", "u", "p"], ["g"])
