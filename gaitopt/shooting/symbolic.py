"""The shooting equations as one CasADi graph (:class:`SymbolicShooting`, a base of
:class:`~gaitopt.shooting.problem.ShootingProblem`): for IPOPT, for the symbolic uses of the
bifurcation curves (:mod:`gaitopt.curves.system`) and as the fallback where a model has no
compiled kernels.  Each function is built on first use."""

from __future__ import annotations

from functools import cached_property
from types import SimpleNamespace

import casadi as ca

from ..hybrid import rate_along
from ..integrators import segment_function, segment_trajectory_function

__all__ = ["SymbolicShooting"]

#: CasADi ``rootfinder`` options of the symbolic Newton (the compiled one stops the same way).
NEWTON_OPTIONS = {
    "error_on_fail": False,
    "show_eval_warnings": False,  # a diverging guess is reported in the result, not on stderr
    "abstol": 1e-12,
    "abstolStep": 1e-15,
    "max_iter": 30,
}


class SymbolicShooting:
    """The CasADi functions of a shooting problem (see :class:`ShootingProblem` for the
    attributes this base reads: ``model_cls``, ``disc``, ``phases``, ``section``, ``chain``,
    ``section_index``, ``m``, ``size``, ``n_g``, ``layout``)."""

    @cached_property
    def _graph(self):
        """The shooting equations as one CasADi MX graph (for IPOPT, the symbolic uses of the
        curves and the fallback where a model has no kernels)."""
        model_cls, disc, m, S = self.model_cls, self.disc, self.m, self.disc.segments
        s = ca.MX.sym("s", m)
        u = ca.MX.sym("u", len(model_cls.inputs))
        p = ca.MX.sym("p", len(model_cls.parameter_specs()))
        segment = {
            i: segment_function(ph.flow, disc.rk_steps).map(S) for i, ph in enumerate(self.phases)
        }
        sampler = self._samplers
        z_parts, nodes, durations = [], [], []
        for k, i in enumerate(self.chain):
            n = self.phases[i].n
            free_cols = S - 1 if k == 0 else S
            free = ca.MX.sym(f"X{k}", n, free_cols)
            X = ca.horzcat(self.section.lift(s, p), free) if k == 0 else free
            T = ca.MX.sym(f"T{k}")
            z_parts += [ca.vec(free), T]
            nodes.append(X)
            durations.append(T)
        w = ca.vertcat(s, *z_parts)

        G, ends, dg, adm, samples = [], [], [], [], []
        for k, i in enumerate(self.chain):
            phase, X, T = self.phases[i], nodes[k], durations[k]
            transition = phase.transitions[0]
            X_end = segment[i](X, u, p, T / S)
            G.append(ca.vec(X[:, 1:] - X_end[:, :-1]))  # close the gaps
            x_end = X_end[:, -1]
            G.append(transition.guard(x_end, u, p))  # the phase ends on its guard
            x_next = transition.reset(x_end, u, p)
            if k + 1 < len(self.chain):
                G.append(nodes[k + 1][:, 0] - x_next)  # the reset links to the next phase
            else:
                x_return = x_next
            ends.append(x_end)
            # Crossing direction at the end: d/dt g = ∇g · f.
            dg.append(_guard_rate(phase, transition)(x_end, u, p))
            adm.append(
                transition.admissible(x_end, u, p)
                if transition.admissible is not None
                else ca.MX(1)
            )
            samples.append(sampler[i](X, u, p, T / S))
        G = ca.vertcat(*G)
        P = x_return[self.section_index]
        F = ca.vertcat(G, P - s)  # periodicity closes the cycle
        assert F.shape[0] == self.size and G.shape[0] == self.n_g, "shooting system not square"
        checks = [
            ca.vertcat(*ends),  # stacked: phases may differ in dimension
            ca.vertcat(*dg),
            ca.vertcat(*adm),
            ca.vertcat(*durations),
        ]
        return SimpleNamespace(
            w=w, u=u, p=p, F=F, GP=ca.vertcat(G, P), x_return=x_return, checks=checks,
            samples=samples,
        )  # fmt: skip

    @cached_property
    def _samplers(self) -> dict[int, ca.Function]:
        S, q = self.disc.segments, self.disc.dense
        return {
            i: segment_trajectory_function(ph.flow, q).map(S) for i, ph in enumerate(self.phases)
        }

    _w = property(lambda self: self._graph.w)
    _u = property(lambda self: self._graph.u)
    _p = property(lambda self: self._graph.p)
    _F = property(lambda self: self._graph.F)
    _GP = property(lambda self: self._graph.GP)
    _x_return = property(lambda self: self._graph.x_return)
    _checks_out = property(lambda self: self._graph.checks)
    _samples = property(lambda self: self._graph.samples)

    # Each function is built on first use: a mesh used only for the error estimate needs just
    # its residual.  Short chains are expanded to SX (their small dense graphs evaluate about
    # twice as fast); long ones (period-k orbits) stay MX, which builds in a fraction of the time
    # and evaluates as fast at that size.
    def _compiled(self, f: ca.Function) -> ca.Function:
        return f.expand() if len(self.chain) <= 2 else f

    @cached_property
    def residual(self) -> ca.Function:
        """``F(w, u, p)``: all shooting equations."""
        return self._compiled(
            ca.Function("residual", [self._w, self._u, self._p], [self._F], ["w", "u", "p"], ["F"])
        )

    @cached_property
    def newton(self) -> ca.Function:
        """Plain Newton (quadratic from a simulated guess)."""
        return ca.rootfinder(
            "limit_cycle", "newton", self.residual, {**NEWTON_OPTIONS, "line_search": False}
        )

    @cached_property
    def newton_line_search(self) -> ca.Function:
        """Newton with line search: the fallback from a poor guess."""
        return ca.rootfinder(
            "limit_cycle_ls", "newton", self.residual, {**NEWTON_OPTIONS, "max_iter": 100}
        )

    @cached_property
    def linearisation(self) -> ca.Function:
        """``(∂[G; P]/∂w, ∂[G; P]/∂u, F, x_return)`` for the multipliers and the error estimate."""
        w, u, p, GP = self._w, self._u, self._p, self._GP
        return self._compiled(
            ca.Function(
                "linearisation",
                [w, u, p],
                [ca.jacobian(GP, w), ca.jacobian(GP, u), self._F, self._x_return],
                ["w", "u", "p"],
                ["J_w", "J_u", "F", "x_return"],
            )
        )

    @cached_property
    def residual_jacobians(self) -> ca.Function:
        """``(F, ∂F/∂w, ∂F/∂p, ∂F/∂u)``: the corrector of continuation in a parameter or input."""
        w, u, p, F = self._w, self._u, self._p, self._F
        return self._compiled(
            ca.Function(
                "residual_jacobians",
                [w, u, p],
                [F, ca.jacobian(F, w), ca.jacobian(F, p), ca.jacobian(F, u)],
                ["w", "u", "p"],
                ["F", "F_w", "F_p", "F_u"],
            )
        )

    @cached_property
    def checks(self) -> ca.Function:
        """Phase-end states, guard rates, admissibility and durations."""
        return ca.Function("checks", [self._w, self._u, self._p], list(self._checks_out))

    @cached_property
    def sample(self) -> ca.Function:
        """Dense samples of every phase."""
        return ca.Function("sample", [self._w, self._u, self._p], self._samples)

    @cached_property
    def guard_maps(self) -> list[list[tuple[ca.Function, ca.Function | None]]]:
        """Guards and admissibility mapped over one phase's dense samples."""
        K = self.disc.segments * self.disc.dense + 1  # segment starts shared
        return [
            [
                (t.guard.map(K), t.admissible.map(K) if t.admissible is not None else None)
                for t in phase.transitions
            ]
            for phase in self.phases
        ]

    @cached_property
    def constraint_maps(self) -> list[list[tuple[ca.Function, ca.Function]]]:
        """Each phase's unilateral constraints ``c`` mapped over its dense samples, with their
        rates ``ċ = ∇c · f`` (for a constraint that starts active: the foot must lift off)."""
        K = self.disc.segments * self.disc.dense + 1
        return [
            [(c.function.map(K), rate_along(phase.flow, c.function)) for c in phase.constraints]
            for phase in self.phases
        ]

    # -- IPOPT: the feasibility problem, or an objective over free inputs ---------------------
    def ipopt_solver(self, objective=None, free_inputs: bool = False) -> ca.Function:
        """IPOPT (CasADi ``nlpsol``, exact derivatives) on ``F(w, u, p) = 0``.

        Parameters
        ----------
        objective : callable, optional
            ``objective(symbols) -> MX`` (a scalar): what to minimise over the solutions, given
            :attr:`symbols` (``w``, ``u``, ``p``, ``s``, ``durations``, ``period``).  ``None``:
            a feasibility problem (objective 0), the square system solved with durations kept
            positive.
        free_inputs : bool
            The per-step inputs ``u`` are decision variables too (after ``w``), bounded by the
            model's :attr:`~gaitopt.HybridModel.input_bounds`; then the system is no longer
            square and the objective picks the solution.

        Returns
        -------
        casadi.Function
            The ``nlpsol`` solver: ``x = [w; u]`` with ``free_inputs``, else ``x = w``;
            ``p = [u; p]`` (``p`` alone with ``free_inputs``).  Cached per arguments.
        """
        key = (objective, bool(free_inputs))
        if key not in self._ipopt_solvers:
            g = self._graph
            f = objective(self.symbols) if objective is not None else 0
            x, par = (ca.vertcat(g.w, g.u), g.p) if free_inputs else (g.w, ca.vertcat(g.u, g.p))
            options = {
                "ipopt.print_level": 0,
                "ipopt.sb": "yes",
                "print_time": False,
                "ipopt.tol": 1e-14 if objective is None else 1e-10,
                "ipopt.constr_viol_tol": 1e-13,
                "ipopt.max_iter": 200 if objective is None else 1000,
                "error_on_fail": False,
            }
            nlp = {"x": x, "p": par, "f": f, "g": g.F}
            self._ipopt_solvers[key] = ca.nlpsol("limit_cycle_ipopt", "ipopt", nlp, options)
        return self._ipopt_solvers[key]

    @property
    def symbols(self) -> SimpleNamespace:
        """The problem's CasADi symbols, for an objective: ``w`` (unknowns), ``u`` (inputs),
        ``p`` (parameters), ``s`` (section coordinates of the fixed point), ``durations`` (one
        per stage, s) and ``period`` (their sum, s)."""
        g = self._graph
        durations = [g.w[off] for kind, _, off, _ in self.layout if kind == "duration"]
        return SimpleNamespace(
            w=g.w, u=g.u, p=g.p, s=g.w[: self.m], durations=durations,
            period=ca.sum1(ca.vertcat(*durations)),
        )  # fmt: skip


def _guard_rate(phase, transition) -> ca.Function:
    """``ġ(x, u, p) = ∇g(x) · f(x)``: the guard's rate of change along the flow."""
    return rate_along(phase.flow, transition.guard)
