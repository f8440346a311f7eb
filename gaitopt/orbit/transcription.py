"""A periodic orbit of a hybrid model, transcribed: the contract both transcriptions keep.

gaitopt has two transcriptions of the same question (an orbit through ``model.phases`` that
returns to its section after ``steps`` cycles): multiple shooting
(:class:`gaitopt.shooting.transcription.ShootingTranscription`, around
:class:`~gaitopt.shooting.problem.ShootingProblem`) and Radau collocation
(:class:`gaitopt.optimize.transcription.CollocationTranscription`, around
:class:`~gaitopt.optimize.collocation.Collocation`).  The solvers of :mod:`gaitopt.orbit.newton`
and :mod:`gaitopt.orbit.ipopt` and :func:`gaitopt.orbit.solve.solve_gait` (solve → refine →
certify → referee) act on either through this contract only.

Rules (what an implementation must do; like SciPy's ``OdeSolver`` contract):

1. **Named blocks.** :attr:`~Transcription.columns` is a :class:`~gaitopt.orbit.layout.Layout`
   of the unknowns ``w``: every entry of ``w`` in exactly one named block (``"s"``, the section
   coordinates of the orbit's first state, always first).  :attr:`~Transcription.rows` names the
   residual's rows the same way.  Nobody reads ``w`` or the residual by position.
2. **One call, residual and Jacobian.** ``evaluate(w, u=None, p=None)`` returns an object with
   ``F`` (``rows.size``) and ``F_w`` (``rows.size × columns.size``, ``∂F/∂w``) at once, ``u``
   and ``p`` defaulting to the transcription's own (:attr:`~Transcription.u`: a constant
   per-step input, empty where the inputs are unknowns; :attr:`~Transcription.p`: the model's
   parameter vector).  It may carry more (the shooting's ``F_u``, ``F_p``, phase ends).
3. **Bounds.** ``bounds()`` returns :class:`Bounds`: ``lbw ≤ w ≤ ubw`` and ``lbg ≤ F ≤ ubg``.
   Rows with ``lbg == ubg`` are equations, the others inequalities.  A square transcription
   (:attr:`~Transcription.square`) has only equations, as many as unknowns.
4. **The orbit.** ``orbit(w)`` returns one :class:`~gaitopt.result.OrbitArc` per phase of the
   orbit (times in s since the section, states and inputs at dense samples); ``dense_arcs(w)``
   the certificate's :class:`~gaitopt.orbit.certificate.DenseArc` s; ``fixed_point(w)`` the
   orbit's full state on the section, ``durations(w)`` each phase's duration (s).
5. **The return map.** ``return_map_jacobians(w)`` returns :class:`ReturnMap`: ``A = ∂P/∂s``
   (its eigenvalues are the nontrivial Floquet multipliers), and ``B_u``, ``B_p``, its
   derivatives in a constant per-step input and in the parameters, or None where the
   transcription does not define them.
6. **Refinement.** ``refined()`` is the same transcription on a finer mesh (twice the RK steps
   per segment; twice the intervals per phase), and ``carry(w, coarse)`` maps a solution of
   ``coarse`` to a start on this mesh.  ``error_estimate(w)`` is a nonnegative number that
   measures the discretisation error at ``w`` and shrinks under :meth:`refined` (the shooting:
   one Newton correction towards the refined mesh; the collocation: the refined mesh's
   collocation defects at ``w``'s polynomials).
7. **Symbols.** :attr:`~Transcription.symbols` is a :class:`Symbols`: the CasADi symbols
   ``w``, ``u``, ``p``, the residual ``F`` and the transcription's own ``objective`` as
   expressions of them, and, per phase of the orbit, the node states, the node inputs and the
   duration as expressions of ``w`` — what an objective is written in.
8. **The referee.** ``referee(w, tol)`` simulates the orbit's fixed point with its inputs (the
   constant input, or the profile as a feedforward) by :func:`gaitopt.orbit.referee.referee`.
9. **A start.** ``guess()`` returns unknowns from a simulation of the model's default start
   (the front doors' own start), a point to hand :func:`gaitopt.orbit.solve_gait`.

Implementations sit above :mod:`gaitopt.orbit` (in ``gaitopt.shooting`` and
``gaitopt.optimize``); this module imports neither.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .layout import Layout

__all__ = ["Bounds", "ReturnMap", "Symbols", "Transcription"]


@dataclass(frozen=True)
class Bounds:
    """Rule 3: ``lbw ≤ w ≤ ubw``, ``lbg ≤ F(w) ≤ ubg`` (equal bounds: an equation)."""

    lbw: np.ndarray
    ubw: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray

    @property
    def equations(self) -> np.ndarray:
        """Boolean mask of the residual rows that are equations."""
        return np.asarray(self.lbg) == np.asarray(self.ubg)


@dataclass(frozen=True)
class ReturnMap:
    """Rule 5: the return map's linearisation in section coordinates.

    Attributes
    ----------
    A : numpy.ndarray
        ``∂P/∂s`` (m × m): its eigenvalues are the nontrivial Floquet multipliers.
    B_u : numpy.ndarray or None
        ``∂P/∂u`` (m × n_u) in a constant per-step input; None where undefined.
    B_p : numpy.ndarray or None
        ``∂P/∂p`` (m × n_p) in the model's parameter vector; None where undefined.
    """

    A: np.ndarray
    B_u: np.ndarray | None = None
    B_p: np.ndarray | None = None

    @property
    def multipliers(self) -> np.ndarray:
        """The eigenvalues of :attr:`A`, by decreasing modulus."""
        lam = np.linalg.eigvals(np.asarray(self.A, dtype=float))
        return lam[np.argsort(-np.abs(lam), kind="stable")]


@dataclass(frozen=True)
class Symbols:
    """Rule 7: the CasADi symbols and expressions an objective is written in.

    Attributes
    ----------
    w, u, p : casadi.MX
        The unknowns, the constant per-step input (empty where the inputs are unknowns) and
        the model's parameter vector (symbols).
    F : casadi.MX
        The residual (rule 2) as an expression of ``w``, ``u``, ``p``.
    objective : casadi.MX
        The transcription's own objective (0 for a feasibility problem).
    states, inputs : list of casadi.MX
        Per phase of the orbit: the states (n × nodes) and inputs (n_u × nodes) at its nodes.
    durations : list of casadi.MX
        Per phase of the orbit: its duration (s).
    state_names, input_names : list of tuple of str
        Per phase of the orbit: the names of the rows of ``states`` and ``inputs``.
    """

    w: Any
    u: Any
    p: Any
    F: Any
    objective: Any
    states: list[Any]
    inputs: list[Any]
    durations: list[Any]
    state_names: list[tuple[str, ...]] = field(default_factory=list)
    input_names: list[tuple[str, ...]] = field(default_factory=list)

    @property
    def period(self) -> Any:
        """The sum of the durations (s)."""
        total = self.durations[0]
        for d in self.durations[1:]:
            total = total + d
        return total

    def state(self, name: str, phase: int = 0) -> Any:
        """State ``name`` at the nodes of phase ``phase`` of the orbit (a row)."""
        names = self.state_names[phase]
        if name not in names:
            raise KeyError(f"no state {name!r} in phase {phase}; its states are {list(names)}")
        return self.states[phase][names.index(name), :]

    def input(self, name: str, phase: int = 0) -> Any:
        """Input ``name`` at the nodes of phase ``phase`` of the orbit (a row)."""
        names = self.input_names[phase]
        if name not in names:
            raise KeyError(f"no input {name!r}; the inputs are {list(names)}")
        return self.inputs[phase][names.index(name), :]


@runtime_checkable
class Transcription(Protocol):
    """A periodic orbit of a hybrid model, transcribed (rules 1–9 of the module docstring)."""

    #: The model, with its parameters.
    model: Any
    #: Returns to the section per orbit.
    steps: int

    @property
    def columns(self) -> Layout: ...

    @property
    def rows(self) -> Layout: ...

    @property
    def u(self) -> np.ndarray: ...

    @property
    def p(self) -> np.ndarray: ...

    @property
    def square(self) -> bool: ...

    @property
    def symbols(self) -> Symbols: ...

    def evaluate(self, w, u=None, p=None) -> Any: ...

    def bounds(self) -> Bounds: ...

    def orbit(self, w) -> list[Any]: ...

    def dense_arcs(self, w) -> list[Any]: ...

    def fixed_point(self, w) -> np.ndarray: ...

    def durations(self, w) -> np.ndarray: ...

    def return_map_jacobians(self, w) -> ReturnMap: ...

    def refined(self) -> Transcription: ...

    def carry(self, w, coarse: Transcription) -> np.ndarray: ...

    def error_estimate(self, w) -> float: ...

    def referee(self, w, tol: float) -> Any: ...

    def guess(self) -> np.ndarray: ...
