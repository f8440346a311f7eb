"""Limit cycles of hybrid models by multiple shooting, solved with CasADi.

Transcription (one stage per phase, resets as linking constraints; rockit's layout):

* unknowns ``w = [s; z]``: the section coordinates ``s`` of the orbit's first state, then for each
  phase of the cycle (repeated ``steps`` times for a period-k orbit) its segment start states and
  its free duration ``T``;
* equations: inside each phase, the end of segment j is the start of segment j + 1 (*close the
  gaps*); the last segment ends on the phase's guard (*impact at the phase end*); the reset of that
  end state is the next phase's first state (*reset links the phases*); and after the last phase,
  the reset state has the section coordinates ``s`` again (*periodicity*).  For smooth autonomous
  systems the section equation, built into ``lift(s)``, is the phase condition.

The system is square; Newton (CasADi ``rootfinder``, with line search) solves it, or IPOPT
(``nlpsol``) as a feasibility problem with positive durations.  The guess comes from a simulation.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from functools import cached_property, lru_cache
from types import SimpleNamespace
from typing import Any

import casadi as ca
import numpy as np

from .errors import GaitoptInputError, GuessError
from .hybrid import HybridModel, rate_along
from .integrators import segment_function, segment_trajectory_function
from .result import LimitCycle, OrbitArc
from .simulation import Simulation, simulate
from .stability import is_stable, section_jacobians

__all__ = ["MultipleShooting", "find_limit_cycle"]

_METHODS = ("newton", "ipopt")
_NEWTON = {
    "error_on_fail": False,
    "show_eval_warnings": False,  # a diverging guess is reported in the result, not on stderr
    "abstol": 1e-12,
    "abstolStep": 1e-15,
    "max_iter": 30,
}


@dataclass(frozen=True)
class MultipleShooting:
    """The discretisation: how each phase is cut and integrated.

    Attributes
    ----------
    segments : int
        Shooting segments per phase (equal fractions of the free phase duration).
    steps : int
        Fixed RK steps (Dormand–Prince order 8) per segment.
    dense : int
        Samples per segment for the guard check and the plotted orbit.
    """

    segments: int = 4
    steps: int = 5
    dense: int = 16

    def __post_init__(self) -> None:
        for name in ("segments", "steps", "dense"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise GaitoptInputError(
                    f"MultipleShooting: `{name}` must be a positive integer, got {value!r}"
                )


class Transcription:
    """The shooting equations of a model class for a number of cycles (built once, cached)."""

    def __init__(self, model_cls: type[HybridModel], disc: MultipleShooting, cycles: int):
        structure = model_cls._structure()
        self.model_cls = model_cls
        self.phases = structure.phases
        self.section = structure.section
        self.cycles = cycles
        self.disc = disc
        self.chain = [i for _ in range(cycles) for i in range(len(self.phases))]
        S = disc.segments
        states0 = self.phases[0].states
        self.section_index = [states0.index(c) for c in self.section.coordinates]
        m = len(self.section.coordinates)
        self.m = m
        self._assemblies: dict[int, Any] = {}

        # The layout of w (cheap; the CasADi graph is built only when a function needs it).
        self.layout = []  # (kind, chain index, offset, shape)
        offset = m
        for k, i in enumerate(self.chain):
            n = self.phases[i].n
            free_cols = S - 1 if k == 0 else S
            self.layout.append(("nodes", k, offset, (n, free_cols)))
            offset += n * free_cols
            self.layout.append(("duration", k, offset, ()))
            offset += 1
        self.size = offset
        self.n_g = self.size - m

    @cached_property
    def _graph(self):
        """The shooting equations as one CasADi MX graph (for IPOPT, the symbolic uses of the
        curves and the fallback where a model has no kernels)."""
        model_cls, disc, m, S = self.model_cls, self.disc, self.m, self.disc.segments
        s = ca.MX.sym("s", m)
        u = ca.MX.sym("u", len(model_cls.inputs))
        p = ca.MX.sym("p", len(model_cls.parameter_specs()))
        segment = {
            i: segment_function(ph.flow, disc.steps).map(S) for i, ph in enumerate(self.phases)
        }
        sampler = self._samplers
        z_parts, nodes, durations = [], [], []
        for k, i in enumerate(self.chain):
            n = self.phases[i].n
            free_cols = S - 1 if k == 0 else S
            free = ca.MX.sym(f"X{k}", n, free_cols)
            X = ca.horzcat(self.section.lift(s, p), free) if k == 0 else free
            T = ca.MX.sym(f"T{k}")
            z_parts += [ca.vec(free), T]
            nodes.append(X)
            durations.append(T)
        w = ca.vertcat(s, *z_parts)

        G, ends, dg, adm, samples = [], [], [], [], []
        for k, i in enumerate(self.chain):
            phase, X, T = self.phases[i], nodes[k], durations[k]
            tr = phase.transitions[0]
            X_end = segment[i](X, u, p, T / S)
            G.append(ca.vec(X[:, 1:] - X_end[:, :-1]))  # close the gaps
            x_end = X_end[:, -1]
            G.append(tr.guard(x_end, u, p))  # the phase ends on its guard
            x_next = tr.reset(x_end, u, p)
            if k + 1 < len(self.chain):
                G.append(nodes[k + 1][:, 0] - x_next)  # the reset links to the next phase
            else:
                x_return = x_next
            ends.append(x_end)
            # Crossing direction at the end: d/dt g = ∇g · f.
            dg.append(_guard_rate(phase, tr)(x_end, u, p))
            adm.append(tr.admissible(x_end, u, p) if tr.admissible is not None else ca.MX(1))
            samples.append(sampler[i](X, u, p, T / S))
        G = ca.vertcat(*G)
        P = x_return[self.section_index]
        F = ca.vertcat(G, P - s)  # periodicity closes the cycle
        assert F.shape[0] == self.size and G.shape[0] == self.n_g, "shooting system not square"
        checks = [
            ca.vertcat(*ends),  # stacked: phases may differ in dimension
            ca.vertcat(*dg),
            ca.vertcat(*adm),
            ca.vertcat(*durations),
        ]
        return SimpleNamespace(
            w=w, u=u, p=p, F=F, GP=ca.vertcat(G, P), x_return=x_return, checks=checks,
            samples=samples,
        )  # fmt: skip

    @cached_property
    def _samplers(self) -> dict[int, ca.Function]:
        S, q = self.disc.segments, self.disc.dense
        return {
            i: segment_trajectory_function(ph.flow, q).map(S) for i, ph in enumerate(self.phases)
        }

    _w = property(lambda self: self._graph.w)
    _u = property(lambda self: self._graph.u)
    _p = property(lambda self: self._graph.p)
    _F = property(lambda self: self._graph.F)
    _GP = property(lambda self: self._graph.GP)
    _x_return = property(lambda self: self._graph.x_return)
    _checks_out = property(lambda self: self._graph.checks)
    _samples = property(lambda self: self._graph.samples)

    # -- the compiled kernels (gaitopt.kernels) ----------------------------------------------
    def assembly(self, steps: int | None = None):
        """The shooting system from the compiled kernels (:mod:`gaitopt.kernels.assemble`),
        with ``steps`` RK steps per segment (default: this mesh's), or None where the model has
        no kernels."""
        key = self.disc.steps if steps is None else steps
        if key not in self._assemblies:
            from .kernels.assemble import Assembly

            try:
                self._assemblies[key] = Assembly(self, steps=key)
            except NotImplementedError:
                self._assemblies[key] = None
        return self._assemblies[key]

    def evaluate(self, w, u, p, *, jacobian: bool = True):
        """The shooting equations at ``w`` (:class:`gaitopt.kernels.assemble.Evaluation`):
        ``F`` and its Jacobians in one compiled call, with the phase ends, guard rates,
        admissibility and durations; from the CasADi graph where there are no kernels."""
        asm = self.assembly()
        if asm is not None:
            return asm(w, u, p, jacobian=jacobian)
        from .kernels.assemble import Evaluation

        F, F_w, F_p, F_u = (np.asarray(v, dtype=float) for v in self.residual_jacobians(w, u, p))
        x_return = np.asarray(self.linearisation(w, u, p)[3], dtype=float).ravel()
        ends, dg, adm, durations = (np.asarray(v, dtype=float) for v in self.checks(w, u, p))
        ends_list, at = [], 0
        for i in self.chain:
            n = self.phases[i].n
            ends_list.append(ends.ravel()[at : at + n])
            at += n
        return Evaluation(
            F.ravel(), F_w, F_u, F_p, x_return, ends_list, dg.ravel(), adm.ravel(),
            durations.ravel(),
        )  # fmt: skip

    def fine_residual(self, w, u, p) -> np.ndarray:
        """``F`` on the mesh with twice the RK steps per segment (the error estimate): only the
        residual, with no second transcription built."""
        asm = self.assembly(2 * self.disc.steps)
        if asm is not None:
            return asm(w, u, p, jacobian=False).F
        fine = transcription(self.model_cls, replace(self.disc, steps=2 * self.disc.steps),
                             self.cycles)  # fmt: skip
        return np.asarray(fine.residual(w, u, p), dtype=float).ravel()

    def segment_starts(self, w, p) -> list[np.ndarray]:
        """The segment start states (n × S) of each phase of the chain."""
        w = np.asarray(w, dtype=float).ravel()
        x0 = np.asarray(self.section.lift(w[: self.m], p), dtype=float).ravel()
        out = []
        for kind, k, off, shape in self.layout:
            if kind == "nodes":
                block = w[off : off + shape[0] * shape[1]].reshape(shape, order="F")
                out.append(np.column_stack([x0, block]) if k == 0 else block)
        return out

    def sample_numeric(self, w, u, p) -> list[np.ndarray]:
        """Dense samples of every phase (n × S·(dense + 1)), without the whole graph."""
        S = self.disc.segments
        starts = self.segment_starts(w, p)
        durations = [w[off] for kind, _, off, _ in self.layout if kind == "duration"]
        return [
            np.asarray(self._samplers[i](starts[k], u, p, durations[k] / S), dtype=float)
            for k, i in enumerate(self.chain)
        ]

    # Each function is built on first use: a mesh used only for the error estimate needs just
    # its residual.  Short chains are expanded to SX (their small dense graphs evaluate about
    # twice as fast); long ones (period-k orbits) stay MX, which builds in a fraction of the time
    # and evaluates as fast at that size.
    def _compiled(self, f: ca.Function) -> ca.Function:
        return f.expand() if len(self.chain) <= 2 else f

    @cached_property
    def residual(self) -> ca.Function:
        """``F(w, u, p)``: all shooting equations."""
        return self._compiled(
            ca.Function("residual", [self._w, self._u, self._p], [self._F], ["w", "u", "p"], ["F"])
        )

    @cached_property
    def newton(self) -> ca.Function:
        """Plain Newton (quadratic from a simulated guess)."""
        return ca.rootfinder(
            "limit_cycle", "newton", self.residual, {**_NEWTON, "line_search": False}
        )

    @cached_property
    def newton_line_search(self) -> ca.Function:
        """Newton with line search: the fallback from a poor guess."""
        return ca.rootfinder(
            "limit_cycle_ls", "newton", self.residual, {**_NEWTON, "max_iter": 100}
        )

    @cached_property
    def linearisation(self) -> ca.Function:
        """``(∂[G; P]/∂w, ∂[G; P]/∂u, F, x_return)`` for the multipliers and the error estimate."""
        w, u, p, GP = self._w, self._u, self._p, self._GP
        return self._compiled(
            ca.Function(
                "linearisation",
                [w, u, p],
                [ca.jacobian(GP, w), ca.jacobian(GP, u), self._F, self._x_return],
                ["w", "u", "p"],
                ["J_w", "J_u", "F", "x_return"],
            )
        )

    @cached_property
    def residual_jacobians(self) -> ca.Function:
        """``(F, ∂F/∂w, ∂F/∂p, ∂F/∂u)``: the corrector of continuation in a parameter or input."""
        w, u, p, F = self._w, self._u, self._p, self._F
        return self._compiled(
            ca.Function(
                "residual_jacobians",
                [w, u, p],
                [F, ca.jacobian(F, w), ca.jacobian(F, p), ca.jacobian(F, u)],
                ["w", "u", "p"],
                ["F", "F_w", "F_p", "F_u"],
            )
        )

    @cached_property
    def checks(self) -> ca.Function:
        """Phase-end states, guard rates, admissibility and durations."""
        return ca.Function("checks", [self._w, self._u, self._p], list(self._checks_out))

    @cached_property
    def sample(self) -> ca.Function:
        """Dense samples of every phase."""
        return ca.Function("sample", [self._w, self._u, self._p], self._samples)

    @cached_property
    def guard_maps(self) -> list[list[tuple[ca.Function, ca.Function | None]]]:
        """Guards and admissibility mapped over one phase's dense samples."""
        K = self.disc.segments * self.disc.dense + 1  # segment starts shared
        return [
            [
                (tr.guard.map(K), tr.admissible.map(K) if tr.admissible is not None else None)
                for tr in phase.transitions
            ]
            for phase in self.phases
        ]

    @cached_property
    def constraint_maps(self) -> list[list[tuple[ca.Function, ca.Function]]]:
        """Each phase's unilateral constraints ``c`` mapped over its dense samples, with their
        rates ``ċ = ∇c · f`` (for a constraint that starts active: the foot must lift off)."""
        K = self.disc.segments * self.disc.dense + 1
        return [
            [(c.function.map(K), rate_along(phase.flow, c.function)) for c in phase.constraints]
            for phase in self.phases
        ]

    @cached_property
    def _ipopt_solver(self) -> ca.Function:
        nlp = {"x": self._w, "p": ca.vertcat(self._u, self._p), "f": 0, "g": self._F}
        options = {
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "print_time": False,
            "ipopt.tol": 1e-14,
            "ipopt.constr_viol_tol": 1e-13,
            "ipopt.max_iter": 200,
            "error_on_fail": False,
        }
        return ca.nlpsol("limit_cycle_ipopt", "ipopt", nlp, options)

    # -- packing ------------------------------------------------------------------------------
    def pack(self, s: np.ndarray, nodes: list[np.ndarray], durations: list[float]) -> np.ndarray:
        """Unknown vector from section coordinates, per-chain node arrays (n × S) and durations."""
        w = np.zeros(self.size)
        w[: self.m] = s
        for kind, k, off, _shape in self.layout:
            if kind == "nodes":
                block = nodes[k][:, 1:] if k == 0 else nodes[k]
                w[off : off + block.size] = block.ravel(order="F")
            else:
                w[off] = durations[k]
        return w

    def ipopt(self) -> ca.Function:
        """IPOPT on the feasibility problem ``F(w) = 0`` with positive durations."""
        return self._ipopt_solver

    def duration_index(self) -> list[int]:
        """Positions of the durations in ``w``."""
        return [off for kind, _, off, _ in self.layout if kind == "duration"]


def _guard_rate(phase, transition) -> ca.Function:
    """``ġ(x, u, p) = ∇g(x) · f(x)``: the guard's rate of change along the flow."""
    return rate_along(phase.flow, transition.guard)


@lru_cache(maxsize=64)
def transcription(
    model_cls: type[HybridModel], disc: MultipleShooting, cycles: int
) -> Transcription:
    """The cached :class:`Transcription` (parameters are symbolic, so one per model class)."""
    return Transcription(model_cls, disc, cycles)


def find_limit_cycle(
    model: HybridModel,
    guess: Mapping[str, float] | LimitCycle | None = None,
    *,
    steps: int = 1,
    inputs: Any = None,
    discretisation: MultipleShooting | None = None,
    method: str = "newton",
    verify: bool = True,
    tol: float = 1e-10,
    follow: bool | None = None,
    starts: int = 1,
    seed: int = 0,
    scheduler: str | None = None,
) -> LimitCycle:
    """Find a periodic orbit (gait) of a hybrid model by multiple shooting.

    Parameters
    ----------
    model : HybridModel
        The model, with its parameters.
    guess : mapping, LimitCycle or None
        Section coordinates to start from (missing ones from ``model.default_start()``): the
        shooting guess is then a simulation of ``steps`` returns from there; ``None`` starts from
        the model's default start.  Or a previous result (warm start, e.g. after a parameter
        change): its orbit seeds the nodes directly.
    steps : int
        Returns to the section per orbit (``2`` for a period-2 gait).
    inputs : array_like, optional
        Constant per-step input (``model.inputs``); default passive.
    discretisation : MultipleShooting, optional
        Segments per phase and RK steps per segment to start from (default: the model's
        ``mesh``).  After convergence the discretisation error is estimated by one Newton
        correction towards twice as many RK steps; while it exceeds ``tol`` the steps are doubled
        and the orbit re-solved (at most four times).
    method : {"newton", "ipopt"}
        CasADi Newton rootfinder on the square system, or IPOPT (``nlpsol``) with durations
        bounded positive.
    verify : bool
        Check the orbit by independent simulation (:func:`gaitopt.simulate`).
    tol : float
        Largest accepted residual of the shooting equations, target of the discretisation-error
        estimate and, scaled by 1e3, the largest accepted difference between the simulated return
        and the fixed point (the simulation runs at ``rtol = 1e-10``, and at ``1e-12`` where
        that check fails).
    follow : bool or None
        Without a ``guess``, at parameters other than the defaults: follow the model's default
        gait from its default parameters to these (a homotopy, :mod:`gaitopt.homotopy`), so that
        the gait found is the one the defaults describe, not whichever orbit lies nearest the
        default start.  ``None`` (default): follow for period-1 gaits when no guess is given;
        where the gait is lost on the way, a direct solve from the default start is tried too.
        ``False``: solve directly.  The result's ``route`` says which was done.
    starts : int
        More than 1: also run a seeded multi-start search (the default start and ``starts − 1``
        Latin-hypercube points around it) and list every distinct gait found in ``gaits``.
    seed : int
        Seed of the multi-start sample (deterministic).
    scheduler : str, optional
        Run the multi-start on the Dask sweep (``"local"`` or a scheduler address).

    Returns
    -------
    LimitCycle
        ``success`` is True only if the equations are solved to ``tol``, every phase duration is
        positive, each phase ends on its guard in the stated direction where the crossing is
        admissible, no guard is crossed earlier inside a phase (dense samples), for ``steps > 1``
        the orbit is not a shorter one repeated, and (with ``verify``) a simulation from the fixed
        point returns to it.  Otherwise ``message`` says what failed.

    Raises
    ------
    GuessError
        If an explicit ``guess`` never reaches the next transition in simulation.
    """
    start = time.perf_counter()
    # -- arguments: every check before any work (issue 9: bad input fails fast) ----------------
    from .arguments import check_count, check_inputs, check_positive, check_start, section_guess
    from .errors import MAX_ORBIT_STEPS, StateError
    from .models import as_model

    model = as_model(model)
    if method not in _METHODS:
        raise GaitoptInputError(f"`method` must be one of {', '.join(_METHODS)}, got {method!r}")
    steps = check_count(
        "steps", steps, 1, MAX_ORBIT_STEPS, "the shooting system of a period-k orbit grows "
        "faster than k (gaitopt.errors.MAX_ORBIT_STEPS)"
    )  # fmt: skip
    tol = check_positive("tol", tol, "1e-10")
    u = check_inputs(model, inputs)
    if discretisation is not None and not isinstance(discretisation, MultipleShooting):
        raise GaitoptInputError(
            f"`discretisation` must be a MultipleShooting, got {discretisation!r}; e.g. "
            f"MultipleShooting(segments=4, steps=5)"
        )
    if not isinstance(guess, LimitCycle):
        x_start = model.lift(section_guess(model, guess))  # unknown names: StateError
        try:
            check_start(model, x_start, u, 0,
                        "guess" if guess is not None else "the default start")  # fmt: skip
        except StateError as exc:
            if guess is None:
                raise
            raise GuessError(str(exc)) from None
    if starts != 1 or (follow is not False and guess is None and steps == 1):
        return _find_the_gait_meant(
            model,
            guess,
            follow=follow,
            starts=starts,
            seed=seed,
            scheduler=scheduler,
            steps=steps,
            inputs=inputs,
            discretisation=discretisation,
            method=method,
            verify=verify,
            tol=tol,
        )
    disc = discretisation or MultipleShooting(*type(model).mesh)
    tr = transcription(type(model), disc, steps)
    p = model.p

    def fail(message: str, **extra: Any) -> LimitCycle:
        note = model.existence_note()
        if note:
            message = f"{message} [{note}]"
        return LimitCycle(
            False,
            message,
            model,
            steps=steps,
            state_names=model.state_names,
            section_coordinates=model.section.coordinates,
            inputs=u,
            solve_time=time.perf_counter() - start,
            **extra,
        )

    # -- guess: a previous orbit (warm start), or a simulation ------------------------------------
    explicit = guess is not None
    warm = isinstance(guess, LimitCycle)
    s0 = guess.section_point if warm else model.section_vector(guess if explicit else {})
    if warm and _reusable(guess, model, tr):
        w0 = tr.pack(s0, *_nodes_from_orbit(guess, tr))
    else:
        sim = simulate(
            model,
            model.lift(s0),
            steps=steps,
            inputs=u,
            max_phase_time=_time_limit(model),
            rtol=1e-8,
            atol=1e-9,  # a guess: Newton does the rest
            constraints=False,  # checked on the orbit found (certify), not on the guess
        )
        if not sim.success:
            where = ", ".join(
                f"{k}={v:.6g}" for k, v in zip(model.section.coordinates, s0, strict=True)
            )
            if explicit and not warm:
                raise GuessError(
                    f"{model.name}: `guess` {where} leads nowhere: {sim.message}; "
                    f"try another guess (e.g. from `gaitopt simulate {model.name}`)"
                )
            return fail(
                f"no gait found: the simulation from {where} does not complete "
                f"{steps} step(s) ({sim.message}); the gait may not exist at these parameters"
            )
        w0 = tr.pack(s0, *_nodes_from_simulation(sim, tr))

    # -- solve, then refine the mesh until the discretisation error is below tol ---------------
    refinements, disc_error, singular = 0, float("nan"), False
    while True:
        w, converged, iterations, ev = _solve(tr, method, w0, u, p)
        # One Jacobian per Newton step: the last one (at the solution) serves the error
        # estimate, the multipliers and the input Jacobian.
        ev = ev if ev is not None else tr.evaluate(w, u, p)
        F, J_w = ev.F, _gp_jacobian(tr, ev.F_w)
        # Newton's own stopping test (abstol 1e-12) is stricter than `tol`: a point that meets
        # `tol` is accepted (and certified) even where Newton stalled just above its abstol.
        # A "converged" point where the equations are not even finite (e.g. a negative duration
        # reached by the line search) is no solution.
        finite = bool(np.all(np.isfinite(J_w)) and np.all(np.isfinite(F)))
        converged = finite and (converged or float(np.max(np.abs(F))) <= tol)
        if not converged:
            break
        try:
            correction = _newton_step(tr, J_w, tr.fine_residual(w, u, p))
        except np.linalg.LinAlgError:  # a singular shooting Jacobian: not an isolated orbit
            converged, singular = False, True
            break
        disc_error = float(np.max(np.abs(correction)))
        # The finest mesh is bounded in absolute terms (not only per call), so that a chain of
        # warm starts (homotopy, libraries) cannot compound refinements without limit.
        finest = type(model).mesh[1] * _MAX_MESH_FACTOR
        if disc_error <= tol or refinements == _MAX_REFINEMENTS or 2 * disc.steps > finest:
            break
        disc = replace(disc, steps=2 * disc.steps)
        tr, w0 = transcription(type(model), disc, steps), w + correction
        refinements += 1

    residual = float(np.max(np.abs(F))) if np.all(np.isfinite(F)) else float("inf")
    durations = np.asarray(ev.durations, dtype=float).ravel()
    # A period only where it means something: every phase duration positive and finite.
    period = (
        float(np.sum(durations))
        if durations.size and np.all(np.isfinite(durations)) and np.all(durations > 0)
        else float("nan")
    )
    if singular:
        return fail(
            f"no isolated gait: the shooting equations are solved (residual {residual:.3g}, "
            f"tolerance {tol:g}) but their Jacobian is singular there, so the orbit is one of a "
            f"continuous family (a multiplier exactly 1: the motion does not depend on some "
            f"coordinate, or a parameter makes a restoring term vanish) and has no fixed point "
            f"or stability of its own; change the parameter that removes the restoring term",
            residual=residual,
            iterations=iterations,
            durations=durations,
            period=period,
        )
    if not converged or not residual <= tol:
        if not np.isfinite(residual):
            how = (
                f"{method} diverged: after {iterations} iterations the shooting equations are "
                f"not even finite (a phase run backwards or far outside the model's range)"
            )
        else:
            how = (
                f"{method} stopped after {iterations} iterations with residual {residual:.3g}, "
                f"above the tolerance {tol:g}"
            )
        return fail(
            f"no periodic orbit found near the guess: {how}; the gait may not exist at these "
            f"parameters, or the guess is too far from it: try a closer guess"
            + (" or the ipopt method" if method == "newton" else ""),
            residual=residual,
            iterations=iterations,
            durations=durations if np.isfinite(period) else np.zeros(0),
            period=float("nan"),  # not an orbit: no period
        )
    if disc_error > tol:
        J_F = J_w.copy()
        J_F[tr.n_g :, : tr.m] -= np.eye(tr.m)
        condition = float(np.linalg.cond(J_F))
        return fail(
            f"no certified gait: the discretisation error estimate {disc_error:.2g} stays above "
            f"the tolerance {tol:g} after {refinements} mesh refinements "
            f"({tr.disc.steps} RK steps per segment), so the orbit is known only to about "
            f"{disc_error:.1g}; the shooting Jacobian's condition number is {condition:.2g} "
            f"(a multiplier near 1 makes the fixed point sensitive to every error): loosen `tol` "
            f"to accept that accuracy",
            residual=residual,
            iterations=iterations,
            durations=durations,
            period=period,
            discretisation_error=disc_error,
        )
    x_star = model.lift(w[: tr.m])
    rate = np.asarray(model.phases[0].flow(x_star, u, p), dtype=float).ravel()
    if float(np.max(np.abs(rate))) <= 1e-8 * (1 + float(np.max(np.abs(x_star)))):
        return fail(
            "no gait: the orbit found is standing still (an equilibrium: the state does not "
            "change, zero step length), which solves the shooting equations with any phase "
            "duration but is not a gait; the gait may not exist at these parameters (a passive "
            "walker needs a slope), or try a guess with more speed",
            residual=residual,
            iterations=iterations,
        )
    disc_error_note = ""
    return certify(
        model,
        tr,
        w,
        u,
        verify=verify,
        tol=tol,
        iterations=iterations,
        discretisation_error=disc_error,
        note=disc_error_note,
        start=start,
        evaluation=ev,
    )


def _find_the_gait_meant(model, guess, *, follow, starts, seed, scheduler, **options) -> LimitCycle:
    """The homotopy from the defaults and the multi-start search around
    :func:`find_limit_cycle`'s direct solve (see :mod:`gaitopt.homotopy`)."""
    from .homotopy import changed_parameters, follow_default_gait, multi_start, path_description

    if not isinstance(starts, int) or isinstance(starts, bool) or not 1 <= starts <= _MAX_STARTS:
        raise GaitoptInputError(
            f"`starts` must be an integer from 1 to {_MAX_STARTS}, got {starts!r}; e.g. starts=8"
        )
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise GaitoptInputError(f"`seed` must be an integer, got {seed!r}; e.g. seed=0")
    start = time.perf_counter()
    steps = options.pop("steps")
    direct = lambda: find_limit_cycle(model, guess, steps=steps, follow=False, **options)  # noqa: E731
    cycle = None
    if guess is None and steps == 1 and follow is not False:
        followed = follow_default_gait(model, **options)
        if followed is not None and followed.success:
            cycle = followed
        elif followed is not None:  # lost on the way: try the default start directly
            cycle = direct()
            lost = followed.message
            if cycle.success:
                cycle = replace(
                    cycle,
                    message=f"{cycle.message}; found from the default start ({lost})",
                    route=f"direct from the default start; {lost}",
                )
            else:
                cycle = replace(
                    cycle,
                    message=(
                        f"no gait found. Following the default gait from the default parameters "
                        f"({path_description(changed_parameters(model))}): {lost}. From the "
                        f"default start: {cycle.message}. Try `--starts 16` (a multi-start "
                        f"search), a --guess near a gait you know, or `gaitopt continue` to see "
                        f"where the branch ends"
                    ),
                    route="homotopy from the defaults, then direct from the default start",
                )
    if cycle is None:
        cycle = direct()
        if guess is None and not cycle.route:
            cycle = replace(cycle, route="direct from the default start")
    if starts > 1:
        gaits = multi_start(
            model, starts, seed=seed, steps=steps, scheduler=scheduler,
            **{k: v for k, v in options.items() if k in ("inputs", "method", "tol")},
        )  # fmt: skip
        if not cycle.success and gaits:  # the multi-start found what the default route did not
            best = gaits[0]
            cycle = find_limit_cycle(
                model,
                {k: best["fixed_point"][k] for k in model.section.coordinates},
                steps=steps,
                follow=False,
                **options,
            )
        count = f"{len(gaits)} distinct gait(s) from {starts} starts (seed {seed})"
        cycle = replace(cycle, gaits=gaits, message=f"{cycle.message}; multi-start: {count}")
    return replace(cycle, solve_time=time.perf_counter() - start)


#: Most starts of one multi-start search (each a full solve: 1000 take minutes).
_MAX_STARTS = 1000


def certify(
    model: HybridModel,
    tr: Transcription,
    w: np.ndarray,
    u: np.ndarray,
    *,
    verify: bool = True,
    tol: float = 1e-10,
    iterations: int = 0,
    discretisation_error: float = float("nan"),
    note: str = "",
    start: float | None = None,
    linearisation: tuple[np.ndarray, ...] | None = None,
    evaluation: Any = None,
) -> LimitCycle:
    """Check a solution ``w`` of the shooting equations and build its :class:`LimitCycle`.

    The checks of :func:`find_limit_cycle` ("no false gaits"): positive durations, admissible
    directional crossing at each phase end, no earlier crossing on dense samples, minimal period,
    and (with ``verify``) the independent simulation; then the multipliers.  Used by
    :func:`find_limit_cycle` and by continuation for every point of a branch.
    """
    start = time.perf_counter() if start is None else start
    p = model.p
    ev = evaluation if evaluation is not None else tr.evaluate(w, u, p)
    if linearisation is None:
        linearisation = (_gp_jacobian(tr, ev.F_w), ev.F_u, ev.F, ev.x_return)
    J_w, J_u, F, x_return = (np.asarray(v, dtype=float) for v in linearisation)
    residual = float(np.max(np.abs(F))) if np.all(np.isfinite(F)) else float("inf")
    ends, dg, adm = ev.ends, ev.rates, ev.admissible
    durations = np.asarray(ev.durations, dtype=float).ravel()
    x_star = model.lift(w[: tr.m])
    steps = tr.cycles
    common = dict(
        model=model,
        steps=steps,
        state_names=model.state_names,
        section_coordinates=model.section.coordinates,
        inputs=u,
        residual=residual,
        iterations=iterations,
        durations=durations,
        discretisation=tr.disc,
        discretisation_error=discretisation_error,
        period=float(np.sum(durations)),
        fixed_point=dict(zip(model.state_names, map(float, x_star), strict=True)),
    )

    def fail(message: str, **extra: Any) -> LimitCycle:
        note_ = model.existence_note()
        message = f"{message} [{note_}]" if note_ else message
        return LimitCycle(False, message, solve_time=time.perf_counter() - start, **common, **extra)

    # -- no false gaits ----------------------------------------------------------------------
    problem = _check_orbit(
        model, tr, w, u, p, ends, dg.ravel(), adm.ravel(), durations, x_return, x_star
    )
    orbit = _orbit_arcs(model, tr, w, u, p, durations)
    if problem is None:
        problem = _check_dense(model, tr, orbit, u, p)
    if problem is None:
        problem = check_constraints(model, tr, orbit, u, p)
    if problem is None and steps > 1:
        problem = _check_minimal_period(model, tr, w, steps)
    if problem is not None:
        return fail(problem, orbit=orbit)

    try:
        A, B = section_jacobians(J_w, J_u, tr.m, tr.n_g)
    except np.linalg.LinAlgError:
        return fail(
            "no isolated gait: the shooting equations are singular at the solution (the orbit "
            "is not transversal to a guard, or not isolated)",
            orbit=orbit,
        )
    multipliers = np.linalg.eigvals(A) if A.size else np.zeros(0, complex)
    multipliers = multipliers[np.argsort(-np.abs(multipliers))]

    verified, error, vmessage = False, float("nan"), "not verified by simulation (verify=False)"
    if verify:
        verified, error, vmessage = _verify(model, x_star, durations, steps, u, tol * 1e3)
    success = verified or not verify
    accuracy = f"discretisation error {discretisation_error:.1g}{note}"
    message = (
        f"periodic orbit found (residual {residual:.2g}, {accuracy}); " + vmessage
        if success
        else "the shooting solution is not confirmed: " + vmessage
    )
    return LimitCycle(
        success=success,
        message=message,
        multipliers=multipliers if success else np.zeros(0, complex),
        stable=is_stable(multipliers) if success else None,
        verified=verified,
        verification_error=error,
        jacobian=A,
        input_jacobian=B,
        orbit=orbit,
        solve_time=time.perf_counter() - start,
        **common,
    )


_MAX_REFINEMENTS = 4
#: The finest mesh any solve may reach, as a multiple of the model's RK steps per segment: a
#: chain of warm starts (homotopy, libraries) refines from where the last one ended, up to here
#: (Van der Pol at μ = 10 needs 32×; without a bound the chain compounded to 22 GB).
_MAX_MESH_FACTOR = 64


def _solve(tr: Transcription, method: str, w0, u, p) -> tuple[np.ndarray, bool, int, Any]:
    """Newton (plain, then with line search), or IPOPT with positive durations; with the
    evaluation (residual and Jacobians) at the point returned where Newton has it."""
    if method == "newton":
        if tr.assembly() is not None:
            w, converged, iterations, ev = newton(tr, w0, u, p)
            if not converged:
                w, converged, more, ev = newton(tr, w0, u, p, line_search=True)
                iterations += more
            return w, converged, iterations, ev
        w, converged, iterations = _newton(tr.newton, w0, u, p)
        if not converged:
            w, converged, more = _newton(tr.newton_line_search, w0, u, p)
            iterations += more
        return w, converged, iterations, None
    lbx = np.full(tr.size, -np.inf)
    lbx[tr.duration_index()] = 1e-9
    solver = tr.ipopt()
    sol = solver(x0=w0, p=np.concatenate([u, p]), lbg=0, ubg=0, lbx=lbx)
    stats = solver.stats()
    return (
        np.asarray(sol["x"], dtype=float).ravel(),
        bool(stats["success"]),
        int(stats["iter_count"]),
        None,
    )


#: Newton's stopping tests (as CasADi's ``rootfinder`` "newton" options before): the largest
#: residual, the largest step.
_ABSTOL, _ABSTOL_STEP = _NEWTON["abstol"], _NEWTON["abstolStep"]


def newton(tr: Transcription, w0, u, p, *, line_search: bool = False):
    """Newton on the compiled shooting system: each iteration one compiled call for ``F`` and
    ``∂F/∂w``, a dense solve, and (with ``line_search``) halving the step until ``‖F‖₂``
    decreases.  Stops where ``max |F| ≤ 1e-12`` or ``max |step| ≤ 1e-15``; 30 iterations
    (100 with line search).

    Returns
    -------
    (w, converged, iterations, evaluation) : the last point, whether a stopping test passed,
    the number of Jacobians evaluated and the evaluation at ``w`` (reused by the caller).
    """
    asm = tr.assembly()
    max_iter = 100 if line_search else _NEWTON["max_iter"]
    w = np.array(w0, dtype=float).ravel()
    ev = None
    for iteration in range(1, max_iter + 1):
        ev = ev if ev is not None else asm(w, u, p)
        F = ev.F
        if not (np.all(np.isfinite(F)) and np.all(np.isfinite(ev.F_w))):
            return w, False, iteration, ev
        if float(np.max(np.abs(F))) <= _ABSTOL:
            return w, True, iteration, ev
        try:
            step = np.linalg.solve(ev.F_w, F)
        except np.linalg.LinAlgError:  # exactly singular (a family of orbits): least squares
            step = np.linalg.lstsq(ev.F_w, F, rcond=None)[0]
        if float(np.max(np.abs(step))) <= _ABSTOL_STEP:
            return w, True, iteration, ev
        if not line_search:
            w, ev = w - step, None
            continue
        norm, alpha = float(F @ F), 1.0
        while True:
            trial = asm(w - alpha * step, u, p)
            if (np.all(np.isfinite(trial.F)) and float(trial.F @ trial.F) < norm) or alpha < 1e-4:
                break
            alpha /= 2
        w, ev = w - alpha * step, trial
    return w, False, max_iter, ev


def _gp_jacobian(tr: Transcription, F_w: np.ndarray) -> np.ndarray:
    """``∂[G; P]/∂w`` from ``∂F/∂w`` (``F = [G; P − s]``)."""
    J = np.array(F_w, dtype=float)
    J[tr.n_g :, : tr.m] += np.eye(tr.m)
    return J


def _newton_step(tr: Transcription, J_w: np.ndarray, F) -> np.ndarray:
    """``−J_F⁻¹ F`` with ``J_F = ∂[G; P − s]/∂w`` from the Jacobian of ``[G; P]``."""
    J_F = J_w.copy()
    J_F[tr.n_g :, : tr.m] -= np.eye(tr.m)
    return -np.linalg.solve(J_F, np.asarray(F, dtype=float).ravel())


def _newton(solver: ca.Function, w0, u, p) -> tuple[np.ndarray, bool, int]:
    w = np.asarray(solver(w0, u, p), dtype=float).ravel()
    stats = solver.stats()
    return w, bool(stats["success"]) and bool(np.all(np.isfinite(w))), int(stats["iter_count"])


def _time_limit(model: HybridModel) -> float:
    return float(model.max_phase_time)


def _nodes_from_simulation(
    sim: Simulation, tr: Transcription
) -> tuple[list[np.ndarray], list[float]]:
    """Segment start states and phase durations of the simulated orbit, in chain order."""
    S = tr.disc.segments
    nodes, durations = [], []
    arcs = sim.arcs[: len(tr.chain)]
    for arc in arcs:
        T = arc.t1 - arc.t0
        t = arc.t0 + T * np.arange(S) / S
        nodes.append(np.atleast_2d(arc.solution(t)).reshape(-1, S))
        durations.append(T)
    return nodes, durations


def _reusable(cycle: LimitCycle, model: HybridModel, tr: Transcription) -> bool:
    """Whether a previous orbit can seed the shooting nodes directly (same model class, same
    phase sequence)."""
    return (
        type(cycle.model) is type(model)
        and cycle.steps == tr.cycles
        and len(cycle.orbit) == len(tr.chain)
        and len(cycle.durations) == len(tr.chain)
    )


def _nodes_from_orbit(cycle: LimitCycle, tr: Transcription) -> tuple[list[np.ndarray], list[float]]:
    """Segment start states of a previous orbit (interpolated in its dense samples)."""
    S = tr.disc.segments
    nodes = []
    for arc in cycle.orbit:
        tau = (arc.t - arc.t[0]) / (arc.t[-1] - arc.t[0])
        at = np.arange(S) / S
        nodes.append(np.array([np.interp(at, tau, row) for row in arc.x]))
    return nodes, [float(d) for d in cycle.durations]


def _phase_label(model: HybridModel, tr: Transcription, k: int) -> str:
    name = model.phases[tr.chain[k]].name
    return f"phase '{name}'" + (f" (step {k // len(model.phases) + 1})" if tr.cycles > 1 else "")


def _check_orbit(model, tr, w, u, p, ends, dg, adm, durations, x_return, x_star) -> str | None:
    """Durations positive; each phase ends on its guard, admissibly and in the stated direction."""
    for k, i in enumerate(tr.chain):
        phase = model.phases[i]
        transition = phase.transitions[0]
        label = _phase_label(model, tr, k)
        if not durations[k] > 0:
            return (
                f"no gait: {label} would last {durations[k]:.3g} s (durations must be positive); "
                f"the orbit through this guess runs backwards in time — the gait may not exist "
                f"at these parameters"
            )
        if not adm[k] > 0:
            return (
                f"no gait: {label} ends on '{transition.name}' where that crossing is excluded "
                f"(spurious crossing rule: {transition.doc})"
            )
        if not transition.direction * dg[k] > 0:
            return (
                f"no gait: {label} reaches '{transition.name}' in the wrong direction "
                f"(grazing or from the other side)"
            )
    error = float(np.max(np.abs(np.asarray(x_return).ravel() - x_star)))
    if error > 1e-8 * (1 + np.max(np.abs(x_star))):
        return (
            f"internal inconsistency: the return state leaves the section parametrisation by "
            f"{error:.3g}; the model's section lift does not match its reset"
        )
    return None


def _orbit_arcs(model, tr, w, u, p, durations) -> list[OrbitArc]:
    samples = tr.sample_numeric(w, u, p)
    S, q = tr.disc.segments, tr.disc.dense
    arcs, t0 = [], 0.0
    for k, i in enumerate(tr.chain):
        X = np.asarray(samples[k], dtype=float)
        # Each segment gives q + 1 samples; drop the duplicated segment starts.
        keep = [j for j in range(X.shape[1]) if j % (q + 1) != 0 or j == 0]
        X = X[:, keep]
        t = t0 + np.linspace(0.0, durations[k], X.shape[1])
        phase = model.phases[i]
        arcs.append(OrbitArc(i, phase.name, phase.states, t, X, phase.transitions[0].name))
        t0 += durations[k]
    del S
    return arcs


def _check_dense(model, tr, orbit, u, p) -> str | None:
    """No guard of the phase is crossed (admissibly, in its direction) before the phase ends."""
    for k, arc in enumerate(orbit):
        phase = model.phases[arc.phase]
        K = arc.x.shape[1]
        for j, transition in enumerate(phase.transitions):
            guard_map, admissible_map = tr.guard_maps[arc.phase][j]
            g = transition.direction * np.asarray(guard_map(arc.x, u, p), dtype=float).ravel()
            a = (
                np.asarray(admissible_map(arc.x, u, p), dtype=float).ravel()
                if admissible_map is not None
                else np.ones(K)
            )
            scale = 1e-9 * (1 + np.max(np.abs(g)))
            armed = np.maximum.accumulate(g < -scale)
            last = K - 1 if j == 0 else K  # the cycle transition fires at the last sample
            for idx in range(1, last):
                if armed[idx - 1] and g[idx - 1] < 0 <= g[idx] and (a[idx - 1] > 0 or a[idx] > 0):
                    t = arc.t[idx]
                    return (
                        f"no gait: the orbit crosses '{transition.name}' inside "
                        f"{_phase_label(model, tr, k)} at t = {t:.4g} s, before the phase ends "
                        f"(e.g. a foot through the ground); not a gait with this phase sequence"
                    )
    return None


#: A unilateral constraint counts as violated where ``c < -_CONSTRAINT_TOL · (1 + max |c|)`` on
#: the dense samples (the shooting solution's own accuracy is ~1e-10), and a constraint that
#: starts active must rise faster than ``_CONSTRAINT_TOL`` per second (in its unit).
_CONSTRAINT_TOL = 1e-9


def check_constraints(model, tr, orbit, u, p) -> str | None:
    """Every unilateral constraint of every phase holds on the orbit's dense samples.

    A constraint declared ``at_start`` (zero where the phase begins: a trailing foot on the
    ground) must also rise there, ``ċ > 0`` (the foot lifts off); one declared ``at_end`` is zero
    at the phase's last sample by construction.  Returns the first violation in words, or None.
    """
    for k, arc in enumerate(orbit):
        phase = model.phases[arc.phase]
        for constraint, (c_map, rate) in zip(
            phase.constraints, tr.constraint_maps[arc.phase], strict=True
        ):
            c = np.asarray(c_map(arc.x, u, p), dtype=float).ravel()
            scale = _CONSTRAINT_TOL * (1 + float(np.max(np.abs(c))))
            unit = f" {constraint.unit}" if constraint.unit else ""
            label = _phase_label(model, tr, k)
            if constraint.at_start:
                c0_rate = float(rate(arc.x[:, 0], u, p))
                if not c0_rate > _CONSTRAINT_TOL:
                    return (
                        f"no gait: {constraint.outcome} at the start of {label}: "
                        f"'{constraint.name}' starts at 0 and must rise, but its rate is "
                        f"{c0_rate:.3g}{unit}/s ({constraint.source})"
                    )
            inner = slice(1 if constraint.at_start else 0, -1 if constraint.at_end else None)
            bad = np.nonzero(c[inner] < -scale)[0]
            if bad.size:
                j = int(bad[0]) + (1 if constraint.at_start else 0)
                return (
                    f"no gait: {constraint.outcome} in {label} at t = {arc.t[j]:.4g} s: "
                    f"'{constraint.name}' fails (value {c[j]:.3g}{unit}, lowest "
                    f"{float(np.min(c[inner])):.3g}{unit}; {constraint.source})"
                )
    return None


def _check_minimal_period(model, tr, w, steps) -> str | None:
    """A period-k orbit must not be a shorter orbit repeated."""
    starts = []
    n_phases = len(model.phases)
    for kind, k, off, shape in tr.layout:
        if kind == "nodes" and k % n_phases == 0 and k > 0:
            n = shape[0]
            starts.append(w[off : off + n])
    x0 = model.lift(w[: tr.m])
    for j, xj in enumerate(starts, start=1):
        if steps % j == 0 and np.max(np.abs(xj - x0)) < 1e-6 * (1 + np.max(np.abs(x0))):
            return (
                f"no period-{steps} gait here: the orbit found is the period-{j} gait repeated; "
                f"try a guess on the period-{steps} orbit (past its period doubling)"
            )
    return None


# The phase timing is a consistency check (same events, same phases), not the measure of
# accuracy: where an orbit creeps past an unstable equilibrium (a rimless wheel that barely
# vaults) the adaptive simulation's event times drift by far more than its states, while the
# shooting durations carry the discretisation-error estimate.  Relative to the period:
_TIMING_TOL = 1e-6


# The verifying simulation's tolerances, (rtol, atol): first the loose pair, whose error at the
# return (1e-13 to 1.4e-10 over the registered models' gaits, measured against the shooting's
# fixed points) stays three orders of magnitude below the 1e-7 it is checked against (``tol *
# 1e3``) in 30-40 % fewer steps; where that check fails, the tight pair decides (near an
# existence boundary, where a rimless wheel barely vaults, the event times need it).
_VERIFY_LOOSE = (1e-10, 1e-12)
_VERIFY_TIGHT = (1e-12, 1e-13)


def _verify(model, x_star, durations, steps, u, tol) -> tuple[bool, float, str]:
    """Simulate from the fixed point with SciPy: the return must be within ``tol`` (relative
    to the state's size) of the fixed point, through the same phases at consistent times
    (at the loose tolerances, then, if that fails, at the tight ones)."""
    verdict = _verify_at(model, x_star, durations, steps, u, tol, *_VERIFY_LOOSE)
    if verdict[0]:
        return verdict
    return _verify_at(model, x_star, durations, steps, u, tol, *_VERIFY_TIGHT)


def _verify_at(model, x_star, durations, steps, u, tol, rtol, atol) -> tuple[bool, float, str]:
    sim = simulate(
        model,
        x_star,
        steps=steps,
        inputs=u,
        max_phase_time=_time_limit(model),
        rtol=rtol,
        atol=atol,
    )
    if not sim.success:
        return False, float("inf"), f"the simulation from the fixed point fails: {sim.message}"
    expected = len(durations)
    if len(sim.arcs) != expected:
        return (
            False,
            float("inf"),
            (f"the simulation passes {len(sim.arcs)} phases where the orbit has {expected}"),
        )
    error = float(np.max(np.abs(sim.section_states[-1] - x_star)))
    sim_durations = np.array([a.t1 - a.t0 for a in sim.arcs])
    timing = float(np.max(np.abs(sim_durations - durations)))
    scale = 1 + float(np.max(np.abs(x_star)))
    if error > tol * scale or timing > _TIMING_TOL * (1 + float(np.sum(durations))):
        return (
            False,
            error,
            (
                f"the simulation from the fixed point returns {error:.3g} away (tolerance "
                f"{tol:g}); phase timing differs by {timing:.3g} s"
            ),
        )
    return (
        True,
        error,
        (f"verified by simulation: return error {error:.2g}, timing error {timing:.2g} s"),
    )
