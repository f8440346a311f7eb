"""The predictor–corrector that follows one bifurcation curve (see :mod:`gaitopt.curves.follow`
for the method), with the mesh following the discretisation error, certified points, and the
codimension-two points and the boundary located along the way."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..continuation.special import LOCATE_TOL
from ..result import LimitCycle
from ..shooting import ShootingProblem, certify, shooting_problem
from ..stability import section_jacobians
from . import codim2
from .locate import CurvePoints
from .result import CurvePoint
from .system import (
    CONSTRAINT_QUANTITIES,
    Parametrisation,
    augmented_system,
    bordering,
    constraint_condition,
    return_map_jacobian,
    singular_matrix,
)

__all__ = ["CurveFollower", "MeshLimit"]

_LOCATE_TOL = LOCATE_TOL  # parameter accuracy of located points (absolute), as continuation's
_MAX_MESH_REFINEMENTS = 2
#: A point of a boundary curve is exactly on the boundary, where the gait is marginal (a foot
#: that grazes the slope, a lift-off rate of zero); the gait certified for it lies just inside,
#: its first parameter moved by these fractions of its scale in turn until the verification
#: simulation confirms it (one-parameter continuation's boundaries are located to 1e-10 alike).
_INSIDE = (1e-9, 1e-8, 1e-7, 1e-6)


class MeshLimit(Exception):
    """The discretisation error stays above the tolerance at the finest mesh allowed."""


# ---------------------------------------------------------------------------------------------
class CurveFollower(CurvePoints):
    """One curve from a located special point towards ``to``."""

    def __init__(self, cycle, kind, paths, boundary, to, at, bounds, options, verify, tol):
        self.kind, self.paths, self.boundary = kind, paths, boundary
        self.options, self.verify, self.tol = options, verify, tol
        par = Parametrisation.build(cycle.model, paths, cycle.inputs)
        # A second parameter starting at (or near) zero is scaled by a tenth of its span, so that
        # the arclength step means the same share of the way whatever the start value.
        span = abs(float(to) - par.lam0[1])
        scale = par.scale.copy()
        scale[1] = max(scale[1], 0.1 * span)
        self.par = replace(par, scale=scale)
        self.to = float(to)
        self.dir2 = 1.0 if self.to > self.par.lam0[1] else -1.0
        self.at = sorted(float(v) for v in at)
        self.bounds = (-math.inf, math.inf) if bounds is None else tuple(map(float, bounds))
        self.steps = cycle.steps
        self.system = augmented_system(
            type(cycle.model), cycle.discretisation, cycle.steps, kind, boundary
        )
        self.start_cycle = cycle
        self.finest = cycle.discretisation.rk_steps * 2**_MAX_MESH_REFINEMENTS
        self.b, self.c = self._border(cycle.jacobian)
        self.cycles: list[LimitCycle] = []
        self.located: list[tuple[float, float]] = []  # (λ₁, λ₂) on the curve, per cycle
        self.special_points: list[CurvePoint] = []
        self.stop = ""
        self.extra0 = np.zeros(self.system.extra)  # initial extra unknowns (t* of a grazing)
        self.sigma = 1.0  # σ g > 0 where the gait exists (boundary curves)
        self._shift = 0.0  # the boundary's margin row is g − shift (the gait just inside)
        self._last = None  # the last evaluation, reused at the same point

    # -- the equations ---------------------------------------------------------------------
    @property
    def problem(self) -> ShootingProblem:
        return self.system.problem

    def lam(self, y: np.ndarray) -> np.ndarray:
        return y[-2:] * self.par.scale

    def _border(self, A):
        if self.kind == "boundary":
            return np.zeros(1), np.zeros(1)
        return bordering(self.kind, np.asarray(A, dtype=float))

    def evaluate(self, y, gradient: bool = True):
        key = (y.tobytes(), self._shift, self.b.tobytes(), self.c.tobytes(), id(self.system))
        if self._last is not None and self._last[0] == key:  # the tangent, tests, multipliers
            H, J, A = self._last[1]
            if not gradient or np.all(np.isfinite(J)):
                return H.copy(), J.copy(), A.copy()
        H, J, A = self.system.evaluate(y, self.b, self.c, self.par, gradient=gradient)
        if self._shift:
            H[self.problem.size] -= self._shift
        self._last = (key, (H.copy(), J.copy(), A.copy()))
        return H, J, A

    def w(self, y: np.ndarray) -> np.ndarray:
        """The shooting unknowns of ``y``."""
        return y[: self.problem.size]

    def accept(self, cycle: LimitCycle, y: np.ndarray) -> None:
        """Append a certified point (its gait and its exact curve parameters)."""
        self.cycles.append(cycle)
        self.located.append(tuple(float(v) for v in self.lam(y)))

    def weights(self, y: np.ndarray) -> np.ndarray:
        n = y.size - 2
        return np.concatenate([np.full(n, 1.0 / n), [1.0, 1.0]])

    def tangent(self, y: np.ndarray, previous: np.ndarray) -> np.ndarray:
        _, J, _ = self.evaluate(y)
        W = self.weights(y)
        rhs = np.zeros(J.shape[0] + 1)
        rhs[-1] = 1.0
        t = np.linalg.solve(np.vstack([J, previous * W]), rhs)
        t /= math.sqrt(float(t @ (W * t)))
        return t if float(t @ (W * previous)) > 0 else -t

    def correct(self, y_pred: np.ndarray, row: np.ndarray, target: float | None = None):
        """Newton on ``H(y) = 0`` plus one scalar constraint: ``⟨row, y − y_pred⟩ = 0``
        (pseudo-arclength, ``row = W t``) or, with ``target``, ``⟨row, y⟩ = target`` (a
        parameter held fixed).  Returns ``(y, converged, iterations)``."""
        # The shooting rows of ∂H/∂y are exact at every iterate (they come with H from the
        # kernels); the condition's row is refreshed only while Newton converges slowly (its
        # gradient costs two more kernel Jacobians): a chord step in that one row.  Convergence
        # is still tested on the exact H.
        y = y_pred.copy()
        H, J, _ = self.evaluate(y)
        g_row = J[self.problem.size :].copy()
        last = math.inf
        for k in range(1, self.options.max_corrector + 1):
            J[self.problem.size :] = g_row
            if not (np.all(np.isfinite(H)) and np.all(np.isfinite(J))):
                return y, False, k
            extra = float(row @ y) - target if target is not None else float(row @ (y - y_pred))
            try:
                dy = np.linalg.solve(np.vstack([J, row]), -np.concatenate([H, [extra]]))
            except np.linalg.LinAlgError:
                return y, False, k
            y = y + dy
            size = float(np.max(np.abs(dy)))
            H, J, _ = self.evaluate(y, gradient=size > 0.1 * last)
            if np.all(np.isfinite(J[self.problem.size :])):
                g_row = J[self.problem.size :].copy()
            last = size
            small = size < 1e-9 * (1 + np.max(np.abs(y)))
            if small and np.all(np.isfinite(H)) and np.max(np.abs(H)) <= self.tol:
                return y, True, k
        return y, False, self.options.max_corrector

    def fix(self, which: int, value: float) -> tuple[np.ndarray, float]:
        """The constraint row holding curve parameter ``which`` at ``value``."""
        row = np.zeros(self.problem.size + self.system.extra + 2)
        row[row.size - 2 + which] = 1.0
        return row, value / self.par.scale[which]

    # -- points ---------------------------------------------------------------------------
    def multipliers_at(self, y: np.ndarray) -> np.ndarray:
        _, _, A = self.evaluate(y, gradient=False)
        return np.linalg.eigvals(A) if A.size else np.zeros(0, complex)

    def tests_at(self, y: np.ndarray, t: np.ndarray) -> dict[str, float]:
        return codim2.tests(
            self.kind, self.multipliers_at(y), t[-2:], (self.paths[0].name, self.paths[1].name)
        )

    def values(self, y: np.ndarray) -> dict[str, float]:
        lam = self.lam(y)
        return {self.paths[0].name: float(lam[0]), self.paths[1].name: float(lam[1])}

    def certified(self, y: np.ndarray) -> tuple[LimitCycle | None, np.ndarray]:
        """The gait at ``y`` (mesh refined while the discretisation error exceeds ``tol``) and
        the possibly re-corrected ``y``; None where the parameters leave their range."""
        lam = self.lam(y)
        model = self.par.model_at(lam)
        if model is None or not self.bounds[0] <= lam[0] <= self.bounds[1]:
            return None, y
        error = self._discretisation_error(y)
        while error > self.tol and self.problem.disc.rk_steps < self.finest:
            self.system = augmented_system(
                type(model), self.problem.disc.refined(), self.steps, self.kind, self.boundary
            )
            y, ok, _ = self.correct(y, *self.fix(1, float(lam[1])))
            if not ok:
                return None, y
            error = self._discretisation_error(y)
        if error > self.tol:
            raise MeshLimit(
                f"the discretisation error {error:.2g} exceeds tol {self.tol:g} at the finest "
                f"mesh ({self.problem.disc.rk_steps} RK steps per segment) near {self._where(y)}"
            )
        if self.kind == "boundary":
            return self._certified_inside(y, error), y
        lam = self.lam(y)
        model = self.par.model_at(lam)
        if model is None:
            return None, y
        cycle = certify(
            model, self.problem, self.w(y), self.par.u(lam), verify=self.verify, tol=self.tol,
            discretisation_error=error,
        )  # fmt: skip
        return cycle, y

    def _certified_inside(self, y: np.ndarray, error: float) -> LimitCycle | None:
        """The gait certified for a point exactly on a boundary: the one just inside, at the
        same second parameter and the first moved by ``δ = f · scale`` (``f`` from
        :data:`_INSIDE` in turn) to the side where ``σ g`` grows (``g`` the boundary's margin:
        the minimum of a constraint, a lift-off rate, a duration ...; ``σ g > 0`` inside), the
        orbit solved there by Newton on the shooting equations alone."""
        N = self.problem.size
        _, J, _ = self.evaluate(y)
        rows = [r for r in range(J.shape[0]) if r != N]
        e1, e2 = np.zeros(y.size), np.zeros(y.size)
        e1[-2], e2[-1] = 1.0, 1.0
        rhs = np.zeros(len(rows) + 2)
        rhs[-1] = 1.0
        try:
            dy = np.linalg.solve(np.vstack([J[rows], e2, e1]), rhs)  # dy/dℓ₁ along the margin
        except np.linalg.LinAlgError:
            return None
        dg = float(J[N] @ dy)
        if not np.isfinite(dg) or dg == 0:
            return None
        cycle = None
        for f in _INSIDE:
            dl = math.copysign(f, self.sigma * dg)  # in ℓ₁ = λ₁ / scale
            lam = self.lam(y) + np.array([dl * self.par.scale[0], 0.0])
            model = self.par.model_at(lam)
            if model is None or not self.bounds[0] <= lam[0] <= self.bounds[1]:
                return None
            u, p = self.par.u(lam), self.par.p(lam)
            w = self.w(y + dy * dl)
            for _ in range(self.options.max_corrector):
                ev = self.problem.evaluate(w, u, p)
                if np.max(np.abs(ev.F)) <= self.tol or not np.all(np.isfinite(ev.F)):
                    break
                w = w - np.linalg.solve(ev.F_w, ev.F)
            cycle = certify(
                model, self.problem, w, u, verify=self.verify, tol=self.tol,
                discretisation_error=error,
                note=f"certified {f:g} × scale inside the boundary ({self.paths[0].name} moved by "
                f"{lam[0] - self.lam(y)[0]:.3g})",
            )  # fmt: skip
            if cycle.success:
                return cycle
        return cycle

    def _discretisation_error(self, y: np.ndarray) -> float:
        """One Newton correction of the extended system towards twice the RK steps: the
        shooting residual and the defining condition at the finer mesh (max over ``w`` and
        both parameters, in their units)."""
        lam = self.lam(y)
        p, u = self.par.p(lam), self.par.u(lam)
        F_fine = self.problem.fine_residual(self.w(y), u, p)
        H, J, _ = self.evaluate(y)
        fine = shooting_problem(type(self.par.model), self.problem.disc.refined(), self.steps)
        g_fine = self._condition(fine, y[:-2], u, p)
        N = self.problem.size
        rhs = np.concatenate([F_fine, g_fine - H[N:], [0.0]])
        row = np.zeros(y.size)
        row[-1] = 1.0  # at fixed λ₂: how far the curve's λ₁ moves
        try:
            dy = np.linalg.solve(np.vstack([J, row]), rhs)
        except np.linalg.LinAlgError:
            return math.inf
        return float(max(np.max(np.abs(dy[:-2])), np.max(np.abs(dy[-2:] * self.par.scale))))

    def _condition(self, problem: ShootingProblem, wz, u, p) -> np.ndarray:
        """The defining condition ``g`` evaluated numerically with another transcription
        (``wz``: the shooting unknowns and the extra ones)."""
        if self.kind == "boundary" and self.boundary[0] in CONSTRAINT_QUANTITIES:
            g = constraint_condition(
                problem.model_cls, problem.disc, problem.cycles, self.boundary
            )(wz, u, p)
            return np.asarray(g, dtype=float).ravel() - np.array(
                [self._shift] + [0.0] * self.system.extra
            )
        w = wz[: problem.size]
        if self.kind == "boundary":
            what, k = self.boundary[:2]
            _, dg, adm, durations = (
                np.asarray(v, dtype=float).ravel() for v in problem.checks(w, u, p)
            )
            value = {"duration": durations, "grazing": dg, "admissible": adm}[what][k]
            return np.array([float(value) - self._shift])
        if problem.assembly() is not None:  # the compiled kernels of the finer mesh
            A = return_map_jacobian(problem, problem.evaluate(w, u, p).F_w)
        else:
            J_w, J_u, _, _ = problem.linearisation(w, u, p)
            A, _ = section_jacobians(np.asarray(J_w), np.asarray(J_u), problem.m, problem.n_g)
        M = singular_matrix(self.kind, A)
        n = M.shape[0]
        K = np.block([[M, self.b[:, None]], [self.c[None, :], np.zeros((1, 1))]])
        rhs = np.zeros(n + 1)
        rhs[-1] = 1.0
        return np.array([float(np.linalg.solve(K, rhs)[-1])])

    # -- the loop ----------------------------------------------------------------------------
    def run(self) -> None:
        try:
            self._run()
        except MeshLimit as exc:
            self.stop = f"the curve stops: {exc}"

    def _run(self) -> None:
        opts = self.options
        problem = self.problem
        y = np.concatenate(
            [
                problem.unknowns_from_cycle(self.start_cycle),
                self.extra0,
                self.par.lam0 / self.par.scale,
            ]
        )
        y, ok, _ = self.correct(y, *self.fix(1, float(self.par.lam0[1])))
        if not ok:
            self.stop = "the extended system does not converge at the start point"
            return
        cycle, y = self.certified(y)
        if cycle is None or not cycle.success:
            why = cycle.message if cycle is not None else "parameters out of range"
            self.stop = f"the start point is not a certified gait: {why}"
            return
        self.accept(cycle, y)
        self.b, self.c = self._border(cycle.jacobian)
        start = np.zeros_like(y)
        start[-1] = self.dir2
        t = self.tangent(y, start)
        tests = self.tests_at(y, t)
        h = opts.step
        while len(self.cycles) < opts.max_points:
            y_new, ok, iterations = self.correct(y + h * t, self.weights(y) * t)
            target = None
            if ok and (self.lam(y_new)[1] - self.to) * self.dir2 >= 0:
                target = self.to
            if ok:
                for value in self.at:  # exact points requested on the way
                    if (value - self.lam(y)[1]) * self.dir2 > 0 and (
                        self.lam(y_new)[1] - value
                    ) * self.dir2 > 0:
                        self._insert_at(y, t, value)
            if target is not None:
                y_new, ok = self._land(y, t, target)
            if not ok:
                h /= 2
                if h < opts.min_step:
                    self.stop = f"the corrector cannot continue the curve near {self._where(y)}"
                    return
                continue
            cycle, y_new = self.certified(y_new)
            if cycle is None or not cycle.success:
                if cycle is None and self.par.model_at(self.lam(y_new)) is None:
                    self.stop = f"a parameter leaves its valid range near {self._where(y_new)}"
                    return
                if cycle is None and not self.bounds[0] <= self.lam(y_new)[0] <= self.bounds[1]:
                    self.stop = f"{self.paths[0].name} leaves its bounds near {self._where(y_new)}"
                    return
                self._boundary(y, t, h if target is None else None, y_new, cycle)
                return
            t_new = self.tangent(y_new, t)
            new_tests = self.tests_at(y_new, t_new)
            self._codim2_between(y, t, y_new, tests, new_tests)
            self.accept(cycle, y_new)
            self.b, self.c = self._border(cycle.jacobian)
            if target is not None:
                self.stop = f"reached {self.paths[1].name} = {self.to:.10g}"
                return
            y, t, tests = y_new, t_new, new_tests
            # chord correctors take one iteration more than Newton (see correct): grow at ≤ 4
            h = min(opts.max_step, h * 1.5) if iterations <= 4 else h / 2 if iterations >= 7 else h
        self.stop = f"stopped after {opts.max_points} points"

    def _where(self, y: np.ndarray) -> str:
        return ", ".join(f"{k} = {v:.8g}" for k, v in self.values(y).items())

    def _land(self, y, t, value) -> tuple[np.ndarray, bool]:
        """Correct at exactly ``λ₂ = value`` from a predictor along the tangent."""
        dl = value / self.par.scale[1] - y[-1]
        y_pred = y + t * (dl / t[-1]) if abs(t[-1]) > 1e-12 else y.copy()
        y_pred[-1] = value / self.par.scale[1]
        y_new, ok, _ = self.correct(y_pred, *self.fix(1, value))
        return y_new, ok

    def _insert_at(self, y, t, value) -> None:
        y_at, ok = self._land(y, t, value)
        if not ok:
            return
        cycle, y_at = self.certified(y_at)
        if cycle is not None and cycle.success:
            self.accept(cycle, y_at)
