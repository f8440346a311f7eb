"""Legendre–Gauss–Radau orthogonal collocation of a gait problem, one stage per phase.

Each phase of the orbit (``steps`` cycles of the model's phases) has a free duration ``T`` cut
into ``N`` equal mesh intervals; on each, the state is the degree-``d`` polynomial through its
start and the ``d`` Radau IIA points ``τ₁ < … < τ_d = 1`` (the flipped Legendre–Gauss–Radau
nodes) and the input the degree-``d − 1`` polynomial through its values at those points.  The
collocation equations ``ẋ(τⱼ) = f(x(τⱼ), u(τⱼ), p)`` are the Radau IIA method, of order
``2d − 1`` at the mesh points (Hairer & Wanner, "Solving ODEs II", §IV.5); the running cost
uses the same points' Radau quadrature, exact for polynomials of degree ``2d − 2`` — for the
effort cost, exactly ``∫ u(t)² dt`` of the input profile.  Garg et al. 2010 (Automatica 46) give
the LGR transcription of optimal control; Kelly 2017 (SIAM Review 59) the gait setting.

Work-based costs are transcribed in two ways.  Without a ``structure``, with slack powers
``pᵢ⁺ − pᵢ⁻ = uᵢωᵢ`` at the nodes: robust, but the quadrature of ``max(0, uᵢωᵢ)`` is only first
order where the power changes sign or the input jumps inside a mesh interval.  With a
``structure`` (an :class:`Arc` sequence per phase, found from that first solution), each phase is
cut into arcs whose durations are decision variables; on each arc every input has a declared
kind: a power sign, ``σ uᵢωᵢ ≥ 0`` at the arc's nodes, midpoints and start (the input fixed at
its bound on a bang arc), coasting (``uᵢ = 0`` at the arc's points, so the input polynomial
vanishes) or a held joint (``ωᵢ(x) = 0`` at the arc's start and points: a rate linear in the
state is then the zero polynomial on each interval, while ``uᵢ ≠ 0`` holds the joint).  The
running cost is ``Σ_{σ=+} uᵢωᵢ`` — a smooth integrand on each arc, and every jump of an input
falls on an arc boundary, so the quadrature keeps the collocation order and the cost is the
positive work of the profile (the compass gait's: to 3e-11 of its simulation).  The
switching times are where the optimum puts them (Betts 2010, "Practical Methods for Optimal
Control", §4.7, phases at the switches of bang-bang and singular arcs).

Active input bounds of a cost without powers (least effort) use the same arcs, with only their
``bounds`` read (:meth:`Collocation._bound_arcs`, found by
:func:`gaitopt.optimize.arcs.detect_bound_arcs`): the input fixed at its bound on a saturated
arc, collocated on a free one (its bound kept at the midpoints between the nodes too), so the
kink where it meets the bound is an arc boundary and the refinement keeps the collocation's
order (the compass gait at |τ| ≤ 4 N·m: 6.6e-11, where a uniform mesh stalls at 2.5e-6).
Touch points of state bounds and limits are junctions of the same arcs (``Arc.touches``, rows
``ċ = 0`` there: :mod:`gaitopt.optimize.state_arcs`).

Linking (as in :mod:`gaitopt.shooting`): the first state is ``lift(s)`` on the section; each phase
ends on its guard (crossing in the stated direction, admissibly); the reset of its end state,
with the input at the end of the phase, is the next phase's first state; the last reset returns
to ``s``.  The model's unilateral constraints (``Phase.constraints``) hold at every node.

Joint limits: the problem's state bounds are bounds of the node variables (every interval start
and Radau point; the section's lifted state, for the states ``lift`` computes, by rows), in each
phase that has the state; its selected limits (``Phase.limits``, ``GaitProblem.path_constraints``:
a knee that must not hyperextend) are rows ``c ≥ 0`` at the same nodes (not at a node where the
limit is 0 by construction, ``at_start``/``at_end``).  A limit that is the side a guard without
admissibility test keeps anyway (the kneed walker's knee flexion is its knee strike's guard) is
already imposed and adds no rows.  :meth:`Collocation.check_limits` checks both on dense samples
of the solution's polynomials; :meth:`Collocation.active_limits` says where they bind.
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import rate_along
from ..kernels.nodes import defect_function, flow_jacobian, node_function, node_kernels
from ..orbit.certificate import CONSTRAINT_TOL
from .nodes import NodeBlock, substitute
from .problem import GaitProblem
from .radau import (
    COAST,
    HELD,
    NEGATIVE,
    POSITIVE,
    Arc,
    Group,
    RadauMesh,
    _Blocks,
    _derivative_matrix,
    lagrange_matrix,
)
from .spectral import add_spectral_bound
from .state_arcs import touch_rows

__all__ = ["RadauMesh", "Collocation", "lagrange_matrix", "Group", "Arc", "warm_kernels"]

#: Uniform samples per mesh interval of the dense check of state bounds and limits
#: (:meth:`Collocation.check_limits`): not the nodes, where they are imposed.
LIMIT_SAMPLES = 64
#: A state bound or limit counts as violated on the dense samples where
#: ``c < −LIMIT_TOL · (1 + max |c|)``: the certificate's one rule for unilateral constraints
#: (:data:`gaitopt.orbit.certificate.CONSTRAINT_TOL`).
LIMIT_TOL = CONSTRAINT_TOL


def _implicit_dynamics(model: Any) -> ca.Function | None:
    """The model's equations of motion in implicit form, if it declares them.

    A mechanical model whose states are ``(q, q̇)`` may provide the classmethod
    ``manipulator() -> Function(q, qd, u, p) -> (M, rhs)`` with ``M(q) q̈ = rhs(q, q̇, u)``
    (the five-link biped does).  Collocating ``M a = rhs`` with the accelerations ``a`` as
    unknowns keeps the NLP's expressions small (no symbolic inverse of ``M``); the flow is
    checked against it at a test point, and ignored if they differ."""
    factory = getattr(type(model), "manipulator", None)
    if factory is None:
        return None
    phase = model.phases[0]
    n = phase.n
    try:
        f = factory()
        if n % 2 or f.size1_in(0) != n // 2 or f.size1_in(1) != n // 2:
            return None
        x = np.linspace(0.1, 0.3, n)
        u = np.linspace(-0.2, 0.2, len(model.inputs))
        M, rhs = (np.asarray(v, dtype=float) for v in f(x[: n // 2], x[n // 2 :], u, model.p))
        explicit = np.asarray(phase.flow(x, u, model.p), dtype=float).ravel()
        if not np.allclose(np.linalg.solve(M, rhs).ravel(), explicit[n // 2 :], rtol=1e-9):
            return None
        if not np.allclose(explicit[: n // 2], x[n // 2 :]):
            return None
    except (RuntimeError, np.linalg.LinAlgError):
        return None
    return f


def phase_node_kernels(
    model: Any, i: int, implicit: ca.Function | None, free: bool = False
) -> tuple[ca.Function, Any] | None:
    """The node function of model phase ``i`` (with the implicit dynamics ``implicit``, if any)
    and its compiled kernels (:mod:`gaitopt.kernels.nodes`), differentiated in the parameters
    too where some are ``free``; None where the model's functions have no SX form."""
    phase = model.phases[i]
    constraints = tuple(c.function for c in getattr(phase, "constraints", ()))
    try:
        node = node_function(phase.flow, constraints, implicit)
    except (TypeError, RuntimeError, NotImplementedError):
        return None
    label = f"{type(model).__name__.lower()}_{i}{'i' if implicit is not None else 'e'}"
    nd = None if free else node.size1_in(0) - len(model.p)
    return node, node_kernels(node, label, nd)


def warm_kernels(model: Any, degree: int = 6) -> bool:
    """Compile (or find in the cache) the node kernels a transcription of ``model`` of Radau
    ``degree`` (default: the default mesh's) uses and the flow Jacobians of its Floquet check
    (``python -m gaitopt.kernels --warm``); whether every one is compiled."""
    phases = model.phases
    implicit = _implicit_dynamics(model) if len(phases) == 1 else None
    compiled = True
    if implicit is not None:  # the interval defects on the default mesh's degree
        n = phases[0].n
        tau = np.array([0.0, *ca.collocation_points(degree, "radau")])
        C = _derivative_matrix(tau, tau[1:]).T  # as Collocation.C
        compiled = node_kernels(defect_function(n, n // 2, C), f"defects_{n}_{degree}").compiled
    for i, phase in enumerate(phases):
        found = phase_node_kernels(model, i, implicit)
        compiled = compiled and found is not None and found[1].compiled
        try:
            flow_jacobian(phase.flow, f"{type(model).__name__.lower()}_{i}")
        except (TypeError, RuntimeError, NotImplementedError):
            compiled = False
    return compiled


class Collocation:
    """The nonlinear program of a :class:`GaitProblem` on a :class:`RadauMesh`.

    The equations repeated at every collocation node (the dynamics, the phase's unilateral
    constraints) are the node function of :mod:`gaitopt.kernels.nodes`: ``node_blocks`` say where
    (:mod:`gaitopt.optimize.nodes`), ``outer`` is ``(f, g)`` with their outputs as symbols, and
    the solver assembles the exact derivatives from the compiled node kernels.

    Attributes
    ----------
    nlp : dict
        ``{"x", "p", "f", "g"}`` for :func:`casadi.nlpsol` (``p`` is the model's parameter
        vector; free parameters are decision variables that replace their entries).
    lbx, ubx, lbg, ubg : numpy.ndarray
        Bounds.
    groups : list of Group
        The constraint blocks, named for messages and the active set.
    """

    #: Transcribe the nodes with the node kernels (False: the whole NLP is one CasADi graph,
    #: differentiated by CasADi; the same NLP, for comparisons).
    use_node_kernels = True

    def __init__(
        self, problem: GaitProblem, mesh: RadauMesh, structure: list[list[Arc]] | None = None
    ):
        self.problem, self.mesh = problem, mesh
        self.structure = structure
        model = problem.model
        self.model = model
        N, d = mesh.intervals, mesh.degree
        self.N, self.d = N, d
        self.tau = np.array([0.0, *ca.collocation_points(d, "radau")])
        # Collocation: ẋ(τⱼ) ≈ Σ_r C[r, j] X_r / h, j = 1..d.
        self.C = _derivative_matrix(self.tau, self.tau[1:]).T  # (d+1) × d
        # Radau quadrature on τ₁..τ_d (exact to degree 2d − 2) and the input basis.
        gl, gw = np.polynomial.legendre.leggauss(d + 2)
        gl, gw = (gl + 1) / 2, gw / 2
        self.weights = gw @ lagrange_matrix(self.tau[1:], gl)
        self.u_at_start = lagrange_matrix(self.tau[1:], np.array([0.0]))[0]
        self.chain = problem.chain
        phases = model.phases
        section = model.section
        m = len(section.coordinates)
        self.m = m
        n_u = len(model.inputs)
        n_p = len(model.parameter_specs())
        states0 = phases[0].states
        self.section_index = [states0.index(c) for c in section.coordinates]

        self.implicit = _implicit_dynamics(model) if len(phases) == 1 else None
        self.node_blocks: list[NodeBlock] = []
        B = _Blocks()
        self.blocks = B
        lo0, hi0 = problem.state_bounds_of(0)
        s = B.add("s", m, 1, lo0[self.section_index], hi0[self.section_index])
        flo, fhi = problem.free_bounds()
        free = B.add("free", len(problem.free), 1, flo, fhi)
        p_in = ca.MX.sym("p", n_p)
        entries = [p_in[i] for i in range(n_p)]
        for j, i in enumerate(problem.free_index):
            entries[i] = free[j]
        p = ca.vertcat(*entries) if entries else p_in
        ulo, uhi = problem.input_bounds()
        work = problem.cost_kind in ("work", "cot")
        if structure is not None:
            if len(structure) != len(self.chain):
                raise GaitoptInputError("Collocation: a structure needs arcs for every phase")
            if not work and not any(any(a.bounds) or a.touches for arcs in structure for a in arcs):
                raise GaitoptInputError(
                    "Collocation: the arcs of a cost without powers are those of input bounds "
                    "or of touch points"
                )
            for arcs in structure:
                if sum(a.intervals for a in arcs) != N:
                    raise GaitoptInputError(
                        f"Collocation: the arcs of a phase must share its {N} mesh intervals"
                    )
        slack = work and structure is None

        self.limit_groups: list[str] = []  # names of the rows of state bounds and limits
        self.guard_limits: list[tuple[int, str]] = []  # (phase, limit) kept by a guard's rows
        X, U, T, Pp, Pm, Th = [], [], [], [], [], []
        for k, i in enumerate(self.chain):
            n = phases[i].n
            lo, hi = problem.state_bounds_of(i)
            cols = N * d if k == 0 else N * d + 1
            Xk = B.add(f"X{k}", n, cols, lo, hi)
            if k == 0:
                Xk = ca.horzcat(section.lift(s, p), Xk)
            X.append(Xk)
            U.append(B.add(f"U{k}", n_u, N * d, ulo, uhi))
            T.append(B.add(f"T{k}", 1, 1, 1e-3, problem.max_phase_time))
            if self.implicit is not None:
                B.add(f"A{k}", n // 2, N * d)
            if structure is not None:
                Th.append(B.add(f"Theta{k}", len(structure[k]), 1, 1e-6, 1.0))
            if slack:
                Pp.append(B.add(f"Pplus{k}", n_u, N * d, 0.0, np.inf))
                Pm.append(B.add(f"Pminus{k}", n_u, N * d, 0.0, np.inf))

        g: list[ca.MX] = []
        lbg: list[np.ndarray] = []
        ubg: list[np.ndarray] = []
        self.groups: list[Group] = []

        def add(name: str, expr: ca.MX, low: float = 0.0, high: float = 0.0) -> None:
            expr = ca.vec(expr)
            start = sum(e.shape[0] for e in g)
            g.append(expr)
            lbg.append(np.full(expr.shape[0], low))
            ubg.append(np.full(expr.shape[0], high))
            self.groups.append(Group(name, start, expr.shape[0], low == high))

        cost_terms, work_terms, effort_terms, distance = [], [], [], []
        brake_terms: list[Any] = []  # ∫uᵢ² dt on braking arcs (GaitProblem.braking_effort)
        step_vectors = []
        for k, i in enumerate(self.chain):
            phase = phases[i]
            tr = phase.transitions[0]
            label = phase.name if len(self.chain) == 1 else f"{phase.name} #{k + 1}"
            Xk, Uk, Tk = X[k], U[k], T[k]
            if structure is None:
                hs = [Tk / N] * N
            else:  # interval lengths from the arc fractions
                add(f"arc fractions ({label})", ca.sum1(Th[k]) - 1.0)
                hs = [
                    Tk * Th[k][a] / arc.intervals
                    for a, arc in enumerate(structure[k])
                    for _ in range(arc.intervals)
                ]
            Xc = Xk[:, 1:]
            for r in problem.impulsive_index:  # an impulse: one value per step, held
                if ulo[r] == uhi[r]:  # switched off by its bounds: already constant
                    continue
                name = model.inputs[r]
                add(f"impulse '{name}' held over {label}", Uk[r, :-1] - Uk[r, -1])
            Ak = B.syms[B.names.index(f"A{k}")] if self.implicit is not None else None
            Yk = self._node_block(i, Xc, Uk, Ak, p)
            if self.implicit is None:
                F = phase.flow.map(N * d)(Xc, Uk, p) if Yk is None else Yk[: phase.n, :]
            else:  # ẋ = (q̇, a) with M(q) a = rhs(q, q̇, u) as constraints
                nq = phase.n // 2
                if Yk is None:
                    M, rhs = self.implicit.map(N * d)(Xc[:nq, :], Xc[nq:, :], Uk, p)
                    Ms = ca.horzsplit(M, nq)
                    balance = ca.horzcat(
                        *[ca.mtimes(Ms[c], Ak[:, c]) - rhs[:, c] for c in range(N * d)]
                    )
                else:
                    balance = Yk[:nq, :]
                add(f"equations of motion ({label})", balance)
                F = ca.vertcat(Xc[nq:, :], Ak)
            if Yk is not None and self.implicit is not None:
                # Every defect is a function of its interval's own variables: one more block
                # of kernels (the interval's defects, compiled), not differentiated per mesh.
                add(f"dynamics ({label})", self._defect_block(Xk, Ak, hs))
            else:
                defects = []
                for j in range(N):
                    Xi = Xk[:, j * d : j * d + d + 1]
                    F_j = F[:, j * d : (j + 1) * d]
                    defects.append(ca.mtimes(Xi, ca.DM(self.C)) - hs[j] * F_j)
                add(f"dynamics ({label})", ca.horzcat(*defects))
            x_end, u_end = Xk[:, -1], Uk[:, -1]
            add(f"guard '{tr.name}' at the end of {label}", tr.guard(x_end, u_end, p))
            if tr.admissible is None and Xc.shape[1] > 1:
                # A guard without an admissibility test ends the phase wherever it is crossed
                # (the simulator's event): it keeps its side, direction · g ≤ 0, at the
                # interior nodes (the kneed walker's knee must not straighten early).
                inner = tr.guard.map(Xc.shape[1] - 1)(Xc[:, :-1], Uk[:, :-1], p)
                inner = tr.direction * inner + self._phase_margin(hs, Tk)[:, :-1]
                add(f"'{tr.name}' not before the end of {label}", inner, -np.inf)
            rate = rate_along(phase.flow, tr.guard)(x_end, u_end, p)
            add(
                f"crossing direction of '{tr.name}' ({label})",
                tr.direction * rate,
                problem.min_crossing_rate,
                np.inf,
            )
            if tr.admissible is not None:
                add(
                    f"admissibility of '{tr.name}' ({label})",
                    tr.admissible(x_end, u_end, p),
                    0.0,
                    np.inf,
                )
            u_start = ca.mtimes(Uk[:, :d], ca.DM(self.u_at_start))
            margin, margin0 = self._clearance_margin(T, hs, k)
            first_row = phase.n // 2 if self.implicit is not None else phase.n
            for r, c in enumerate(phase.constraints):
                nodes = Xk[:, 1:-1] if c.at_end else Xk[:, 1:]
                unodes = Uk[:, :-1] if c.at_end else Uk
                # A length (a foot's height) keeps the problem's clearance margin.
                lift = margin if c.unit == "m" else ca.MX.zeros(1, N * d)
                if nodes.shape[1]:
                    if Yk is None:
                        values = c.function.map(nodes.shape[1])(nodes, unodes, p)
                    else:  # the node kernel's row of this constraint
                        values = Yk[first_row + r, : nodes.shape[1]]
                    values = values - (lift[:, :-1] if c.at_end else lift)
                    add(f"'{c.name}' ({label})", values, 0.0, np.inf)
                if c.at_start:
                    rate_c = rate_along(phase.flow, c.function)(Xk[:, 0], u_start, p)
                    add(f"'{c.name}' rising at the start of {label}", rate_c, 0.0, np.inf)
                else:
                    add(
                        f"'{c.name}' at the start of {label}",
                        c.function(Xk[:, 0], u_start, p) - (margin0 if c.unit == "m" else 0.0),
                        0.0,
                        np.inf,
                    )
            self._add_limits(add, k, i, label, Xk, Uk, u_start, p)
            x_next = tr.reset(x_end, u_end, p)
            if k + 1 < len(self.chain):
                add(f"reset after {label}", X[k + 1][:, 0] - x_next)
            smooth = [r for r in range(len(model.inputs)) if r not in problem.impulsive_index]
            if problem.continuous_inputs and smooth and (k + 1) % len(model.phases):
                # The profile has no jump inside a step (GaitProblem.continuous_inputs): the next
                # phase's input polynomial starts where this one ends.
                u_next = ca.mtimes(U[k + 1][:, :d], ca.DM(self.u_at_start))
                add(f"inputs continuous after {label}", u_next[smooth] - u_end[smooth])
            else:
                add("periodicity", x_next[self.section_index] - s)
            step = problem.step_vector(i, x_end, p)
            if step is not None:
                step_vectors.append(step)
                distance.append(ca.norm_2(step))
            # Running cost by Radau quadrature: Σ_intervals h_j Σ_c w_c L_c.
            if structure is None:
                hq, wq = Tk / N, ca.DM(np.tile(self.weights, N))
            else:
                hq, wq = 1.0, ca.vertcat(*[hs[j] * ca.DM(self.weights) for j in range(N)])
            if slack:
                rates = model.input_rates(i).map(N * d)(Xc, p)
                power = Uk * rates
                add(f"power split ({label})", Pp[k] - Pm[k] - power)
                work_terms.append(hq * ca.mtimes(ca.sum1(Pp[k]), wq))
                work_terms.append(problem.impulse_work(i, x_end, u_end, p))
                effort_terms.append(hq * ca.mtimes(ca.sum1(Uk**2), wq))
            elif work:  # arcs: σ uᵢωᵢ ≥ 0 (σ = ±1), u ≡ 0 or ω ≡ 0; cost Σ_{σ=+} uᵢωᵢ (exact)
                rate_fn = model.input_rates(i)
                rates = rate_fn.map(N * d)(Xc, p)
                power = Uk * rates
                kinds = np.array(
                    [arc.signs for arc in structure[k] for _ in range(arc.intervals)], dtype=int
                ).T  # n_u × N
                # An input whose rate vanishes identically in this phase (the locked knee's)
                # does no work: it needs no arc constraint.
                kinds[self._idle_inputs(i), :] = NEGATIVE
                node_kinds = np.repeat(kinds, d, axis=1)  # n_u × N·d
                signed = np.isin(kinds, (POSITIVE, NEGATIVE))
                signed[self._idle_inputs(i), :] = False
                # Bang and coasting arcs fix the input at the arc's points (its bound, or 0):
                # fixed variables, which IPOPT removes from the problem.
                bangs = np.array(
                    [a.bounds or (0,) * n_u for a in structure[k] for _ in range(a.intervals)],
                    dtype=int,
                ).T  # n_u × N
                bangs[~signed] = 0
                fixed = np.where(bangs > 0, uhi[:, None], np.where(bangs < 0, ulo[:, None], np.nan))
                fixed[kinds == COAST] = 0.0
                fixed[self._idle_inputs(i), :] = np.nan
                slot = B.names.index(f"U{k}")
                values = np.repeat(fixed, d, axis=1).ravel(order="F")
                keep = np.isnan(values)
                B.lb[slot] = np.where(keep, B.lb[slot], values)
                B.ub[slot] = np.where(keep, B.ub[slot], values)
                # An idle input the flow ignores too (the locked knee's torque) would be free
                # values the cost cannot fix (a singular NLP): it is held at the value it takes
                # as the phase begins (continuous with the previous phase inside a step), else 0.
                for r in self._ignored_inputs(i):
                    if r in problem.impulsive_index or ulo[r] == uhi[r]:  # a reset's; fixed
                        continue
                    if problem.continuous_inputs and k % len(model.phases):
                        add(f"'{model.inputs[r]}' held over {label}", Uk[r, 1:] - Uk[r, 0])
                    else:
                        B.lb[slot][r::n_u] = 0.0
                        B.ub[slot][r::n_u] = 0.0
                u0 = ca.DM(self.u_at_start)
                starts_u = ca.horzcat(*[ca.mtimes(Uk[:, j * d : j * d + d], u0) for j in range(N)])
                starts_x = ca.horzcat(*[Xk[:, j * d] for j in range(N)])
                start_rates = rate_fn.map(N)(starts_x, p)
                start_power = starts_u * start_rates
                # Between the nodes too (the midpoints): the profile the simulator applies is
                # the polynomial, whose power must keep its arc's sign and whose value must
                # keep its bounds there as well.
                mids = 0.5 * (self.tau[:-1] + self.tau[1:])
                Lx = ca.DM(lagrange_matrix(self.tau, mids).T)
                Lu = ca.DM(lagrange_matrix(self.tau[1:], mids).T)
                xs = ca.horzcat(*[ca.mtimes(Xk[:, j * d : j * d + d + 1], Lx) for j in range(N)])
                us = ca.horzcat(*[ca.mtimes(Uk[:, j * d : (j + 1) * d], Lu) for j in range(N)])
                mid_power = us * rate_fn.map(N * d)(xs, p)
                sign_rows, start_rows, mid_rows, held_rows = [], [], [], []
                for r in range(n_u):
                    nodes = [c for c in range(N * d) if signed[r, c // d]]
                    if nodes:
                        sigma = ca.DM(node_kinds[r, nodes].astype(float)).T
                        sign_rows.append(sigma * power[r, nodes])
                        mid_rows.append(sigma * mid_power[r, nodes])
                    ivals = [j for j in range(N) if signed[r, j]]
                    if ivals:
                        sigma = ca.DM(kinds[r, ivals].astype(float)).T
                        start_rows.append(sigma * start_power[r, ivals])
                    # A held joint: ω = 0 at the collocation points of the arc's intervals and
                    # at the arc's start (the other interval starts are the previous
                    # interval's last point): ω(x(τ)) ≡ 0 on the arc.
                    held = [c for c in range(N * d) if kinds[r, c // d] == HELD]
                    entries = [j for j in range(N) if kinds[r, j] == HELD]
                    entries = [j for j in entries if j == 0 or kinds[r, j - 1] != HELD]
                    if held:
                        held_rows.append(rates[r, held])
                        held_rows.append(start_rates[r, entries])
                for name, rows, low in (
                    ("power sign", sign_rows, 0.0),
                    ("power sign at arc starts", start_rows, 0.0),
                    ("power sign between nodes", mid_rows, 0.0),
                    ("held joint (rate zero)", held_rows, None),
                ):
                    if rows:
                        expr = ca.horzcat(*rows)
                        if low is None:
                            add(f"{name} ({label})", expr)
                        else:
                            add(f"{name} ({label})", expr, low, np.inf)
                for r in range(n_u):
                    free_nodes = [c for c in range(N * d) if np.isnan(fixed[r, c // d])]
                    if np.isfinite(uhi[r]) and free_nodes:
                        name = f"|{model.inputs[r]}| between nodes ({label})"
                        add(name, us[r, free_nodes], ulo[r], uhi[r])
                positive = ca.DM((node_kinds == POSITIVE).astype(float))
                work_terms.append(ca.mtimes(ca.sum1(positive * power), wq))
                if problem.braking_effort > 0:  # ∫uᵢ² dt on the braking arcs (GaitProblem)
                    braking = (node_kinds == NEGATIVE) & np.repeat(signed, d, axis=1)
                    brake_terms.append(ca.mtimes(ca.sum1(ca.DM(braking.astype(float)) * Uk**2), wq))
                work_terms.append(problem.impulse_work(i, x_end, u_end, p))
                touch_rows(self, k, i, Xk, Uk, p, label, add)  # guards' touch points, if cut
            else:
                if structure is not None and any(any(a.bounds) for x in structure for a in x):
                    self._bound_arcs(k, Xk, Uk, p, label, add)  # the arcs of input bounds
                if structure is not None:  # touch points of state bounds and limits
                    touch_rows(self, k, i, Xk, Uk, p, label, add)
                L = ca.vertcat(*[problem.integrand(i, Xc[:, c], Uk[:, c], p) for c in range(N * d)])
                cost_terms.append(hq * ca.mtimes(L.T, wq))

        period = ca.sum1(ca.vertcat(*T))
        total = ca.sum1(ca.vertcat(*distance)) if distance else ca.MX(0)
        # The fixed period, step length and speed are the bounds of their rows, not constants in
        # the graph: problems that differ only in them (a library's points) share one compiled
        # NLP.  The speed row is distance / period (the period is a sum of durations bounded
        # away from 0); with the period and step length both fixed it is implied (the statement
        # checks they agree) and left out, so the rows stay independent.
        if problem.period is not None:
            add("period", period, problem.period, problem.period)
        if problem.step_length is not None:
            add("step length", total / problem.steps, problem.step_length, problem.step_length)
        if problem.speed is not None and (problem.period is None or problem.step_length is None):
            add("speed", total / period, problem.speed, problem.speed)
        if work:
            positive_work = ca.sum1(ca.vertcat(*work_terms))
            if problem.cost_kind == "cot":
                weight = problem.total_mass(p) * problem.gravity(p)
                J = positive_work / (weight * total)
            else:
                J = positive_work
        else:
            J = ca.sum1(ca.vertcat(*cost_terms))
        # ρ(A) ≤ R: the variational equations, A and the Schur–Cohn–Jury rows (spectral.py).
        self.spectral = (
            None
            if problem.max_multiplier is None
            else add_spectral_bound(self, B, add, X, U, T, Th, p, p_in)
        )
        w = B.vector()
        self._w, self._p = w, p_in
        objective = J
        if slack and problem.regularisation > 0:
            # Positive work alone leaves singular arcs (inputs that chatter between the nodes);
            # a small effort term selects a smooth optimum.  The reported cost is J alone.
            objective = J + problem.regularisation * ca.sum1(ca.vertcat(*effort_terms))
        braking = ca.sum1(ca.vertcat(*brake_terms)) if brake_terms else ca.MX(0)
        if brake_terms:  # the singular braking arcs' least-effort torque; reported apart
            objective = J + problem.braking_effort * braking
        g_all = ca.vertcat(*g)
        positive_work = ca.sum1(ca.vertcat(*work_terms)) if work else ca.MX(np.nan)
        # The node outputs Y stand for the node function at the nodes (gaitopt.optimize.nodes):
        # the solver assembles its derivatives from compiled kernels; everyone else sees the
        # ordinary graph.
        self.outer = (objective, g_all)
        objective, g_all, J, positive_work, braking = substitute(
            self.node_blocks, [objective, g_all, J, positive_work, braking]
        )
        self.nlp = {"x": w, "p": p_in, "f": objective, "g": g_all}
        self.lbx = np.concatenate(B.lb)
        self.ubx = np.concatenate(B.ub)
        self.lbg = np.concatenate(lbg)
        self.ubg = np.concatenate(ubg)
        self._outputs = {
            "cost": J,
            "period": period,
            "distance": total,
            "p_used": p,
            "positive_work": positive_work,
            "braking_effort": braking,
        }
        self._X, self._U, self._T = X, U, T
        self._theta = Th

    def _node_block(self, i: int, Xc: Any, Uk: Any, Ak: Any, p: Any) -> ca.MX | None:
        """The node outputs ``Y`` (dynamics rows, then one row per unilateral constraint) of a
        phase of model phase ``i`` at its ``N·d`` collocation points (``Xc``, ``Uk``, ``Ak``:
        their states, inputs, accelerations), a block of :mod:`gaitopt.optimize.nodes`; None
        where the node function cannot be built in SX or :attr:`use_node_kernels` is off."""
        if not self.use_node_kernels:
            return None
        found = phase_node_kernels(self.model, i, self.implicit, bool(self.problem.free))
        if found is None:
            return None
        node, kernels = found
        count = Xc.shape[1]
        parts = [Xc, Uk] + ([Ak] if Ak is not None else []) + [ca.repmat(p, 1, count)]
        Y = ca.MX.sym(f"Y{len(self.node_blocks)}", node.size1_out(0), count)
        self.node_blocks.append(NodeBlock(kernels, node, Y, ca.vertcat(*parts)))
        return Y

    def _defect_block(self, Xk: Any, Ak: Any, hs: list[Any]) -> ca.MX:
        """The collocation defects ``X_j C − h_j (q̇, a)`` of an implicit phase's intervals as
        the outputs ``Y`` (n·d × N) of a block of :mod:`gaitopt.optimize.nodes` whose inputs
        are each interval's states, accelerations and length (the interval kernel
        :func:`gaitopt.kernels.nodes.defect_function`)."""
        N, d = self.N, self.d
        n = Xk.shape[0]
        nq = n // 2
        fn = defect_function(n, nq, self.C)
        kernels = node_kernels(fn, f"defects_{n}_{d}")
        cols = [
            ca.vertcat(
                ca.vec(Xk[:, j * d : j * d + d + 1]), ca.vec(Ak[:, j * d : (j + 1) * d]), hs[j]
            )
            for j in range(N)
        ]
        Y = ca.MX.sym(f"Y{len(self.node_blocks)}", n * d, N)
        self.node_blocks.append(NodeBlock(kernels, fn, Y, ca.horzcat(*cols)))
        return Y

    def _bound_arcs(self, k: int, Xk: Any, Uk: Any, p: Any, label: str, add: Any) -> None:
        """The arcs of active input bounds for a cost without powers (least effort): on an
        arc where an input sits at its bound (``Arc.bounds``; ``Arc.signs`` are not read) its
        values at the arc's points are fixed there (``u ≡ bound``: fixed variables), on the
        others it is collocated as usual and keeps its bounds between the nodes (the
        midpoints) too, so the kink where it meets the bound is an arc boundary."""
        N, d, B = self.N, self.d, self.blocks
        ulo, uhi = self.problem.input_bounds()
        n_u = len(self.model.inputs)
        bangs = np.array(
            [a.bounds or (0,) * n_u for a in self.structure[k] for _ in range(a.intervals)],
            dtype=int,
        ).T  # n_u × N
        fixed = np.where(bangs > 0, uhi[:, None], np.where(bangs < 0, ulo[:, None], np.nan))
        slot = B.names.index(f"U{k}")
        values = np.repeat(fixed, d, axis=1).ravel(order="F")
        keep = np.isnan(values)
        B.lb[slot] = np.where(keep, B.lb[slot], values)
        B.ub[slot] = np.where(keep, B.ub[slot], values)
        mids = 0.5 * (self.tau[:-1] + self.tau[1:])
        Lu = ca.DM(lagrange_matrix(self.tau[1:], mids).T)
        us = ca.horzcat(*[ca.mtimes(Uk[:, j * d : (j + 1) * d], Lu) for j in range(N)])
        for r in range(n_u):
            free_nodes = [c for c in range(N * d) if np.isnan(fixed[r, c // d])]
            if (np.isfinite(ulo[r]) or np.isfinite(uhi[r])) and ulo[r] < uhi[r] and free_nodes:
                name = f"|{self.model.inputs[r]}| between nodes ({label})"
                add(name, us[r, free_nodes], ulo[r], uhi[r])
        if self.problem.cost != "effort" or not self._affine_in_inputs(self.chain[k]):
            return
        # Junctions: least effort with a flow affine in u has u = sat(−Bᵀλ/2) with λ
        # continuous inside a phase (Bryson & Ho 1975, §3.10), so u is continuous where it
        # leaves or meets its bound: the free arc's polynomial takes the bound's value at the
        # junction (its last node, τ = 1, fixed there; its start, τ = 0, by a row).  Without
        # that the junction time is pinned only to third order (a junction off by δ costs
        # ~|u̇|²δ³) and the first solution with arcs can hide the kink inside the free arc's
        # first interval (the compass gait at |τ| ≤ 4 N·m: the junction 4.9e-3 s early on 6
        # intervals, 8e-6 below the optimum; refinement then crept towards it at order ~3).
        arcs = self.structure[k]
        if any(a.touches for a in arcs):
            # A touch point of a state bound makes λ jump (Bryson & Ho §3.11): the rows are not
            # imposed in such a phase.  Measured: the compass gait at |τ| ≤ 6 N·m with swing ≥
            # −0.45 rad certifies without them (8.909004809, error 5.8e-12) and stalls at 2e-7
            # with them (tests/test_optimize_touch.py); why, at the bound junctions away from the
            # touch, is not understood yet.
            return
        u0 = ca.DM(self.u_at_start)
        rows, end = [], 0
        for a, b in zip(arcs[:-1], arcs[1:], strict=True):
            end += a.intervals
            if a.touches:  # λ may jump at a touch point
                continue
            before, after = a.bounds or (0,) * n_u, b.bounds or (0,) * n_u
            for r in range(n_u):
                if before[r] == 0 and after[r] != 0:  # the free arc's last node (τ = 1): fixed
                    B.lb[slot][(end * d - 1) * n_u + r] = B.ub[slot][(end * d - 1) * n_u + r] = (
                        uhi[r] if after[r] > 0 else ulo[r]
                    )
                elif before[r] != 0 and after[r] == 0:  # the free arc's start (τ = 0)
                    start = ca.mtimes(Uk[r, end * d : (end + 1) * d], u0)
                    rows.append(start - (uhi[r] if before[r] > 0 else ulo[r]))
        if rows:
            add(f"inputs continuous at the junctions ({label})", ca.vertcat(*rows))

    def _affine_in_inputs(self, phase: int) -> bool:
        """Whether ``phase``'s flow is affine in the inputs (its input Jacobian is free of them)."""
        flow = self.model.phases[phase].flow
        x = ca.SX.sym("x", flow.size1_in(0))
        u = ca.SX.sym("u", flow.size1_in(1))
        rhs = flow(x, u, ca.SX.sym("p", flow.size1_in(2)))
        return not ca.depends_on(ca.jacobian(rhs, u), u)

    def _add_limits(
        self, add: Any, k: int, i: int, label: str, Xk: Any, Uk: Any, u_start: Any, p: Any
    ) -> None:
        """Rows of phase ``k`` (model phase ``i``) for the selected limits and, at the section,
        the bounds of the states ``lift`` computes (the other nodes' bounds are variable bounds)."""
        problem, phase = self.problem, self.model.phases[i]
        if k == 0:
            lo, hi = problem.state_bounds_of(i)
            rows = [
                j
                for j in range(phase.n)
                if j not in self.section_index and (np.isfinite(lo[j]) or np.isfinite(hi[j]))
            ]
            for j in rows:
                name = f"bound on '{phase.states[j]}' at the section"
                add(name, Xk[j, 0], lo[j], hi[j])
                self.limit_groups.append(name)
        for c in problem.limits_of(i):
            if self._kept_by_guard(i, c):
                self.guard_limits.append((i, c.name))
                continue
            first = 1 if c.at_start else 0
            last = Xk.shape[1] - 1 if c.at_end else Xk.shape[1]
            nodes = Xk[:, first:last]
            # The input at a node: the start's extrapolated value, then the Radau points'.
            unodes = ca.horzcat(u_start, Uk)[:, first:last]
            if nodes.shape[1]:
                name = f"limit '{c.name}' ({label})"
                add(name, c.function.map(nodes.shape[1])(nodes, unodes, p), 0.0, np.inf)
                self.limit_groups.append(name)

    def _kept_by_guard(self, i: int, c: Any) -> bool:
        """Whether limit ``c`` of phase ``i`` is ``direction · g ≤ 0`` of its cycle transition's
        guard without admissibility test, ``c = −direction · g`` (checked at random states),
        which the transcription keeps at the interior nodes anyway (with the problem's
        guard margin, never less)."""
        tr = self.model.phases[i].transitions[0]
        if tr.admissible is not None:
            return False
        rng = np.random.default_rng(0)
        n, n_u = self.model.phases[i].n, len(self.model.inputs)
        for _ in range(4):
            x, u = rng.normal(size=n), rng.normal(size=n_u)
            value = float(c.function(x, u, self.model.p))
            guard = float(tr.guard(x, u, self.model.p))
            if abs(value + tr.direction * guard) > 1e-12 * (1 + abs(value)):
                return False
        return True

    # -- joint limits on the solution ---------------------------------------------------------
    def _limit_values(
        self, sol: dict[str, Any], k: int, X: np.ndarray, U: np.ndarray
    ) -> list[tuple[str, np.ndarray, bool, bool]]:
        """``(label, c, at_start, at_end)`` of every state bound side (``x − low``,
        ``high − x``) and selected limit of phase ``k`` at the samples ``X``, ``U`` (``c ≥ 0``
        wanted)."""
        problem = self.problem
        i = self.chain[k]
        phase = self.model.phases[i]
        out = []
        lo, hi = problem.state_bounds_of(i)
        for j, state in enumerate(phase.states):
            if np.isfinite(lo[j]):
                out.append((f"{state} >= {lo[j]:g}", X[j] - lo[j], False, False))
            if np.isfinite(hi[j]):
                out.append((f"{state} <= {hi[j]:g}", hi[j] - X[j], False, False))
        for c in problem.limits_of(i):
            values = np.asarray(c.function.map(X.shape[1])(X, U, sol["p"]), dtype=float).ravel()
            out.append((f"{c.name} >= 0", values, c.at_start, c.at_end))
        return out

    def _phase_label(self, k: int) -> str:
        """The phase's name (with its place in the orbit when the orbit has several phases)."""
        phase = self.model.phases[self.chain[k]]
        return phase.name if len(self.chain) == 1 else f"{phase.name} #{k + 1}"

    def check_limits(self, sol: dict[str, Any], samples: int = LIMIT_SAMPLES) -> str | None:
        """None if every state bound and selected limit holds on ``samples`` uniform samples per
        mesh interval of each phase's polynomials, ``c ≥ −1e-9 · (1 + max |c|)`` (the rule of
        :func:`gaitopt.shooting.certify`'s unilateral constraints); else the first failure."""
        tn = np.linspace(0.0, 1.0, self.N * samples + 1)
        t0 = 0.0
        for k in range(len(self.chain)):
            X, U = self.evaluate(sol["X"][k], sol["U"][k], tn, sol["breaks"][k])
            for label, c, at_start, at_end in self._limit_values(sol, k, X, U):
                inner = c[1 if at_start else 0 : c.size - 1 if at_end else c.size]
                scale = LIMIT_TOL * (1 + float(np.max(np.abs(c))))
                bad = np.nonzero(inner < -scale)[0]
                if bad.size:
                    j = int(bad[0]) + (1 if at_start else 0)
                    return (
                        f"the limit '{label}' fails between the nodes of phase "
                        f"'{self._phase_label(k)}' at t = {t0 + tn[j] * sol['T'][k]:.4g} s (by "
                        f"{-float(np.min(inner)):.3g}; dense samples, tolerance {scale:.2g})"
                    )
            t0 += sol["T"][k]
        return None

    def active_limits(self, sol: dict[str, Any]) -> dict[str, list[list[float]]]:
        """The state bounds and selected limits active at the nodes (within 1e-6 of their bound,
        relative to 1 + the largest |c|): ``{"LABEL (phase)": [[t_first, t_last], ...]}``, the
        times (s since the orbit's section) of each run of consecutive active nodes."""
        out: dict[str, list[list[float]]] = {}
        t0 = 0.0
        for k in range(len(self.chain)):
            X, U = sol["X"][k], sol["U"][k]
            times = t0 + self.node_times(sol["breaks"][k]) * sol["T"][k]
            U = np.hstack([self.u_start_of(U), U])
            for label, c, at_start, at_end in self._limit_values(sol, k, X, U):
                hit = np.abs(c) <= 1e-6 * (1 + float(np.max(np.abs(c))))
                if at_start:
                    hit[0] = False
                if at_end:
                    hit[-1] = False
                if not hit.any():
                    continue
                spans, j = [], 0
                while j < hit.size:
                    if hit[j]:
                        e = j
                        while e + 1 < hit.size and hit[e + 1]:
                            e += 1
                        spans.append([float(times[j]), float(times[e])])
                        j = e + 1
                    else:
                        j += 1
                out.setdefault(f"{label} ({self._phase_label(k)})", []).extend(spans)
            t0 += sol["T"][k]
        return out

    def certify_limits(self, w: np.ndarray, result: Any) -> None:
        """The certificate's part for the state bounds and selected limits of an optimum
        ``result`` (an :class:`~gaitopt.optimize.result.OptimalGait` from ``w``): its
        ``active_constraints`` name each active bound or limit with its phase (``active_spans``:
        the time spans), and a gait whose dense samples violate one (:meth:`check_limits`) is
        no gait (``success`` False, the message says which, where and by how much)."""
        problem = self.problem
        if not problem.state_bounds and not problem.path_constraints:
            return
        sol = self.unpack(w, self.model.p)
        spans = self.active_limits(sol)
        generic = {f"{lo:g} <= {n} <= {hi:g}" for n, (lo, hi) in problem.state_bounds.items()}
        drop = generic | set(self.limit_groups)
        kept = [a for a in result.active_constraints if a not in drop]
        result.active_constraints = kept + list(spans)
        result.active_spans = spans
        if result.cost is None or result.message.startswith("not a gait"):
            return
        failure = self.check_limits(sol)
        if failure is not None:
            result.success, result.stable, result.status = False, None, "not_a_gait"
            result.message = "not a gait: " + failure

    def u_start_of(self, U: np.ndarray) -> np.ndarray:
        """The input polynomial of the first interval at its start (a column)."""
        return U[:, : self.d] @ self.u_at_start.reshape(-1, 1)

    def _idle_inputs(self, phase: int) -> list[int]:
        """Inputs whose rate (:meth:`~gaitopt.HybridModel.input_rates`) is identically zero in
        ``phase``: they do no work there (the kneed walker's knee torque once the knee locks)."""
        fn = self.model.input_rates(phase)
        x = ca.SX.sym("x", fn.size1_in(0))
        rates = fn(x, ca.SX.sym("p", fn.size1_in(1)))
        return [r for r in range(rates.shape[0]) if rates[r].is_zero()]

    def _ignored_inputs(self, phase: int) -> list[int]:
        """Idle inputs (:meth:`_idle_inputs`) on which ``phase``'s flow does not depend either."""
        flow = self.model.phases[phase].flow
        x = ca.SX.sym("x", flow.size1_in(0))
        u = ca.SX.sym("u", flow.size1_in(1))
        rhs = flow(x, u, ca.SX.sym("p", flow.size1_in(2)))
        return [r for r in self._idle_inputs(phase) if not ca.depends_on(rhs, u[r])]

    def _clearance_margin(self, T: list[ca.MX], hs: list[Any], k: int) -> tuple[Any, Any]:
        """The clearance margin ``c · sin(π t / T_step)`` (m) at the collocation nodes of phase
        ``k`` (a 1 × N·d row) and at its start, ``t`` the time since its step's section
        (:attr:`GaitProblem.clearance`; zeros when it is 0)."""
        c = self.problem.clearance
        if not c:
            return ca.MX.zeros(1, self.N * self.d), 0.0
        n_cycle = len(self.model.phases)
        first = n_cycle * (k // n_cycle)
        before = ca.sum1(ca.vertcat(*T[first:k])) if k > first else ca.MX(0)
        step = ca.sum1(ca.vertcat(*T[first : first + n_cycle]))
        times, edge = [], before
        for h in hs:
            times.extend(edge + h * tau for tau in self.tau[1:])
            edge = edge + h
        row = ca.horzcat(*times)
        return c * ca.sin(np.pi * row / step), c * ca.sin(np.pi * before / step)

    def _phase_margin(self, hs: list[Any], Tk: ca.MX) -> Any:
        """``m · sin(π t / T)`` at the collocation nodes of a phase (a 1 × N·d row), ``t`` the
        time since the phase began (:attr:`GaitProblem.guard_margin`; zeros when it is 0)."""
        m = self.problem.guard_margin
        if not m:
            return ca.MX.zeros(1, self.N * self.d)
        times, edge = [], ca.MX(0)
        for h in hs:
            times.extend(edge + h * tau for tau in self.tau[1:])
            edge = edge + h
        return m * ca.sin(np.pi * ca.horzcat(*times) / Tk)

    # -- evaluation ---------------------------------------------------------------------------
    @cached_property
    def outputs(self) -> ca.Function:
        """``outputs(w, p) -> (cost, period, distance, p_used, positive_work)``."""
        names = list(self._outputs)
        return ca.Function(
            "outputs", [self._w, self._p], [self._outputs[k] for k in names], ["w", "p"], names
        )

    @cached_property
    def states(self) -> ca.Function:
        """``states(w, p) -> X₀, …`` (full node arrays, the first column of X₀ lifted)."""
        return ca.Function("states", [self._w, self._p], self._X)

    @cached_property
    def constraints(self) -> ca.Function:
        """``g(w, p)``."""
        return ca.Function("g", [self._w, self._p], [self.nlp["g"]])

    def unpack(self, w: np.ndarray, p: np.ndarray) -> dict[str, Any]:
        """The solution's pieces: ``s``, ``p`` (with free values), per phase ``X``, ``U``, ``T``."""
        w = np.asarray(w, dtype=float).ravel()
        out = {k: np.asarray(v, dtype=float) for k, v in self.outputs(w=w, p=p).items()}
        X = self.states(w, p)
        X = X if isinstance(X, (list, tuple)) else [X]
        return {
            "s": self.blocks.get(w, "s").ravel(),
            "free": self.blocks.get(w, "free").ravel(),
            "p": out["p_used"].ravel(),
            "cost": float(out["cost"].ravel()[0]),
            "period": float(out["period"].ravel()[0]),
            "distance": float(out["distance"].ravel()[0]),
            "positive_work": float(out["positive_work"].ravel()[0]),
            "braking_effort": float(out["braking_effort"].ravel()[0]),
            "X": [np.asarray(x, dtype=float) for x in X],
            "U": [self.blocks.get(w, f"U{k}") for k in range(len(self.chain))],
            "T": np.array(
                [float(self.blocks.get(w, f"T{k}")[0, 0]) for k in range(len(self.chain))]
            ),
            "breaks": [self.breaks(self.theta_of(w, k), k) for k in range(len(self.chain))],
        }

    def theta_of(self, w: np.ndarray, k: int) -> np.ndarray | None:
        """Arc fractions of phase ``k`` in ``w`` (None without a structure)."""
        if self.structure is None:
            return None
        return self.blocks.get(np.asarray(w, dtype=float).ravel(), f"Theta{k}").ravel()

    def breaks(self, theta: np.ndarray | None, k: int) -> np.ndarray:
        """Normalised interval boundaries (0..1) of phase ``k`` for arc fractions ``theta``."""
        if self.structure is None or theta is None:
            return np.linspace(0.0, 1.0, self.N + 1)
        lengths = [
            theta[a] / arc.intervals
            for a, arc in enumerate(self.structure[k])
            for _ in range(arc.intervals)
        ]
        edges = np.concatenate([[0.0], np.cumsum(lengths)])
        return edges / edges[-1]

    def node_times(self, breaks: np.ndarray | None = None) -> np.ndarray:
        """Normalised times (0..1 of a phase) of the state nodes: start, then each interval's
        Radau points (``breaks``: the interval boundaries, uniform by default)."""
        if breaks is None or self.structure is None:
            N = self.N
            return np.concatenate([[0.0], ((np.arange(N)[:, None] + self.tau[1:]) / N).ravel()])
        inner = breaks[:-1, None] + np.diff(breaks)[:, None] * self.tau[1:]
        return np.concatenate([[0.0], inner.ravel()])

    def evaluate(
        self, X: np.ndarray, U: np.ndarray, times: np.ndarray, breaks: np.ndarray | None = None
    ) -> tuple[np.ndarray, ...]:
        """State and input polynomials of one phase at normalised ``times`` in [0, 1]
        (``breaks``: the phase's interval boundaries, uniform by default)."""
        N, d = self.N, self.d
        times = np.clip(np.asarray(times, dtype=float), 0.0, 1.0)
        if breaks is None or np.array_equal(breaks, np.linspace(0.0, 1.0, N + 1)):
            interval = np.minimum((times * N).astype(int), N - 1)
            local = times * N - interval
        else:
            interval = np.clip(np.searchsorted(breaks, times, side="right") - 1, 0, N - 1)
            local = (times - breaks[interval]) / (breaks[interval + 1] - breaks[interval])
        xs = np.zeros((X.shape[0], times.size))
        us = np.zeros((U.shape[0], times.size))
        for i in np.unique(interval):
            sel = interval == i
            xs[:, sel] = X[:, i * d : i * d + d + 1] @ lagrange_matrix(self.tau, local[sel]).T
            us[:, sel] = U[:, i * d : (i + 1) * d] @ lagrange_matrix(self.tau[1:], local[sel]).T
        return xs, us

    def pack(
        self,
        s: np.ndarray,
        free: np.ndarray,
        states: list[Any],
        inputs: list[Any],
        durations: np.ndarray,
        p: np.ndarray,
        thetas: list[np.ndarray] | None = None,
    ) -> np.ndarray:
        """A decision vector from callables ``states[k](τ) -> n × len(τ)`` and ``inputs[k](τ)``
        per phase (normalised time ``τ``), durations and section coordinates (``thetas``: the
        arc fractions of a structure, by default its guesses).  Slack powers are set to the
        split of the guessed power."""
        B = self.blocks
        w = np.zeros(B.size)
        B.put(w, "s", s)
        B.put(w, "free", free)
        work = self.problem.cost_kind in ("work", "cot") and self.structure is None
        for k, i in enumerate(self.chain):
            theta = None
            if self.structure is not None:
                theta = (
                    np.asarray(thetas[k], dtype=float)
                    if thetas is not None
                    else np.array([a.fraction for a in self.structure[k]])
                )
                theta = theta / theta.sum()
                B.put(w, f"Theta{k}", theta)
            tn = self.node_times(self.breaks(theta, k))
            Xk = np.asarray(states[k](tn), dtype=float)
            Uk = np.asarray(inputs[k](tn[1:]), dtype=float).reshape(len(self.model.inputs), -1)
            B.put(w, f"X{k}", Xk[:, 1:] if k == 0 else Xk)
            B.put(w, f"U{k}", Uk)
            B.put(w, f"T{k}", durations[k])
            if self.implicit is not None:
                flow = self.model.phases[i].flow.map(Xk.shape[1] - 1)
                rates = np.asarray(flow(Xk[:, 1:], Uk, p), dtype=float)
                B.put(w, f"A{k}", rates[Xk.shape[0] // 2 :])
            if work:
                rates = np.asarray(
                    self.model.input_rates(i).map(Xk.shape[1] - 1)(Xk[:, 1:], p), dtype=float
                )
                power = Uk * rates
                B.put(w, f"Pplus{k}", np.maximum(power, 0.0))
                B.put(w, f"Pminus{k}", np.maximum(-power, 0.0))
        return w

    def from_solution(self, other: Collocation, w: np.ndarray, p: np.ndarray) -> np.ndarray:
        """A warm start on this mesh from a solution ``w`` of ``other`` (its polynomials)."""
        sol = other.unpack(w, p)
        br = sol["breaks"]
        states = [
            (lambda t, k=k: other.evaluate(sol["X"][k], sol["U"][k], t, br[k])[0])
            for k in range(len(self.chain))
        ]
        inputs = [
            (lambda t, k=k: other.evaluate(sol["X"][k], sol["U"][k], t, br[k])[1])
            for k in range(len(self.chain))
        ]
        thetas = None
        if self.structure is not None and other.structure is not None:
            thetas = [other.theta_of(w, k) for k in range(len(self.chain))]
        return self.pack(sol["s"], sol["free"], states, inputs, sol["T"], sol["p"], thetas)
