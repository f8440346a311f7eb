"""Radau collocation as a :class:`~gaitopt.orbit.transcription.Transcription`: a
:class:`~gaitopt.optimize.collocation.Collocation` (a :class:`GaitProblem` on a
:class:`RadauMesh`) seen through the contract both transcriptions keep.

Columns (rule 1): the collocation's own blocks — ``"s"``, ``"free"`` (free parameters), per
phase ``k`` ``"Xk"`` (states at the nodes), ``"Uk"`` (inputs at the Radau points), ``"Tk"``
(duration) and, where the transcription has them, ``"Ak"``, ``"Thetak"``, ``"Pplusk"``,
``"Pminusk"`` and the spectral bound's blocks.  Rows: its constraint groups
(``"dynamics (stance)"``, ``"guard 'heel strike' at the end of stance"``, ``"periodicity"``, …;
a name used twice gets ``" #2"``).  The residual is the NLP's constraint vector ``g``, with its
inequalities (rule 3); the inputs are unknowns, so ``u`` is empty."""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from ..orbit.layout import Layout
from ..orbit.referee import TIGHT
from ..orbit.referee import referee as _referee
from ..orbit.transcription import Bounds, ReturnMap, Symbols
from .collocation import Collocation, RadauMesh
from .floquet import return_map_jacobian
from .problem import GaitProblem, as_problem
from .verify import (
    REPEATED_OPTIMUM,
    dense_arcs,
    feedforward_of,
    orbit_arcs,
    profiles,
    simulated_cost,
)

__all__ = ["CollocationTranscription", "Residual"]

#: The referee's return tolerance of an optimum (relative to ``1 + max |x*|``), as
#: :func:`gaitopt.optimize_gait`'s.
RETURN_TOL = 1e-6


@dataclass(frozen=True)
class Residual:
    """Rule 2: the constraint vector ``F = g(w)`` and its Jacobian ``F_w``."""

    F: np.ndarray
    F_w: np.ndarray | None


class CollocationTranscription:
    """The collocation of a gait statement (``problem``: a :class:`GaitProblem`, or the model
    and :func:`gaitopt.optimize_gait`'s keywords) on ``mesh``, or around a given ``col``.

    The front door :func:`gaitopt.optimize_gait` keeps its own solver (IPOPT with the compiled
    node kernels' derivatives); this view differentiates the plain graph ``Collocation.nlp``.
    """

    def __init__(
        self,
        problem: GaitProblem | Any = None,
        mesh: RadauMesh | None = None,
        *,
        col: Collocation | None = None,
        **statement: Any,
    ):
        if col is None:
            if not isinstance(problem, GaitProblem):
                problem = as_problem(problem, **statement)
            col = Collocation(problem, mesh or RadauMesh(6, 6))
        self.col = col
        self.model = col.problem.model
        self.steps = col.problem.steps

    # -- rule 1 -------------------------------------------------------------------------------
    @cached_property
    def columns(self) -> Layout:
        B = self.col.blocks
        # A column block (s, T, free) is a run of entries; a matrix (X, U) keeps its shape.
        shapes = [(r,) if c == 1 else (r, c) for r, c in B.shapes]
        return Layout.from_sizes(zip(B.names, shapes, strict=True))

    @cached_property
    def rows(self) -> Layout:
        entries, seen = [], {}
        for g in self.col.groups:
            seen[g.name] = seen.get(g.name, 0) + 1
            name = g.name if seen[g.name] == 1 else f"{g.name} #{seen[g.name]}"
            entries.append((name, g.size))
        return Layout.from_sizes(entries)

    @property
    def u(self) -> np.ndarray:
        return np.zeros(0)

    @property
    def p(self) -> np.ndarray:
        return np.asarray(self.model.p, dtype=float)

    @property
    def square(self) -> bool:
        return bool(np.all(self.col.lbg == self.col.ubg) and self.rows.size == self.columns.size)

    # -- rules 2, 3 ---------------------------------------------------------------------------
    @cached_property
    def _residual_jacobian(self) -> ca.Function:
        nlp = self.col.nlp
        g, x = nlp["g"], nlp["x"]
        return ca.Function("g_jac", [x, nlp["p"]], [g, ca.jacobian(g, x)])

    def evaluate(self, w, u=None, p=None, *, jacobian: bool = True) -> Residual:
        p = self.p if p is None else p
        w = np.asarray(w, dtype=float).ravel()
        if not jacobian:
            return Residual(np.asarray(self.col.constraints(w, p), dtype=float).ravel(), None)
        F, F_w = self._residual_jacobian(w, p)
        return Residual(np.asarray(F, dtype=float).ravel(), np.asarray(ca.DM(F_w).full()))

    def bounds(self) -> Bounds:
        c = self.col
        return Bounds(c.lbx.copy(), c.ubx.copy(), c.lbg.copy(), c.ubg.copy())

    # -- rule 4 -------------------------------------------------------------------------------
    def _sol(self, w) -> dict[str, Any]:
        return self.col.unpack(w, self.p)

    def orbit(self, w) -> list[Any]:
        return orbit_arcs(self.col, self._sol(w))

    def dense_arcs(self, w) -> list[Any]:
        return dense_arcs(self.col, self._sol(w))

    def fixed_point(self, w) -> np.ndarray:
        return np.asarray(self.model.lift(self._sol(w)["s"]), dtype=float).ravel()

    def durations(self, w) -> np.ndarray:
        return np.asarray(self._sol(w)["T"], dtype=float)

    # -- rule 5 -------------------------------------------------------------------------------
    def return_map_jacobians(self, w) -> ReturnMap:
        """``A`` by the implicit function theorem on the collocation equations
        (:func:`gaitopt.optimize.floquet.return_map_jacobian`); the inputs are a profile, not a
        per-step constant, so ``B_u`` and ``B_p`` are None."""
        return ReturnMap(return_map_jacobian(self.col, np.asarray(w, float).ravel(), self.p))

    # -- rule 6 -------------------------------------------------------------------------------
    def refined(self) -> CollocationTranscription:
        """Twice the intervals per phase (each arc of a structure too)."""
        c = self.col
        structure = c.structure
        if structure is not None:
            structure = [[replace(a, intervals=2 * a.intervals) for a in arcs]
                         for arcs in structure]  # fmt: skip
        return CollocationTranscription(col=Collocation(c.problem, c.mesh.refined(), structure))

    def carry(self, w, coarse: CollocationTranscription) -> np.ndarray:
        """``coarse``'s polynomials at this mesh's nodes (:meth:`Collocation.from_solution`)."""
        return self.col.from_solution(coarse.col, np.asarray(w, float).ravel(), self.p)

    def error_estimate(self, w) -> float:
        """The collocation defects of ``w``'s polynomials on the refined mesh: the largest
        ``|x'(τ) h − h f(x(τ), u(τ))|`` row of its ``dynamics`` groups (state units), at
        ``refined()``'s nodes — zero where the polynomials solve the ODE exactly."""
        fine = self.refined()
        F = fine.evaluate(fine.carry(w, self), jacobian=False).F
        rows = [b for b in fine.rows if b.name.startswith("dynamics")]
        return float(max(np.max(np.abs(F[b.slice])) for b in rows))

    # -- rule 7 -------------------------------------------------------------------------------
    @cached_property
    def symbols(self) -> Symbols:
        c = self.col
        phases = self.model.phases
        return Symbols(
            w=c.nlp["x"], u=ca.MX.sym("u", 0), p=c.nlp["p"], F=c.nlp["g"], objective=c.nlp["f"],
            states=list(c._X), inputs=list(c._U), durations=list(c._T),
            state_names=[tuple(phases[i].states) for i in c.chain],
            input_names=[tuple(self.model.inputs)] * len(c.chain),
        )  # fmt: skip

    # -- the optional hooks of gaitopt.orbit.solve ----------------------------------------------
    #: What to ask for when a period-k optimum is a shorter one repeated.
    repeated_advice = REPEATED_OPTIMUM

    def parameters(self, w) -> np.ndarray:
        """The parameter vector at ``w`` (the free parameters' values in it)."""
        return np.asarray(self._sol(w)["p"], dtype=float).ravel()

    def gait_model(self, w) -> Any:
        """The model at ``w``'s free parameter values (the model itself without free ones)."""
        free = self.col.problem.free
        if not free:
            return self.model
        values = self.col.blocks.get(np.asarray(w, float).ravel(), "free").ravel()
        return self.model.replace(**dict(zip(free, map(float, values), strict=True)))

    def consistency(self, w) -> str | None:
        """The slack transcription of a work cost splits the power into its positive and
        negative parts complementarily (``p⁺ p⁻ ≤ 1e-6`` W at every node), else why not."""
        col = self.col
        if col.problem.cost_kind not in ("work", "cot") or col.structure is not None:
            return None
        B, w = col.blocks, np.asarray(w, float).ravel()
        overlap = max(
            float(np.max(np.minimum(B.get(w, f"Pplus{k}"), B.get(w, f"Pminus{k}"))))
            for k in range(len(col.chain))
        )
        if overlap > 1e-6:
            return f"the power split is not complementary (p⁺p⁻ overlap {overlap:.2g} W)"
        return None

    # -- rule 8 -------------------------------------------------------------------------------
    def referee(self, w, tol: float = RETURN_TOL):
        """The common referee with the input profile as a feedforward and the cost, at the
        tight tolerances (its return error and cost are reported figures), on the model at
        ``w``'s free parameter values (as :func:`gaitopt.optimize_gait`'s certificate)."""
        problem, sol = self.col.problem, self._sol(w)
        model = self.gait_model(w)
        profs = profiles(self.col, sol)
        return _referee(
            model, model.lift(sol["s"]), np.asarray(sol["T"], dtype=float),
            problem.steps, tol=tol, feedforward=feedforward_of(profs),
            max_phase_time=problem.max_phase_time,
            cost=(float(sol["cost"]), lambda sim: simulated_cost(problem, model, sim, profs)),
            tolerances=(TIGHT,),
        )  # fmt: skip

    # -- a start ------------------------------------------------------------------------------
    def guess(self) -> np.ndarray:
        """The optimiser's start 0: a simulation from the model's default start
        (:mod:`gaitopt.optimize.guess`)."""
        from .guess import _start_guess

        return _start_guess(self.col, self.col.problem, 0, 0, None)
