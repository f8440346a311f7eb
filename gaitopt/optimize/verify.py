"""Trust in an optimal gait: dense checks of the transcription, independent simulation.

* :func:`check_dense` samples each phase's collocation polynomials (:func:`dense_arcs`) and
  applies the certificate the shooting uses too (:mod:`gaitopt.orbit.certificate`).
* :func:`simulate_gait` simulates the gait with :func:`gaitopt.simulate` (adaptive DOP853 with
  located events: independent of the collocation) with the optimal input as a feedforward
  ``u(t)`` in the time since the section; :func:`simulated_cost` is the cost of a simulation by
  Gauss–Legendre quadrature.  The referee of :mod:`gaitopt.orbit.referee` (return, timing,
  cost) uses both.
* :func:`map_jacobian_fd`: the return map's Jacobian by central differences of that simulated
  map, the check of :func:`gaitopt.optimize.floquet.return_map_jacobian`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..orbit.certificate import DenseArc, certify_orbit
from ..result import OrbitArc
from ..simulation import Simulation, simulate
from .collocation import Collocation
from .problem import GaitProblem

__all__ = [
    "check_dense",
    "dense_arcs",
    "orbit_arcs",
    "simulate_gait",
    "simulated_cost",
    "map_jacobian_fd",
]

_SAMPLES = 24  # per mesh interval for the dense checks

#: The guard at each phase's last node is one of the NLP's equalities (IPOPT's
#: ``constr_viol_tol`` 1e-11); the certificate re-reads it to this relative tolerance.
GUARD_TOL = 1e-6


#: A period-k optimum that is a shorter orbit repeated is no period-k gait (the certificate's
#: minimal-period rule, as for a shooting search); what to ask for instead.
REPEATED_OPTIMUM = (
    "the least-cost {steps}-step orbit is the {j}-step optimum repeated: optimise with "
    "steps={j}, or try more `starts` for an orbit whose steps differ"
)


def dense_arcs(col: Collocation, sol: dict[str, Any], samples: int = _SAMPLES) -> list[DenseArc]:
    """The collocation orbit's dense samples as the certificate reads them: each phase's state
    and input polynomials at ``samples`` uniform samples per mesh interval (not the nodes, where
    the NLP imposes its equations), times in s since the orbit's section."""
    model = col.model
    tn = np.linspace(0.0, 1.0, col.N * samples + 1)
    n_cycle = len(model.phases)
    out, t0 = [], 0.0
    for k, i in enumerate(col.chain):
        X, U = col.evaluate(sol["X"][k], sol["U"][k], tn, sol["breaks"][k])
        T = float(sol["T"][k])
        step = f" (step {k // n_cycle + 1})" if len(col.chain) > n_cycle else ""
        label = f"phase '{model.phases[i].name}'{step}"
        out.append(DenseArc(i, label, T, t0 + tn * T, X, U))
        t0 += T
    return out


def orbit_arcs(col: Collocation, sol: dict[str, Any], samples: int = 8) -> list[OrbitArc]:
    """The optimum's orbit for results and plots: one :class:`~gaitopt.OrbitArc` per phase, its
    state and input polynomials at ``samples`` uniform samples per mesh interval (and the
    phase's ends), times in s since the orbit's section."""
    model = col.model
    dense = np.linspace(0.0, 1.0, col.N * samples + 1)
    out, t0 = [], 0.0
    for k, i in enumerate(col.chain):
        X, U = col.evaluate(sol["X"][k], sol["U"][k], dense, sol["breaks"][k])
        phase = model.phases[i]
        t = t0 + dense * sol["T"][k]
        out.append(OrbitArc(i, phase.name, phase.states, t, X, phase.transitions[0].name, U))
        t0 += sol["T"][k]
    return out


def check_dense(col: Collocation, sol: dict[str, Any]) -> str | None:
    """None if the sampled orbit is a gait by the common certificate
    (:func:`gaitopt.orbit.certify_orbit`: positive durations, each phase ending on its guard in
    its direction and admissibly, no guard crossed early, every declared unilateral constraint
    ``c ≥ −1e-9 · (1 + max |c|)`` with an ``at_start`` one rising, the minimal period) on the
    collocation polynomials; else why."""
    arcs = dense_arcs(col, sol)
    return certify_orbit(
        col.model, arcs, sol["p"], steps=col.problem.steps, guard_tol=GUARD_TOL,
        repeated_advice=REPEATED_OPTIMUM,
    )  # fmt: skip


def profiles(col: Collocation, sol: dict[str, Any]) -> list[Any]:
    """One :class:`~gaitopt.optimize.profile.InputProfile` per step of the orbit (time since
    that step's section)."""
    from .profile import InputProfile

    n_cycle = len(col.model.phases)
    out = []
    for step in range(col.problem.steps):
        starts, lengths, values = [], [], []
        t0 = 0.0
        for k in range(step * n_cycle, (step + 1) * n_cycle):
            T = float(sol["T"][k])
            edges = t0 + T * np.asarray(sol["breaks"][k])
            for j in range(col.N):
                if col.structure is None:  # uniform: t0 + j h exactly
                    starts.append(t0 + j * (T / col.N))
                    lengths.append(T / col.N)
                else:
                    starts.append(edges[j])
                    lengths.append(edges[j + 1] - edges[j])
                values.append(sol["U"][k][:, j * col.d : (j + 1) * col.d])
            t0 += T
        out.append(
            InputProfile.from_nodes(np.array(starts), np.array(lengths), col.tau[1:], values)
        )
    return out


class _Feedforward:
    """``feedforward(t, step)``: step ``step``'s profile at ``t`` (s since that step's section);
    ``feedforward.vectorised(times, step)`` at many times at once (inputs × times) and
    ``feedforward.breaks(step)``, which :func:`gaitopt.simulate` uses for one CasADi call per
    integrator step, with steps that end at the profile's breakpoints."""

    def __init__(self, profs: list[Any]):
        self.profs = list(profs)

    def __call__(self, t: float, step: int) -> np.ndarray:
        return self.profs[step % len(self.profs)](t)

    def vectorised(self, times: np.ndarray, step: int) -> np.ndarray:
        return self.profs[step % len(self.profs)].vectorised(times)

    def breaks(self, step: int) -> np.ndarray:
        """Where step ``step``'s input may jump (s since the section): the mesh points and the
        profile's end."""
        return self.profs[step % len(self.profs)].breaks


def feedforward_of(profs: list[Any]) -> Callable[[float, int], np.ndarray]:
    """``feedforward(t, step)`` for :func:`gaitopt.simulate` (vectorised: see
    :class:`_Feedforward`)."""
    return _Feedforward(profs)


def simulate_gait(
    problem: GaitProblem, model: Any, x0: np.ndarray, profs: list[Any], steps: int
) -> Simulation:
    """Simulate ``steps`` returns from ``x0`` with the profile as feedforward (rtol 1e-12)."""
    return simulate(
        model,
        x0,
        steps=steps,
        feedforward=feedforward_of(profs),
        rtol=1e-12,
        atol=1e-13,
        max_phase_time=problem.max_phase_time,
    )


def _integrand(problem: GaitProblem, phase: int) -> Callable[[np.ndarray, np.ndarray, Any], float]:
    kind = problem.cost_kind
    model = problem.model
    if kind == "effort":  # the inputs acting in the flow (not the impulses)
        flow = problem.flow_index
        return lambda x, u, p: float(np.dot(u[flow], u[flow]))
    if kind in ("work", "cot"):
        rates = model.input_rates(phase)
        return lambda x, u, p: float(
            np.sum(np.maximum(0.0, u * np.asarray(rates(x, p), dtype=float).ravel()))
        )
    n, n_u = model.phases[phase].n, len(model.inputs)
    xs, us, ps = ca.MX.sym("x", n), ca.MX.sym("u", n_u), ca.MX.sym("p", len(model.p))
    f = ca.Function("integrand", [xs, us, ps], [problem.cost(xs, us, ps)])
    return lambda x, u, p: float(f(x, u, p))


def simulated_cost(problem: GaitProblem, model: Any, sim: Simulation, profs: list[Any]) -> float:
    """The cost of a simulated orbit by composite Gauss–Legendre quadrature (64 panels of 8
    points per phase, split at the profile's breakpoints, where the input may jump; the
    positive part of the power is evaluated pointwise)."""
    nodes, weights = np.polynomial.legendre.leggauss(8)
    p = model.p
    total = 0.0
    section_times = list(sim.section_times)
    distance = 0.0
    for arc in sim.arcs:
        f = _integrand(problem, arc.phase)
        step = max(int(np.searchsorted(section_times, arc.t0, side="right")) - 1, 0)
        t_sec = section_times[step]
        prof = profs[step % len(profs)]
        inner = t_sec + prof.breaks
        inner = inner[(inner > arc.t0 + 1e-12) & (inner < arc.t1 - 1e-12)]
        edges = np.sort(np.concatenate([np.linspace(arc.t0, arc.t1, 65), inner]))
        edges = edges[np.append(True, edges[1:] != edges[:-1])]  # np.unique without numpy.ma
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            ts = (a + b) / 2 + (b - a) / 2 * nodes
            xs = arc.solution(ts)
            for tt, xx, ww in zip(ts, xs.T, weights, strict=True):
                u = profs[step % len(profs)](tt - t_sec)
                total += (b - a) / 2 * ww * f(xx, u, p)
    if problem.cost_kind in ("work", "cot") and model.impulsive_inputs:
        # The impulses' work at each cycle transition, with the input the reset saw.
        for event in sim.events:
            if (
                event.state_after is None
                or event.transition != model.phases[event.phase].transitions[0].name
            ):
                continue
            step = max(int(np.searchsorted(section_times, event.t, side="left")) - 1, 0)
            u = profs[step % len(profs)](event.t - section_times[step])
            total += problem.impulse_work(event.phase, event.state_before, u, p)
    if problem.cost_kind == "cot":
        for event in sim.events:
            if event.state_after is None:
                continue
            vec = problem.step_vector(event.phase, event.state_before, p)
            if vec is not None:
                distance += float(np.linalg.norm(np.asarray(vec, dtype=float)))
        mass = float(problem.total_mass(p))
        gravity = float(problem.gravity(ca.DM(p)))
        return total / (mass * gravity * distance)
    return total


def map_jacobian_fd(
    problem: GaitProblem, model: Any, s_star: np.ndarray, profs: list[Any], h: float = 1e-6
) -> np.ndarray | None:
    """``∂P/∂s`` by central differences of the simulated return map (``steps`` returns), with
    the input as a feedforward; None if a perturbed simulation does not complete.

    The step ``h`` balances truncation against the simulation's noise, O(rtol/h) with rtol
    1e-12.  Truncation is O(h) where the held input makes the map's second derivative jump
    (compass gait: 2.2e-5 at h = 1e-5, ~1e-6 at 1e-6), O(h²) otherwise.  The simulation ends
    its steps at the profile's breakpoints (:func:`feedforward_of`), so its result is smooth in
    the start state and the noise small: on the five-link biped's optimum (period 0.6 s, step
    0.4 m; |μ| up to 42) the relative gap to the AD multipliers is 2.8e-3 at h = 1e-4, 3.4e-5
    at 1e-5, 1.7e-7 at 1e-6 and 4.6e-7 (noise) at 1e-7 (1.1e-4 at 1e-6 when SciPy's steps
    straddle the breakpoints, as with a plain callable)."""
    m = s_star.size
    A = np.zeros((m, m))
    for j in range(m):
        cols = []
        for sign in (1.0, -1.0):
            s = s_star.copy()
            s[j] += sign * h
            sim = simulate_gait(problem, model, model.lift(s), profs, problem.steps)
            if not sim.success:
                return None
            cols.append(model.section_coordinates_of(sim.section_states[-1]))
        A[:, j] = (cols[0] - cols[1]) / (2 * h)
    return A
