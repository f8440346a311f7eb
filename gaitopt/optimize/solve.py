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

import numpy as np

from ..arguments import check_count, check_positive
from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..threads import single_blas_thread
from ..workers import Map, check_workers, worker_map
from .active import _active
from .attempt import (
    _collocation,
    _converged,  # noqa: F401 (read by tests as solve._converged)
    _run,  # noqa: F401 (read by tests as solve._run)
    attempt,
)
from .collocation import RadauMesh
from .finish import finish
from .guess import check_warm_start
from .mesh import refined as _refined  # noqa: F401 (the name tests read)
from .problem import _WHY_STEPS, MAX_STEPS, GaitProblem, as_problem
from .result import Minimum, OptimalGait, StartRecord
from .spectral_bound import with_roughness_budget
from .starts import mapped_starts

__all__ = [
    "optimize_gait",
    "solve_problem",
    "DEFAULT_MESH",
    "MAX_STEPS",
    "MAX_STARTS",
    "MAX_SEED",
    "MAX_MESH_INTERVALS",
    "MAX_MESH_DEGREE",
]

DEFAULT_MESH = RadauMesh(6, 6)

# -- limits of the counts, checked before any work (`gaitopt optimize` states the same) -------
#: Most starts of one multi-start (``starts``, ``--starts``): each is a solve of 1–3 s on the
#: five-link biped, and each distinct minimum it finds is refined and simulated.
MAX_STARTS = 256
#: Largest seed (``seed``, ``--seed``): seeds are non-negative 64-bit integers.
MAX_SEED = 2**63 - 1
#: Most intervals per phase of an initial ``mesh`` (refined up to three times by doubling:
#: at most 192); the default is 6.
MAX_MESH_INTERVALS = 24
#: Highest Radau degree of a ``mesh`` (the default is 6; beyond about 10 the collocation's
#: Lagrange bases lose accuracy in double precision).
MAX_MESH_DEGREE = 10


@single_blas_thread
def optimize_gait(
    model: HybridModel,
    cost: str | Callable[..., Any] = "effort",
    *,
    period: float | None = None,
    step_length: float | None = None,
    speed: float | None = None,
    bounds: dict[str, float] | None = None,
    state_bounds: dict[str, tuple[float, float]] | None = None,
    path_constraints: tuple[str, ...] | str = (),
    free: tuple[str, ...] | str = (),
    steps: int = 1,
    starts: int | Sequence[int] = 1,
    seed: int = 0,
    mesh: RadauMesh | None = None,
    tol: float = 1e-8,
    verify: bool = True,
    guess: OptimalGait | None = None,
    workers: int | Map = 1,
    scheduler: str | None = None,
    max_multiplier: float | None = None,
    max_roughness: float | None = None,
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
        ``{input: max}``: ``|u| ≤ max``, or ``{input: (low, high)}`` (input units).
    state_bounds : dict, optional
        ``{state: (low, high)}``, ``low < high`` (one side may be infinite): joint and rate
        limits, at every collocation node of every phase with that state, checked on dense
        samples of the optimum (``c ≥ −1e-9 (1 + max|c|)``); a state in ``bounds`` is an error.
    path_constraints : tuple of str, optional
        Limits the model declares (``Phase.limits``), imposed at every collocation node and
        checked on dense samples like ``state_bounds``: ``("knee_flexion",)`` keeps the
        five-link biped's or the kneed walker's knees from hyperextending.  Default: none.
    free : tuple of str
        Parameters to optimise too, within their declared ranges.
    steps : int
        Returns to the section per orbit, 1 to :data:`MAX_STEPS` (4: the transcription grows
        faster than the number of steps; the five-link biped takes 9 GB at 4).
    starts : int or sequence of int
        Number of seeded starts, 1 to :data:`MAX_STARTS` (256) (start 0 from the model's
        default start, start ``j`` perturbed with ``numpy.random.default_rng([seed, j])``), or
        the distinct indices (0 to :data:`MAX_SEED`) of at most 256 starts to run (to re-run a
        given start alone); every distinct local minimum is reported in ``minima`` with the
        starts that reached it, and every start's outcome in ``starts``: a start that cannot
        begin (its perturbed section point is not a state of the model) or does not converge
        is recorded with its reason, and the search goes on.
    seed : int
        Seed of the multi-start, 0 to :data:`MAX_SEED` (2⁶³ − 1).
    mesh : RadauMesh, optional
        Initial mesh (default: 6 intervals of degree 6 per phase; at most
        :data:`MAX_MESH_INTERVALS` (24) intervals and degree :data:`MAX_MESH_DEGREE` (10)),
        refined by doubling the intervals (at most three times) until the discretisation error
        is below ``tol``.
    tol : float
        Target of the relative discretisation error of the cost and the orbit: a positive
        finite number (a target below IPOPT's 1e-11 is never met, and the result says so).
    verify : bool
        Re-simulate the optimum and compute the multipliers (always, unless False for speed).
    guess : OptimalGait, optional
        A previous optimum to warm start from (a library of gaits): a result with an orbit of
        the same model and steps (a certified optimum, or a converged one its checks rejected).
    workers : int or callable
        What runs the starts (:func:`gaitopt.workers.worker_map`): ``1`` (default) serially in
        this process, ``n`` a pool of ``n`` processes (``-1``: one per CPU), or a map-like
        ``workers(func, iterable)``; other than 1, each start is sent as plain data
        (:func:`gaitopt.optimize.starts.mapped_starts`).  The minima and the refined optimum
        are those of the serial run.
    scheduler : str, optional
        Run the starts on Dask instead (``"local"``: a local cluster; or a scheduler address):
        an adapter onto a Dask-backed map (:func:`gaitopt.sweep.dask_map`).
    max_multiplier : float, optional
        Bound ``R > 0`` on the spectral radius of the return map's Jacobian ``A`` (section
        coordinates, the input a feedforward in the time since the section), imposed inside the
        NLP: ``A`` from the variational equations collocated alongside the orbit (the same
        Radau scheme, so exactly the implicit-function-theorem Jacobian of
        :mod:`gaitopt.optimize.floquet`) with the saltation and reset Jacobians at every phase
        end, and ``ρ(A) ≤ R`` as the ``m + 1`` Schur–Cohn–Jury conditions (bilinear
        Liénard–Chipart form) on the characteristic polynomial of ``A/R``, smooth in ``A``
        (:mod:`gaitopt.optimize.spectral`, :mod:`gaitopt.optimize.schur`).  ``R < 1`` asks
        for an open-loop stable optimum.  An inactive bound leaves the optimum unchanged; an
        active one is listed in ``active_constraints`` as ``spectral radius <= R``.  The
        certificate checks the AD multipliers (to 1e-8) and those by extrapolated finite
        differences of the simulated map (to 1e-5) against ``R``
        (:mod:`gaitopt.optimize.spectral_certify`).  Sections of at most 4 coordinates; least effort
        or a callable cost (not ``"work"``/``"cot"``).  Default: no bound.
    max_roughness : float, optional
        With ``max_multiplier``: bound on ``∫ Σᵣ u̇ᵣ² dt`` over the orbit ((input unit)²/s;
        N²·m²/s for torques), the inputs also continuous between mesh intervals.  The Jacobian
        depends on the input at each impact instant, which the effort does not charge, so
        without it the bound is met by a torque spike at impact whose width shrinks with the
        mesh, and no optimum exists (:mod:`gaitopt.optimize.spectral_bound`).  Default: twice
        the roughness of the optimum without the bound, which is solved first and warm starts
        the bounded one.

    Returns
    -------
    OptimalGait

    Raises
    ------
    GaitoptInputError
        Bad input, before any work: a count above its limit (``steps``, ``starts``, ``seed``,
        ``mesh``), a ``tol`` that is not a positive number, a statement with no optimum (level
        ground with nothing fixed: the least effort is standing still; positive work without
        input bounds), a ``max_multiplier`` that is not a positive finite number or cannot
        apply (a section of more than 4 coordinates, a work cost), a ``guess`` that cannot warm
        start
        (:class:`~gaitopt.optimize.guess.WarmStartError`).
    """
    _check_counts(steps=steps, starts=starts, seed=seed, mesh=mesh, tol=tol, verify=verify)
    check_workers(workers, scheduler)
    problem = as_problem(
        model,
        cost=cost,
        period=period,
        step_length=step_length,
        speed=speed,
        bounds=bounds,
        state_bounds=state_bounds,
        path_constraints=path_constraints,
        free=free,
        steps=steps,
        max_multiplier=max_multiplier,
        max_roughness=max_roughness,
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
        workers=workers,
        scheduler=scheduler,
    )


_WHY_STARTS = (
    "each start is a full solve (1-3 s on the five-link biped) and each minimum it finds is "
    f"refined and simulated; use starts <= {MAX_STARTS} (gaitopt.optimize.solve.MAX_STARTS), or "
    "several searches with other seeds"
)
_WHY_SEED = "seeds are non-negative 64-bit integers; e.g. seed=0"


def _check_counts(*, steps: Any, starts: Any, seed: Any, mesh: Any, tol: Any, verify: Any) -> None:
    """Every count and tolerance of :func:`optimize_gait` against its limit, before any work
    (:func:`gaitopt.arguments.check_count`, as :func:`gaitopt.find_limit_cycle` does)."""
    check_count("steps", steps, 1, MAX_STEPS, _WHY_STEPS)
    _start_indices(starts)
    check_count("seed", seed, 0, MAX_SEED, _WHY_SEED)
    if mesh is not None:
        if not isinstance(mesh, RadauMesh):
            raise GaitoptInputError(
                f"`mesh` must be a RadauMesh or None, got {mesh!r}; e.g. mesh=RadauMesh(6, 6)"
            )
        check_count("mesh.intervals", mesh.intervals, 1, MAX_MESH_INTERVALS,
                    f"the mesh is refined by doubling up to three times; start at most at "
                    f"{MAX_MESH_INTERVALS} intervals, e.g. mesh=RadauMesh(12, 6)")  # fmt: skip
        check_count("mesh.degree", mesh.degree, 1, MAX_MESH_DEGREE,
                    "high-degree Lagrange bases lose accuracy; use more intervals instead, "
                    "e.g. mesh=RadauMesh(12, 6)")  # fmt: skip
    check_positive("tol", tol, "1e-8")
    if not isinstance(verify, (bool, np.bool_)):
        raise GaitoptInputError(f"`verify` must be True or False, got {verify!r}")


def _start_indices(starts: int | Sequence[int]) -> list[int]:
    """``starts`` as a list of start indices (an int ``N`` means ``0 … N − 1``), at most
    :data:`MAX_STARTS` of them."""
    why = _WHY_STARTS
    if isinstance(starts, (int, np.integer)) and not isinstance(starts, bool):
        return list(range(check_count("starts", starts, 1, MAX_STARTS, why)))
    try:
        indices = [int(i) for i in starts]  # type: ignore[union-attr]
        exact = all(int(i) == i for i in starts)  # type: ignore[union-attr]
    except (TypeError, ValueError, OverflowError):
        indices, exact = [], False
    if (
        not exact
        or not indices
        or any(i < 0 or i > MAX_SEED for i in indices)
        or len(set(indices)) != len(indices)
    ):
        raise GaitoptInputError(
            f"`starts` must be a positive integer or distinct start indices from 0 to "
            f"{MAX_SEED}, got {starts!r:.200}; e.g. starts=4 or starts=[0, 3]"
        )
    if len(indices) > MAX_STARTS:
        raise GaitoptInputError(
            f"`starts` lists {len(indices)} start indices, above the limit {MAX_STARTS}: {why}"
        )
    return indices


def _same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    cost_close = abs(a["cost"] - b["cost"]) <= 1e-6 * max(abs(a["cost"]), abs(b["cost"])) + 1e-9
    s_close = np.max(np.abs(a["s"] - b["s"])) <= 1e-4 * (1 + np.max(np.abs(a["s"])))
    return bool(cost_close and s_close)


def _start_records(runs: list[dict[str, Any]], minima: list[dict[str, Any]]) -> list[StartRecord]:
    """Every start's outcome, in start order (the minimum it reached, by index)."""
    where = {start: k for k, m in enumerate(minima) for start in m["starts"]}
    records = []
    for run in runs:
        status = run.get("status") or ("converged" if run["ok"] else "not_converged")
        records.append(
            StartRecord(
                int(run["start"]),
                status,
                run.get("reason", ""),
                float(run["cost"]) if run["ok"] else None,
                where.get(run["start"]),
                int(run["stats"].get("iter_count", 0)),
            )
        )
    return records


def solve_problem(
    problem: GaitProblem,
    *,
    starts: int | Sequence[int] = 1,
    seed: int = 0,
    mesh: RadauMesh | None = None,
    tol: float = 1e-8,
    verify: bool = True,
    guess: OptimalGait | None = None,
    workers: int | Map = 1,
    scheduler: str | None = None,
) -> OptimalGait:
    """Solve a :class:`GaitProblem` (see :func:`optimize_gait`: the same arguments, the same
    limits, checked before any work)."""
    t_start = time.perf_counter()
    if not isinstance(problem, GaitProblem):
        raise GaitoptInputError(
            f"`problem` must be a GaitProblem, got {type(problem).__name__}; e.g. "
            f"GaitProblem(gaitopt.model('compass_gait', slope=0), period=0.8, step_length=0.3)"
        )
    _check_counts(steps=problem.steps, starts=starts, seed=seed, mesh=mesh, tol=tol,
                  verify=verify)  # fmt: skip
    check_workers(workers, scheduler)
    elsewhere = scheduler is not None or workers != 1
    if elsewhere and problem.path_constraints:  # workers rebuild without them
        which = "`scheduler`" if scheduler is not None else "`workers`"
        raise GaitoptInputError(
            f"{which} does not carry `path_constraints` "
            f"({', '.join(problem.path_constraints)}) to its workers yet; run the starts "
            f"serially (workers=1, scheduler=None)"
        )
    check_warm_start(problem, guess)
    longest = problem.model.max_step_length()
    if problem.step_length is not None and longest is not None and problem.step_length > longest:
        unit = problem.model.length_unit
        return OptimalGait(
            False,
            f"no gait: a step length of {problem.step_length:g} {unit} is longer than the legs "
            f"can span ({longest:g} {unit}, {problem.model.name}.max_step_length()); fix a step "
            f"length below it",
            status="not_a_gait",
            model=problem.model,
            cost_kind=problem.cost_kind,
            problem=problem.describe(),
        )
    # ρ(A) ≤ R needs a roughness budget: by default from the optimum without the bound.
    problem, unbounded, failure = with_roughness_budget(
        problem,
        lambda q: solve_problem(q, starts=starts, seed=seed, mesh=mesh, tol=tol, verify=verify,
                                guess=guess, workers=workers, scheduler=scheduler),
    )  # fmt: skip
    if failure is not None:
        return failure
    guess = guess if guess is not None else unbounded
    model = problem.model
    p = model.p
    mesh = mesh or DEFAULT_MESH
    indices = _start_indices(starts)
    seed = int(seed)
    col = _collocation(problem, mesh)
    if elsewhere:  # the same attempts, by the workers' map
        with worker_map(workers, scheduler) as run:
            runs = mapped_starts(problem, mesh, indices, seed, run, guess)
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
    records = _start_records(runs, minima)
    not_begun = [r for r in runs if r.get("status") == "no_start"]
    tally = (
        f" ({len(not_begun)} of {len(runs)} starts could not begin: "
        f"{', '.join(str(r['start']) for r in not_begun)})"
        if not_begun
        else ""
    )
    if not minima:
        solved = [r for r in runs if r.get("status") != "no_start"]
        if not solved:
            return OptimalGait(
                False,
                f"no start could begin: {'; '.join(r['reason'] for r in runs)}; try other starts "
                f"(another seed) or parameters where the model's default start is a state",
                status="no_start",
                solve_time=time.perf_counter() - t_start,
                starts=records,
                **common,
            )
        best = min(solved, key=lambda r: r["violation"][1])
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
            f"(a larger input bound, a shorter step, a longer period){tally}",
            status="not_converged",
            solve_time=time.perf_counter() - t_start,
            iterations=int(best["stats"].get("iter_count", 0)),
            starts=records,
            **common,
        )

    # Every distinct minimum is refined and certified (a reported minimum is a gait); the
    # result is the lowest certified one.
    results = [
        finish(problem, col, m["w"], m["stats"], tol, verify, guess, common, t_start)
        for m in minima
    ]
    chosen = next((j for j, r in enumerate(results) if r.success), 0)
    result = results[chosen]
    if chosen > 0:
        result.message += (
            f"; the lower minimum {minima[0]['cost']:.10g} (starts {minima[0]['starts']}) is "
            f"not certified: {results[0].message}"
        )
    result.minima = [_minimum(model, m, r) for m, r in zip(minima, results, strict=True)]
    result.starts = records
    if len(runs) > 1:
        certified = sum(r.success for r in results)
        unsolved = sum(r.get("status") == "not_converged" for r in runs)
        begun = f"{len(not_begun)} could not begin, " if not_begun else ""
        result.message += (
            f"; {len(minima)} distinct local minim{'um' if len(minima) == 1 else 'a'} from "
            f"{len(runs)} starts ({begun}{unsolved} did not converge; {certified} certified)"
        )
    result.solve_time = time.perf_counter() - t_start
    return result


def _minimum(model: HybridModel, m: dict[str, Any], r: OptimalGait) -> Minimum:
    """One multi-start minimum: refined values where its refinement succeeded, the starts'
    otherwise; ``verified`` only if the simulation confirmed it too."""
    if r.success:
        return Minimum(r.cost, r.period, dict(r.fixed_point), m["starts"], bool(r.verified),
                       r.discretisation_error, r.message)  # fmt: skip
    x = model.lift(m["s"])
    fixed_point = dict(zip(model.state_names, map(float, x), strict=True))
    return Minimum(m["cost"], m["period"], fixed_point, m["starts"], False, None, r.message)
