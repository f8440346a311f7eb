"""The extended system of a two-parameter curve: the orbit's shooting equations plus one defining
condition, built as one CasADi function so that its Jacobian is exact (automatic
differentiation, second derivatives of the flow included).

Unknowns ``y = (w, ℓ₁, ℓ₂)``: the shooting unknowns ``w`` of :mod:`gaitopt.shooting` and the two
scaled curve parameters ``ℓᵢ = λᵢ / scaleᵢ``.  Equations ``H(y) = (F(w, u, p), g(w, u, p))``:

* ``F = 0`` — the orbit (multiple shooting, :class:`gaitopt.shooting.Transcription`);
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
  phase end (a grazing impact), or an admissibility function (a crossing becomes spurious).

The parameters enter through :class:`ParameterPath`: each curve parameter sets one model
parameter, or several along an affine path (the compass gait's leg-mass position ``a`` with
``b = L − a``; the mass ratio with ``mass_hip = μ · mass_leg``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError, ParameterError, did_you_mean
from ..hybrid import HybridModel
from ..shooting import MultipleShooting, Transcription, transcription

__all__ = [
    "CURVE_KINDS",
    "ParameterPath",
    "Parametrisation",
    "AugmentedSystem",
    "augmented_system",
    "bialternate",
    "bordering",
    "BOUNDARY_QUANTITIES",
]

CURVE_KINDS = ("PD", "LP", "NS", "boundary")
BOUNDARY_QUANTITIES = ("duration", "grazing", "admissible")


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
    tr : Transcription
        The shooting equations.
    kind : str
        ``"PD"``, ``"LP"``, ``"NS"`` or ``"boundary"``.
    boundary : (str, int) or None
        For a boundary: the vanishing quantity (one of :data:`BOUNDARY_QUANTITIES`) and the
        phase (chain index) it belongs to.
    function : casadi.Function
        ``(w, ℓ, b, c, p_base, K, u_base, D, scale) -> (g, ∂g/∂y, A)``: the condition, its
        exact gradient (reverse-mode AD) and the return map's Jacobian.
    """

    tr: Transcription
    kind: str
    boundary: tuple[str, int] | None
    function: ca.Function

    @property
    def border(self) -> int:
        """Length of the bordering vectors."""
        return border_size(self.kind, self.tr.m)

    def evaluate(
        self, y: np.ndarray, b: np.ndarray, c: np.ndarray, par: Parametrisation
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``H(y)``, ``∂H/∂y`` and the return map's Jacobian ``A`` at ``y``."""
        w, ell = y[:-2], y[-2:]
        g, grad, A = self.function(w, ell, b, c, *par.inputs().values())
        lam = ell * par.scale
        F, F_w, F_p, F_u = (
            np.asarray(v, dtype=float)
            for v in self.tr.residual_jacobians(w, par.u(lam), par.p(lam))
        )
        F_ell = (F_p @ par.K + F_u @ par.D) * par.scale  # ∂F/∂ℓ = (F_p K + F_u D) diag(scale)
        H = np.concatenate([F.ravel(), [float(g)]])
        J = np.vstack([np.hstack([F_w, F_ell]), np.asarray(grad, dtype=float).ravel()])
        return H, J, np.asarray(A, dtype=float).reshape(self.tr.m, self.tr.m)


def augmented_system(
    model_cls: type[HybridModel],
    disc: MultipleShooting,
    steps: int,
    kind: str,
    boundary: tuple[str, int] | None = None,
) -> AugmentedSystem:
    """The cached :class:`AugmentedSystem` (built once per class, mesh, period and kind)."""
    return _augmented_system(model_cls, disc, steps, kind, boundary)


@lru_cache(maxsize=32)
def _augmented_system(model_cls, disc, steps, kind, boundary) -> AugmentedSystem:
    if kind not in CURVE_KINDS:
        raise GaitoptInputError(f"`kind` must be one of {', '.join(CURVE_KINDS)}, got {kind!r}")
    tr = transcription(model_cls, disc, steps)
    m, n_g, n_p, n_u = tr.m, tr.n_g, len(model_cls.parameter_specs()), len(model_cls.inputs)
    nb = border_size(kind, m)
    sym = ca.SX if disc.steps * len(tr.chain) <= _SX_MAX_STEPS else ca.MX
    w, ell = sym.sym("w", tr.size), sym.sym("ell", 2)
    b, c = sym.sym("b", nb), sym.sym("c", nb)
    p_base, K = sym.sym("p_base", n_p), sym.sym("K", n_p, 2)
    u_base, D = sym.sym("u_base", n_u), sym.sym("D", n_u, 2)
    scale = sym.sym("scale", 2)
    lam = scale * ell
    p = p_base + K @ lam
    u = u_base + D @ lam
    J_w, _, _, _ = _symbolic(tr.linearisation, sym)(w, u, p)
    # A = P_s − P_z G_z⁻¹ G_s (implicit function theorem; gaitopt.stability.section_jacobians)
    G_s, G_z, P_s, P_z = J_w[:n_g, :m], J_w[:n_g, m:], J_w[n_g:, :m], J_w[n_g:, m:]
    A = P_s - P_z @ ca.solve(G_z, G_s) if n_g else P_s
    if kind == "boundary":
        if boundary is None or boundary[0] not in BOUNDARY_QUANTITIES:
            raise GaitoptInputError(f"a boundary curve needs one of {BOUNDARY_QUANTITIES}")
        what, k = boundary
        _, dg, adm, durations = _symbolic(tr.checks, sym)(w, u, p)
        g = {"duration": durations, "grazing": dg, "admissible": adm}[what][k]
    else:
        if nb == 0:
            raise GaitoptInputError(
                f"{model_cls.name} has {m} section coordinate(s): no complex pair of multipliers, "
                f"so no Neimark–Sacker curve; follow PD or LP"
            )
        M = singular_matrix(kind, A)
        bordered = ca.blockcat([[M, b], [c.T, sym(1, 1)]])
        rhs = ca.DM.zeros(nb + 1)
        rhs[nb] = 1
        g = ca.solve(bordered, rhs)[nb]
    y = ca.vertcat(w, ell)
    # The scalar condition's gradient by reverse mode (one sweep through the second derivatives
    # of the flow, not N forward directions); F's Jacobian comes from the transcription's own AD
    # (``residual_jacobians``) and the chain rule through the affine parameter map.
    function = ca.Function(
        f"condition_{kind}",
        [w, ell, b, c, p_base, K, u_base, D, scale],
        [g, ca.gradient(g, y), A],
        ["w", "ell", "b", "c", "p_base", "K", "u_base", "D", "scale"],
        ["g", "grad_g", "A"],
    )
    return AugmentedSystem(tr, kind, boundary, function)
