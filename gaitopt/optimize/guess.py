"""Starting points of the gait optimisation: a simulation from a seeded start with an input
profile, or a previous optimum (warm start) interpolated onto another transcription.

A start whose perturbed section point is not a state of the model (the five-link biped's
section lift takes an arccos, undefined for some perturbations: start 13 of seed 0 at OptimTraj's
statement) cannot begin: :class:`NoStart` says why, and the multi-start records it as that
start's outcome and goes on (:func:`gaitopt.optimize.solve.attempt`).
"""

from __future__ import annotations

import numpy as np

from ..errors import GaitoptInputError, GuessError
from ..simulation import simulate
from .collocation import Collocation
from .problem import GaitProblem
from .result import OptimalGait


class NoStart(Exception):
    """A start of the multi-start from which no guess can be built (its section point lifts to
    no state of the model, or its simulation cannot begin there); the message says why.  Not an
    input error: the start is generated, not given, and is recorded as failed."""


def _shown(names: tuple[str, ...] | list[str], values: np.ndarray) -> str:
    return ", ".join(f"{n}={v:.6g}" for n, v in zip(names, values, strict=False))


def _guess_from_simulation(
    col: Collocation, problem: GaitProblem, s0: np.ndarray, rng: np.random.Generator | None
) -> np.ndarray:
    model = problem.model
    p = model.p
    n_u = len(model.inputs)
    x0 = model.lift(s0)
    if not np.all(np.isfinite(x0)):
        raise NoStart(
            f"its section point ({_shown(model.section.coordinates, s0)}) is not a state of "
            f"{model.name}: the section's lift is undefined there ({model.section.doc})"
        )
    try:
        sim = simulate(model, x0, steps=problem.steps, max_phase_time=5.0)
    except GaitoptInputError as exc:  # a generated state the simulator refuses (overflow)
        raise NoStart(f"its simulation cannot begin: {exc}") from None
    arcs = sim.arcs
    chain = col.chain
    states, durations = [], []
    for k, i in enumerate(chain):
        arc = arcs[k] if k < len(arcs) and arcs[k].phase == i else None
        if arc is None or not arc.t1 > arc.t0:
            held = x0 if i == 0 else np.zeros(model.phases[i].n)
            states.append(lambda t, held=held: np.tile(held[:, None], (1, np.size(t))))
            durations.append(0.5)
        else:
            states.append(
                lambda t, a=arc: np.atleast_2d(a.solution(a.t0 + np.asarray(t) * (a.t1 - a.t0)))
            )
            durations.append(arc.t1 - arc.t0)
    durations = np.array(durations)
    target = problem.period
    if target is None and problem.speed and problem.step_length:
        target = problem.step_length * problem.steps / problem.speed
    if target is not None:
        durations = durations * target / durations.sum()
    low, high = problem.input_bounds()
    reach = np.maximum(np.abs(low), np.abs(high))
    amplitude = np.minimum(np.where(np.isfinite(reach), reach, 1.0), 1.0)
    phases_ = rng.uniform(0, 2 * np.pi, n_u) if rng is not None else np.zeros(n_u)
    scale = 0.5 * amplitude if rng is not None else np.zeros(n_u)

    def inputs(t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(t)
        return scale[:, None] * np.sin(2 * np.pi * t[None, :] + phases_[:, None])

    free = np.array([model.params[n] for n in problem.free])
    return col.pack(s0, free, states, [inputs] * len(chain), durations, p)


class WarmStartError(GuessError):
    """A ``guess`` (warm start) of :func:`gaitopt.optimize_gait` that cannot start it: not an
    :class:`OptimalGait`, a failed result with no orbit (IPOPT found no solution to start from),
    or the optimum of another model or number of steps."""


def check_warm_start(problem: GaitProblem, guess: object) -> None:
    """``guess`` must be ``None`` or an :class:`OptimalGait` with an orbit of ``problem``'s
    model and phases (a certified optimum, or a converged one its checks rejected).

    Raises
    ------
    WarmStartError
        Naming ``guess``, what is wrong with it and what to pass instead.
    """
    if guess is None:
        return
    model = problem.model
    if not isinstance(guess, OptimalGait):
        raise WarmStartError(
            f"`guess` must be an OptimalGait (a result of gaitopt.optimize_gait) or None, got "
            f"{type(guess).__name__} {guess!r:.80}; pass a previous optimum, e.g. "
            f"guess=optimize_gait(model, period=0.8, step_length=0.3), or leave it out"
        )
    if not guess.orbit:
        reason = guess.message.split(";")[0] if guess.message else "no message"
        raise WarmStartError(
            f"`guess` is a failed OptimalGait (success=False: {reason}) with no orbit to warm "
            f"start from; pass a result with an orbit (check `gait.orbit`, e.g. one with "
            f"success=True), or guess=None for a cold start"
        )
    name = getattr(guess.model, "name", None)
    if name != model.name:
        raise WarmStartError(
            f"`guess` is an optimum of {name!r}, not of {model.name!r}; pass an optimum of "
            f"{model.name}, or guess=None for a cold start"
        )
    chain = problem.chain
    phases = [getattr(arc, "phase", None) for arc in guess.orbit]
    if phases != chain:
        steps = len(guess.orbit) // max(len(model.phases), 1)
        raise WarmStartError(
            f"`guess` has an orbit of {len(guess.orbit)} phase(s) ({steps} step(s)), the problem "
            f"{len(chain)} ({problem.steps} step(s)); pass an optimum with steps="
            f"{problem.steps}, or guess=None for a cold start"
        )


def _guess_from_gait(col: Collocation, gait: OptimalGait) -> np.ndarray:
    model = col.model
    problem = col.problem
    states, inputs = [], []
    for k in range(len(col.chain)):
        arc = gait.orbit[k]
        tau = (arc.t - arc.t[0]) / (arc.t[-1] - arc.t[0])
        states.append(
            lambda t, arc=arc, tau=tau: np.array([np.interp(t, tau, row) for row in arc.x])
        )
        us = arc.u
        inputs.append(lambda t, us=us, tau=tau: np.array([np.interp(t, tau, row) for row in us]))
    s0 = model.section_coordinates_of(model.state_vector(gait.fixed_point))
    free = np.array([gait.params.get(n, model.params[n]) for n in problem.free])
    return col.pack(s0, free, states, inputs, np.asarray(gait.durations), model.p)


def _start_guess(
    col: Collocation, problem: GaitProblem, start: int, seed: int, gait: OptimalGait | None
) -> np.ndarray:
    model = problem.model
    if start == 0 and gait is not None:
        return _guess_from_gait(col, gait)
    s0 = model.section_vector(model.default_start())
    if start == 0:
        return _guess_from_simulation(col, problem, s0, None)
    rng = np.random.default_rng([seed, start])
    s = s0 * (1 + 0.3 * rng.uniform(-1, 1, s0.size)) + 0.05 * rng.normal(size=s0.size)
    return _guess_from_simulation(col, problem, s, rng)


# -- the solve ---------------------------------------------------------------------------------
