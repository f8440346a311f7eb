"""Limit cycles of hybrid models by multiple shooting, solved with CasADi.

Transcription (one stage per phase, resets as linking constraints; rockit's layout):

* unknowns ``w = [s; z]``: the section coordinates ``s`` of the orbit's first state, then for each
  phase of the cycle (repeated ``cycles`` times for a period-k orbit) its segment start states and
  its free duration ``T``;
* equations: inside each phase, the end of segment j is the start of segment j + 1 (*close the
  gaps*); the last segment ends on the phase's guard (*impact at the phase end*); the reset of that
  end state is the next phase's first state (*reset links the phases*); and after the last phase,
  the reset state has the section coordinates ``s`` again (*periodicity*).  For smooth autonomous
  systems the section equation, built into ``lift(s)``, is the phase condition.

The system is square; Newton (CasADi ``rootfinder``, with line search) solves it, or IPOPT
(``nlpsol``) as a feasibility problem with positive durations.  The guess comes from a simulation.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..fastcall import call1
from ..hybrid import HybridModel
from ..orbit.sensitivity import map_blocks
from ..result import OrbitArc
from .newton import solve as _solve
from .symbolic import SymbolicShooting

__all__ = ["MultipleShooting", "ShootingProblem", "shooting_problem"]


@dataclass(frozen=True)
class MultipleShooting:
    """The discretisation: how each phase is cut and integrated.

    Attributes
    ----------
    segments : int
        Shooting segments per phase (equal fractions of the free phase duration).
    rk_steps : int
        Fixed RK steps (Dormand–Prince order 8) per segment (``steps`` elsewhere in gaitopt
        always counts returns to the section).
    dense : int
        Samples per segment for the guard check and the plotted orbit.
    """

    segments: int = 4
    rk_steps: int = 5
    dense: int = 16

    def __post_init__(self) -> None:
        for name in ("segments", "rk_steps", "dense"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise GaitoptInputError(
                    f"MultipleShooting: `{name}` must be a positive integer, got {value!r}"
                )

    def refined(self) -> MultipleShooting:
        """The same mesh with twice the RK steps per segment (the error estimate's mesh)."""
        return replace(self, rk_steps=2 * self.rk_steps)

    def coarsened(self) -> MultipleShooting:
        """The same mesh with half the RK steps per segment (at least one)."""
        return replace(self, rk_steps=max(self.rk_steps // 2, 1))


class ShootingProblem(SymbolicShooting):
    """The shooting equations of a model class, a discretisation and a number of cycles.

    The *problem* (rockit's stage, BifurcationKit's problem interface): its unknowns ``w`` (laid
    out in :attr:`layout`), residual ``F(w, u, p)`` and Jacobians (:meth:`evaluate`), bounds
    (:meth:`bounds`), and the map back to phases and orbits (:meth:`pack`, :meth:`unpack`,
    :meth:`orbit`, :meth:`section_point`).  The *methods* that solve it are separate:
    :meth:`solve` runs Newton (:mod:`gaitopt.shooting.newton`) or IPOPT, with an optional
    objective; :func:`gaitopt.shooting.certify` turns a solution into a checked
    :class:`~gaitopt.LimitCycle`.  Parameters ``p`` and inputs ``u`` are arguments, not part of
    the problem, so one problem (built once per model class, cached by :func:`shooting_problem`)
    serves every parameter value.

    Attributes
    ----------
    model_cls : type of HybridModel
    disc : MultipleShooting
    cycles : int
        Returns to the section per orbit (period-k orbits: ``cycles = k``).
    chain : list of int
        The phase index of each stage, in orbit order (the phases repeated ``cycles`` times).
    m : int
        Number of section coordinates ``s`` (the first ``m`` unknowns).
    size : int
        Number of unknowns (and of equations: the system is square).
    n_g : int
        Number of equations before the periodicity block (``F = [G; P − s]``).
    layout : list of tuple
        ``(kind, stage, offset, shape)`` for each block of ``w`` after ``s``: ``"nodes"``
        (segment start states, ``n × S`` column-major; the first stage's first column is the
        lifted section point and is not an unknown) and ``"duration"``.
    """

    def __init__(self, model_cls: type[HybridModel], disc: MultipleShooting, cycles: int):
        structure = model_cls.structure()
        self.model_cls = model_cls
        self.phases = structure.phases
        self.section = structure.section
        self.cycles = cycles
        self.disc = disc
        self.chain = [i for _ in range(cycles) for i in range(len(self.phases))]
        S = disc.segments
        states0 = self.phases[0].states
        self.section_index = [states0.index(c) for c in self.section.coordinates]
        m = len(self.section.coordinates)
        self.m = m
        self._assemblies: dict[int, Any] = {}
        self._ipopt_solvers: dict[tuple, ca.Function] = {}

        # The layout of w (cheap; the CasADi graph is built only when a function needs it).
        self.layout = []  # (kind, chain index, offset, shape)
        offset = m
        for k, i in enumerate(self.chain):
            n = self.phases[i].n
            free_cols = S - 1 if k == 0 else S
            self.layout.append(("nodes", k, offset, (n, free_cols)))
            offset += n * free_cols
            self.layout.append(("duration", k, offset, ()))
            offset += 1
        self.size = offset
        self.n_g = self.size - m

    # -- the compiled kernels (gaitopt.kernels) ----------------------------------------------
    def assembly(self, rk_steps: int | None = None):
        """The shooting system from the compiled kernels (:mod:`gaitopt.kernels.assemble`),
        with ``rk_steps`` RK steps per segment (default: this mesh's), or None where the model has
        no kernels."""
        key = self.disc.rk_steps if rk_steps is None else rk_steps
        if key not in self._assemblies:
            from ..kernels.assemble import Assembly

            try:
                self._assemblies[key] = Assembly(self, rk_steps=key)
            except NotImplementedError:
                self._assemblies[key] = None
        return self._assemblies[key]

    def evaluate(self, w, u, p, *, jacobian: bool = True):
        """The shooting equations at ``w`` (:class:`gaitopt.kernels.assemble.Evaluation`):
        ``F`` and its Jacobians in one compiled call, with the phase ends, guard rates,
        admissibility and durations; from the CasADi graph where there are no kernels."""
        asm = self.assembly()
        if asm is not None:
            return asm(w, u, p, jacobian=jacobian)
        from ..kernels.assemble import Evaluation

        F, F_w, F_p, F_u = (np.asarray(v, dtype=float) for v in self.residual_jacobians(w, u, p))
        x_return = np.asarray(self.linearisation(w, u, p)[3], dtype=float).ravel()
        ends, dg, adm, durations = (np.asarray(v, dtype=float) for v in self.checks(w, u, p))
        ends_list, at = [], 0
        for i in self.chain:
            n = self.phases[i].n
            ends_list.append(ends.ravel()[at : at + n])
            at += n
        return Evaluation(
            F.ravel(), F_w, F_u, F_p, x_return, ends_list, dg.ravel(), adm.ravel(),
            durations.ravel(),
        )  # fmt: skip

    def fine_residual(self, w, u, p) -> np.ndarray:
        """``F`` on the mesh with twice the RK steps per segment (the error estimate): only the
        residual, with no second transcription built."""
        asm = self.assembly(2 * self.disc.rk_steps)
        if asm is not None:
            return asm(w, u, p, jacobian=False).F
        fine = shooting_problem(self.model_cls, self.disc.refined(),
                             self.cycles)  # fmt: skip
        return np.asarray(fine.residual(w, u, p), dtype=float).ravel()

    def segment_starts(self, w, p) -> list[np.ndarray]:
        """The segment start states (n × S) of each phase of the chain."""
        w = np.asarray(w, dtype=float).ravel()
        x0 = call1(self.section.lift, w[: self.m], p).ravel()
        out = []
        for kind, k, off, shape in self.layout:
            if kind == "nodes":
                block = w[off : off + shape[0] * shape[1]].reshape(shape, order="F")
                out.append(np.column_stack([x0, block]) if k == 0 else block)
        return out

    def sample_numeric(self, w, u, p) -> list[np.ndarray]:
        """Dense samples of every phase (n × S·(dense + 1)), without the whole graph: in one
        call of the compiled Newton's library where the system has it
        (:meth:`gaitopt.kernels.newton.CompiledNewton.samples`, the same step kernels)."""
        S, q = self.disc.segments, self.disc.dense
        asm = self.assembly()
        compiled = asm.compiled_newton() if asm is not None else None
        if compiled is not None:
            return compiled.samples(w, u, p, q)
        starts = self.segment_starts(w, p)
        durations = [w[off] for kind, _, off, _ in self.layout if kind == "duration"]
        if self.assembly() is not None:  # the compiled RK step (gaitopt.kernels)
            from ..kernels import trajectory_function

            sampler = {i: trajectory_function(self.model_cls, i, S, q) for i in set(self.chain)}
        else:
            sampler = self._samplers
        return [
            call1(sampler[i], starts[k], u, p, durations[k] / S) for k, i in enumerate(self.chain)
        ]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` bounds of the unknowns: every duration at least
        :data:`MIN_DURATION` (a phase runs forwards in time), the rest free."""
        lower, upper = np.full(self.size, -np.inf), np.full(self.size, np.inf)
        lower[self.duration_index()] = MIN_DURATION
        return lower, upper

    def solve(self, w0, u, p, *, method: str = "newton", objective=None, free_inputs=False):
        """Solve from ``w0`` (:func:`gaitopt.shooting.newton.solve`): Newton on the square
        system, or IPOPT with :meth:`bounds` and an optional objective.

        Returns
        -------
        Solution
            ``w``, ``u`` (the inputs: optimised with ``free_inputs``), ``converged``,
            ``iterations`` and the :meth:`evaluate` result at ``w`` where Newton has it.
        """
        return _solve(self, w0, u, p, method=method, objective=objective, free_inputs=free_inputs)

    # -- the map between unknowns, phases and orbits ------------------------------------------
    def pack(self, s: np.ndarray, nodes: list[np.ndarray], durations: list[float]) -> np.ndarray:
        """Unknown vector from section coordinates, per-stage node arrays (n × S) and durations
        (s).  The first stage's first column (the lifted section point) is not stored."""
        w = np.zeros(self.size)
        w[: self.m] = s
        for kind, k, off, _shape in self.layout:
            if kind == "nodes":
                block = nodes[k][:, 1:] if k == 0 else nodes[k]
                w[off : off + block.size] = block.ravel(order="F")
            else:
                w[off] = durations[k]
        return w

    def unpack(self, w, p) -> tuple[np.ndarray, list[np.ndarray], np.ndarray]:
        """The inverse of :meth:`pack`: ``(s, nodes, durations)`` with each stage's segment
        start states (n × S; the first stage's first column lifted from ``s``)."""
        w = np.asarray(w, dtype=float).ravel()
        return w[: self.m].copy(), self.segment_starts(w, p), self.durations(w)

    def durations(self, w) -> np.ndarray:
        """Each stage's duration (s), in orbit order."""
        return np.asarray(w, dtype=float).ravel()[self.duration_index()]

    def section_point(self, w) -> np.ndarray:
        """The section coordinates ``s`` of the orbit's first state."""
        return np.asarray(w, dtype=float).ravel()[: self.m].copy()

    def duration_index(self) -> list[int]:
        """Positions of the durations in ``w``."""
        return [off for kind, _, off, _ in self.layout if kind == "duration"]

    def unknowns_from_simulation(self, s, sim) -> np.ndarray:
        """``w`` from a :class:`~gaitopt.Simulation` of the orbit's phases from the section point
        ``s``: each stage's segment starts sampled at equal fractions of its simulated arc."""
        S = self.disc.segments
        nodes, durations = [], []
        for arc in sim.arcs[: len(self.chain)]:
            T = arc.t1 - arc.t0
            t = arc.t0 + T * np.arange(S) / S
            nodes.append(np.atleast_2d(arc.solution(t)).reshape(-1, S))
            durations.append(T)
        return self.pack(s, nodes, durations)

    def fits(self, cycle) -> bool:
        """Whether a previous :class:`~gaitopt.LimitCycle` of a model of this class has this
        problem's phase sequence (so that :meth:`unknowns_from_cycle` can seed it)."""
        return (
            type(cycle.model) is self.model_cls
            and cycle.steps == self.cycles
            and len(cycle.orbit) == len(self.chain)
            and len(cycle.durations) == len(self.chain)
        )

    def unknowns_from_cycle(self, cycle) -> np.ndarray:
        """``w`` for a previous :class:`~gaitopt.LimitCycle` (a warm start, e.g. after a
        parameter change): its own solution vector where it was solved on this problem,
        otherwise its segment starts interpolated in its dense samples."""
        if cycle.problem is self and cycle.solution is not None:
            return np.array(cycle.solution, dtype=float)
        S = self.disc.segments
        nodes = []
        for arc in cycle.orbit:
            tau = (arc.t - arc.t[0]) / (arc.t[-1] - arc.t[0])
            at = np.arange(S) / S
            nodes.append(np.array([np.interp(at, tau, row) for row in arc.x]))
        return self.pack(cycle.section_point, nodes, [float(d) for d in cycle.durations])

    def orbit(self, w, u, p) -> list[OrbitArc]:
        """The orbit's dense samples, one :class:`~gaitopt.OrbitArc` per stage (times from 0 at
        the section, s; the input ``u`` held at every sample), from the same integrator as the
        residual."""
        samples = self.sample_numeric(w, u, p)
        durations = self.durations(w)
        q = self.disc.dense
        arcs, t0 = [], 0.0
        for k, i in enumerate(self.chain):
            X = np.asarray(samples[k], dtype=float)
            # Each segment gives q + 1 samples; drop the duplicated segment starts.
            j = np.arange(X.shape[1])
            X = X[:, (j % (q + 1) != 0) | (j == 0)]
            t = t0 + np.linspace(0.0, durations[k], X.shape[1])
            phase = self.phases[i]
            U = np.tile(np.asarray(u, dtype=float).reshape(-1, 1), (1, X.shape[1]))
            arcs.append(OrbitArc(i, phase.name, phase.states, t, X, phase.transitions[0].name, U))
            t0 += durations[k]
        return arcs

    # -- the return map's linearisation from the residual's Jacobian --------------------------
    def map_jacobian(self, F_w) -> np.ndarray:
        """``∂[G; P]/∂w`` from ``∂F/∂w`` (``F = [G; P − s]``): the blocks of the return map's
        Jacobian (:func:`gaitopt.orbit.sensitivity.section_jacobians`)."""
        return map_blocks(F_w, self.m, self.n_g)

    def correction(self, F_w, w, u, p) -> np.ndarray:
        """``−(∂F/∂w)⁻¹ F_fine(w)``: one Newton correction from ``w`` towards the mesh with twice
        the RK steps per segment (:meth:`fine_residual`), in one compiled call where the system
        has the compiled Newton (:mod:`gaitopt.kernels.newton`), else by :meth:`newton_step`;
        raises ``LinAlgError`` where ``F_w`` is singular."""
        asm = self.assembly()
        compiled = asm.compiled_newton() if asm is not None else None
        if compiled is not None:
            return compiled.correction(F_w, w, u, p, 2 * self.disc.rk_steps)
        return self.newton_step(F_w, self.fine_residual(w, u, p))

    def newton_step(self, F_w, F) -> np.ndarray:
        """``−(∂F/∂w)⁻¹ F``: one Newton correction (raises ``LinAlgError`` where singular)."""
        return -np.linalg.solve(np.asarray(F_w, dtype=float), np.asarray(F, dtype=float).ravel())


#: The shortest duration a phase may have in IPOPT's bounds (s): positive, so that a phase runs
#: forwards in time.
MIN_DURATION = 1e-9


@lru_cache(maxsize=64)
def shooting_problem(
    model_cls: type[HybridModel], disc: MultipleShooting, cycles: int
) -> ShootingProblem:
    """The cached :class:`ShootingProblem` (parameters are symbolic, so one per model class)."""
    return ShootingProblem(model_cls, disc, cycles)
