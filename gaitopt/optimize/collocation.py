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
``bounds`` read (:func:`~gaitopt.optimize.collocation_cost.bound_arcs`, found by
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

The transcription is five modules with one job each: this one (the :class:`Collocation`: its
mesh, and the map between the unknowns and the polynomials: :meth:`~Collocation.unpack`,
:meth:`~Collocation.evaluate`, :meth:`~Collocation.pack`), :mod:`.collocation_rows` (the
unknowns and each phase's rows, the NLP), :mod:`.collocation_cost` (the running cost and its
arcs), :mod:`.collocation_limits` (state bounds and limits: rows and checks) and
:mod:`.collocation_kernels` (the node kernels).
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from .collocation_cost import affine_in_inputs, bound_arcs, cost_rows, idle_inputs, ignored_inputs
from .collocation_kernels import (
    _implicit_dynamics,
    defect_block,
    node_block,
    phase_node_kernels,
    warm_kernels,
)
from .collocation_limits import (
    LIMIT_SAMPLES,
    LIMIT_TOL,
    active_limits,
    add_limits,
    certify_limits,
    check_limits,
    kept_by_guard,
    limit_values,
    phase_label,
)
from .collocation_rows import (
    Rows,
    Terms,
    check_structure,
    clearance_margin,
    finish,
    phase_margin,
    phase_rows,
    unknowns,
)
from .nodes import NodeBlock
from .problem import GaitProblem
from .radau import Arc, Group, RadauMesh, _derivative_matrix, lagrange_matrix

__all__ = [
    "Arc",
    "Collocation",
    "Group",
    "LIMIT_SAMPLES",
    "LIMIT_TOL",
    "RadauMesh",
    "lagrange_matrix",
    "phase_node_kernels",
    "warm_kernels",
]


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
        section = model.section
        self.m = len(section.coordinates)
        states0 = model.phases[0].states
        self.section_index = [states0.index(c) for c in section.coordinates]
        self.implicit = _implicit_dynamics(model) if len(model.phases) == 1 else None
        self.node_blocks: list[NodeBlock] = []
        work = problem.cost_kind in ("work", "cot")
        check_structure(self, structure, work)
        self.limit_groups: list[str] = []  # names of the rows of state bounds and limits
        self.guard_limits: list[tuple[int, str]] = []  # (phase, limit) kept by a guard's rows
        v = unknowns(self, structure, work and structure is None)  # sets self.blocks
        self.groups: list[Group] = []
        rows, terms = Rows(self.groups), Terms()
        for k, i in enumerate(self.chain):
            phase = phase_rows(self, rows.add, v, terms, k, i)
            cost_rows(self, rows.add, v, terms, k, i, phase)
        finish(self, rows, v, terms)  # the orbit's rows, the objective, the NLP

    # -- the pieces of the construction, from their modules ------------------------------------
    _node_block = node_block
    _defect_block = defect_block
    _bound_arcs = bound_arcs
    _affine_in_inputs = affine_in_inputs
    _idle_inputs = idle_inputs
    _ignored_inputs = ignored_inputs
    _add_limits = add_limits
    _kept_by_guard = kept_by_guard
    _clearance_margin = clearance_margin
    _phase_margin = phase_margin
    # -- state bounds and limits on a solution (collocation_limits) ----------------------------
    _limit_values = limit_values
    _phase_label = phase_label
    check_limits = check_limits
    active_limits = active_limits
    certify_limits = certify_limits

    def u_start_of(self, U: np.ndarray) -> np.ndarray:
        """The input polynomial of the first interval at its start (a column)."""
        return U[:, : self.d] @ self.u_at_start.reshape(-1, 1)

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
        for i in np.flatnonzero(np.bincount(interval)):  # the intervals sampled (np.unique
            # would import numpy.ma for its masked-array check: 16 ms of a first call)
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
        if (
            self.structure is not None
            and other.structure is not None
            and [len(a) for a in self.structure] == [len(a) for a in other.structure]
        ):  # the same arcs (else: this structure's own fractions, a cut of other's)
            thetas = [other.theta_of(w, k) for k in range(len(self.chain))]
        return self.pack(sol["s"], sol["free"], states, inputs, sol["T"], sol["p"], thetas)
