"""Pseudo-arclength continuation of gaits in a model parameter, special points, and
period-doubling cascades.

A branch is followed in ``y = (w, ℓ)``: the shooting unknowns ``w`` of
:mod:`gaitopt.shooting` and the scaled parameter ``ℓ = λ / λ_scale``.  Each step predicts along
the tangent ``t`` (the null vector of ``[F_w, F_ℓ]``) and corrects with Newton on
``F(w, ℓ) = 0, ⟨t, y − y_pred⟩ = 0`` (Keller's pseudo-arclength method; Allgower & Georg,
"Numerical Continuation Methods", §2.1); the inner product weights the ``N`` shooting unknowns by
``1/N`` so that states and parameter count alike.  The step adapts to the corrector's work.  Every
accepted point is certified like a solved gait (:func:`gaitopt.shooting.certify`: no false
gaits, multipliers, independent simulation) and its discretisation error estimated (the mesh is
refined along the branch when needed).

Special points come from test functions of the return map's Jacobian ``A`` (Kuznetsov,
"Elements of Applied Bifurcation Theory", §10.2, maps): fold ``LP`` where ``det(A − I)`` changes
sign (a multiplier +1), period doubling ``PD`` where ``det(A + I)`` does (−1), Neimark–Sacker
``NS`` where the bialternate product ``∏_{i<j}(μ_i μ_j − 1)`` does with a complex pair on the unit
circle.  Each is located by regula falsi (Illinois) along the arclength to 1e-10 in the parameter.
A ``boundary`` is where the gait stops existing: a certification check fails (a guard grazes, a
duration reaches zero, a guard is crossed early, the simulation disagrees) or the corrector cannot
continue; it is located by bisection.  At a PD the period-2 orbit is found (perturbing along the
eigenvector of −1) and followed, and so on down the cascade.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import GaitoptInputError, ParameterError, did_you_mean
from .hybrid import HybridModel
from .result import LimitCycle
from .shooting import MultipleShooting, Transcription, certify, find_limit_cycle, transcription
from .stability import section_jacobians

__all__ = ["PseudoArclength", "SpecialPoint", "Branch", "continuation", "SPECIAL_KINDS"]

SPECIAL_KINDS = ("LP", "PD", "NS", "boundary")
_LOCATE_TOL = 1e-10  # parameter accuracy of located special points (absolute)
_MAX_MESH_REFINEMENTS = 4


@dataclass(frozen=True)
class PseudoArclength:
    """Options of the pseudo-arclength continuation (validated on construction).

    Attributes
    ----------
    step : float
        First arclength step (scaled units: parameter relative to its start value, states in
        their units averaged over the unknowns).
    min_step, max_step : float
        Bounds of the adaptive step.
    max_points : int
        Most points per branch (each direction).
    max_corrector : int
        Newton iterations allowed per corrector.
    """

    step: float = 0.02
    min_step: float = 1e-8
    max_step: float = 0.25
    max_points: int = 400
    max_corrector: int = 8

    def __post_init__(self) -> None:
        for name in ("step", "min_step", "max_step"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise GaitoptInputError(f"PseudoArclength: `{name}` must be > 0, got {value!r}")
        if not self.min_step <= self.step <= self.max_step:
            raise GaitoptInputError(
                f"PseudoArclength: need min_step ≤ step ≤ max_step, got {self.min_step:g}, "
                f"{self.step:g}, {self.max_step:g}"
            )
        for name in ("max_points", "max_corrector"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise GaitoptInputError(
                    f"PseudoArclength: `{name}` must be a positive integer, got {value!r}"
                )


@dataclass
class SpecialPoint:
    """A located special point of a branch.

    Attributes
    ----------
    kind : str
        ``"LP"`` (fold, multiplier +1), ``"PD"`` (period doubling, −1), ``"NS"``
        (Neimark–Sacker, complex pair on the unit circle) or ``"boundary"`` (the gait stops
        existing).
    param : float
        Parameter value where it lies.
    index : int
        Index of the branch point just before it.
    cycle : LimitCycle or None
        The gait at the point (for ``boundary``: the last certified gait before it).
    message : str
        What happens there.
    """

    kind: str
    param: float
    index: int
    cycle: LimitCycle | None
    message: str

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: ``kind``, ``param`` (the contract), plus the gait there."""
        out: dict[str, Any] = {
            "kind": self.kind,
            "param": float(self.param),
            "message": self.message,
        }
        if self.cycle is not None:
            out["period"] = float(self.cycle.period)
            out["steps"] = int(self.cycle.steps)
            out["fixed_point"] = {k: float(v) for k, v in self.cycle.fixed_point.items()}
            out["multipliers"] = [[float(z.real), float(z.imag)] for z in self.cycle.multipliers]
        return out


@dataclass
class Branch:
    """A branch of gaits, stored by column (BifurcationKit's habit).

    Attributes
    ----------
    model : HybridModel
        The model at the branch's start.
    param : str
        The continued parameter.
    steps : int
        Returns to the section per orbit on this branch (2 after a period doubling, …).
    cycles : list of LimitCycle
        The certified gait at every point, in increasing order along the branch.
    special_points : list of SpecialPoint
        Located special points, in branch order.
    children : list of Branch
        Branches born at this branch's period doublings (period 2k), each with its own children.
    message : str
        How the branch ended (each direction).
    success : bool
        Whether the start was a certified gait and at least one point was computed.
    """

    model: HybridModel
    param: str
    steps: int
    cycles: list[LimitCycle] = field(default_factory=list)
    special_points: list[SpecialPoint] = field(default_factory=list)
    children: list[Branch] = field(default_factory=list)
    message: str = ""
    success: bool = True

    # -- columns ------------------------------------------------------------------------------
    @property
    def params(self) -> np.ndarray:
        """Parameter value of each point."""
        return np.array([getattr(c.model, self.param) for c in self.cycles])

    @property
    def periods(self) -> np.ndarray:
        """Orbit period of each point (s)."""
        return np.array([c.period for c in self.cycles])

    @property
    def fixed_points(self) -> np.ndarray:
        """Fixed point of each point (rows, in ``state_names`` order)."""
        return np.array([c.x for c in self.cycles])

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the fixed-point columns."""
        return self.model.state_names

    @property
    def multipliers(self) -> np.ndarray:
        """Multipliers of each point (rows, sorted by decreasing modulus)."""
        return np.array([c.multipliers for c in self.cycles])

    @property
    def stable(self) -> np.ndarray:
        """Stability of each point."""
        return np.array([bool(c.stable) for c in self.cycles])

    @property
    def discretisation_errors(self) -> np.ndarray:
        """Discretisation-error estimate of each point."""
        return np.array([c.discretisation_error for c in self.cycles])

    def descendants(self) -> list[Branch]:
        """This branch and every branch born from it, depth first."""
        out = [self]
        for child in self.children:
            out.extend(child.descendants())
        return out

    # -- output ---------------------------------------------------------------------------------
    def as_dict(self) -> dict[str, Any]:
        """The JSON object of ``gaitopt continue --json`` (docs/design.md's contract), with the
        period-doubled branches under ``branches``."""
        return {
            "model": self.model.name,
            "param": self.param,
            "params": self.model.params,
            "steps": self.steps,
            "success": self.success,
            "message": self.message,
            "points": [
                {
                    "param": float(getattr(c.model, self.param)),
                    "period": float(c.period),
                    "fixed_point": {k: float(v) for k, v in c.fixed_point.items()},
                    "multipliers": [[float(z.real), float(z.imag)] for z in c.multipliers],
                    "stable": bool(c.stable),
                }
                for c in self.cycles
            ],
            "special_points": [sp.as_dict() for sp in self.special_points],
            "branches": [child.as_dict() for child in self.children],
        }

    def csv_rows(self) -> tuple[list[str], list[list[float]]]:
        """Header and rows of the branch table (this branch and its descendants)."""
        m = max((len(c.multipliers) for b in self.descendants() for c in b.cycles), default=0)
        header = ["steps", self.param, "period", *self.state_names]
        header += [f"multiplier_{i}_{part}" for i in range(m) for part in ("re", "im")]
        header += ["max_abs_multiplier", "stable"]
        rows = []
        for branch in self.descendants():
            for c in branch.cycles:
                mult = list(c.multipliers) + [complex("nan")] * (m - len(c.multipliers))
                rows.append(
                    [branch.steps, getattr(c.model, self.param), c.period, *c.x]
                    + [v for z in mult for v in (z.real, z.imag)]
                    + [float(np.max(np.abs(c.multipliers))), int(bool(c.stable))]
                )
        return header, rows

    def __repr__(self) -> str:
        kinds = ", ".join(f"{sp.kind}@{sp.param:.8g}" for sp in self.special_points)
        span = f"{self.params.min():.6g}..{self.params.max():.6g}" if self.cycles else "empty"
        return (
            f"Branch({self.model.name}, {self.param} {span}, {len(self.cycles)} points, "
            f"period-{self.steps}, special points [{kinds}], {len(self.children)} children)"
        )


# ---------------------------------------------------------------------------------------------
def continuation(
    model: HybridModel,
    param: str,
    *,
    to: float | None = None,
    start: LimitCycle | Mapping[str, float] | None = None,
    steps: int = 1,
    options: PseudoArclength = PseudoArclength(),
    both_directions: bool = False,
    bounds: tuple[float, float] | None = None,
    cascade: bool = True,
    max_period: int = 16,
    verify: bool = True,
    tol: float = 1e-10,
) -> Branch:
    """Follow a gait through a model parameter.

    Parameters
    ----------
    model : HybridModel
        The model at the start.
    param : str
        Name of the parameter to vary (any of ``model.params``).
    to : float, optional
        Parameter value to stop at (the direction of continuation).  Default: the end of the
        parameter's valid range above the start.
    start : LimitCycle or mapping, optional
        The gait to start from (a solved cycle at ``model``), or a guess for
        :func:`find_limit_cycle`; default: the model's default start.
    steps : int
        Period of the starting gait in steps.
    options : PseudoArclength
        Step control.
    both_directions : bool
        Also follow the branch from the start away from ``to`` (until the parameter's range ends
        or the gait stops existing).
    bounds : (float, float), optional
        Parameter interval the branch stays in (both directions, also after folds); default the
        parameter's valid range.
    cascade : bool
        At each period doubling switch to the period-2k branch and follow it too (in the
        continuation direction), down the cascade until ``max_period``.
    max_period : int
        Deepest period of the cascade.
    verify : bool
        Verify every point by independent simulation (as :func:`find_limit_cycle` does).
    tol : float
        Residual and discretisation-error tolerance (as :func:`find_limit_cycle`).

    Returns
    -------
    Branch
        Points in increasing arclength order (for ``both_directions`` from the far end of the
        backward part), special points, and the period-doubled branches as ``children``.

    Raises
    ------
    ParameterError
        If ``param`` is not a parameter of the model or ``to`` is outside its range.
    """
    specs = {s.name: s for s in model.parameter_specs()}
    if param not in specs:
        raise ParameterError(
            f"{model.name}: unknown parameter {param!r} to continue in; "
            f"{did_you_mean(param, specs)}parameters: {', '.join(specs)}"
        )
    spec = specs[param]
    if spec.integer:
        raise ParameterError(
            f"{model.name}: parameter `{param}` takes integer values and cannot be continued; "
            f"choose a real parameter"
        )
    lam0 = float(getattr(model, param))
    if to is not None:
        to = float(to)
        model.replace(**{param: to})  # raises ParameterError when `to` is out of range
        if to == lam0:
            raise ParameterError(
                f"`to` = {to:g} equals the start value of `{param}`; nothing to do"
            )
    if isinstance(start, LimitCycle):
        first = start
        if type(first.model) is not type(model) or first.model.params != model.params:
            raise GaitoptInputError("`start` must be a gait of the given model at its parameters")
    else:
        first = find_limit_cycle(model, start, steps=steps, verify=verify, tol=tol)
    branch = Branch(model, param, first.steps)
    if not first.success:
        branch.success = False
        branch.message = f"no gait to start from: {first.message}"
        return branch
    direction = 1.0 if to is None or to > lam0 else -1.0
    lo, hi = (-math.inf, math.inf) if bounds is None else (float(bounds[0]), float(bounds[1]))
    if not lo <= lam0 <= hi:
        raise ParameterError(
            f"`bounds` = ({lo:g}, {hi:g}) must contain the start value {param} = {lam0:g}"
        )
    return _follow_branch(
        first,
        param,
        direction,
        to,
        (lo, hi),
        options,
        both_directions,
        cascade,
        max_period,
        verify,
        tol,
    )


def _follow_branch(
    first: LimitCycle,
    param,
    direction,
    to,
    bounds,
    options,
    both_directions,
    cascade,
    max_period,
    verify,
    tol,
) -> Branch:
    """Follow a certified gait in ``direction`` (and back, if asked); switch at PDs."""
    branch = Branch(first.model, param, first.steps)
    lo, hi = bounds
    if to is not None:
        lo, hi = (lo, min(hi, to)) if direction > 0 else (max(lo, to), hi)
    forward = _Follower(first, param, direction, (lo, hi), options, verify, tol).run()
    points, specials, message = forward.cycles, forward.special_points, forward.stop
    if both_directions:
        backward = _Follower(first, param, -direction, bounds, options, verify, tol).run()
        n_back = len(backward.cycles) - 1  # the start is shared
        points = backward.cycles[::-1] + points[1:]
        specials = [_reindex(sp, n_back - sp.index - 1) for sp in backward.special_points[::-1]] + [
            _reindex(sp, sp.index + n_back) for sp in specials
        ]
        message = f"backward: {backward.stop}; forward: {message}"
    branch.cycles, branch.special_points, branch.message = points, specials, message
    if cascade:
        for sp in branch.special_points:
            if sp.kind == "PD" and 2 * branch.steps <= max_period:
                child = _switch_at_period_doubling(
                    sp, param, direction, to, bounds, options, verify, tol, max_period
                )
                if child is not None:
                    branch.children.append(child)
    return branch


def _reindex(sp: SpecialPoint, index: int) -> SpecialPoint:
    return SpecialPoint(sp.kind, sp.param, max(index, 0), sp.cycle, sp.message)


# ---------------------------------------------------------------------------------------------
class _Follower:
    """One direction of pseudo-arclength continuation from a certified gait."""

    def __init__(self, first, param, direction, limits, options, verify, tol):
        self.first, self.param, self.direction = first, param, direction
        self.limits, self.options, self.verify, self.tol = limits, options, verify, tol
        model = first.model
        self.model0 = model
        self.index = [s.name for s in model.parameter_specs()].index(param)
        self.scale = max(abs(float(getattr(model, param))), 1e-3)
        # A model whose nominal per-step input is a parameter (the SLIP's touchdown angle) moves
        # its input with that parameter, unless the start used other inputs on purpose.
        nominal = model.nominal_input()
        self.u0 = np.asarray(first.inputs, dtype=float)
        self.du = np.zeros_like(self.u0)
        if self.u0.size and np.allclose(self.u0, nominal, rtol=0, atol=1e-15):
            h = 1e-6 * self.scale
            lam0 = float(getattr(model, param))
            try:
                up = model.replace(**{param: lam0 + h}).nominal_input()
                self.du = (up - nominal) / h  # nominal inputs are affine in the parameter
            except ParameterError:
                down = model.replace(**{param: lam0 - h}).nominal_input()
                self.du = (nominal - down) / h
        self.lam0 = float(getattr(model, param))
        disc = first.discretisation or MultipleShooting(*type(model).mesh)
        self.tr: Transcription = transcription(type(model), disc, first.steps)
        self.refinements = 0
        self._last_evaluation = None
        self.cycles: list[LimitCycle] = [first]
        self.special_points: list[SpecialPoint] = []
        self.stop = ""

    # -- the equations ---------------------------------------------------------------------
    def lam(self, y: np.ndarray) -> float:
        return float(y[-1] * self.scale)

    def _p(self, y: np.ndarray) -> np.ndarray:
        p = self.model0.p.copy()
        p[self.index] = self.lam(y)
        return p

    def _u(self, y: np.ndarray) -> np.ndarray:
        return self.u0 + self.du * (self.lam(y) - self.lam0)

    def jacobian(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``F(y)`` and ``[F_w, F_ℓ]`` (``F_ℓ`` through the parameter and the input it sets)."""
        ev = self._evaluate(y)
        F_lam = ev.F_p[:, self.index] + ev.F_u @ self.du
        J = np.hstack([ev.F_w, F_lam[:, None] * self.scale])
        return ev.F, J

    def _evaluate(self, y: np.ndarray):
        """The shooting equations and all their Jacobians at ``y`` in one compiled call
        (:meth:`gaitopt.shooting.ShootingProblem.evaluate`), kept for the next use at the same
        point (the tangent, the error estimate, the multipliers and the certificate)."""
        key = (id(self.tr), y.tobytes())
        if self._last_evaluation is None or self._last_evaluation[0] != key:
            self._last_evaluation = (key, self.tr.evaluate(y[:-1], self._u(y), self._p(y)))
        return self._last_evaluation[1]

    def weights(self, y: np.ndarray) -> np.ndarray:
        n = y.size - 1
        return np.concatenate([np.full(n, 1.0 / n), [1.0]])

    def tangent(self, y: np.ndarray, previous: np.ndarray) -> np.ndarray:
        """Null vector of ``[F_w, F_ℓ]``, unit in the weighted norm, oriented like ``previous``."""
        _, J = self.jacobian(y)
        W = self.weights(y)
        K = np.vstack([J, previous * W])
        rhs = np.zeros(K.shape[0])
        rhs[-1] = 1.0
        t = np.linalg.solve(K, rhs)
        t /= math.sqrt(float(t @ (W * t)))
        return t if float(t @ (W * previous)) > 0 else -t

    def correct(self, y_pred: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, bool, int]:
        """Newton on ``F(y) = 0, ⟨t, y − y_pred⟩_W = 0``; converged when ``|F| ≤ tol`` after a
        step below 1e-12 (relative)."""
        y = y_pred.copy()
        W = self.weights(y)
        F, J = self.jacobian(y)
        for k in range(1, self.options.max_corrector + 1):
            if not np.all(np.isfinite(F)):
                return y, False, k
            G = np.concatenate([F, [float(t @ (W * (y - y_pred)))]])
            dy = np.linalg.solve(np.vstack([J, t * W]), -G)
            y = y + dy
            F, J = self.jacobian(y)
            small = np.max(np.abs(dy)) < 1e-9 * (1 + np.max(np.abs(y)))
            if small and np.max(np.abs(F)) <= self.tol:
                return y, True, k
        return y, False, self.options.max_corrector

    # -- a point on the branch ---------------------------------------------------------------
    def model_at(self, y: np.ndarray) -> HybridModel | None:
        try:
            return self.model0.replace(**{self.param: self.lam(y)})
        except ParameterError:
            return None

    def multipliers_at(self, y: np.ndarray) -> np.ndarray:
        """Multipliers only (no checks): for locating special points."""
        ev = self._evaluate(y)
        J_w = ev.F_w.copy()
        J_w[self.tr.n_g :, : self.tr.m] += np.eye(self.tr.m)  # ∂[G; P]/∂w from ∂F/∂w
        A, _ = section_jacobians(J_w, ev.F_u, self.tr.m, self.tr.n_g)
        return np.linalg.eigvals(A) if A.size else np.zeros(0, complex)

    def certified(self, y: np.ndarray) -> LimitCycle | None:
        """The gait at ``y`` if every check passes, else None.  The mesh follows the
        discretisation error: refined (steps doubled) while the estimate exceeds ``tol``,
        coarsened again where half the steps would still meet it (the error scales as h⁸)."""
        model = self.model_at(y)
        self.y_last = y
        if model is None:
            return None
        error = self._discretisation_error(y)
        while error > self.tol and self.refinements < _MAX_MESH_REFINEMENTS:
            self.tr = transcription(type(model), _doubled(self.tr.disc), self.tr.cycles)
            self.refinements += 1
            y, ok, _ = self.correct(y, self._unit_lambda())
            if not ok:
                return None
            error = self._discretisation_error(y)
        if self.tr.disc.steps > type(model).mesh[1] and error < self.tol / 1000:
            coarse = transcription(type(model), _halved(self.tr.disc), self.tr.cycles)
            previous = self.tr
            self.tr = coarse
            y_coarse, ok, _ = self.correct(y, self._unit_lambda())
            coarse_error = self._discretisation_error(y_coarse) if ok else math.inf
            if coarse_error <= self.tol:
                y, error = y_coarse, coarse_error
                self.refinements = max(self.refinements - 1, 0)
            else:
                self.tr = previous
        self.y_last = y
        return certify(
            model,
            self.tr,
            y[:-1],
            self._u(y),
            verify=self.verify,
            tol=self.tol,
            discretisation_error=error,
            evaluation=self._evaluate(y),
        )

    def _unit_lambda(self) -> np.ndarray:
        t = np.zeros(self.tr.size + 1)
        t[-1] = 1.0  # correct at fixed parameter
        return t

    def _discretisation_error(self, y: np.ndarray) -> float:
        F_fine = self.tr.fine_residual(y[:-1], self._u(y), self._p(y))
        F_w = self._evaluate(y).F_w
        return float(np.max(np.abs(np.linalg.solve(F_w, F_fine))))

    # -- the loop ----------------------------------------------------------------------------
    def run(self) -> _Follower:
        opts = self.options
        first = self.first
        y = np.concatenate(
            [_w_of(first, self.tr), [float(getattr(first.model, self.param)) / self.scale]]
        )
        start = np.zeros_like(y)
        start[-1] = self.direction
        t = self.tangent(y, start)
        h = opts.step
        tests = _test_functions(first.multipliers)
        slow = 0
        while len(self.cycles) < opts.max_points:
            y_new, ok, iterations = self.correct(y + h * t, t)
            lam_new = self.lam(y_new)
            limit = self._crossed_limit(lam_new) if ok else None
            if limit is not None:
                y_new, ok = self._land_on(limit, y, t)
                lam_new = self.lam(y_new)
                if ok:
                    cycle = self.certified(y_new)
                    y_new = self.y_last
                    if cycle is not None and cycle.success:
                        self._special_points_between(y, t, y_new, tests, cycle, h_total=None)
                        self.cycles.append(cycle)
                        self.stop = f"reached {self.param} = {lam_new:.10g}"
                        return self
                    ok = False
            if not ok:
                h /= 2
                if h < opts.min_step:
                    self._boundary(y, t, 2 * h, "the corrector cannot continue the branch")
                    return self
                continue
            cycle = self.certified(y_new)
            y_new = self.y_last
            if cycle is None or not cycle.success:
                if cycle is None and self.model_at(y_new) is None:
                    self.stop = f"{self.param} left its valid range near {lam_new:.10g}"
                    return self
                self._boundary(y, t, h, cycle.message if cycle is not None else "")
                return self
            new_tests = _test_functions(cycle.multipliers)
            self._special_points_between(y, t, y_new, tests, cycle, h_total=h, new_tests=new_tests)
            self.cycles.append(cycle)
            t = self.tangent(y_new, t)
            slow = slow + 1 if abs(lam_new - self.lam(y)) < 1e-12 * self.scale else 0
            if slow >= 5:
                self._boundary(
                    y_new,
                    t,
                    opts.min_step,
                    "the parameter stops advancing (a phase duration grows without bound)",
                    locate=False,
                )
                return self
            y, tests = y_new, new_tests
            h = min(opts.max_step, h * 1.5) if iterations <= 3 else h / 2 if iterations >= 6 else h
        self.stop = f"stopped after {opts.max_points} points"
        return self

    def _crossed_limit(self, lam: float) -> float | None:
        lo, hi = self.limits
        return hi if lam > hi else lo if lam < lo else None

    def _land_on(self, limit: float, y: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, bool]:
        """Correct at exactly the limit (natural parameter step from ``y``)."""
        dl = limit / self.scale - y[-1]
        y_pred = y + t * (dl / t[-1]) if abs(t[-1]) > 1e-12 else y.copy()
        y_pred[-1] = limit / self.scale
        y_new, ok, _ = self.correct(y_pred, self._unit_lambda())
        return y_new, ok

    # -- special points ---------------------------------------------------------------------
    def _special_points_between(self, y, t, y_new, tests, cycle, h_total, new_tests=None):
        new_tests = _test_functions(cycle.multipliers) if new_tests is None else new_tests
        if h_total is None:  # the target step is not along t: use the chord
            h_total = math.sqrt(float((y_new - y) @ (self.weights(y) * (y_new - y))))
            t = (y_new - y) / h_total
        found = []
        for kind in ("LP", "PD", "NS"):
            a, b = tests[kind], new_tests[kind]
            if a == 0 or b == 0 or np.sign(a) == np.sign(b):
                continue
            located = self._locate(y, t, h_total, kind, a, b)
            if located is not None:
                found.append(located)
        for sp in sorted(found, key=lambda s: (s.param - self.lam(y)) * self.direction):
            self.special_points.append(sp)

    def _locate(self, y, t, h_b, kind, psi_a, psi_b) -> SpecialPoint | None:
        """Illinois regula falsi on the arclength for the test function's zero, until the
        bracket is below 1e-10 in the parameter and 1e-9 in the arclength."""
        lo, hi, f_lo, f_hi = 0.0, h_b, psi_a, psi_b
        lam_lo, lam_hi = self.lam(y), None
        side, y_mid = 0, y
        for _ in range(60):
            h = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
            if not lo < h < hi:
                h = 0.5 * (lo + hi)
            y_mid, ok, _ = self.correct(y + h * t, t)
            if not ok:
                return None
            f = _test_functions(self.multipliers_at(y_mid))[kind]
            if f == 0:
                break
            if np.sign(f) == np.sign(f_lo):
                lo, f_lo, lam_lo = h, f, self.lam(y_mid)
                if side == -1:
                    f_hi /= 2
                side = -1
            else:
                hi, f_hi, lam_hi = h, f, self.lam(y_mid)
                if side == 1:
                    f_lo /= 2
                side = 1
            # Both brackets: near a fold λ is quadratic in the arclength, so a tight λ alone
            # would leave the point (and its multiplier +1) loose.
            if lam_hi is not None and abs(lam_hi - lam_lo) < _LOCATE_TOL and hi - lo < 1e-9:
                break
        model = self.model_at(y_mid)
        if model is None:
            return None
        cycle = certify(
            model, self.tr, y_mid[:-1], self._u(y_mid), verify=self.verify, tol=self.tol
        )
        multipliers = cycle.multipliers if cycle.success else self.multipliers_at(y_mid)
        if kind == "NS" and not _has_complex_pair_on_unit_circle(multipliers):
            return None  # a neutral saddle (real μ_i μ_j = 1), not a Neimark–Sacker point
        what = {
            "LP": "fold: a multiplier passes +1 (two gaits meet)",
            "PD": "period doubling: a multiplier passes −1",
            "NS": "Neimark–Sacker: a complex pair crosses the unit circle",
        }[kind]
        return SpecialPoint(kind, self.lam(y_mid), len(self.cycles) - 1, cycle, what)

    def _boundary(self, y, t, h_fail, reason, locate=True) -> None:
        """Bisect between the last certified point and the failure; record a boundary."""
        lo, hi = 0.0, h_fail
        last, y_lo = self.cycles[-1], y
        if locate:
            while hi - lo > 1e-14:
                h = 0.5 * (lo + hi)
                y_mid, ok, _ = self.correct(y + h * t, t)
                cycle = self.certified(y_mid) if ok else None
                if cycle is not None and cycle.success:
                    lo, last, y_lo = h, cycle, self.y_last
                else:
                    hi = h
                    if cycle is not None:
                        reason = cycle.message
                lam_lo = float(getattr(last.model, self.param))
                lam_hi = self.lam(self.correct(y + hi * t, t)[0])
                if abs(lam_hi - lam_lo) < _LOCATE_TOL:
                    break
        if last is not self.cycles[-1]:
            # Special points between the last accepted point and the boundary's last gait (a
            # period doubling just before the end would otherwise be stepped over).
            tests = _test_functions(self.cycles[-1].multipliers)
            self._special_points_between(y, t, y_lo, tests, last, h_total=lo)
            self.cycles.append(last)
        lam = float(getattr(last.model, self.param))
        growth = last.period / self.first.period
        if growth > 3:
            reason = (
                f"its period grows without bound ({last.period:.4g} s here, "
                f"{self.first.period:.4g} s at the start): the orbit comes ever closer to an "
                f"unstable equilibrium; {reason}"
            )
        message = f"the gait stops existing: {reason}" if reason else "the gait stops existing"
        self.special_points.append(
            SpecialPoint("boundary", lam, len(self.cycles) - 1, last, message)
        )
        self.stop = f"boundary at {self.param} = {lam:.10g}"


def _doubled(disc: MultipleShooting) -> MultipleShooting:
    return MultipleShooting(disc.segments, 2 * disc.steps, disc.dense)


def _halved(disc: MultipleShooting) -> MultipleShooting:
    return MultipleShooting(disc.segments, max(disc.steps // 2, 1), disc.dense)


def _w_of(cycle: LimitCycle, tr: Transcription) -> np.ndarray:
    """The shooting unknowns of a certified cycle (from its dense orbit)."""
    from .shooting import _nodes_from_orbit

    return tr.pack(cycle.section_point, *_nodes_from_orbit(cycle, tr))


def _born_at(doubled: LimitCycle, parent: LimitCycle) -> bool:
    """Whether a period-2k orbit found next to a PD was born there: it lies near the parent
    orbit and has the multiplier ≈ +1 into which the parent's −1 squares (another period-2k
    orbit further away may also be found from the perturbed guess)."""
    scale = 1 + np.max(np.abs(parent.section_point))
    near = np.max(np.abs(doubled.section_point - parent.section_point)) < 0.2 * scale
    return bool(near and np.min(np.abs(doubled.multipliers - 1)) < 0.3)


def _test_functions(multipliers: np.ndarray) -> dict[str, float]:
    """Kuznetsov's test functions of a map's fixed point, from its multipliers."""
    mu = np.asarray(multipliers, dtype=complex)
    ns = 1.0 + 0j
    for i in range(len(mu)):
        for j in range(i + 1, len(mu)):
            ns *= mu[i] * mu[j] - 1
    return {
        "LP": float(np.prod(mu - 1).real),
        "PD": float(np.prod(mu + 1).real),
        "NS": float(ns.real) if len(mu) > 1 else 1.0,
    }


def _has_complex_pair_on_unit_circle(multipliers: np.ndarray) -> bool:
    mu = np.asarray(multipliers, dtype=complex)
    return bool(np.any((np.abs(mu.imag) > 1e-8) & (np.abs(np.abs(mu) - 1) < 1e-4)))


# ---------------------------------------------------------------------------------------------
def _switch_at_period_doubling(
    sp: SpecialPoint, param, direction, to, bounds, options, verify, tol, max_period
) -> Branch | None:
    """Find the period-2k orbit born at a PD and follow it away from the PD (and its own
    doublings).  It is sought first on the continuation's side of the PD (a supercritical
    doubling), then on the other side (subcritical), perturbing the period-k fixed point along
    the eigenvector of the multiplier −1 by an amplitude ∝ sqrt(|λ − λ_PD|)."""
    cycle = sp.cycle
    if cycle is None or not cycle.success:
        return None
    mu, vectors = np.linalg.eig(cycle.jacobian)
    v = np.real(vectors[:, int(np.argmin(np.abs(mu + 1)))])
    v /= np.max(np.abs(v))
    steps = 2 * cycle.steps
    lam_pd = sp.param
    names = cycle.section_coordinates
    for side in (direction, -direction):
        # Not too close: the shooting Jacobian is singular at the PD, which amplifies the
        # discretisation error (and the mesh needed) of orbits found right next to it.
        for offset in (1e-3, 1e-2, 1e-4):
            lam = lam_pd + side * offset * max(abs(lam_pd), 1e-3)
            if to is not None and side == direction and (lam - to) * direction > 0:
                continue
            if not bounds[0] <= lam <= bounds[1]:
                continue
            try:
                model = cycle.model.replace(**{param: lam})
            except ParameterError:
                continue
            # Small perturbations first; large ones for strongly curved branches.
            for amplitude in (0.1, 0.03, 0.3, 1.0, 3.0):
                eps = amplitude * math.sqrt(offset)
                guess = dict(zip(names, cycle.section_point + eps * v, strict=True))
                try:
                    doubled = find_limit_cycle(model, guess, steps=steps, verify=verify, tol=tol)
                except GaitoptInputError:
                    continue
                if doubled.success and _born_at(doubled, cycle):
                    return _follow_branch(
                        doubled,
                        param,
                        side,
                        to if side == direction else None,
                        bounds,
                        options,
                        False,
                        True,
                        max_period,
                        verify,
                        tol,
                    )
    return None
