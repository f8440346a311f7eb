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

from ..fastcall import call1
from ..hybrid import HybridModel
from ..orbit.layout import Layout
from ..orbit.referee import LADDER, referee
from ..orbit.sensitivity import section_jacobians
from ..orbit.transcription import Bounds, ReturnMap, Symbols
from .dense import check_section, dense_arcs
from .problem import MultipleShooting, ShootingProblem, shooting_problem

__all__ = ["MAX_MESH_FACTOR", "ShootingTranscription"]

#: The finest mesh any solve may reach, as a multiple of the model's RK steps per segment: a
#: chain of warm starts (homotopy, libraries) refines from where the last one ended, up to here
#: (Van der Pol at μ = 10 needs 32×; without a bound the chain compounded to 22 GB).
MAX_MESH_FACTOR = 64


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

    Its evaluation at the last ``w`` it saw (a solver's, :meth:`remember`) is kept, so that
    the error estimate, the certificate and the multipliers read the Jacobian of the solve's
    last step (as :func:`gaitopt.find_limit_cycle` always has); ``linearisation`` (``(∂[G;
    P]/∂w, ∂[G; P]/∂u, F, x_return)``) overrides the return map's Jacobians and the section
    check where a caller has its own.
    """

    def __init__(
        self,
        model: HybridModel,
        *,
        steps: int = 1,
        u: Any = None,
        disc: MultipleShooting | None = None,
        problem: ShootingProblem | None = None,
        linearisation: tuple[Any, ...] | None = None,
    ):
        if problem is None:
            disc = disc or MultipleShooting(*type(model).mesh)
            problem = shooting_problem(type(model), disc, steps)
        self.problem = problem
        self.model = model
        self.steps = problem.cycles
        self._u = np.asarray(model.nominal_input() if u is None else u, dtype=float).ravel()
        self._memo: tuple[bytes, Any] | None = None  # (w's bytes, evaluation at w)
        self._correction: tuple[bytes, np.ndarray] | None = None  # (w's bytes, Newton step)
        self._orbit: tuple[bytes, list[Any]] | None = None  # (w's bytes, orbit at w)
        self.linearisation = linearisation

    def remember(self, w, evaluation: Any) -> None:
        """Keep ``evaluation`` (:meth:`ShootingProblem.evaluate` at ``w`` with this ``u`` and
        ``p``, a solver's last) as this transcription's evaluation at ``w``."""
        self._memo = (np.asarray(w, dtype=float).ravel().tobytes(), evaluation)

    def _evaluation(self, w) -> Any:
        key = np.asarray(w, dtype=float).ravel().tobytes()
        if self._memo is None or self._memo[0] != key:
            self._memo = (key, self.problem.evaluate(w, self._u, self.p))
        return self._memo[1]

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
        """:meth:`ShootingProblem.evaluate`: ``F``, ``F_w``, ``F_u``, ``F_p``, phase ends (the
        kept evaluation at ``w`` where ``u`` and ``p`` are the transcription's)."""
        if u is None and p is None:
            return self._evaluation(w)
        return self.problem.evaluate(w, self._u if u is None else u, self.p if p is None else p)

    def bounds(self) -> Bounds:
        lbw, ubw = self.problem.bounds()
        zero = np.zeros(self.problem.size)
        return Bounds(lbw, ubw, zero, zero.copy())

    # -- rule 4: the orbit --------------------------------------------------------------------
    def orbit(self, w) -> list[Any]:
        key = np.asarray(w, dtype=float).ravel().tobytes()
        if self._orbit is None or self._orbit[0] != key:  # kept: the certificate's and results'
            self._orbit = (key, self.problem.orbit(w, self._u, self.p))
        return self._orbit[1]

    def dense_arcs(self, w) -> list[Any]:
        ev = self._evaluation(w)
        durations = np.asarray(ev.durations, dtype=float).ravel()
        return dense_arcs(self.model, self.problem, self.orbit(w), self._u, durations,
                          ev.ends)  # fmt: skip

    def fixed_point(self, w) -> np.ndarray:
        return np.asarray(self.model.lift(self.problem.section_point(w)), dtype=float).ravel()

    def durations(self, w) -> np.ndarray:
        return self.problem.durations(w)

    # -- rule 5: the return map ---------------------------------------------------------------
    def return_map_jacobians(self, w) -> ReturnMap:
        """By the implicit function theorem on the shooting equations
        (:func:`gaitopt.orbit.sensitivity.section_jacobians`), in ``s`` and ``u`` (as
        :func:`gaitopt.find_limit_cycle` reports them), then in ``p``; raises
        ``numpy.linalg.LinAlgError`` where the equations are singular."""
        ev = self._evaluation(w)
        pr = self.problem
        if self.linearisation is None and getattr(ev, "return_map", None) is not None:
            return ReturnMap(*ev.return_map)  # the compiled Newton's, from the same Jacobian
        if self.linearisation is not None:
            J_w, J_u = (np.asarray(v, dtype=float) for v in self.linearisation[:2])
        else:
            J_w, J_u = pr.map_jacobian(ev.F_w), ev.F_u
        J_w, J_u = np.asarray(J_w, dtype=float), np.asarray(J_u, dtype=float)
        A, B_u = section_jacobians(J_w, J_u, pr.m, pr.n_g)
        _, B_p = section_jacobians(J_w, np.asarray(ev.F_p, dtype=float), pr.m, pr.n_g)
        return ReturnMap(A, B_u, B_p)

    # -- rule 6: refinement -------------------------------------------------------------------
    @property
    def refinable(self) -> bool:
        """Whether :meth:`refined` stays within :data:`MAX_MESH_FACTOR` times the model's RK
        steps (bounded in absolute terms, so that a chain of warm starts cannot compound
        refinements without limit)."""
        return 2 * self.problem.disc.rk_steps <= type(self.model).mesh[1] * MAX_MESH_FACTOR

    def refined(self) -> ShootingTranscription:
        """Twice the RK steps per segment (the same unknowns)."""
        fine = shooting_problem(type(self.model), self.problem.disc.refined(), self.steps)
        return ShootingTranscription(self.model, u=self._u, problem=fine)

    def carry(self, w, coarse) -> np.ndarray:
        """The unknowns do not depend on the RK steps: ``w`` plus ``coarse``'s Newton correction
        towards twice its RK steps (its :meth:`error_estimate`'s step) where this is that mesh,
        else ``w`` as it is."""
        w = np.array(w, dtype=float).ravel()
        if (
            isinstance(coarse, ShootingTranscription)
            and coarse.problem.disc.refined() == self.problem.disc
        ):
            return w + coarse.correction(w)
        return w

    def correction(self, w) -> np.ndarray:
        """One Newton step from ``w`` towards the mesh with twice the RK steps: ``−F_w⁻¹
        F_fine(w)`` (kept for ``w``); raises ``numpy.linalg.LinAlgError`` where ``F_w`` is
        singular."""
        key = np.asarray(w, dtype=float).ravel().tobytes()
        if self._correction is None or self._correction[0] != key:
            ev = self._evaluation(w)
            step = self.problem.correction(ev.F_w, w, self._u, self.p)
            self._correction = (key, step)
        return self._correction[1]

    def error_estimate(self, w) -> float:
        """The size of one Newton correction from ``w`` towards the mesh with twice the RK steps
        (what :func:`gaitopt.find_limit_cycle` reports as ``discretisation_error``)."""
        return float(np.max(np.abs(self.correction(w))))

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

    # -- the optional hooks of gaitopt.orbit.solve ----------------------------------------------
    def precheck(self, w) -> tuple[str, str] | None:
        """``("standing", why)`` where the orbit is an equilibrium (the state does not change:
        it solves the shooting equations with any phase duration), else None."""
        x_star = self.model.lift(np.asarray(w, dtype=float).ravel()[: self.problem.m])
        rate = call1(self.model.phases[0].flow, x_star, self._u, self.model.p)
        if float(np.max(np.abs(rate.ravel()))) <= 1e-8 * (1 + float(np.max(np.abs(x_star)))):
            return "standing", (
                "no gait: the orbit found is standing still "
                "(an equilibrium: the state does not change, zero step length), which solves the "
                "shooting equations with any phase "
                "duration but is not a gait; the gait may not exist at these parameters (a "
                "passive walker needs a slope), or try a guess with more speed"
            )
        return None

    def consistency(self, w) -> str | None:
        """The return state lies where the section's lift puts it (the model's own
        consistency)."""
        x_return = (self.linearisation[3] if self.linearisation is not None
                    else self._evaluation(w).x_return)  # fmt: skip
        x_star = self.model.lift(np.asarray(w, dtype=float).ravel()[: self.problem.m])
        return check_section(x_return, x_star)

    # -- rule 8 -------------------------------------------------------------------------------
    def referee(self, w, tol: float):
        """The common referee with the constant input (:mod:`gaitopt.shooting.verify`'s)."""
        durations = np.asarray(self._evaluation(w).durations, dtype=float).ravel()
        return referee(
            self.model, self.fixed_point(w), durations, self.steps, tol=tol,
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
