"""One direction of pseudo-arclength continuation from a certified gait (Keller's method;
Allgower & Georg, "Numerical Continuation Methods", §2.1): predictor along the tangent,
Newton corrector with the arclength condition, adaptive step, every point certified."""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from ..hybrid import HybridModel
from ..orbit import structured
from ..result import LimitCycle
from ..shooting import MultipleShooting, ShootingProblem, certify, shooting_problem
from ..shooting.pattern import pattern_of
from ..stability import section_jacobians
from .branch import SpecialPoint
from .special import SpecialPoints, test_functions

__all__ = ["Follower"]

_MAX_MESH_REFINEMENTS = 4
#: An error estimate at most this many times the step of the residual alone is at the residual's
#: rounding floor (:meth:`Follower._try_coarser`).
NOISE_FLOOR = 10.0


class Follower(SpecialPoints):
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
        self.nominal = bool(self.u0.size) and np.allclose(self.u0, nominal, rtol=0, atol=1e-15)
        if self.nominal:
            h = 1e-6 * self.scale
            lam0 = float(getattr(model, param))
            try:
                up = model.replace(**{param: lam0 + h}).nominal_input()
                self.du = (up - nominal) / h  # nominal inputs are affine in the parameter
            except ParameterError:
                down = model.replace(**{param: lam0 - h}).nominal_input()
                self.du = (nominal - down) / h
        self.lam0 = float(getattr(model, param))
        # The base class's nominal input (u = 0) depends on no parameter: no model to build.
        self.nominal_varies = type(model).nominal_input is not HybridModel.nominal_input
        disc = first.discretisation or MultipleShooting(*type(model).mesh)
        self.problem: ShootingProblem = shooting_problem(type(model), disc, first.steps)
        self.refinements = 0
        self._coarsen_wait, self._coarsen_backoff = 0, 1  # see _try_coarser
        self._refined_here = False
        self._last_evaluation = None
        # The evaluation at the last certified point, kept while special points between it and
        # the one before are located (its tangent is taken after them).
        self._accepted = None
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
        """The per-step input at the point ``y``.  A nominal input that the parameter sets is
        the model's own at that parameter, exactly (``du`` from a difference quotient is right
        only to ~1e-10, and a gait whose input differs from its model's nominal one by that much
        is no longer recognised as nominal downstream, e.g. by the switch at a PD)."""
        lam = self.lam(y)
        if self.nominal and lam != self.lam0 and self.nominal_varies:
            try:
                return self.model0.replace(**{self.param: lam}).nominal_input()
            except ParameterError:  # a predictor or corrector iterate outside the range
                pass  # (never accepted as a point: the follower stops at the range's end)
        return self.u0 + self.du * (lam - self.lam0)

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
        key = (id(self.problem), y.tobytes())
        if self._accepted is not None and self._accepted[0] == key:
            return self._accepted[1]
        if self._last_evaluation is None or self._last_evaluation[0] != key:
            self._last_evaluation = (key, self.problem.evaluate(y[:-1], self._u(y), self._p(y)))
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
        t = self._solve_bordered(K, rhs)
        t /= math.sqrt(float(t @ (W * t)))
        return t if float(t @ (W * previous)) > 0 else -t

    def correct(self, y_pred: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, bool, int]:
        """Newton on ``F(y) = 0, ⟨t, y − y_pred⟩_W = 0``; converged when ``|F| ≤ tol`` after a
        step below 1e-9 (relative)."""
        y = y_pred.copy()
        W = self.weights(y)
        F, J = self.jacobian(y)
        for k in range(1, self.options.max_corrector + 1):
            if not np.all(np.isfinite(F)):
                return y, False, k
            G = np.concatenate([F, [float(t @ (W * (y - y_pred)))]])
            dy = self._solve_bordered(np.vstack([J, t * W]), -G)
            y = y + dy
            F, J = self.jacobian(y)
            small = np.max(np.abs(dy)) < 1e-9 * (1 + np.max(np.abs(y)))
            if small and np.max(np.abs(F)) <= self.tol:
                return y, True, k
        return y, False, self.options.max_corrector

    def _solve_bordered(self, K: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """``K⁻¹ rhs`` for ``K = [[F_w, F_ℓ], [rowᵀ]]``: on the shooting Jacobian's block
        pattern bordered by the parameter's column and the arclength row where the system is
        large (period-k orbits, :mod:`gaitopt.orbit.structured`), densely otherwise."""
        pattern = pattern_of(self.problem)
        return structured.solve(K, rhs, None if pattern is None else pattern.bordered())

    # -- a point on the branch ---------------------------------------------------------------
    def model_at(self, y: np.ndarray) -> HybridModel | None:
        try:
            return self.model0.replace(**{self.param: self.lam(y)})
        except ParameterError:
            return None

    def multipliers_at(self, y: np.ndarray) -> np.ndarray:
        """Multipliers only (no checks): for locating special points."""
        ev = self._evaluate(y)
        J_w = self.problem.map_jacobian(ev.F_w)
        A, _ = section_jacobians(J_w, ev.F_u, self.problem.m, self.problem.n_g)
        return np.linalg.eigvals(A) if A.size else np.zeros(0, complex)

    def certified(self, y: np.ndarray) -> tuple[LimitCycle | None, np.ndarray]:
        """The gait at ``y`` (None where the parameter leaves its range or the refined mesh
        cannot be corrected) and the point it was certified at (moved by a mesh change).

        The mesh follows the discretisation error: refined (steps doubled) while the estimate
        exceeds ``tol``, coarsened again where half the steps would still meet it (the error
        scales as h⁸; :meth:`_try_coarser`), level by level while it does."""
        model = self.model_at(y)
        if model is None:
            return None, y
        error = self._discretisation_error(y)
        while error > self.tol and self.refinements < _MAX_MESH_REFINEMENTS:
            self.problem = shooting_problem(
                type(model), self.problem.disc.refined(), self.problem.cycles
            )
            self.refinements += 1
            self._refined_here = True
            y, ok, _ = self.correct(y, self._unit_lambda())
            if not ok:
                return None, y
            error = self._discretisation_error(y)
        again = False
        while self.problem.disc.rk_steps > type(model).mesh[1] and self._try_coarser(
            y, error, again
        ):
            coarse = shooting_problem(
                type(model), self.problem.disc.coarsened(), self.problem.cycles
            )
            previous = self.problem
            self.problem = coarse
            y_coarse, ok, _ = self.correct(y, self._unit_lambda())
            coarse_error = self._discretisation_error(y_coarse) if ok else math.inf
            if coarse_error <= self.tol:
                y, error = y_coarse, coarse_error
                self.refinements = max(self.refinements - 1, 0)
                self._coarsen_backoff, again = 1, True
            else:
                self.problem = previous
                self._coarsen_wait = self._coarsen_backoff
                self._coarsen_backoff *= 2
                break
        cycle = certify(
            model,
            self.problem,
            y[:-1],
            self._u(y),
            verify=self.verify,
            tol=self.tol,
            discretisation_error=error,
            evaluation=self._evaluate(y),
        )
        self._accepted = self._last_evaluation
        return cycle, y

    def _try_coarser(self, y: np.ndarray, error: float, again: bool = False) -> bool:
        """Whether to try the mesh with half the RK steps at ``y`` (its error estimate
        ``error``): where the estimate is below ``tol / 1000`` (the coarser mesh's error, about
        2⁸ times larger, then meets ``tol``); or where it is below ``tol / 10`` but no larger than
        :data:`NOISE_FLOOR` times the step the residual left at ``y`` alone would take (``|F_w⁻¹
        F(y)|``): then the estimate measures that residual, at its rounding floor, and not the
        mesh (a period-8 orbit on a refined mesh: ~1e-12 either way), so only trying says whether
        the coarser mesh meets ``tol``.  The second kind only for a mesh the branch started on
        (its first gait's, e.g. chosen by the switch's solve next to a PD), never once the branch
        has refined its mesh itself.  After a failed try of the second kind the next points skip
        it, for twice as many points after each further failure.  ``again``: a coarser mesh
        was just taken at this point; only the second kind goes on down (one level per point by
        the first, as the error's h⁸ scaling has it)."""
        if error < self.tol / 1000 and not again:
            return True
        if error >= self.tol / 10 or self._coarsen_wait > 0 or self._refined_here:
            self._coarsen_wait = max(self._coarsen_wait - 1, 0)
            return False
        ev = self._evaluate(y)
        leftover = structured.solve(ev.F_w, ev.F, pattern_of(self.problem))
        return bool(error <= NOISE_FLOOR * np.max(np.abs(leftover)))

    def _unit_lambda(self) -> np.ndarray:
        t = np.zeros(self.problem.size + 1)
        t[-1] = 1.0  # correct at fixed parameter
        return t

    def _discretisation_error(self, y: np.ndarray) -> float:
        F_fine = self.problem.fine_residual(y[:-1], self._u(y), self._p(y))
        F_w = self._evaluate(y).F_w
        step = structured.solve(F_w, F_fine, pattern_of(self.problem))
        return float(np.max(np.abs(step)))

    # -- the loop ----------------------------------------------------------------------------
    def run(self) -> Follower:
        opts = self.options
        first = self.first
        y = np.concatenate(
            [
                self.problem.unknowns_from_cycle(first),
                [float(getattr(first.model, self.param)) / self.scale],
            ]
        )
        start = np.zeros_like(y)
        start[-1] = self.direction
        t = self.tangent(y, start)
        h = opts.step
        tests = test_functions(first.multipliers)
        slow = 0
        while len(self.cycles) < opts.max_points:
            y_new, ok, iterations = self.correct(y + h * t, t)
            lam_new = self.lam(y_new)
            limit = self._crossed_limit(lam_new) if ok else None
            if limit is not None:
                y_new, ok = self._land_on(limit, y, t)
                lam_new = self.lam(y_new)
                if ok:
                    cycle, y_new = self.certified(y_new)
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
            cycle, y_new = self.certified(y_new)
            if cycle is None or not cycle.success:
                if cycle is None and self.model_at(y_new) is None:
                    self.stop = f"{self.param} left its valid range near {lam_new:.10g}"
                    return self
                self._boundary(y, t, h, cycle.message if cycle is not None else "")
                return self
            new_tests = test_functions(cycle.multipliers)
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
