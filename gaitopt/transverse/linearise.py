"""The transverse linearisation of a hybrid periodic orbit (Shiriaev, Freidovich & Manchester
2008; Manchester, Tobenkin, Levashov & Tedrake 2011).

**Coordinates.** In each stage the moving Poincaré surface at phase ``τ`` is the hyperplane
through ``x*(τ)`` orthogonal to the orbit's velocity ``f*(τ) = f(x*(τ), u*(τ))``; a state ``x``
near the orbit has the phase ``τ(x)`` of its nearest orbit point (where
``f*(τ)ᵀ (x − x*(τ)) = 0``) and the transverse coordinates ``x⊥ = Π(τ) (x − x*(τ))``, ``Π(τ)``
an orthonormal basis ((n−1) × n) of that hyperplane.  ``Π`` is the Householder reflection that
takes ``f̂ = f*/|f*|`` to ``σ e_k`` with row ``k`` removed, ``(k, σ)`` chosen per stage so that
``σ f̂_k`` stays as far below 1 as it can (the reflection is smooth in ``f`` there).

**Flow.** Differentiating the constraint ``f*(τ)ᵀ δx = 0`` (``δx = x − x*(τ)``) along the
controlled flow ``ẋ = f(x, u*(τ) + δu)`` gives, to first order, ``τ̇ = 1 + (f*ᵀ A δx + f*ᵀ B δu
+ ḟ*ᵀ δx)/|f*|²`` and

    ``ẋ⊥ = A⊥(τ) x⊥ + B⊥(τ) δu,   A⊥ = Π A Πᵀ + Π̇ Πᵀ,   B⊥ = Π B``,

``A = ∂f/∂x``, ``B = ∂f/∂u`` along the orbit, ``Π̇ = (∂Π/∂f) ḟ*`` with ``ḟ* = A f* + B u̇*``
(exact, by CasADi's forward mode).

**Jumps.** A state on the last surface of a stage (``τ = T``), ``δx⁻ = Πᵀ x⊥⁻``, reaches the
guard ``dt = −(g_x δx⁻ + g_u δu)/ġ`` later (``ġ = g_x f⁻ + g_u u̇*``); the reset's image is
projected on the next stage's first surface (``τ = 0``).  That is the saltation matrix
``S = r_x + (f⁺ − r_x f⁻ − r_u u̇*) g_xᵀ/ġ`` (Aizerman & Gantmacher 1958; Hiskens & Pai 2000)
seen through the projections: ``Π⁺`` removes the ``f⁺`` term (a state moved along the orbit has
the same transverse coordinates), so

    ``x⊥⁺ = J x⊥⁻ + J_u δu,   J = Π⁺ (r_x − (r_x f⁻ + r_u u̇*) g_x/ġ) Π⁻ᵀ,
    J_u = Π⁺ (r_u − (r_x f⁻ + r_u u̇*) g_u/ġ)``,

the transverse map of the reset with the impact-time correction (the form of Manchester et
al. 2011, eq. 11; it needs no post-impact velocity, and it is the only form in which a phase
whose state changes dimension — the kneed walker's knee strike — maps one hyperplane onto the
other).  The monodromy ``M = J_K Φ_K ⋯ J_1 Φ_1`` (``Φ_k`` the transition matrix of ``A⊥`` over
stage ``k``) has the return map's nontrivial Floquet multipliers among its eigenvalues; the
others are 0 (where a reset's image has lower dimension) or 1 (a conserved quantity).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from ..orbit.sensitivity import end_values, multipliers, saltation
from .orbit import NominalOrbit, Stage, integrate_pieces, nominal_orbit

__all__ = [
    "TransverseLinearisation",
    "StageFrame",
    "transverse_linearisation",
    "frame_functions",
    "householder",
    "stage_transition",
]


def householder(f: np.ndarray, axis: int, sign: float) -> np.ndarray:
    """``Π`` ((n−1) × n): the reflection taking ``f̂`` to ``sign · e_axis``, row ``axis``
    removed (numpy; the CasADi form is in :func:`frame_functions`)."""
    fh = np.asarray(f, dtype=float) / np.linalg.norm(f)
    v = fh.copy()
    v[axis] -= sign
    H = np.eye(fh.size) - 2.0 * np.outer(v, v) / float(v @ v)
    return np.delete(H, axis, axis=0)


@lru_cache(maxsize=64)
def frame_functions(flow: ca.Function) -> ca.Function:
    """``frame(x, u, u̇, p, a) -> (f, ḟ, A, B, H, Ḣ)`` along the flow, ``a = σ e_k`` the
    reflection's target axis (``H`` is the full reflection; ``Π`` is ``H`` without row ``k``)."""
    n, n_u, n_p = flow.size1_in(0), flow.size1_in(1), flow.size1_in(2)
    x, u, ud = ca.SX.sym("x", n), ca.SX.sym("u", n_u), ca.SX.sym("ud", n_u)
    p, a = ca.SX.sym("p", n_p), ca.SX.sym("a", n)
    f = flow(x, u, p)
    A, B = ca.jacobian(f, x), ca.jacobian(f, u)
    fdot = ca.mtimes(A, f) + ca.mtimes(B, ud)
    v = f / ca.norm_2(f) - a
    H = ca.SX.eye(n) - 2 * ca.mtimes(v, v.T) / ca.dot(v, v)
    Hdot = ca.jtimes(H, ca.vertcat(x, u), ca.vertcat(f, ud))
    return ca.Function("frame", [x, u, ud, p, a], [f, fdot, A, B, H, Hdot])


@dataclass
class StageFrame:
    """A stage's transverse frame and linear dynamics.

    Attributes
    ----------
    stage : Stage
        The nominal stage.
    axis, sign : int, float
        The reflection's target ``σ e_k``.
    """

    stage: Stage
    axis: int
    sign: float
    flow: ca.Function
    frame: ca.Function
    p: np.ndarray

    @property
    def n(self) -> int:
        return self.stage.x0.size

    def at(self, tau: float) -> dict[str, np.ndarray]:
        """At stage time ``τ`` (s): ``x``, ``u``, ``f``, ``fdot``, ``A``, ``B``, ``Pi``,
        ``A_perp``, ``B_perp``."""
        x = self.stage.x(tau)
        u, ud = self.stage.input(tau)
        a = np.zeros(self.n)
        a[self.axis] = self.sign
        f, fdot, A, B, H, Hdot = (
            np.asarray(v, dtype=float) for v in self.frame(x, u, ud, self.p, a)
        )
        Pi = np.delete(H, self.axis, axis=0)
        Pid = np.delete(Hdot, self.axis, axis=0)
        return {
            "x": x,
            "u": u,
            "f": f.ravel(),
            "fdot": fdot.ravel(),
            "A": A,
            "B": B,
            "Pi": Pi,
            "A_perp": Pi @ A @ Pi.T + Pid @ Pi.T,
            "B_perp": Pi @ B,
        }


@dataclass
class TransverseLinearisation:
    """The transverse linearisation of a hybrid periodic orbit.

    Attributes
    ----------
    orbit : NominalOrbit
        The nominal orbit (its stages extended past both ends).
    frames : list of StageFrame
        Per stage: the frame ``Π(τ)`` and ``A⊥(τ)``, ``B⊥(τ)``.
    jumps, jump_inputs : list of numpy.ndarray
        ``J`` and ``J_u`` at each stage's end (to the next stage's start).
    transitions : list of numpy.ndarray
        ``Φ_k``: the transition matrix of ``A⊥`` over stage ``k``.
    monodromy : numpy.ndarray
        ``J_K Φ_K ⋯ J_1 Φ_1`` from the first stage's start surface back to it.
    multipliers : numpy.ndarray
        Its eigenvalues, largest modulus first.
    """

    orbit: NominalOrbit
    frames: list[StageFrame]
    jumps: list[np.ndarray] = field(default_factory=list)
    jump_inputs: list[np.ndarray] = field(default_factory=list)
    transitions: list[np.ndarray] = field(default_factory=list)
    monodromy: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    clock_monodromy: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    clock_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))

    @property
    def dimensions(self) -> list[int]:
        """Transverse dimension ``n − 1`` of each stage."""
        return [fr.n - 1 for fr in self.frames]

    def nontrivial(self, tol: float = 1e-9) -> np.ndarray:
        """The monodromy's eigenvalues that are neither 0 nor 1 to ``tol`` (largest first)."""
        mu = self.multipliers
        keep = (np.abs(mu) > tol) & (np.abs(mu - 1.0) > tol)
        return mu[keep]


def _choose_axis(stage: Stage, flow: ca.Function, p: np.ndarray) -> tuple[int, float]:
    """``(k, σ)`` minimising the largest ``σ f̂_k`` over the stage (sampled), so that the
    Householder vector ``f̂ − σ e_k`` stays away from zero."""
    taus = np.linspace(-stage.before, stage.duration + stage.after, 101)
    F = np.array([np.asarray(flow(stage.x(t), stage.input(t)[0], p)).ravel() for t in taus])
    F /= np.linalg.norm(F, axis=1, keepdims=True)
    best = None
    for k in range(F.shape[1]):
        for sign in (1.0, -1.0):
            worst = float(np.max(sign * F[:, k]))
            if best is None or worst < best[0]:
                best = (worst, k, sign)
    assert best is not None
    return best[1], best[2]


def stage_transition(
    frame: StageFrame, generator: Callable | None = None, size: int | None = None,
    rtol: float = 1e-11,
) -> np.ndarray:  # fmt: skip
    """``Φ`` over the stage ``[0, T]`` of ``dΦ/dτ = G(τ) Φ``, ``Φ(0) = I``: ``G = A⊥`` (the
    stage's transverse state-transition matrix), or ``generator(τ, frame.at(τ))`` (``size ×
    size``: a closed loop, or ``A⊥`` with the clock's lead), integrated between the input's
    breaks (rtol ``rtol``, atol 1e-12)."""
    stage = frame.stage
    m = frame.n - 1 if size is None else size

    def rhs(tau: float, y: np.ndarray) -> np.ndarray:
        d = frame.at(tau)
        G = d["A_perp"] if generator is None else generator(tau, d)
        return (G @ y.reshape(m, m)).ravel()

    edges = stage.breaks[(stage.breaks >= 0) & (stage.breaks <= stage.duration)]
    y, _ = integrate_pieces(rhs, np.eye(m).ravel(), edges, rtol=rtol, atol=1e-12, dense=False)
    return y.reshape(m, m)


def transverse_linearisation(gait, *, extension: float = 0.15) -> TransverseLinearisation:
    """The transverse linearisation of a gait's orbit.

    Parameters
    ----------
    gait : LimitCycle or OptimalGait
        A successful gait of :func:`gaitopt.find_limit_cycle` (passive, or with its constant
        per-step input) or :func:`gaitopt.optimize_gait` (its input profile as ``u*(τ)``).
    extension : float
        Each stage's nominal orbit is continued past both ends by this fraction of its duration
        (for the phase of states near an impact).

    Returns
    -------
    TransverseLinearisation
        Frames, jumps, stage transition matrices, the monodromy and its eigenvalues.
    """
    orbit = nominal_orbit(gait, extension)
    model, p = orbit.model, orbit.p
    frames = []
    for stage in orbit.stages:
        flow = model.phases[stage.phase].flow
        k, sign = _choose_axis(stage, flow, p)
        frames.append(StageFrame(stage, k, sign, flow, frame_functions(flow), p))
    lin = TransverseLinearisation(orbit, frames)
    for j, frame in enumerate(frames):
        J, Ju = _jump(orbit, frame, frames[(j + 1) % len(frames)])
        lin.jumps.append(J)
        lin.jump_inputs.append(Ju)
        lin.transitions.append(stage_transition(frame))
    lin.monodromy = monodromy(lin.transitions, lin.jumps)
    lin.multipliers = multipliers(lin.monodromy)
    lin.clock_monodromy = clock_monodromy(lin)
    lin.clock_multipliers = multipliers(lin.clock_monodromy)
    return lin


def clock_monodromy(lin: TransverseLinearisation) -> np.ndarray:
    """The transverse monodromy of the orbit driven by its input on the clock ``u*(t)`` (``t``
    since the last return to the section: how :func:`gaitopt.simulate` applies an optimum's
    profile as a feedforward) rather than on the phase ``u*(τ)``.

    A state then carries, besides ``x⊥``, the clock's lead over its phase, ``θ = t − t*(τ)``
    (``t*(τ)`` the nominal clock at phase ``τ``), and sees the input ``u*(τ) + u̇* θ``.  From
    ``τ̇ − 1 = (f*ᵀ A δx + ḟ*ᵀ δx + f*ᵀ B u̇* θ)/|f*|²`` (the flow of
    :mod:`~gaitopt.transverse.linearise` with ``δu = u̇* θ``):

        ``d/dτ [x⊥; θ] = [[A⊥, B⊥ u̇*], [−(f*ᵀA + ḟ*ᵀ)Πᵀ/|f*|², −f*ᵀ B u̇*/|f*|²]] [x⊥; θ]``.

    At a stage's end the impact comes ``dt`` late, the reset's image ``D`` is split into its
    transverse part ``Π⁺ D`` and its phase ``τ' = f⁺ᵀ D/|f⁺|²`` on the next stage, and
    ``θ⁺ = θ + dt − τ'``; where the transition returns to the section the clock restarts at the
    impact, ``θ⁺ = −τ'``.  With a constant input ``θ`` never acts on ``x⊥`` and the eigenvalues
    are :attr:`TransverseLinearisation.multipliers` and a 0."""
    orbit = lin.orbit
    model, p = orbit.model, orbit.p
    n_phases = len(model.phases)
    M = None
    for j, frame in enumerate(lin.frames):
        stage = frame.stage
        m = frame.n - 1

        def generator(tau: float, d: dict, stage: Stage = stage, m: int = m) -> np.ndarray:
            ud = stage.input(tau)[1]
            f, Pi = d["f"], d["Pi"]
            ff = float(f @ f)
            G = np.zeros((m + 1, m + 1))
            G[:m, :m] = d["A_perp"]
            G[:m, m] = d["B_perp"] @ ud
            G[m, :m] = -(f @ d["A"] + d["fdot"]) @ Pi.T / ff
            G[m, m] = -float(f @ d["B"] @ ud) / ff
            return G

        Phi = stage_transition(frame, generator, m + 1)
        nxt = lin.frames[(j + 1) % len(lin.frames)]
        # the jump of [δx⊥; θ] (rule 3 of gaitopt.orbit.sensitivity, θ the clock's lead)
        tr, end, ud, ends = _stage_end(frame, model, p)
        theta = np.zeros((1, m + 1))
        theta[0, m] = 1.0
        D, dt_event = saltation(ends, ud, np.hstack([end["Pi"].T, np.zeros((frame.n, 1))]), theta)
        start = nxt.at(0.0)
        tau_next = start["f"] @ D / float(start["f"] @ start["f"])
        closes = (stage.phase == n_phases - 1) or tr.returns_to_section
        Jz = np.vstack([start["Pi"] @ D, -tau_next if closes else dt_event[0] - tau_next])
        step = Jz @ Phi
        M = step if M is None else step @ M
    assert M is not None
    return M


def monodromy(transitions: list[np.ndarray], jumps: list[np.ndarray]) -> np.ndarray:
    """``J_K Φ_K ⋯ J_1 Φ_1``."""
    M = np.eye(transitions[0].shape[0])
    for Phi, J in zip(transitions, jumps, strict=True):
        M = J @ Phi @ M
    return M


def _jump(orbit: NominalOrbit, frame: StageFrame, nxt: StageFrame) -> tuple[np.ndarray, ...]:
    """``J`` and ``J_u`` from ``frame``'s last surface to ``nxt``'s first."""
    _, end, ud, ends = _stage_end(frame, orbit.model, orbit.p)
    m, n_u = frame.n - 1, ud.shape[0]
    # columns: δx⁻ = Πᵀ x⊥⁻, then δu (rule 3 of gaitopt.orbit.sensitivity with δt₀ = 0)
    dx = np.hstack([end["Pi"].T, np.zeros((frame.n, n_u))])
    delta = np.hstack([np.zeros((n_u, m)), np.eye(n_u)])
    D, _ = saltation(ends, ud, dx, np.zeros((1, m + n_u)), delta)
    JJ = nxt.at(0.0)["Pi"] @ D
    return JJ[:, :m], JJ[:, m:]


def _stage_end(frame: StageFrame, model, p: np.ndarray) -> tuple:
    """``(transition, frame.at(T), u̇ (a column), (f, g_x, g_u, r_x, r_u))`` at a stage's end
    ``T``; ``u̇`` the input's rate just before it (held after it): the left derivative."""
    stage = frame.stage
    tr = model.phases[stage.phase].transitions[0]
    end = frame.at(stage.duration)
    ud = stage.input(float(np.nextafter(stage.duration, -np.inf)))[1][:, None]
    return tr, end, ud, end_values(frame.flow, tr.guard, tr.reset, end["x"], end["u"], p)
