"""The periodic Riccati differential equation of the transverse dynamics, with its jumps.

Along each stage (Manchester et al. 2011, §IV; Drake's ``transverseLQR.m``)

    ``−Ṡ = A⊥ᵀ S + S A⊥ − S B⊥ R⁻¹ B⊥ᵀ S + Q⊥``,   ``Q⊥(τ) = Π(τ) Q Π(τ)ᵀ``,

and at each impact ``S⁻ = Jᵀ S⁺ J`` (the cost-to-go is carried through the transverse jump;
the input's effect through the impact, ``J_u``, is not designed for: it is zero where guards and
resets do not depend on the inputs, as for the walkers' joint torques, and the closed-loop
monodromy includes it either way).  The gain is ``K(τ) = R⁻¹ B⊥ᵀ S(τ)``, ``δu = −K x⊥``.

Each stage is solved through its Hamiltonian system: ``d/dτ [X; Y] = [[A⊥, −B⊥R⁻¹B⊥ᵀ],
[−Q⊥, −A⊥ᵀ]] [X; Y]``, whose transition ``Ψ(τ, T)`` from the stage's end (integrated backwards
once, dense) gives ``S(τ) = (Ψ₂₁ + Ψ₂₂ S_T)(Ψ₁₁ + Ψ₁₂ S_T)⁻¹`` for any end value ``S_T``.  The
periodic solution is the limit of the backward iteration over whole orbits (from ``S = 0``), which
converges to the stabilising solution where the transverse system is stabilisable and detectable
(Bittanti, Colaneri & De Nicolao 1991); it stops when one orbit changes ``S`` by less than
``1e-11`` relative.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .linearise import StageFrame, TransverseLinearisation
from .orbit import Pieces, integrate_pieces

__all__ = ["PeriodicRiccati", "periodic_riccati"]

_MAX_ORBITS = 2000
_RTOL = 1e-11


@dataclass
class PeriodicRiccati:
    """The periodic solution ``S(τ)`` and the gains ``K(τ)`` of each stage.

    Attributes
    ----------
    Q, R : numpy.ndarray
        The weights (state units⁻², input units⁻²).
    hamiltonians : list of Pieces
        Per stage, ``vec Ψ(τ, T)`` (backwards from the stage's end).
    ends : list of numpy.ndarray
        ``S`` at each stage's end (just before its impact).
    starts : list of numpy.ndarray
        ``S`` at each stage's start.
    orbits : int
        Backward orbits the iteration took.
    converged : bool
        The iteration met its tolerance.
    """

    lin: TransverseLinearisation
    Q: np.ndarray
    R: np.ndarray
    hamiltonians: list[Pieces] = field(default_factory=list)
    ends: list[np.ndarray] = field(default_factory=list)
    starts: list[np.ndarray] = field(default_factory=list)
    orbits: int = 0
    converged: bool = False

    def cost_matrix(self, stage: int, tau: float) -> np.ndarray:
        """``S(τ)`` in stage ``stage`` (``τ`` clipped to ``[0, T]``)."""
        frame = self.lin.frames[stage]
        T = frame.stage.duration
        tau = min(max(float(tau), 0.0), T)
        m = frame.n - 1
        Psi = self.hamiltonians[stage](tau).reshape(2 * m, 2 * m)
        S_T = self.ends[stage]
        S = (Psi[m:, :m] + Psi[m:, m:] @ S_T) @ np.linalg.inv(Psi[:m, :m] + Psi[:m, m:] @ S_T)
        return 0.5 * (S + S.T)

    def gain(self, stage: int, tau: float) -> np.ndarray:
        """``K(τ) = R⁻¹ B⊥ᵀ S(τ)`` (input units per transverse unit), ``τ`` clipped to
        ``[0, T]`` (the gain at the nearest end holds on the extensions)."""
        frame = self.lin.frames[stage]
        tau = min(max(float(tau), 0.0), frame.stage.duration)
        B = frame.at(tau)["B_perp"]
        return np.linalg.solve(self.R, B.T @ self.cost_matrix(stage, tau))


def _hamiltonian(frame: StageFrame, Q: np.ndarray, R_inv: np.ndarray) -> Pieces:
    stage = frame.stage
    m = frame.n - 1

    def rhs(tau: float, y: np.ndarray) -> np.ndarray:
        d = frame.at(tau)
        A, B, Pi = d["A_perp"], d["B_perp"], d["Pi"]
        H = np.block([[A, -B @ R_inv @ B.T], [-Pi @ Q @ Pi.T, -A.T]])
        return (H @ y.reshape(2 * m, 2 * m)).ravel()

    edges = stage.breaks[(stage.breaks >= 0) & (stage.breaks <= stage.duration)][::-1]
    _, pieces = integrate_pieces(rhs, np.eye(2 * m).ravel(), edges, rtol=_RTOL, atol=1e-12)
    assert pieces is not None
    return pieces


def periodic_riccati(
    lin: TransverseLinearisation, Q_stages: list[np.ndarray], R: np.ndarray
) -> PeriodicRiccati:
    """The periodic solution of the jump Riccati equation (``Q_stages``: the state weight in
    each stage's own states, n × n)."""
    R = np.atleast_2d(np.asarray(R, dtype=float))
    R_inv = np.linalg.inv(R)
    sol = PeriodicRiccati(lin, Q_stages[0], R)
    sol.hamiltonians = [
        _hamiltonian(fr, Q, R_inv) for fr, Q in zip(lin.frames, Q_stages, strict=True)
    ]
    K = len(lin.frames)
    starts = [np.zeros((fr.n - 1, fr.n - 1)) for fr in lin.frames]
    ends = [np.zeros_like(s) for s in starts]
    Psi0 = []
    for j, fr in enumerate(lin.frames):
        m = fr.n - 1
        Psi0.append(sol.hamiltonians[j](0.0).reshape(2 * m, 2 * m))
    S_next = starts[0]
    for orbit in range(1, _MAX_ORBITS + 1):
        previous = starts[0].copy()
        for j in reversed(range(K)):
            m = lin.frames[j].n - 1
            J = lin.jumps[j]
            S_T = J.T @ S_next @ J
            S_T = 0.5 * (S_T + S_T.T)
            Psi = Psi0[j]
            S0 = (Psi[m:, :m] + Psi[m:, m:] @ S_T) @ np.linalg.inv(Psi[:m, :m] + Psi[:m, m:] @ S_T)
            ends[j], starts[j] = S_T, 0.5 * (S0 + S0.T)
            S_next = starts[j]
        change = np.max(np.abs(starts[0] - previous))
        sol.orbits = orbit
        if change <= 1e-11 * max(1.0, float(np.max(np.abs(starts[0])))):
            sol.converged = True
            break
        if not np.all(np.isfinite(starts[0])):
            break
    sol.starts, sol.ends = starts, ends
    return sol
