"""Solve a gait optimisation problem: IPOPT with exact derivatives, multi-start, refinement, checks.

:func:`optimize_gait` transcribes the problem (:mod:`gaitopt.optimize.collocation`), solves the
nonlinear program with IPOPT through :func:`casadi.nlpsol` (exact first and second derivatives
by CasADi's AD) from ``starts`` seeded guesses, sorts the converged ones into distinct local
minima, refines the mesh of the best (warm started) until the cost and the orbit change by less
than ``tol`` (relative), checks it on dense samples, re-simulates it with the independent
simulator and computes its Floquet multipliers two ways.  A problem with no solution is answered
with ``success=False`` naming the constraint that cannot be met.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..result import OrbitArc
from ..simulation import simulate
from ..stability import is_stable
from .collocation import Arc, Collocation, RadauMesh
from .floquet import multipliers_of, return_map_jacobian
from .problem import GaitProblem, as_problem
from .result import Minimum, OptimalGait
from .verify import (
    check_dense,
    map_jacobian_fd,
    profiles,
    simulate_gait,
    simulated_cost,
)

__all__ = ["optimize_gait", "solve_problem", "DEFAULT_MESH"]

DEFAULT_MESH = RadauMesh(6, 6)
_IPOPT = {
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": False,
    "ipopt.tol": 1e-11,
    "ipopt.constr_viol_tol": 1e-11,
    "ipopt.acceptable_tol": 1e-9,
    "ipopt.max_iter": 1000,
    "error_on_fail": False,
    "expand": True,
}
_SOLVERS: dict[int, tuple[Collocation, ca.Function]] = {}
_MAX_REFINEMENTS = 3
_ARC_INTERVALS = 2  # mesh intervals per arc of the switching-time transcription, before refinement


def optimize_gait(
    model: HybridModel,
    cost: str | Callable[..., Any] = "effort",
    *,
    period: float | None = None,
    step_length: float | None = None,
    speed: float | None = None,
    bounds: dict[str, float] | None = None,
    state_bounds: dict[str, tuple[float, float]] | None = None,
    free: tuple[str, ...] | str = (),
    steps: int = 1,
    starts: int | Sequence[int] = 1,
    seed: int = 0,
    mesh: RadauMesh | None = None,
    tol: float = 1e-8,
    verify: bool = True,
    guess: OptimalGait | None = None,
    scheduler: str | None = None,
) -> OptimalGait:
    """Synthesise the optimal gait of an actuated hybrid model.

    Parameters
    ----------
    model : HybridModel
        The model (its inputs become time-varying profiles).
    cost : {"effort", "work", "cot"} or callable
        ``∫Σuᵢ² dt`` (N²·m²·s), positive actuator work (J), cost of transport (1), or the
        integrand ``cost(x, u, p)`` of CasADi symbols.
    period, step_length, speed : float, optional
        Fixed orbit period (s), mean step length (m), average speed (m/s); free when omitted.
    bounds : dict, optional
        ``{input: max}``: ``|u| ≤ max`` (input units).
    state_bounds : dict, optional
        ``{state: (low, high)}`` at every node (joint and rate limits).
    free : tuple of str
        Parameters to optimise too, within their declared ranges.
    steps : int
        Returns to the section per orbit.
    starts : int or sequence of int
        Number of seeded starts (start 0 from the model's default start, start ``j`` perturbed
        with ``numpy.random.default_rng([seed, j])``), or the indices of the starts to run (to
        re-run a given start alone); every distinct local minimum is reported in ``minima``
        with the starts that reached it.
    seed : int
        Seed of the multi-start.
    mesh : RadauMesh, optional
        Initial mesh (default: 6 intervals of degree 6 per phase), refined by doubling the
        intervals until the discretisation error is below ``tol``.
    tol : float
        Target of the relative discretisation error of the cost and the orbit.
    verify : bool
        Re-simulate the optimum and compute the multipliers (always, unless False for speed).
    guess : OptimalGait, optional
        A previous optimum to warm start from (a library of gaits).
    scheduler : str, optional
        Run the starts on Dask (``"local"``: a local cluster; or a scheduler address), as
        :func:`gaitopt.sweep.sweep` does (:func:`gaitopt.optimize.library.dask_starts`); the
        minima and the refined optimum are those of the serial run.  Default: serially.

    Returns
    -------
    OptimalGait
    """
    problem = as_problem(
        model,
        cost=cost,
        period=period,
        step_length=step_length,
        speed=speed,
        bounds=bounds,
        state_bounds=state_bounds,
        free=free,
        steps=steps,
    )
    indices = _start_indices(starts)
    return solve_problem(
        problem,
        starts=indices,
        seed=seed,
        mesh=mesh,
        tol=tol,
        verify=verify,
        guess=guess,
        scheduler=scheduler,
    )


def _start_indices(starts: int | Sequence[int]) -> list[int]:
    """``starts`` as a list of start indices (an int ``N`` means ``0 … N − 1``)."""
    if isinstance(starts, (int, np.integer)) and not isinstance(starts, bool):
        if starts < 1:
            raise GaitoptInputError(f"`starts` must be a positive integer, got {starts!r}; e.g. 4")
        return list(range(int(starts)))
    try:
        indices = [int(i) for i in starts]  # type: ignore[union-attr]
    except (TypeError, ValueError):
        indices = []
    if not indices or any(i < 0 for i in indices) or len(set(indices)) != len(indices):
        raise GaitoptInputError(
            f"`starts` must be a positive integer or distinct start indices >= 0, got "
            f"{starts!r}; e.g. starts=4 or starts=[0, 3]"
        )
    return indices


def _solver(col: Collocation) -> ca.Function:
    key = id(col)
    entry = _SOLVERS.get(key)
    if entry is None or entry[0] is not col:  # an id may be reused once its object is freed
        _SOLVERS.clear()  # one at a time: each holds a compiled NLP
        _SOLVERS[key] = (col, ca.nlpsol("gait", "ipopt", col.nlp, _IPOPT))
    return _SOLVERS[key][1]


def _run(col: Collocation, w0: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, dict[str, Any]]:
    solver = _solver(col)
    w0 = np.clip(w0, col.lbx, col.ubx)
    sol = solver(x0=w0, p=p, lbx=col.lbx, ubx=col.ubx, lbg=col.lbg, ubg=col.ubg)
    return np.asarray(sol["x"], dtype=float).ravel(), dict(solver.stats())


def _violation(col: Collocation, w: np.ndarray, p: np.ndarray) -> tuple[str, float]:
    """The constraint group with the largest violation at ``w`` and its size."""
    g = np.asarray(col.constraints(w, p), dtype=float).ravel()
    worst, name = 0.0, ""
    for group in col.groups:
        sl = slice(group.start, group.start + group.size)
        v = np.maximum(col.lbg[sl] - g[sl], g[sl] - col.ubg[sl])
        v = float(np.max(v)) if v.size else 0.0
        if v > worst:
            worst, name = v, group.name
    return name, worst


def _active(col: Collocation, w: np.ndarray, p: np.ndarray) -> list[str]:
    """Inequality groups and variable bounds that are active (within 1e-6) at ``w``."""
    out = []
    problem = col.problem
    g = np.asarray(col.constraints(w, p), dtype=float).ravel()
    for group in col.groups:
        sl = slice(group.start, group.start + group.size)
        if group.equality:
            if group.name in ("period", "step length", "speed"):
                out.append(f"{group.name} (fixed)")
            continue
        near = np.minimum(np.abs(g[sl] - col.lbg[sl]), np.abs(g[sl] - col.ubg[sl]))
        if near.size and np.min(near) < 1e-6:
            out.append(group.name)
    B = col.blocks
    names = problem.model.inputs
    lows, highs = problem.input_bounds()
    for k in range(len(col.chain)):
        U = B.get(w, f"U{k}")
        for i, name in enumerate(names):
            low, high = lows[i], highs[i]
            if name not in problem.bounds or high <= low:  # unbounded, or switched off
                continue
            tol = 1e-6 * max(abs(low), abs(high))
            count = int(np.sum(U[i] > high - tol) + np.sum(U[i] < low + tol))
            label = f"|{name}| <= {high:g}" if low == -high else f"{low:g} <= {name} <= {high:g}"
            if count and label not in out:
                out.append(label)
        phase = problem.model.phases[col.chain[k]]
        X = B.get(w, f"X{k}")
        for j, state in enumerate(phase.states):
            if state in problem.state_bounds:
                low, high = problem.state_bounds[state]
                tol = 1e-6 * (1 + abs(low) + abs(high))
                hit = np.any(X[j] < low + tol) or np.any(X[j] > high - tol)
                label = f"{low:g} <= {state} <= {high:g}"
                if hit and label not in out:
                    out.append(label)
    if problem.free:
        values = B.get(w, "free").ravel()
        lo, hi = problem.free_bounds()
        for name, v, a, b in zip(problem.free, values, lo, hi, strict=True):
            if v < a + 1e-6 * (1 + abs(a)) or v > b - 1e-6 * (1 + abs(b)):
                out.append(f"range of parameter {name}")
    return out


# -- guesses -----------------------------------------------------------------------------------
def _guess_from_simulation(
    col: Collocation, problem: GaitProblem, s0: np.ndarray, rng: np.random.Generator | None
) -> np.ndarray:
    model = problem.model
    p = model.p
    n_u = len(model.inputs)
    sim = simulate(model, model.lift(s0), steps=problem.steps, max_phase_time=5.0)
    arcs = sim.arcs
    chain = col.chain
    states, durations = [], []
    for k, i in enumerate(chain):
        arc = arcs[k] if k < len(arcs) and arcs[k].phase == i else None
        if arc is None or not arc.t1 > arc.t0:
            x0 = model.lift(s0) if i == 0 else np.zeros(model.phases[i].n)
            states.append(lambda t, x0=x0: np.tile(x0[:, None], (1, np.size(t))))
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
        us = arc.u  # type: ignore[attr-defined]
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
def _same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    cost_close = abs(a["cost"] - b["cost"]) <= 1e-6 * max(abs(a["cost"]), abs(b["cost"])) + 1e-9
    s_close = np.max(np.abs(a["s"] - b["s"])) <= 1e-4 * (1 + np.max(np.abs(a["s"])))
    return bool(cost_close and s_close)


def _converged(stats: dict[str, Any]) -> bool:
    return bool(stats.get("success")) or stats.get("return_status") == "Solved_To_Acceptable_Level"


def attempt(
    col: Collocation, problem: GaitProblem, start: int, seed: int, guess: OptimalGait | None
) -> dict[str, Any]:
    """One start of the multi-start on the initial mesh: ``{"start", "w", "stats", "ok"}`` and
    ``cost``, ``s``, ``period`` if IPOPT converged, else ``violation`` (worst group, size)."""
    p = problem.model.p
    w0 = _start_guess(col, problem, start, seed, guess)
    w, stats = _run(col, w0, p)
    ok = bool(_converged(stats) and np.all(np.isfinite(w)))
    entry: dict[str, Any] = {"start": start, "w": w, "stats": stats, "ok": ok}
    if ok:
        sol = col.unpack(w, p)
        entry.update(cost=sol["cost"], s=sol["s"], period=sol["period"])
    else:
        entry["violation"] = _violation(col, w, p)
    return entry


def solve_problem(
    problem: GaitProblem,
    *,
    starts: int | Sequence[int] = 1,
    seed: int = 0,
    mesh: RadauMesh | None = None,
    tol: float = 1e-8,
    verify: bool = True,
    guess: OptimalGait | None = None,
    scheduler: str | None = None,
) -> OptimalGait:
    """Solve a :class:`GaitProblem` (see :func:`optimize_gait`)."""
    t_start = time.perf_counter()
    model = problem.model
    p = model.p
    mesh = mesh or DEFAULT_MESH
    col = Collocation(problem, mesh)
    indices = _start_indices(starts)
    if scheduler is not None:  # the same attempts, on Dask workers
        from .library import dask_starts

        runs = dask_starts(problem, mesh, indices, seed, scheduler, guess)
    else:
        runs = [attempt(col, problem, start, seed, guess) for start in indices]

    minima: list[dict[str, Any]] = []
    for run in runs:
        if not run["ok"]:
            continue
        for m in minima:
            if _same(m, run):
                m["starts"].append(run["start"])
                break
        else:
            minima.append({**run, "starts": [run["start"]]})
    minima.sort(key=lambda m: m["cost"])

    common = dict(model=model, cost_kind=problem.cost_kind, problem=problem.describe())
    if not minima:
        best = min(runs, key=lambda r: r["violation"][1])
        name, size = best["violation"]
        active = _active(col, best["w"], p)
        bound_note = (
            f"; at the limit: {', '.join(a for a in active if '<=' in a or 'range' in a)}"
            if any("<=" in a or "range" in a for a in active)
            else ""
        )
        return OptimalGait(
            False,
            f"no gait meets the constraints: IPOPT stopped ({best['stats'].get('return_status')})"
            f" with the constraint '{name}' violated by {size:.3g}{bound_note}; relax it "
            f"(a larger input bound, a shorter step, a longer period)",
            solve_time=time.perf_counter() - t_start,
            iterations=int(best["stats"].get("iter_count", 0)),
            **common,
        )

    # Refine the best minimum's mesh until cost and orbit settle.
    best = minima[0]
    w, stats = best["w"], best["stats"]
    structure_note = ""
    if problem.cost_kind in ("work", "cot"):
        # Second stage: the exact switching-time transcription with the arcs of the slack
        # solution (its quadrature of max(0, uω) is first order across the switches).
        structure = detect_structure(col, w, p)
        exact = Collocation(
            problem,
            RadauMesh(sum(a.intervals for a in structure[0]), col.d),
            structure,
        )
        w_exact, stats_exact = _run(exact, exact.from_solution(col, w, p), p)
        if not _converged(stats_exact):
            return OptimalGait(
                False,
                f"the exact positive-work transcription (arcs {_describe(structure)}) did not "
                f"converge from the slack solution ({stats_exact.get('return_status')}); try "
                f"more starts or other bounds",
                solve_time=time.perf_counter() - t_start,
                **common,
            )
        col, w, stats = exact, w_exact, stats_exact
        structure_note = f"; arcs of the power signs {_describe(structure)}"
    sol = col.unpack(w, p)
    cost_error = orbit_error = float("inf")
    refinements = 0
    while refinements < _MAX_REFINEMENTS:
        fine = _refined(col)
        w_fine, stats_fine = _run(fine, fine.from_solution(col, w, p), p)
        if not _converged(stats_fine):
            break
        sol_fine = fine.unpack(w_fine, p)
        scale = abs(sol_fine["cost"])
        cost_error = abs(sol_fine["cost"] - sol["cost"]) / (scale if scale > 1e-8 else 1.0)
        orbit_error = float(
            max(
                np.max(np.abs(sol_fine["s"] - sol["s"])) / (1 + np.max(np.abs(sol_fine["s"]))),
                abs(sol_fine["period"] - sol["period"]) / sol_fine["period"],
            )
        )
        col, w, stats, sol = fine, w_fine, stats_fine, sol_fine
        refinements += 1
        if max(cost_error, orbit_error) <= tol:
            break
    disc_error = max(cost_error, orbit_error)
    result = _certify(problem, col, w, stats, verify=verify)
    # The final transcription and its solution (the stabilising design differentiates it).
    result.transcription = (col, w)  # type: ignore[attr-defined]
    result.discretisation_error = disc_error if np.isfinite(disc_error) else None
    result.discretisation = {
        "intervals": col.N,
        "degree": col.d,
        "cost_error": cost_error if np.isfinite(cost_error) else None,
        "orbit_error": orbit_error if np.isfinite(orbit_error) else None,
    }
    result.message += structure_note
    if result.success and not disc_error <= tol:
        # Never a gait known less well than promised: the refinement did not reach ``tol``.
        result.success, result.stable = False, None
        result.message = (
            f"no certified optimum: the discretisation error {disc_error:.2g} (cost and orbit "
            f"under mesh refinement) stays above the target {tol:g} after {refinements} "
            f"refinements; the optimum is known only to about that (cost {sol['cost']:.10g}). "
            f"Loosen `tol` to accept it, or bound the inputs so the optimum is smoother. "
            + result.message
        )
    fixed_names = model.state_names
    result.minima = []
    for m in minima:
        x = model.lift(m["s"])
        result.minima.append(
            Minimum(
                m["cost"],
                m["period"],
                dict(zip(fixed_names, map(float, x), strict=True)),
                m["starts"],
                verified=(m is best and result.verified),
            )
        )
    if len(runs) > 1:
        result.message += (
            f"; {len(minima)} distinct local minim{'um' if len(minima) == 1 else 'a'} from "
            f"{len(runs)} starts ({sum(not r['ok'] for r in runs)} did not converge)"
        )
    result.solve_time = time.perf_counter() - t_start
    return result


def _refined(col: Collocation) -> Collocation:
    """The same transcription with every mesh interval halved (each arc's too)."""
    if col.structure is None:
        return Collocation(col.problem, col.mesh.refined())
    structure = [
        [Arc(2 * a.intervals, a.signs, a.fraction) for a in arcs] for arcs in col.structure
    ]
    return Collocation(col.problem, col.mesh.refined(), structure)


def _describe(structure: list[list[Arc]]) -> str:
    """``+ − +`` per phase (per input, joined by ``/``)."""
    phases = []
    for arcs in structure:
        phases.append(" ".join("/".join("+" if s > 0 else "-" for s in a.signs) for a in arcs))
    return "; ".join(f"[{p}]" for p in phases)


def detect_structure(
    col: Collocation, w: np.ndarray, p: np.ndarray, intervals: int = _ARC_INTERVALS
) -> list[list[Arc]]:
    """Arcs of a slack solution: maximal runs of nodes on which every input keeps its class,
    the switch put halfway between the last node of a run and the first of the next.

    An input's class at a node is its bound (lower, upper, neither) with its power sign
    (``+``: ``uω > δ``, ``−``: ``uω < −δ``), or for a power within ``δ`` (10⁻⁶ of the largest)
    whether the input vanishes (``u ≈ 0``, a coasting arc) or the rate does (``ω ≈ 0``, a
    held joint): the input may jump wherever the class changes.  An arc's sign is ``+`` if its
    power is positive, else ``−`` (power ≤ 0, not counted).

    Returns, per phase of the orbit, its arcs with ``intervals`` mesh intervals each (a phase
    with fewer arcs than another gives its longest arcs the spare intervals, so that every
    phase has the same count)."""
    sol = col.unpack(w, p)
    problem, model = col.problem, col.model
    low, high = problem.input_bounds()
    per_phase = []
    for k, i in enumerate(col.chain):
        X, U = sol["X"][k][:, 1:], sol["U"][k]
        rates = np.asarray(model.input_rates(i).map(X.shape[1])(X, sol["p"]), dtype=float)
        power = U * rates
        scale = 1e-6 * (np.max(np.abs(power), axis=1, keepdims=True) + 1e-12)
        u_scale = 1e-6 * (np.max(np.abs(U), axis=1, keepdims=True) + 1e-12)
        # Power class: +1 positive, -1 negative, 0 input ≈ 0, 2 rate ≈ 0 (input held).
        kind = np.where(
            power > scale, 1, np.where(power < -scale, -1, np.where(np.abs(U) <= u_scale, 0, 2))
        )
        span = np.where(np.isfinite(high), high - low, 1.0)[:, None]
        bound = np.where(
            U <= low[:, None] + 1e-4 * span, -1, np.where(U >= high[:, None] - 1e-4 * span, 1, 0)
        )
        classes = [tuple(kind[:, c]) + tuple(bound[:, c]) for c in range(U.shape[1])]
        n_u = U.shape[0]

        def signs(cls: tuple[int, ...], n_u: int = n_u) -> tuple[int, ...]:
            return tuple(1 if v == 1 else -1 for v in cls[:n_u])

        times = col.node_times(sol["breaks"][k])[1:]
        arcs, start = [], 0.0
        current = classes[0]
        for c in range(1, len(classes)):
            if classes[c] != current:
                switch = 0.5 * (times[c - 1] + times[c])
                arcs.append((switch - start, signs(current)))
                start, current = switch, classes[c]
        arcs.append((1.0 - start, signs(current)))
        per_phase.append(_merge_blips(arcs, 1.0 / col.N))
    most = max(len(a) for a in per_phase)
    total = intervals * most
    structure = []
    for arcs in per_phase:
        counts = [intervals] * len(arcs)
        order = np.argsort([-f for f, _ in arcs])
        for extra in range(total - sum(counts)):
            counts[int(order[extra % len(arcs)])] += 1
        structure.append(
            [Arc(n, signs, max(f, 1e-3)) for n, (f, signs) in zip(counts, arcs, strict=True)]
        )
    return structure


def _merge_blips(
    arcs: list[tuple[float, tuple[int, ...]]], shortest: float
) -> list[tuple[float, tuple[int, ...]]]:
    """Arcs without blips: an arc shorter than ``shortest`` (a fraction of the phase) between
    two arcs of the same signs, or next to an arc of its own signs, is merged with them — a
    node or two where the input passes between classes at a switch, or noise where the cost is
    flat (a coasting arc), not a switch of the optimum's own; then neighbours of the same signs
    are joined (the transcription treats them alike, so a switch between them would be a free
    variable the cost does not fix)."""
    arcs = list(arcs)
    changed = True
    while changed and len(arcs) >= 2:
        changed = False
        for j, (f, signs) in enumerate(arcs):
            if f >= shortest:
                continue
            before = arcs[j - 1][1] if j > 0 else None
            after = arcs[j + 1][1] if j + 1 < len(arcs) else None
            if before is not None and before == after:
                lo, hi, signs = j - 1, j + 1, before
            else:
                lo = j - 1 if before == signs else j
                hi = j + 1 if after == signs else j
            if lo == hi:
                continue
            arcs[lo : hi + 1] = [(sum(a[0] for a in arcs[lo : hi + 1]), signs)]
            changed = True
            break
    joined: list[tuple[float, tuple[int, ...]]] = []
    for f, signs in arcs:
        if joined and joined[-1][1] == signs:
            joined[-1] = (joined[-1][0] + f, signs)
        else:
            joined.append((f, signs))
    return joined


def _certify(
    problem: GaitProblem, col: Collocation, w: np.ndarray, stats: dict[str, Any], verify: bool
) -> OptimalGait:
    """Checks and the result object of a converged solution ``w``."""
    model = problem.model
    p = model.p
    sol = col.unpack(w, p)
    free_values = dict(zip(problem.free, map(float, sol["free"]), strict=True))
    gait_model = model.replace(**free_values) if free_values else model
    x_star = gait_model.lift(sol["s"])
    profs = profiles(col, sol)
    period = sol["period"]
    step_length = sol["distance"] / problem.steps if problem.footholds() else None
    t_grid, u_grid, orbit = [], [], []
    t0 = 0.0
    dense = np.linspace(0.0, 1.0, col.N * 8 + 1)
    for k, i in enumerate(col.chain):
        X, U = col.evaluate(sol["X"][k], sol["U"][k], dense, sol["breaks"][k])
        t = t0 + dense * sol["T"][k]
        arc = OrbitArc(
            i, model.phases[i].name, model.phases[i].states, t, X,
            model.phases[i].transitions[0].name,
        )  # fmt: skip
        arc.u = U  # type: ignore[attr-defined]
        orbit.append(arc)
        t_grid.append(t if k == 0 else t[1:])
        u_grid.append(U if k == 0 else U[:, 1:])
        t0 += sol["T"][k]
    t_all = np.concatenate(t_grid)
    u_all = np.hstack(u_grid)
    inputs = {"time": t_all.tolist(), **{n: u_all[j].tolist() for j, n in enumerate(model.inputs)}}
    result = OptimalGait(
        False,
        "",
        gait_model,
        problem.cost_kind,
        cost=sol["cost"],
        period=period,
        step_length=step_length,
        speed=(sol["distance"] / period) if step_length is not None else None,
        fixed_point=dict(zip(model.state_names, map(float, x_star), strict=True)),
        inputs=inputs,
        profiles=profs,
        durations=sol["T"],
        active_constraints=_active(col, w, p),
        params=gait_model.params,
        iterations=int(stats.get("iter_count", 0)),
        problem=problem.describe(),
        orbit=orbit,
    )
    problem_msg = check_dense(col, sol)
    if problem_msg is None and problem.cost_kind in ("work", "cot") and col.structure is None:
        B = col.blocks
        overlap = max(
            float(np.max(np.minimum(B.get(w, f"Pplus{k}"), B.get(w, f"Pminus{k}"))))
            for k in range(len(col.chain))
        )
        if overlap > 1e-6:
            problem_msg = f"the power split is not complementary (p⁺p⁻ overlap {overlap:.2g} W)"
    if problem_msg is not None:
        result.message = "not a gait: " + problem_msg
        return result
    if not verify:
        result.success = True
        result.message = "optimal gait found (not verified: verify=False)"
        return result

    sim = simulate_gait(problem, gait_model, x_star, profs, problem.steps)
    if not sim.success or len(sim.arcs) != len(col.chain):
        result.message = (
            "the optimum is not confirmed by simulation: "
            + (sim.message if not sim.success else f"{len(sim.arcs)} phases instead of "
               f"{len(col.chain)}")
        )  # fmt: skip
        return result
    error = float(np.max(np.abs(sim.section_states[-1] - x_star)))
    sim_cost = simulated_cost(problem, gait_model, sim, profs)
    cost_error = abs(sim_cost - sol["cost"]) / max(abs(sol["cost"]), 1e-300)
    cost_ok = abs(sim_cost - sol["cost"]) <= 1e-6 * abs(sol["cost"]) + 1e-12
    state_ok = error <= 1e-6 * (1 + float(np.max(np.abs(x_star))))
    result.verification = {
        "return_error": error,
        "cost_simulated": sim_cost,
        "cost_error": cost_error if sol["cost"] != 0 else abs(sim_cost),
        "period_simulated": float(sim.section_times[-1]),
    }
    result.verified = bool(state_ok and cost_ok)

    A = return_map_jacobian(col, w, p)
    result.multipliers = multipliers_of(A)
    A_fd = map_jacobian_fd(problem, gait_model, sol["s"], profs)
    if A_fd is not None:
        result.multipliers_fd = multipliers_of(A_fd)
    result.stable = is_stable(result.multipliers)
    if not result.verified:
        result.message = (
            f"the optimum is not confirmed by simulation: it returns {error:.3g} away and costs "
            f"{sim_cost:.10g} against {sol['cost']:.10g}"
        )
        return result
    result.success = True
    result.message = (
        f"optimal gait found (IPOPT {stats.get('return_status')}, {result.iterations} "
        f"iterations); verified by simulation: return error {error:.2g}, cost "
        f"{sim_cost:.10g} simulated"
    )
    return result
