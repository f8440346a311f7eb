"""Floquet multipliers of an optimal gait with its input applied as a feedforward ``u(t)``.

The return map takes section coordinates ``s`` to those of the next return, with the input a
fixed function of the time since the section (so a perturbed step that lasts longer or shorter
sees the same ``u(t)``; past the profile's end the last value holds).  Its Jacobian is built
here by differentiating *the transcription itself*: on each phase, the Radau collocation
equations at the nominal duration define the discrete flow map; the implicit function theorem
on them (exact CasADi derivatives) gives its sensitivity to the phase's start state and to a
shift ``δt₀`` of its start time (which shifts the inputs the nodes see by ``u̇ δt₀``).  Each phase
end adds the time to the guard, ``δτ = −(g_x δx + g_u u̇ δt₀) / ġ`` (the saltation correction,
Aizerman & Gantmacher 1958; Hiskens & Pai 2000), and the reset's Jacobian.  The construction is
:mod:`gaitopt.orbit.sensitivity`'s (rules 2–4); this module reads the transcription's solution
into its arcs.  The independent
check is :func:`gaitopt.optimize.verify.map_jacobian_fd`: finite differences of the simulated
map.
"""

from __future__ import annotations

import numpy as np

from ..orbit.sensitivity import (
    CollocatedArc,
    collocated_return_map,
    defect_function,
    defect_jacobians,
    lift_jacobian,
    multipliers,
)
from .collocation import Collocation
from .radau import _derivative_matrix

__all__ = ["collocated_arcs", "return_map_jacobian", "multipliers_of"]

_phase_residual = defect_function  # the symbolic defects' Jacobians (rule 2's reference)


def _sensitivity(col: Collocation, k: int, flow, X, U, Ud, hs, p) -> tuple[np.ndarray, ...]:
    """``(R_X, R_z)`` of phase ``k``'s defects (:func:`gaitopt.orbit.sensitivity.defect_jacobians`
    with this transcription's collocation matrix and kernel label)."""
    return defect_jacobians(flow, col.C, X, U, Ud, hs, p, label=_label(col, k))


def _label(col: Collocation, k: int) -> str:
    return f"{type(col.model).__name__.lower()}_{col.chain[k]}"


def collocated_arcs(
    col: Collocation, w: np.ndarray, p_model: np.ndarray
) -> tuple[list[CollocatedArc], np.ndarray, np.ndarray]:
    """The solution's phases as :class:`~gaitopt.orbit.sensitivity.CollocatedArc` (with the
    inputs' rates at the Radau points), ``∂lift/∂s`` at its section point, and ``p``."""
    sol = col.unpack(w, p_model)
    p, model, N, d = sol["p"], col.model, col.N, col.d
    D = _derivative_matrix(col.tau[1:], col.tau[1:])  # du/dτ at the Radau points
    n_cycle = len(model.phases)
    arcs = []
    for k, i in enumerate(col.chain):
        phase = model.phases[i]
        tr = phase.transitions[0]
        U = sol["U"][k]
        hs = float(sol["T"][k]) * np.diff(sol["breaks"][k])
        Ud = np.hstack([U[:, j * d : (j + 1) * d] @ D.T / hs[j] for j in range(N)])
        arcs.append(CollocatedArc(phase.flow, tr.guard, tr.reset, col.C, sol["X"][k], U, Ud, hs,
                                  _label(col, k), (k + 1) % n_cycle == 0))  # fmt: skip
    L = np.asarray(lift_jacobian(model.section.lift)(sol["s"], p), dtype=float)
    return arcs, L, p


def return_map_jacobian(col: Collocation, w: np.ndarray, p_model: np.ndarray) -> np.ndarray:
    """``∂P/∂s`` of the return map (all ``steps`` returns of the orbit) in section coordinates,
    with the optimal input as a feedforward in the time since each return to the section."""
    arcs, L, p = collocated_arcs(col, w, p_model)
    return collocated_return_map(arcs, L, col.section_index, p)[0]


multipliers_of = multipliers  # eigenvalues of the return-map Jacobian, largest modulus first
