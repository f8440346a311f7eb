"""Deadbeat control: each step solve ``P(s, u) = s*`` for ``u`` by Newton on the shooting
equations."""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from functools import cached_property

import casadi as ca
import numpy as np

from ..result import LimitCycle
from ..shooting import shooting_problem
from .codegen import GeneratedPolicy, compile_policy, policy_function
from .decision import Decision, fmt_point, fmt_u
from .errors import ControlDesignError

_NEWTON = {
    "error_on_fail": False,
    "abstol": 1e-12,
    "abstolStep": 1e-12,
    "max_iter": 25,
    "show_eval_warnings": False,
}


class Deadbeat:
    """``u(s)`` solving ``P(s, u) = s*``: Newton on the shooting equations with ``u`` unknown.

    The unknowns are the gait's shooting unknowns (segment starts, phase durations; the mesh of
    the solved gait, so the accuracy is its discretisation error) and the input; the equations
    are the shooting equations of one step from ``lift(s)`` and ``P = s*`` in place of
    periodicity.  The guess is the solved gait.  A solution counts only if Newton converged,
    every phase lasts a positive time and ends on its guard admissibly and in the stated
    direction.

    Parameters
    ----------
    cycle : LimitCycle
        The solved gait (its mesh, its orbit as the guess).
    """

    def __init__(self, cycle: LimitCycle):
        if not cycle.success:
            raise ControlDesignError(f"`cycle` is not a solved gait ({cycle.message})")
        self.cycle = cycle
        self.model = cycle.model
        model_cls = type(cycle.model)
        self.shooting = shooting = shooting_problem(model_cls, cycle.discretisation, cycle.steps)
        self.m, self.n_u = shooting.m, len(model_cls.inputs)
        self.n_z = shooting.size - shooting.m
        self._guess = np.concatenate([self._orbit_unknowns(), np.asarray(cycle.inputs, float)])

    def _orbit_unknowns(self) -> np.ndarray:
        """The shooting unknowns ``z`` of the solved gait (its solution vector after ``s``)."""
        return self.shooting.unknowns_from_cycle(self.cycle)[self.shooting.m :]

    @cached_property
    def equations(self) -> ca.Function:
        """``F(v, s, s_target, p)`` with ``v = [z; u]``: the step's shooting equations and
        ``P(s, u) − s_target``."""
        shooting = self.shooting
        v = ca.MX.sym("v", self.n_z + self.n_u)
        s = ca.MX.sym("s", self.m)
        s_t = ca.MX.sym("s_target", self.m)
        p = ca.MX.sym("p", self.model.p.size)
        F = shooting.residual(ca.vertcat(s, v[: self.n_z]), v[self.n_z :], p)
        G, periodicity = F[: shooting.n_g], F[shooting.n_g :]
        eq = ca.vertcat(G, periodicity + s - s_t)  # periodicity = P − s: P = s_target instead
        return ca.Function(
            "deadbeat_equations", [v, s, s_t, p], [eq], ["v", "s", "s_target", "p"], ["F"]
        ).expand()

    @cached_property
    def _predictor(self) -> tuple[np.ndarray, np.ndarray]:
        """``(dv/ds, dv/ds_target)`` at the gait (implicit function theorem on the equations):
        Newton starts from the first-order prediction, which saves half the iterations."""
        eq = self.equations
        v, s, s_t, p = (ca.SX.sym(n, eq.size1_in(i)) for i, n in enumerate("vstp"))
        F = eq(v, s, s_t, p)
        J = ca.Function("predictor", [v, s, s_t, p], [ca.jacobian(F, ca.vertcat(v, s, s_t))])
        s_star = self.cycle.section_point
        Jn = np.asarray(J(self._guess, s_star, s_star, self.model.p), dtype=float)
        n_v = self._guess.size
        sens = -np.linalg.solve(Jn[:, :n_v], Jn[:, n_v:])
        return sens[:, : self.m], sens[:, self.m :]

    @cached_property
    def solver(self) -> ca.Function:
        """The CasADi Newton rootfinder ``v(v0, s, s_target, p)``."""
        return ca.rootfinder("deadbeat", "newton", self.equations, _NEWTON)

    def solve(
        self,
        s: Sequence[float] | np.ndarray,
        *,
        target: Sequence[float] | np.ndarray | None = None,
        p: np.ndarray | None = None,
        guess: np.ndarray | None = None,
    ) -> Decision:
        """The deadbeat input from section coordinates ``s``.

        Parameters
        ----------
        s : array_like
            Section coordinates now.
        target : array_like, optional
            Next section coordinates wanted (default: the gait's fixed point).
        p : numpy.ndarray, optional
            Parameter vector the step is predicted with (default: the model's; e.g. a known
            ground height).
        guess : numpy.ndarray, optional
            Start ``v = [z; u]`` for Newton (default: the first-order prediction from the gait;
            if Newton fails from there, a continuation from the gait in eight steps).
        """
        start = time.perf_counter()
        s = np.asarray(s, dtype=float).ravel()
        s_t = self.cycle.section_point if target is None else np.asarray(target, float).ravel()
        p = self.model.p if p is None else np.asarray(p, dtype=float)
        if guess is None:
            d_s, d_t = self._predictor
            s_star = self.cycle.section_point
            v0 = self._guess + d_s @ (s - s_star) + d_t @ (s_t - s_star)
        else:
            v0 = guess
        v = np.asarray(self.solver(v0, s, s_t, p), dtype=float).ravel()
        if guess is None and not self._converged(v, s, s_t, p):
            v = self._continuation(s, s_t, p)
        stats = self.solver.stats()
        iterations = int(stats.get("iter_count", 0))
        u = v[self.n_z :]
        problem = None
        if not np.all(np.isfinite(v)):
            problem = (
                "no step exists from there (the step's equations are undefined on the way, "
                "e.g. an apex below the touchdown height)"
            )
        elif not self._converged(v, s, s_t, p):
            problem = f"Newton found no input after {iterations} iterations"
        else:
            problem = self._check(s, v, u, p)
        bounds = self.model.input_box()
        if problem is None and bounds is not None:
            lo, hi = (np.asarray(b, dtype=float) for b in bounds)
            if np.any(u < lo) or np.any(u > hi):
                problem = (
                    f"the input needed, {fmt_u(self.model, u)}, is outside its range "
                    f"[{fmt_u(self.model, lo)}, {fmt_u(self.model, hi)}]"
                )
        self.last_solution = v
        elapsed = time.perf_counter() - start
        if problem is not None:
            return Decision(False, problem, u, s, s_t, iterations, elapsed)
        return Decision(
            True,
            f"deadbeat: {fmt_u(self.model, u)} brings {fmt_point(self.model, s)} to "
            f"{fmt_point(self.model, s_t)}",
            u,
            s,
            s_t,
            iterations,
            elapsed,
        )

    def _converged(self, v, s, s_t, p) -> bool:
        return bool(self.solver.stats()["success"]) and self._residual(v, s, s_t, p) <= 1e-9

    def _continuation(self, s, s_t, p, pieces: int = 8) -> np.ndarray:
        """Far from the gait: walk from the gait to ``(s, s_target)`` in ``pieces`` steps, each
        Newton solve starting from the last (the last result, converged or not)."""
        s_star = self.cycle.section_point
        v = self._guess
        for k in range(1, pieces + 1):
            a = k / pieces
            s_k, t_k = s_star + a * (s - s_star), s_star + a * (s_t - s_star)
            v = np.asarray(self.solver(v, s_k, t_k, p), dtype=float).ravel()
            if not self._converged(v, s_k, t_k, p):
                break
        return v

    def _residual(self, v, s, s_t, p) -> float:
        """Max-norm of the equations at ``v`` (Newton's own success flag is not enough)."""
        F = np.asarray(self.equations(v, s, s_t, p), dtype=float)
        return float(np.max(np.abs(F))) if np.all(np.isfinite(F)) else float("inf")

    @cached_property
    def _checks(self) -> ca.Function:
        return self.shooting.checks.expand()

    def _check(self, s, v, u, p) -> str | None:
        """Positive durations; each phase ends on its guard admissibly, in its direction."""
        shooting = self.shooting
        w = np.concatenate([s, v[: self.n_z]])
        outputs = self._checks(w, u, p)
        _, dg, adm, durations = (np.asarray(a, dtype=float).ravel() for a in outputs)
        model = self.model
        for k, i in enumerate(shooting.chain):
            phase = model.phases[i]
            transition = phase.transitions[0]
            if not durations[k] > 0:
                return f"no valid step: phase '{phase.name}' would last {durations[k]:.3g} s"
            if not adm[k] > 0 or not transition.direction * dg[k] > 0:
                return (
                    f"no valid step: phase '{phase.name}' would not end by '{transition.name}' "
                    f"as a gait step must"
                )
        return None

    def feasible_range(
        self, interval: tuple[float, float] | None = None, *, samples: int = 41
    ) -> tuple[float, float] | None:
        """For a 1-D section: the interval around the target from which deadbeat succeeds.

        Sampled on ``interval`` (default: the model's ``map_domain()`` if it has one, else
        ±50 % around the fixed point), its ends located by bisection to 1e-6 relative.
        ``None`` for sections of more than one coordinate.
        """
        if self.m != 1:
            return None
        key = (interval, samples)
        cache = self.__dict__.setdefault("_ranges", {})
        if key in cache:
            return cache[key]
        s_star = float(self.cycle.section_point[0])
        if interval is None:
            domain = self.model.map_domain()
            interval = domain or (s_star - 0.5 * abs(s_star), s_star + 0.5 * abs(s_star))
        lo, hi = map(float, interval)

        def ok(x: float) -> bool:
            return self.solve([x]).success

        if not ok(s_star):
            cache[key] = None
            return None
        ends = []
        for edge in (lo, hi):
            grid = np.linspace(s_star, edge, samples)[1:]
            good = s_star
            bad = None
            for x in grid:
                if ok(x):
                    good = x
                else:
                    bad = x
                    break
            if bad is None:
                ends.append(good)
                continue
            for _ in range(40):
                mid = 0.5 * (good + bad)
                if abs(bad - good) < 1e-6 * max(1.0, abs(mid)):
                    break
                if ok(mid):
                    good = mid
                else:
                    bad = mid
            ends.append(good)
        cache[key] = (float(ends[0]), float(ends[1]))
        return cache[key]

    # -- generated C (gaitopt.control.codegen) -------------------------------------------------
    def policy_function(self, steps: Sequence[int] | None = None) -> ca.Function:
        """The deadbeat policy as one CasADi function (see
        :func:`gaitopt.control.codegen.policy_function`)."""
        return policy_function(self, steps)

    def codegen(
        self, directory: str | os.PathLike | None = None, *, steps: Sequence[int] | None = None
    ) -> GeneratedPolicy:
        """The policy as compiled C (see :func:`gaitopt.control.codegen.compile_policy`)."""
        return compile_policy(self, directory, steps=steps)
