"""Gait libraries: an optimum continued in a constraint, with its folds and active-set changes.

:func:`gait_library` solves :func:`gaitopt.optimize_gait` at a sequence of values of one
quantity — the period, step length or speed a gait is held to, or a model parameter such as the
slope — each point warm started from its neighbour's optimum (natural-parameter continuation of
the optimum).  Between neighbours it compares:

* the **active sets** (:attr:`OptimalGait.active_constraints`: the input and state bounds and
  inequality constraints within 1e-6 of their limits); where they differ, the value at which the
  set changes is located by bisection (warm started from the side already known);
* the **reduced Hessian** of the Lagrangian on the active constraints' null space (second-order
  sufficient condition, Nocedal & Wright 2006, Thm 12.6): its smallest eigenvalue, relative to the
  largest, is positive at a strict local minimum and falls to zero where the KKT matrix becomes
  singular — a fold, where the minimum meets a saddle and the library cannot continue.  A
  sign change between neighbours, or a warm start that stops converging after a point whose
  reduced Hessian is near singular, is reported as a fold; a warm start that stops converging
  otherwise ends the library (``end``, with the solver's reason); either boundary is located by
  bisection.

The library is checked against cold starts (the model's default start, no warm start) at a few
points: the same optimal cost to ``1e-8`` relative, else the library has followed another local
minimum and says so.  The cold starts, and the starts of a multi-start
(:func:`dask_starts`, ``optimize_gait(..., scheduler=...)``), can run on Dask through
:func:`gaitopt.sweep.sweep`: each worker rebuilds the problem from plain data (registered model
and parameters) and returns plain data.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError, did_you_mean
from ..files import jsonable
from ..hybrid import HybridModel
from .collocation import Collocation, RadauMesh
from .problem import GaitProblem
from .result import OptimalGait

__all__ = [
    "gait_library",
    "GaitLibrary",
    "LibraryPoint",
    "LibraryEvent",
    "ColdCheck",
    "reduced_hessian",
    "dask_starts",
    "CONSTRAINTS",
]

#: Gait constraints a library can be continued in (besides any model parameter).
CONSTRAINTS = ("period", "step_length", "speed")
_COLD_RTOL = 1e-8  # library against cold starts: relative cost difference
_FOLD_RATIO = 1e-3  # λmin/λmax of the reduced Hessian fallen below this × its start: singular
_ACTIVE_TOL = 1e-7  # a constraint or bound within this (relative) of its limit is active


# -- second-order information -------------------------------------------------------------------
def reduced_hessian(col: Collocation, w: np.ndarray, p: np.ndarray) -> tuple[float, float]:
    """Smallest and largest eigenvalue of the reduced Hessian of the Lagrangian at ``w``.

    The active set: the equality constraints, the inequalities within 1e-7 (relative) of a
    limit and the variables at a bound.  Multipliers by least squares on the stationarity
    condition ``∇f + J_Aᵀ λ = 0`` (over the free variables); ``Z`` an orthonormal basis of the
    null space of the active Jacobian (SVD), so the eigenvalues of ``Zᵀ ∇²L Z`` do not depend on
    the basis chosen.

    Returns
    -------
    (float, float)
        ``(λ_min, λ_max)`` (cost units per decision-variable unit squared); ``(nan, nan)`` if
        the active constraints leave no freedom.
    """
    from .solve import _solver

    w = np.asarray(w, dtype=float).ravel()
    solver = _solver(col)  # IPOPT's own derivative functions (cached with the last solve)
    ng = col.lbg.size
    g, J = (np.asarray(v, dtype=float) for v in solver.get_function("nlp_jac_g")(w, p))
    grad = np.asarray(solver.get_function("nlp_grad_f")(w, p)[1], dtype=float)
    hess = solver.get_function("nlp_hess_l")
    g, grad = g.ravel(), grad.ravel()
    scale = 1 + np.abs(g)
    active = (col.lbg == col.ubg) | (np.abs(g - col.lbg) <= _ACTIVE_TOL * scale)
    active |= np.abs(g - col.ubg) <= _ACTIVE_TOL * scale
    at_bound = (np.abs(w - col.lbx) <= _ACTIVE_TOL * (1 + np.abs(w))) | (
        np.abs(w - col.ubx) <= _ACTIVE_TOL * (1 + np.abs(w))
    )
    free = ~at_bound
    JA = J[active][:, free]
    lam_a = np.linalg.lstsq(JA.T, -grad[free], rcond=None)[0]
    lam_full = np.zeros(ng)
    lam_full[active] = lam_a
    upper = np.asarray(hess(w, p, 1.0, lam_full), dtype=float)
    H = (upper + upper.T - np.diag(np.diag(upper)))[np.ix_(free, free)]
    _, sigma, Vt = np.linalg.svd(JA, full_matrices=True)
    rank = int(np.sum(sigma > 1e-10 * (sigma[0] if sigma.size else 1.0)))
    Z = Vt[rank:].T
    if Z.shape[1] == 0:
        return float("nan"), float("nan")
    eig = np.linalg.eigvalsh(0.5 * (Z.T @ H @ Z + (Z.T @ H @ Z).T))
    return float(eig[0]), float(eig[-1])


# -- records ----------------------------------------------------------------------------------
@dataclass
class LibraryPoint:
    """One optimum of the library.

    Attributes
    ----------
    value : float
        The continued quantity's value (its unit: s, m, m/s or the parameter's).
    gait : OptimalGait
        The optimum found there (warm started from the previous successful point).
    warm : bool
        Whether it was warm started.
    time : float
        Wall-clock seconds of its solve.
    hessian : tuple of float
        ``(λ_min, λ_max)`` of the reduced Hessian (:func:`reduced_hessian`).
    """

    value: float
    gait: OptimalGait
    warm: bool
    time: float
    hessian: tuple[float, float] = (float("nan"), float("nan"))

    @property
    def hessian_ratio(self) -> float:
        """``λ_min / λ_max`` of the reduced Hessian (1; > 0 at a strict minimum)."""
        lo, hi = self.hessian
        return lo / hi if np.isfinite(hi) and hi != 0 else float("nan")

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types (the gait's summary, not its profile)."""
        g = self.gait
        return jsonable(
            {
                "value": self.value,
                "success": g.success,
                "message": g.message,
                "cost": g.cost,
                "period": g.period,
                "step_length": g.step_length,
                "speed": g.speed,
                "fixed_point": g.fixed_point,
                "multipliers": [complex(z) for z in g.multipliers],
                "stable": g.stable,
                "verified": g.verified,
                "discretisation_error": g.discretisation_error,
                "active_constraints": g.active_constraints,
                "reduced_hessian": list(self.hessian),
                "reduced_hessian_ratio": self.hessian_ratio,
                "warm": self.warm,
                "time": self.time,
            }
        )


@dataclass
class LibraryEvent:
    """A change between two neighbouring library points, located by bisection.

    Attributes
    ----------
    kind : str
        ``"active set"``, ``"fold"`` or ``"end"`` (warm starts stop converging, not at a fold).
    value : float
        Located value (midpoint of the final bracket).
    bracket : tuple of float
        The final bracket ``(before, after)``.
    before, after : list of str
        Active constraints on each side (``after`` empty for a fold or an end).
    message : str
        What changed.
    """

    kind: str
    value: float
    bracket: tuple[float, float]
    before: list[str]
    after: list[str]
    message: str

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types."""
        return jsonable(
            {
                "kind": self.kind,
                "value": self.value,
                "bracket": list(self.bracket),
                "before": self.before,
                "after": self.after,
                "message": self.message,
            }
        )


@dataclass
class ColdCheck:
    """The library against a cold start at one of its points.

    Attributes
    ----------
    value : float
    library_cost, cold_cost : float or None
    relative_difference : float or None
    agree : bool
        Both succeeded with costs equal to ``1e-8`` relative.
    time : float
        Wall-clock seconds of the cold solve.
    message : str
    """

    value: float
    library_cost: float | None
    cold_cost: float | None
    relative_difference: float | None
    agree: bool
    time: float
    message: str

    def to_json(self) -> dict[str, Any]:
        """Plain JSON types."""
        return jsonable(self.__dict__)


@dataclass
class GaitLibrary:
    """A library of optimal gaits along one quantity.

    Attributes
    ----------
    success : bool
        Every point was solved and certified, and every cold-start check agrees.
    message : str
    vary : str
        The quantity continued (``period``, ``step_length``, ``speed`` or a parameter).
    points : list of LibraryPoint
    events : list of LibraryEvent
    cold_checks : list of ColdCheck
    solve_time : float
        Wall-clock seconds of the whole library.
    """

    success: bool
    message: str
    vary: str
    points: list[LibraryPoint] = field(default_factory=list)
    events: list[LibraryEvent] = field(default_factory=list)
    cold_checks: list[ColdCheck] = field(default_factory=list)
    solve_time: float = 0.0

    def __bool__(self) -> bool:
        return self.success

    @property
    def values(self) -> np.ndarray:
        """The continued quantity at each point."""
        return np.array([pt.value for pt in self.points])

    @property
    def costs(self) -> np.ndarray:
        """The optimal cost at each point (NaN where none was certified)."""
        return np.array(
            [pt.gait.cost if pt.gait.success else np.nan for pt in self.points], dtype=float
        )

    def to_json(self) -> dict[str, Any]:
        """The ``library`` object of ``gaitopt optimize --library ... --json``."""
        return jsonable(
            {
                "success": self.success,
                "message": self.message,
                "vary": self.vary,
                "points": [pt.to_json() for pt in self.points],
                "events": [e.to_json() for e in self.events],
                "cold_checks": [c.to_json() for c in self.cold_checks],
                "solve_time": self.solve_time,
            }
        )


# -- problems as plain data (for Dask workers) --------------------------------------------------
def _problem_data(problem: GaitProblem) -> dict[str, Any]:
    """The problem as JSON-able data, rebuilt by :func:`_problem_from` in a worker."""
    model = problem.model
    if not isinstance(problem.cost, str):
        raise GaitoptInputError(
            "`scheduler`: a callable cost cannot be sent to Dask workers; use cost='effort', "
            "'work' or 'cot', or run without a scheduler"
        )
    from ..models import model as make_model

    try:
        rebuilt = make_model(model.name, **model.params)
    except GaitoptInputError:
        rebuilt = None
    if rebuilt is None or not np.array_equal(rebuilt.p, model.p):
        raise GaitoptInputError(
            f"`scheduler`: {model.name!r} cannot be rebuilt by name in a Dask worker (not a "
            f"registered model); gaitopt.register it, or run without a scheduler"
        )
    return {
        "model": model.name,
        "params": dict(model.params),
        "cost": problem.cost,
        "period": problem.period,
        "step_length": problem.step_length,
        "speed": problem.speed,
        "bounds": {
            k: (list(v) if isinstance(v, (tuple, list)) else v)
            for k, v in dict(problem.bounds).items()
        },  # fmt: skip
        "state_bounds": {k: list(v) for k, v in dict(problem.state_bounds).items()},
        "free": list(problem.free),
        "steps": problem.steps,
        "max_phase_time": problem.max_phase_time,
        "regularisation": problem.regularisation,
        "min_crossing_rate": problem.min_crossing_rate,
    }


def _problem_from(data: Mapping[str, Any]) -> GaitProblem:
    from ..models import model as make_model

    model = make_model(data["model"], **data["params"])
    return GaitProblem(
        model,
        data["cost"],
        period=data["period"],
        step_length=data["step_length"],
        speed=data["speed"],
        bounds={k: (tuple(v) if isinstance(v, list) else v) for k, v in data["bounds"].items()},
        state_bounds={k: tuple(v) for k, v in data["state_bounds"].items()},
        free=tuple(data["free"]),
        steps=int(data["steps"]),
        max_phase_time=float(data["max_phase_time"]),
        regularisation=float(data["regularisation"]),
        min_crossing_rate=float(data["min_crossing_rate"]),
    )


_WORKER_TRANSCRIPTIONS: dict[str, Collocation] = {}


def start_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Dask task: one start of a multi-start (:func:`gaitopt.optimize.solve.attempt`) on the
    initial mesh; the transcription is built once per worker process and problem."""
    import json

    from .solve import attempt

    key = json.dumps([point["problem"], point["mesh"]], sort_keys=True)
    col = _WORKER_TRANSCRIPTIONS.get(key)
    if col is None:
        _WORKER_TRANSCRIPTIONS.clear()
        col = Collocation(_problem_from(point["problem"]), RadauMesh(*point["mesh"]))
        _WORKER_TRANSCRIPTIONS[key] = col
    entry = attempt(col, col.problem, int(point["start"]), int(point["seed"]), None)
    stats = entry["stats"]
    out = {
        "start": entry["start"],
        "ok": entry["ok"],
        "w": entry["w"].tolist(),
        "stats": {
            "success": bool(stats.get("success")),
            "return_status": str(stats.get("return_status")),
            "iter_count": int(stats.get("iter_count", 0)),
        },
    }
    if entry["ok"]:
        out.update(cost=entry["cost"], s=entry["s"].tolist(), period=entry["period"])
    else:
        out["violation"] = [entry["violation"][0], entry["violation"][1]]
    return out


def dask_starts(
    problem: GaitProblem,
    mesh: RadauMesh,
    indices: Sequence[int],
    seed: int,
    scheduler: str,
    guess: OptimalGait | None = None,
) -> list[dict[str, Any]]:
    """The starts of a multi-start on Dask (:func:`gaitopt.sweep.sweep`), in start order, as
    :func:`gaitopt.optimize.solve.attempt` returns them.

    Parameters
    ----------
    scheduler : str
        ``"serial"``, ``"local"`` (a local cluster of 2 processes) or a scheduler address.
    guess : OptimalGait, optional
        Not supported (a warm start stays in this process): an error.
    """
    from ..sweep import sweep

    if guess is not None:
        raise GaitoptInputError(
            "`scheduler` with `guess`: a warm start is not sent to Dask workers; run it without "
            "a scheduler"
        )
    data = _problem_data(problem)
    points = [
        {"problem": data, "mesh": [mesh.intervals, mesh.degree], "start": int(i), "seed": seed}
        for i in indices
    ]
    result = sweep(start_task, points, scheduler=scheduler, progress=False, description="starts")
    runs = []
    for r in result.results:
        entry = dict(r)
        entry["w"] = np.array([np.nan if v is None else v for v in r["w"]], dtype=float)
        if entry["ok"]:
            entry["s"] = np.asarray(r["s"], dtype=float)
        else:
            entry["violation"] = (r["violation"][0], float(r["violation"][1] or np.inf))
        runs.append(entry)
    return runs


def cold_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Dask task: a cold :func:`solve_problem` of the problem in ``point`` (cost, success,
    message, wall-clock time)."""
    from .solve import solve_problem

    t0 = time.perf_counter()
    gait = solve_problem(_problem_from(point["problem"]), tol=float(point["tol"]))
    return {
        "success": gait.success,
        "cost": gait.cost,
        "message": gait.message,
        "time": time.perf_counter() - t0,
    }


# -- the library ------------------------------------------------------------------------------
def _check_vary(model: HybridModel, vary: str, fixed: Mapping[str, float | None]) -> None:
    if vary in CONSTRAINTS:
        if fixed.get(vary) is not None:
            raise GaitoptInputError(
                f"`vary` {vary!r} is also fixed ({vary}={fixed[vary]!r}); leave {vary} out: the "
                f"library sets it at each point"
            )
        return
    if vary not in model.params:
        choices = (*CONSTRAINTS, *model.params)
        raise GaitoptInputError(
            f"`vary` must be one of {', '.join(CONSTRAINTS)} or a parameter of {model.name}, "
            f"got {vary!r}; {did_you_mean(vary, choices)}e.g. vary='step_length'"
        )


def _values(values: Sequence[float]) -> np.ndarray:
    try:
        v = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        v = np.zeros(0)
    if (
        v.size < 2
        or not np.all(np.isfinite(v))
        or not (np.all(np.diff(v) > 0) or np.all(np.diff(v) < 0))
    ):
        raise GaitoptInputError(
            f"`values` must be at least 2 finite numbers, strictly increasing or decreasing, "
            f"got {values!r}; e.g. numpy.linspace(0.2, 0.5, 7)"
        )
    return v


def gait_library(
    model: HybridModel,
    vary: str,
    values: Sequence[float],
    cost: str = "effort",
    *,
    period: float | None = None,
    step_length: float | None = None,
    speed: float | None = None,
    bounds: Mapping[str, float] | None = None,
    state_bounds: Mapping[str, tuple[float, float]] | None = None,
    free: tuple[str, ...] | str = (),
    steps: int = 1,
    tol: float = 1e-8,
    cold: int | Sequence[float] = 2,
    locate: float = 1e-3,
    scheduler: str | None = None,
) -> GaitLibrary:
    """Continue an optimal gait in a constraint or parameter, warm starting each point.

    Parameters
    ----------
    model : HybridModel
        The actuated model.
    vary : str
        ``"period"`` (s), ``"step_length"`` (m), ``"speed"`` (m/s) or a model parameter (e.g.
        ``"slope"``, rad).
    values : sequence of float
        Its values, in the order continued (strictly monotone).
    cost, period, step_length, speed, bounds, state_bounds, free, steps, tol
        As for :func:`gaitopt.optimize_gait` (the one varied must be left out).
    cold : int or sequence of float
        Cold-start checks: at this many library points spread over it (first and last first;
        default 2), or at these values (each must be a library value); 0 for none.
    locate : float
        Bisection of an event stops when its bracket is below ``locate`` times the spacing of
        the two neighbours (default 1e-3: about 10 solves per event).
    scheduler : str, optional
        Run the cold-start checks on Dask (``"local"`` or an address; :func:`gaitopt.sweep.sweep`).

    Returns
    -------
    GaitLibrary
    """
    from .solve import optimize_gait

    t_start = time.perf_counter()
    fixed = {"period": period, "step_length": step_length, "speed": speed}
    _check_vary(model, vary, fixed)
    grid = _values(values)
    if not (isinstance(locate, (int, float)) and 0 < locate < 1):
        raise GaitoptInputError(f"`locate` must be in (0, 1), got {locate!r}; e.g. 1e-3")
    cold_values = _cold_values(grid, cold)
    options = dict(bounds=bounds, state_bounds=state_bounds, free=free, steps=steps, tol=tol)

    def solve(value: float, guess: OptimalGait | None, verify: bool = True) -> OptimalGait:
        if vary in CONSTRAINTS:
            return optimize_gait(
                model, cost, **{**fixed, vary: value}, guess=guess, verify=verify, **options
            )
        return optimize_gait(
            model.replace(**{vary: value}), cost, **fixed, guess=guess, verify=verify, **options
        )

    library = GaitLibrary(False, "", vary)
    last: LibraryPoint | None = None
    for value in grid:
        t0 = time.perf_counter()
        gait = solve(float(value), last.gait if last is not None else None)
        point = LibraryPoint(float(value), gait, last is not None, time.perf_counter() - t0)
        if gait.success and getattr(gait, "transcription", None) is not None:
            col, w = gait.transcription
            point.hessian = reduced_hessian(col, w, col.model.p)
        library.points.append(point)
        event = None
        if last is not None:
            event = _compare(last, point, solve, locate, library.points[0].hessian_ratio)
            if event is not None:
                library.events.append(event)
        if gait.success:
            last = point
        elif event is not None and event.kind in ("fold", "end"):
            break  # past a fold or the end of the branch: nothing to warm start from
    library.cold_checks = _cold_checks(library, cold_values, model, vary, fixed, cost, options,
                                       scheduler)  # fmt: skip
    failed = [pt.value for pt in library.points if not pt.gait.success]
    disagree = [c.value for c in library.cold_checks if not c.agree]
    library.success = not failed and not disagree and len(library.points) == grid.size
    parts = [
        f"{sum(pt.gait.success for pt in library.points)} of {grid.size} optima in {vary} certified"
    ]
    if failed:
        parts.append(f"no certified optimum at {vary} = {', '.join(f'{v:g}' for v in failed)}")
    for e in library.events:
        parts.append(e.message)
    if library.cold_checks:
        parts.append(
            f"cold starts agree at {sum(c.agree for c in library.cold_checks)} of "
            f"{len(library.cold_checks)} points"
            + (f" (not at {', '.join(f'{v:g}' for v in disagree)})" if disagree else "")
        )
    library.message = "; ".join(parts)
    library.solve_time = time.perf_counter() - t_start
    return library


def _cold_values(grid: np.ndarray, cold: int | Sequence[float]) -> list[float]:
    if isinstance(cold, (int, np.integer)) and not isinstance(cold, bool):
        if cold < 0:
            raise GaitoptInputError(f"`cold` must be >= 0, got {cold!r}; e.g. cold=2")
        if cold == 0:
            return []
        idx = np.unique(np.round(np.linspace(0, grid.size - 1, min(cold, grid.size))).astype(int))
        return [float(grid[i]) for i in idx]
    try:
        chosen = [float(v) for v in cold]  # type: ignore[union-attr]
    except (TypeError, ValueError):
        chosen = [float("nan")]
    for v in chosen:
        if not np.any(np.isclose(grid, v, rtol=0, atol=1e-12 * (1 + abs(v)))):
            raise GaitoptInputError(
                f"`cold` value {v!r} is not one of the library's values "
                f"{np.round(grid, 12).tolist()}; choose among them"
            )
    return chosen


def _compare(
    a: LibraryPoint, b: LibraryPoint, solve: Any, locate: float, reference: float
) -> LibraryEvent | None:
    """The event between a successful point ``a`` and the next point ``b``, located.

    A ``b`` that converged to an optimum which then failed a check (simulation, discretisation
    target) still has an active set to compare; one with no optimum ends the library there."""
    width = locate * abs(b.value - a.value)
    if _optimum(b.gait):
        before, after = set(a.gait.active_constraints), set(b.gait.active_constraints)
        if before != after:
            return _bisect_active(a, b, before, solve, width)
        if (
            b.gait.success
            and np.isfinite(a.hessian[0])
            and np.isfinite(b.hessian[0])
            and np.sign(a.hessian[0]) != np.sign(b.hessian[0])
        ):
            return LibraryEvent(
                "fold",
                0.5 * (a.value + b.value),
                (a.value, b.value),
                sorted(before),
                sorted(after),
                f"fold between {a.value:g} and {b.value:g}: the reduced Hessian's smallest "
                f"eigenvalue changes sign ({a.hessian[0]:.3g} → {b.hessian[0]:.3g})",
            )
        return None
    return _bisect_end(a, b, solve, width, reference)


def _optimum(gait: OptimalGait) -> bool:
    """IPOPT converged and the dense checks passed (a bisection probe, not verified by
    simulation nor held to the discretisation target: only its active set and its existence
    are used)."""
    return gait.cost is not None and not gait.message.startswith("not a gait")


def _bisect_active(
    a: LibraryPoint, b: LibraryPoint, before: set[str], solve: Any, width: float
) -> LibraryEvent:
    lo, hi, guess = a.value, b.value, a.gait
    after = set(b.gait.active_constraints)
    while abs(hi - lo) > width:
        mid = 0.5 * (lo + hi)
        gait = solve(mid, guess, verify=False)
        if _optimum(gait) and set(gait.active_constraints) == before:
            lo, guess = mid, gait
        else:
            hi = mid
    gained = sorted(after - before)
    lost = sorted(before - after)
    what = ", ".join(
        [f"'{c}' becomes active" for c in gained] + [f"'{c}' becomes inactive" for c in lost]
    )
    return LibraryEvent(
        "active set",
        0.5 * (lo + hi),
        (lo, hi),
        sorted(before),
        sorted(after),
        f"active set changes at {0.5 * (lo + hi):.6g} (± {0.5 * abs(hi - lo):.2g}): {what}",
    )


def _bisect_end(
    a: LibraryPoint, b: LibraryPoint, solve: Any, width: float, reference: float
) -> LibraryEvent:
    lo, hi, last = a.value, b.value, a
    reason = b.gait.message
    while abs(hi - lo) > width:
        mid = 0.5 * (lo + hi)
        gait = solve(mid, last.gait, verify=False)
        if _optimum(gait):
            point = LibraryPoint(mid, gait, True, 0.0)
            col, w = gait.transcription
            point.hessian = reduced_hessian(col, w, col.model.p)
            lo, last = mid, point
        else:
            hi, reason = mid, gait.message
    ratio = last.hessian_ratio
    # Near singular relative to the library's first point (the ratio carries the mesh's
    # quadrature weights, so only its fall along the library means something).
    fold = bool(np.isfinite(ratio) and np.isfinite(reference) and ratio < _FOLD_RATIO * reference)
    kind = "fold" if fold else "end"
    detail = (
        f"the reduced Hessian becomes singular there (λmin/λmax {ratio:.2g}, against "
        f"{reference:.2g} at the library's start): a fold"
        if fold
        else f"λmin/λmax of the reduced Hessian {ratio:.2g} at the last optimum ({reference:.2g} "
        f"at the library's start): not a fold; {reason}"
    )
    return LibraryEvent(
        kind,
        0.5 * (lo + hi),
        (lo, hi),
        sorted(last.gait.active_constraints),
        [],
        f"warm starts stop converging at {0.5 * (lo + hi):.6g} (± {0.5 * abs(hi - lo):.2g}); "
        + detail,
    )


def _cold_checks(
    library: GaitLibrary,
    values: list[float],
    model: HybridModel,
    vary: str,
    fixed: Mapping[str, float | None],
    cost: str,
    options: Mapping[str, Any],
    scheduler: str | None,
) -> list[ColdCheck]:
    from .problem import as_problem
    from .solve import solve_problem

    if not values:
        return []
    by_value = {pt.value: pt for pt in library.points}
    problems = []
    for v in values:
        if vary in CONSTRAINTS:
            problems.append(as_problem(model, cost=cost, **{**fixed, vary: v}, **_opts(options)))
        else:
            problems.append(
                as_problem(model.replace(**{vary: v}), cost=cost, **fixed, **_opts(options))
            )
    tol = float(options["tol"])
    if scheduler is not None:
        from ..sweep import sweep

        points = [{"problem": _problem_data(p), "tol": tol} for p in problems]
        outcomes = sweep(cold_task, points, scheduler=scheduler, progress=False).results
    else:
        outcomes = []
        for p in problems:
            t0 = time.perf_counter()
            gait = solve_problem(p, tol=tol)
            outcomes.append(
                {
                    "success": gait.success,
                    "cost": gait.cost,
                    "message": gait.message,
                    "time": time.perf_counter() - t0,
                }  # fmt: skip
            )
    checks = []
    for v, out in zip(values, outcomes, strict=True):
        point = min(by_value.values(), key=lambda pt, v=v: abs(pt.value - v))
        lib_cost = point.gait.cost if point.gait.success else None
        cold_cost = out["cost"] if out["success"] else None
        rel = (
            abs(lib_cost - cold_cost) / max(abs(cold_cost), 1e-300)
            if lib_cost is not None and cold_cost is not None
            else None
        )
        agree = rel is not None and (rel <= _COLD_RTOL or abs(lib_cost - cold_cost) <= 1e-12)
        if agree:
            message = f"same cost to {rel:.2g} relative"
        elif rel is not None:
            message = (
                f"the cold start finds cost {cold_cost:.10g} against the library's "
                f"{lib_cost:.10g}: another local minimum"
            )
        else:
            message = f"no comparison: {out['message'] if not out['success'] else 'library failed'}"
        checks.append(ColdCheck(v, lib_cost, cold_cost, rel, agree, float(out["time"]), message))
    return checks


def _opts(options: Mapping[str, Any]) -> dict[str, Any]:
    return {k: options[k] for k in ("bounds", "state_bounds", "free", "steps")}
