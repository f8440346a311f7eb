"""A library across one quantity built so that no single start decides a point: a cold start at
every value, and warm-start chains from both ends, keeping the lowest certified optimum per
value and flagging values where certified attempts reached different local minima.

:func:`gaitopt.optimize.library.gait_library` follows one optimum from one end (natural-parameter
continuation, its active-set changes and folds located); where the cost has several local
minima and a warm start leads to whichever its seed is near (the kneed walker's cost of
transport), one direction is not enough.  :func:`library_both_ends`:

* ``cold``: :func:`~gaitopt.optimize.solve.solve_problem` from the model's default start at
  every value;
* ``from above``: continuation down from the largest value with a seed, each value warm
  started from the lowest certified attempt at its neighbour behind it — or, where none is
  certified, the lowest converged one that its checks rejected (an orbit is a start like any
  other; what it leads to is certified on its own) — or from the nearest value behind that has
  one;
* ``from below``: likewise upwards from the smallest value.

The two chains alternate (from above first) and are repeated while a pass finds a lower optimum
at a seed value (later passes re-solve only the values whose seed changed; labels ``from above,
pass 2`` ...), at most ``max_passes`` passes.  Attempts whose certified costs differ by more than
``same`` (relative) reached different local minima: :func:`disagreement` names them.
(Moved here from ``problems/optimal_kneed_cot.py``, unchanged in behaviour.)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..problem import GaitProblem
from ..solve import solve_problem

__all__ = ["CHAINS", "library_both_ends", "lowest", "seed_of", "disagreement"]

CHAINS = ("from above", "from below")  # the continuations, in the order of their first passes


def lowest(attempts: list[dict]) -> int | None:
    """Index of the attempt whose certified optimum costs least (ties: the earliest), or None
    where none is certified.  Each attempt is ``{"start", "success", "cost", ...}``."""
    good = [i for i, a in enumerate(attempts) if a["success"]]
    return min(good, key=lambda i: attempts[i]["cost"]) if good else None


def seed_of(attempts: list[dict]) -> int | None:
    """Index of the attempt a chain continues from: the lowest certified one, else the lowest
    one that converged but whose checks rejected it, else None."""
    i = lowest(attempts)
    if i is not None:
        return i
    near = [i for i, a in enumerate(attempts) if a["converged_cost"] is not None]
    return min(near, key=lambda i: attempts[i]["converged_cost"]) if near else None


def disagreement(attempts: list[dict], same: float = 1e-6) -> str:
    """Empty where the certified attempts agree to ``same`` relative (or fewer than two are
    certified); else every certified attempt's cost, lowest first, e.g.
    ``"from below 0.01942516336 < from above 0.04333637603"``."""
    good = sorted((a["cost"], a["start"]) for a in attempts if a["success"])
    if len(good) < 2 or good[-1][0] <= good[0][0] * (1 + same):
        return ""
    return " < ".join(f"{k} {c:.10g}" for c, k in good)


def _solve(
    problem_at: Callable[[float], GaitProblem],
    v: float,
    label: str,
    seed: tuple[float, int] | None,
    points: dict,
    log: Callable[[str], Any],
    solve: Callable[..., Any],
) -> None:
    """Solve at ``v`` (cold, or warm started from attempt ``seed = (value, index)``), append the
    attempt to ``points[v]`` and log it."""
    t0 = time.perf_counter()
    guess = points[seed[0]][seed[1]]["gait"] if seed else None
    gait = solve(problem_at(v), guess=guess)
    elapsed = time.perf_counter() - t0
    ok = bool(gait.success)
    seed_text = None
    if seed:
        used = points[seed[0]][seed[1]]
        seed_text = f"{seed[0]:.2f} {used['start']}" + ("" if used["success"] else " (rejected)")
    converged = bool(gait.orbit) and gait.cost is not None and np.isfinite(gait.cost)
    points[v].append({
        "start": label,
        "success": ok,
        "cost": float(gait.cost) if ok else None,
        "converged_cost": float(gait.cost) if converged else None,
        "seed": seed_text,
        "time_s": round(elapsed, 1),
        "message": gait.message or "(the solver gave no reason)",
        "gait": gait,
    })  # fmt: skip
    where = f" (seed {seed_text})" if seed else ""
    result = (
        f"certified, cost {gait.cost:.10g}, discretisation error {gait.discretisation_error:.1e}"
        if ok
        else f"FAILED: {gait.message}"
    )
    log(f"{v:.3f} {label}{where}: {result} ({elapsed:.1f} s)")


def _chain_pass(
    problem_at: Callable[[float], GaitProblem],
    values: list[float],
    direction: str,
    points: dict,
    used: dict,
    same: float,
    log: Callable[[str], Any],
    solve: Callable[..., Any],
) -> int:
    """One pass of the continuation ``direction`` ("from below": up; "from above": down): each
    value warm started from :func:`seed_of` its neighbour behind it (or of the nearest value
    behind that has one), unless this chain already started it from that value at the same
    cost (to ``same``): the same minimum again; returns the number of solves."""
    order = values if direction == "from below" else values[::-1]
    seed_value, solves = None, 0
    for j, v in enumerate(order):
        if j and seed_of(points[order[j - 1]]) is not None:
            seed_value = order[j - 1]
        if seed_value is None:
            continue
        seed = (seed_value, seed_of(points[seed_value]))
        cost = points[seed_value][seed[1]]["converged_cost"]
        last = used.get((direction, v))
        if last is not None and last[0] == seed_value and abs(cost / last[1] - 1) <= same:
            continue
        used[direction, v] = (seed_value, cost)
        n = sum(a["start"].startswith(direction) for a in points[v])
        label = direction if n == 0 else f"{direction}, pass {n + 1}"
        _solve(problem_at, v, label, seed, points, log, solve)
        solves += 1
    return solves


def library_both_ends(
    problem_at: Callable[[float], GaitProblem],
    values: Sequence[float],
    *,
    max_passes: int = 6,
    same: float = 1e-6,
    cold: bool = True,
    log: Callable[[str], Any] = lambda text: print(text, flush=True),
    solve: Callable[..., Any] = solve_problem,
) -> dict[float, list[dict]]:
    """Every attempt at every value: a cold start (``cold``), then the chains alternately
    (:data:`CHAINS`) until two passes in a row solve nothing or ``max_passes`` are done.

    Parameters
    ----------
    problem_at : callable
        ``problem_at(value) -> GaitProblem``, the statement at one value.
    values : sequence of float
        The values, increasing.
    max_passes : int
        Chain passes in all (alternating).
    same : float
        Relative cost difference below which two certified attempts reached the same minimum.
    cold : bool
        Solve from the model's default start at every value first.
    log : callable
        Receives one line per attempt.
    solve : callable
        ``solve(problem, guess=...) -> OptimalGait`` (default
        :func:`~gaitopt.optimize.solve.solve_problem`).

    Returns
    -------
    dict
        ``{value: [attempt, ...]}``; an attempt is ``{"start", "success", "cost",
        "converged_cost", "seed", "time_s", "message", "gait"}``.  The reported optimum at a
        value is :func:`lowest` of its attempts, its flag :func:`disagreement`.
    """
    values = [float(v) for v in values]
    points: dict[float, list[dict]] = {v: [] for v in values}
    if cold:
        for v in values:
            _solve(problem_at, v, "cold", None, points, log, solve)
    used: dict[tuple[str, float], tuple[float, float]] = {}  # the seed each chain last used
    idle = 0
    for n in range(max_passes):
        solved = _chain_pass(problem_at, values, CHAINS[n % 2], points, used, same, log, solve)
        idle = 0 if solved else idle + 1
        if idle == 2:
            break
    return points
