"""The periodic Riccati differential equation of the transverse dynamics, with its jumps.

Along each stage (Manchester et al. 2011, §IV; Drake's ``transverseLQR.m``)

    ``−Ṡ = A⊥ᵀ S + S A⊥ − S B⊥ R⁻¹ B⊥ᵀ S + Q⊥``,   ``Q⊥(τ) = Π(τ) Q Π(τ)ᵀ``,

and at each impact ``S⁻ = Jᵀ S⁺ J`` (the cost-to-go is carried through the transverse jump;
the input's effect through the impact, ``J_u``, is not designed for: it is zero where guards and
resets do not depend on the inputs, as for the walkers' joint torques, and the closed-loop
monodromy includes it either way).  The gain is ``K(τ) = R⁻¹ B⊥ᵀ S(τ)``, ``δu = −K x⊥``.

Each stage is solved through its Hamiltonian system: ``d/dτ [X; Y] = [[A⊥, −B⊥R⁻¹B⊥ᵀ],
[−Q⊥, −A⊥ᵀ]] [X; Y]``, whose transition ``Ψ(τ, b)`` from the end ``b`` of a sub-interval
(integrated backwards once, dense) gives ``S(τ) = (Ψ₂₁ + Ψ₂₂ S_b)(Ψ₁₁ + Ψ₁₂ S_b)⁻¹`` for any
end value ``S_b``; the sub-intervals are short enough for the transitions to stay well
conditioned.  The
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
    hamiltonians : list of list of Pieces
        Per stage and sub-interval ``[a, b]`` (``edges``), ``vec Ψ(τ, b)`` backwards from ``b``.
    edges : list of numpy.ndarray
        Per stage, the sub-interval edges (s).
    sub_ends : list of list of numpy.ndarray
        ``S`` at each sub-interval's end ``b``.
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
    hamiltonians: list[list[Pieces]] = field(default_factory=list)
    edges: list[np.ndarray] = field(default_factory=list)
    sub_ends: list[list[np.ndarray]] = field(default_factory=list)
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
        edges = self.edges[stage]
        i = min(max(int(np.searchsorted(edges, tau, side="right")) - 1, 0), edges.size - 2)
        Psi = self.hamiltonians[stage][i](tau).reshape(2 * m, 2 * m)
        return _riccati_map(Psi, self.sub_ends[stage][i], m)

    def gain(self, stage: int, tau: float) -> np.ndarray:
        """``K(τ) = R⁻¹ B⊥ᵀ S(τ)`` (input units per transverse unit), ``τ`` clipped to
        ``[0, T]`` (the gain at the nearest end holds on the extensions)."""
        frame = self.lin.frames[stage]
        tau = min(max(float(tau), 0.0), frame.stage.duration)
        B = frame.at(tau)["B_perp"]
        return np.linalg.solve(self.R, B.T @ self.cost_matrix(stage, tau))


def _riccati_map(Psi: np.ndarray, S_b: np.ndarray, m: int) -> np.ndarray:
    """``S(a) = (Ψ₂₁ + Ψ₂₂ S_b)(Ψ₁₁ + Ψ₁₂ S_b)⁻¹`` from ``S`` at the sub-interval's end."""
    S = np.linalg.solve((Psi[:m, :m] + Psi[:m, m:] @ S_b).T, (Psi[m:, :m] + Psi[m:, m:] @ S_b).T).T
    return 0.5 * (S + S.T)


def _hamiltonian(
    frame: StageFrame, Q: np.ndarray, R_inv: np.ndarray
) -> tuple[np.ndarray, list[Pieces]]:
    """The sub-interval edges of a stage and, per sub-interval, ``Ψ(τ, b)`` backwards from its
    end ``b``.  The stage is cut where the input may jump and so finely that the Hamiltonian's
    spectral radius ``ρ`` times a sub-interval's length stays below 2: its transition then
    stays well conditioned (the kneed walker's light shank gives ``ρ`` ≈ 1700 /s, where one
    transition over its 0.35 s swing has a condition number of 1e18)."""
    stage = frame.stage
    m = frame.n - 1

    def hamiltonian(tau: float) -> np.ndarray:
        d = frame.at(tau)
        A, B, Pi = d["A_perp"], d["B_perp"], d["Pi"]
        return np.block([[A, -B @ R_inv @ B.T], [-Pi @ Q @ Pi.T, -A.T]])

    def rhs(tau: float, y: np.ndarray) -> np.ndarray:
        return (hamiltonian(tau) @ y.reshape(2 * m, 2 * m)).ravel()

    T = stage.duration
    rho = max(np.max(np.abs(np.linalg.eigvals(hamiltonian(t)))) for t in np.linspace(0, T, 9))
    count = max(4, int(np.ceil(T * rho / 2.0)))
    breaks = stage.breaks[(stage.breaks >= 0) & (stage.breaks <= T)]
    edges = np.unique(np.concatenate([breaks, np.linspace(0.0, T, count + 1)]))
    pieces = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        _, piece = integrate_pieces(rhs, np.eye(2 * m).ravel(), np.array([b, a]), rtol=_RTOL,
                                    atol=1e-12)  # fmt: skip
        assert piece is not None
        pieces.append(piece)
    return edges, pieces


def periodic_riccati(
    lin: TransverseLinearisation, Q_stages: list[np.ndarray], R: np.ndarray
) -> PeriodicRiccati:
    """The periodic solution of the jump Riccati equation (``Q_stages``: the state weight in
    each stage's own states, n × n)."""
    R = np.atleast_2d(np.asarray(R, dtype=float))
    R_inv = np.linalg.inv(R)
    sol = PeriodicRiccati(lin, Q_stages[0], R)
    built = [_hamiltonian(fr, Q, R_inv) for fr, Q in zip(lin.frames, Q_stages, strict=True)]
    sol.edges = [e for e, _ in built]
    sol.hamiltonians = [p for _, p in built]
    Psi0 = [  # each sub-interval's transition over its whole length
        [pc(a).reshape(2 * (fr.n - 1), 2 * (fr.n - 1)) for pc, a in zip(pcs, e[:-1], strict=True)]
        for fr, e, pcs in zip(lin.frames, sol.edges, sol.hamiltonians, strict=True)
    ]
    K = len(lin.frames)
    starts = [np.zeros((fr.n - 1, fr.n - 1)) for fr in lin.frames]
    ends = [np.zeros_like(s) for s in starts]
    sub_ends: list[list[np.ndarray]] = [
        [np.zeros_like(s)] * len(p) for s, p in zip(starts, Psi0, strict=True)
    ]
    S_next = starts[0]
    for orbit in range(1, _MAX_ORBITS + 1):
        previous = starts[0].copy()
        for j in reversed(range(K)):
            m = lin.frames[j].n - 1
            J = lin.jumps[j]
            S = J.T @ S_next @ J
            ends[j] = S = 0.5 * (S + S.T)
            for i in reversed(range(len(Psi0[j]))):
                sub_ends[j][i] = S
                S = _riccati_map(Psi0[j][i], S, m)
            starts[j] = S
            S_next = starts[j]
        change = np.max(np.abs(starts[0] - previous))
        sol.orbits = orbit
        if change <= 1e-11 * max(1.0, float(np.max(np.abs(starts[0])))):
            sol.converged = True
            break
        if not np.all(np.isfinite(starts[0])):
            break
    sol.sub_ends = sub_ends
    sol.starts, sol.ends = starts, ends
    return sol
