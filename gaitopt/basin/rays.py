"""The rays of the star-shaped estimate: their directions (:func:`ray_directions`) and the sweep
task that scans and bisects each (:func:`rays_task`; :func:`rays_batch`, the rays in lockstep
through the batch simulation: the same radii)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .classify import classify, classify_many, model_of, small

__all__ = ["midpoints", "ray_directions", "rays_batch", "rays_task"]


def rays_task(point: Mapping[str, Any]) -> dict[str, Any]:
    """Rays → per ray the radius, first failure and scan (a point of :func:`sweep`)."""
    setup = point["setup"]
    model = model_of(setup)
    centre, scale = np.asarray(setup["centre"]), np.asarray(setup["scale"])
    index = [setup["coordinates"].index(c) for c in point["coordinates"]]
    scan, bisections, top = point["scan"], point["bisections"], point["max_radius"]
    rays = []
    for direction in point["directions"]:
        step = np.zeros_like(centre)
        step[index] = np.asarray(direction) * scale[index]

        def converges(r: float, step: np.ndarray = step) -> bool:
            return classify(setup, model, centre + r * step) == "converged"

        grid = [top * k / scan for k in range(1, scan + 1)]
        fates = [converges(r) for r in grid]
        runs = len(grid)
        failed = [r for r, ok in zip(grid, fates, strict=True) if not ok]
        if not failed:
            rays.append({"radius": top, "first_failure": None, "beyond": [], "runs": runs})
            continue
        high = failed[0]
        low = max([0.0] + [r for r, ok in zip(grid, fates, strict=True) if ok and r < high])
        for _ in range(bisections):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if converges(middle) else (low, middle)
            runs += 1
        beyond = [r for r, ok in zip(grid, fates, strict=True) if ok and r > failed[0]]
        rays.append({"radius": low, "first_failure": high, "beyond": beyond, "runs": runs})
    return {"rays": rays}


def rays_batch(points: list[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """:func:`rays_task` on many points (one setup), the rays in lockstep: every ray's scan in
    one batch simulation, then each round of bisection (one radius per ray still bracketing)
    in one batch.  The same radii, the same rule, every start simulated."""
    if not points:
        return []
    setup = points[0]["setup"]
    keys = ("setup", "coordinates", "scan", "bisections", "max_radius")
    if any(any(p[k] != points[0][k] for k in keys) for p in points):
        return [rays_task(point) for point in points]
    model = model_of(setup)
    centre, scale = np.asarray(setup["centre"]), np.asarray(setup["scale"])
    index = [setup["coordinates"].index(c) for c in points[0]["coordinates"]]
    scan, bisections, top = points[0]["scan"], points[0]["bisections"], points[0]["max_radius"]
    directions = np.array([d for p in points for d in p["directions"]], dtype=float)
    steps = np.zeros((len(directions), len(centre)))
    steps[:, index] = directions * scale[index]
    grid = np.array([top * k / scan for k in range(1, scan + 1)])

    def converges(rows: np.ndarray, radii: np.ndarray) -> np.ndarray:
        starts = centre + radii[:, None] * steps[rows]
        return np.array(classify_many(setup, model, starts)) == "converged"

    n = len(directions)
    fates = converges(np.repeat(np.arange(n), scan), np.tile(grid, n)).reshape(n, scan)
    low, high = np.zeros(n), np.full(n, np.nan)
    for i in range(n):
        failed = grid[~fates[i]]
        if failed.size:
            high[i] = failed[0]
            below = grid[fates[i] & (grid < failed[0])]
            low[i] = below.max() if below.size else 0.0
    open_ = np.flatnonzero(~np.isnan(high))
    left, runs = bisections if open_.size else 0, np.zeros(n, dtype=int)
    while left:
        # several halvings per batch: every midpoint the next `levels` halvings of each ray can
        # visit (2**levels - 1, by the same 0.5 * (low + high) as one halving at a time, so the
        # radii are those of sequential bisection), enough for a batch of _BISECT starts
        # (few rays, or a compiled batch, whose starts cost the same in any number: one halving
        # at a time, as many simulations as one by one)
        levels = max(1, min(left, _LEVELS, int(np.log2(_BISECT / open_.size + 1))))
        if 3 * open_.size < small(model) or small(model) == 1:
            levels = 1
        tree = midpoints(low[open_], high[open_], levels)  # rays × (2**levels − 1), in order
        fate = converges(np.repeat(open_, tree.shape[1]), tree.ravel()).reshape(tree.shape)
        runs[open_] += tree.shape[1]
        node = np.zeros(open_.size, dtype=int)  # heap index of the midpoint taken next
        for _ in range(levels):
            middle = tree[np.arange(open_.size), node]
            ok = fate[np.arange(open_.size), node]
            low[open_] = np.where(ok, middle, low[open_])
            high[open_] = np.where(ok, high[open_], middle)
            node = 2 * node + np.where(ok, 2, 1)
        left -= levels
    rays = []
    for i in range(n):
        if np.isnan(high[i]):
            rays.append({"radius": top, "first_failure": None, "beyond": [], "runs": scan})
            continue
        failed_first = grid[~fates[i]][0]
        beyond = [float(r) for r, ok in zip(grid, fates[i], strict=True) if ok and r > failed_first]
        rays.append({"radius": float(low[i]), "first_failure": float(high[i]),
                     "beyond": beyond, "runs": scan + int(runs[i])})  # fmt: skip
    sizes = np.cumsum([0, *(len(p["directions"]) for p in points)])
    return [{"rays": rays[a:b]} for a, b in zip(sizes[:-1], sizes[1:], strict=True)]


rays_task.batched = rays_batch  # type: ignore[attr-defined]
#: Starts per round of the rays' bisection in a batch (several halvings per round), and the most
#: halvings per round (each costs twice the simulations of the one before).
_BISECT = 256
_LEVELS = 3


def midpoints(low: np.ndarray, high: np.ndarray, levels: int) -> np.ndarray:
    """Every midpoint ``levels`` halvings of ``[low, high]`` can visit, per row, in heap order
    (node k's halves are 2k + 1, the lower, and 2k + 2), each ``0.5 * (a + b)`` of its bracket."""
    count = 2**levels - 1
    tree = np.empty((low.size, count))
    brackets = {0: (low, high)}
    for k in range(count):
        a, b = brackets.pop(k)
        tree[:, k] = m = 0.5 * (a + b)
        if 2 * k + 2 < count:
            brackets[2 * k + 1], brackets[2 * k + 2] = (a, m), (m, b)
    return tree


def ray_directions(rays: int, dimension: int, seed: int) -> np.ndarray:
    """Unit vectors: ±1 in one dimension, equal angles in two, otherwise pairs ±v of normalised
    Gaussian vectors (seeded) so that every direction has its opposite."""
    if dimension == 1:
        return np.array([[1.0], [-1.0]])[: min(rays, 2)]
    if dimension == 2:
        angles = 2 * np.pi * np.arange(rays) / rays
        return np.column_stack([np.cos(angles), np.sin(angles)])
    rng = np.random.default_rng(seed)
    half = rng.standard_normal(((rays + 1) // 2, dimension))
    half /= np.linalg.norm(half, axis=1, keepdims=True)
    return np.concatenate([half, -half])[:rays]
