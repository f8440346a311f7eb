"""Multiple shooting as a :class:`~gaitopt.orbit.transcription.Transcription`: a
:class:`~gaitopt.shooting.problem.ShootingProblem` (the shooting equations of a model class, its
compiled kernels underneath) bound to a model's parameters and a constant per-step input.

Columns (rule 1): ``"s"`` (the section coordinates), then per phase ``k`` of the orbit ``"Xk"``
(its segment start states, ``n × S``; the first phase's first column is ``lift(s)`` and not an
unknown) and ``"Tk"`` (its duration).  Rows: per phase ``"continuity (…)"`` (the segments' gaps),
``"guard '…' (…)"`` (the phase ends on its guard), ``"reset after …"`` (the next phase starts at
the reset state), and last ``"periodicity"``."""

from __future__ import annotations

from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from ..hybrid import HybridModel
from ..orbit.layout import Layout
from ..orbit.referee import LADDER, referee
from ..orbit.transcription import Bounds, ReturnMap, Symbols
from ..stability import section_jacobians
from .certify import dense_arcs
from .problem import MultipleShooting, ShootingProblem, shooting_problem

__all__ = ["ShootingTranscription"]


class ShootingTranscription:
    """The shooting equations of ``model`` (its class, its parameters) with the constant
    per-step input ``u`` (default the model's nominal one), ``steps`` returns per orbit and the
    mesh ``disc`` (default the model's), or around a given ``problem``.

    Attributes
    ----------
    problem : ShootingProblem
        The shooting equations (cached per model class, mesh and steps).
    model, steps, u, p
        As the protocol says (rules 2, 4).
    """

    def __init__(
        self,
        model: HybridModel,
        *,
        steps: int = 1,
        u: Any = None,
        disc: MultipleShooting | None = None,
        problem: ShootingProblem | None = None,
    ):
        if problem is None:
            disc = disc or MultipleShooting(*type(model).mesh)
            problem = shooting_problem(type(model), disc, steps)
        self.problem = problem
        self.model = model
        self.steps = problem.cycles
        self._u = np.asarray(model.nominal_input() if u is None else u, dtype=float).ravel()

    # -- rule 1: named blocks -----------------------------------------------------------------
    @cached_property
    def columns(self) -> Layout:
        entries: list[tuple[str, Any]] = [("s", self.problem.m)]
        for kind, k, _off, shape in self.problem.layout:
            entries.append((f"X{k}", shape) if kind == "nodes" else (f"T{k}", 1))
        return Layout.from_sizes(entries)

    @cached_property
    def rows(self) -> Layout:
        pr = self.problem
        S = pr.disc.segments
        entries: list[tuple[str, Any]] = []
        for k, i in enumerate(pr.chain):
            phase = pr.phases[i]
            label = phase.name if len(pr.chain) == 1 else f"{phase.name} #{k + 1}"
            entries.append((f"continuity ({label})", (phase.n, S - 1)))
            entries.append((f"guard '{phase.transitions[0].name}' ({label})", 1))
            if k + 1 < len(pr.chain):
                entries.append((f"reset after {label}", pr.phases[pr.chain[k + 1]].n))
        entries.append(("periodicity", pr.m))
        return Layout.from_sizes(entries)

    @property
    def u(self) -> np.ndarray:
        return self._u

    @property
    def p(self) -> np.ndarray:
        return np.asarray(self.model.p, dtype=float)

    @property
    def square(self) -> bool:
        return True

    # -- rules 2, 3 ---------------------------------------------------------------------------
    def evaluate(self, w, u=None, p=None):
        """:meth:`ShootingProblem.evaluate`: ``F``, ``F_w``, ``F_u``, ``F_p``, phase ends."""
        return self.problem.evaluate(w, self._u if u is None else u, self.p if p is None else p)

    def bounds(self) -> Bounds:
        lbw, ubw = self.problem.bounds()
        zero = np.zeros(self.problem.size)
        return Bounds(lbw, ubw, zero, zero.copy())

    # -- rule 4: the orbit --------------------------------------------------------------------
    def orbit(self, w) -> list[Any]:
        return self.problem.orbit(w, self._u, self.p)

    def dense_arcs(self, w) -> list[Any]:
        ev = self.problem.evaluate(w, self._u, self.p, jacobian=False)
        return dense_arcs(self.model, self.problem, self.orbit(w), self._u,
                          self.durations(w), ev.ends)  # fmt: skip

    def fixed_point(self, w) -> np.ndarray:
        return np.asarray(self.model.lift(self.problem.section_point(w)), dtype=float).ravel()

    def durations(self, w) -> np.ndarray:
        return self.problem.durations(w)

    # -- rule 5: the return map ---------------------------------------------------------------
    def return_map_jacobians(self, w) -> ReturnMap:
        """By the implicit function theorem on the shooting equations
        (:func:`gaitopt.stability.section_jacobians`), in ``s``, ``u`` and ``p``."""
        ev = self.evaluate(w)
        pr = self.problem
        J_up = np.hstack([np.asarray(ev.F_u, float), np.asarray(ev.F_p, float)])
        A, B = section_jacobians(pr.map_jacobian(ev.F_w), J_up, pr.m, pr.n_g)
        n_u = self._u.size
        return ReturnMap(A, B[:, :n_u], B[:, n_u:])

    # -- rule 6: refinement -------------------------------------------------------------------
    def refined(self) -> ShootingTranscription:
        """Twice the RK steps per segment (the same unknowns)."""
        fine = shooting_problem(type(self.model), self.problem.disc.refined(), self.steps)
        return ShootingTranscription(self.model, u=self._u, problem=fine)

    def carry(self, w, coarse) -> np.ndarray:
        """The unknowns do not depend on the RK steps: ``w`` as it is."""
        return np.array(w, dtype=float).ravel()

    def error_estimate(self, w) -> float:
        """The size of one Newton correction from ``w`` towards the mesh with twice the RK steps
        (what :func:`gaitopt.find_limit_cycle` reports as ``discretisation_error``)."""
        ev = self.evaluate(w)
        correction = self.problem.newton_step(
            ev.F_w, self.problem.fine_residual(w, self._u, self.p)
        )
        return float(np.max(np.abs(correction)))

    # -- rule 7: symbols ----------------------------------------------------------------------
    @cached_property
    def symbols(self) -> Symbols:
        pr = self.problem
        g = pr._graph  # the one MX graph of the shooting equations (shooting/symbolic.py)
        cols = self.columns
        s = g.w[cols["s"]]
        states, inputs, durations, names = [], [], [], []
        for k, i in enumerate(pr.chain):
            phase = pr.phases[i]
            b = cols.block(f"X{k}")
            X = ca.reshape(g.w[b.slice], b.shape[0], b.shape[1])
            if k == 0:
                X = ca.horzcat(pr.section.lift(s, g.p), X)
            states.append(X)
            inputs.append(ca.repmat(g.u, 1, pr.disc.segments))
            durations.append(g.w[cols[f"T{k}"]])
            names.append(tuple(phase.states))
        return Symbols(
            w=g.w, u=g.u, p=g.p, F=g.F, objective=ca.MX(0), states=states, inputs=inputs,
            durations=durations, state_names=names,
            input_names=[tuple(self.model.inputs)] * len(pr.chain),
        )  # fmt: skip

    # -- rule 8 -------------------------------------------------------------------------------
    def referee(self, w, tol: float):
        """The common referee with the constant input (:mod:`gaitopt.shooting.verify`'s)."""
        return referee(
            self.model, self.fixed_point(w), self.durations(w), self.steps, tol=tol,
            inputs=self._u, max_phase_time=float(self.model.max_phase_time), tolerances=LADDER,
        )  # fmt: skip

    # -- a start ------------------------------------------------------------------------------
    def guess(self, guess=None) -> np.ndarray:
        """Unknowns from a simulation of ``steps`` returns from the section point ``guess``
        (a mapping of section coordinates; default the model's default start)."""
        from ..arguments import section_guess
        from ..simulation import simulate

        s = section_guess(self.model, guess)
        sim = simulate(
            self.model,
            self.model.lift(s),
            steps=self.steps,
            inputs=self._u,
            max_phase_time=float(self.model.max_phase_time),
            rtol=1e-8,
            atol=1e-9,
            constraints=False,
        )  # fmt: skip (as find_limit_cycle's guess)
        return self.problem.unknowns_from_simulation(s, sim)
