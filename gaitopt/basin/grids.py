"""Every start of a set simulated: :func:`classify_starts` (given starts), :func:`basin_slice`
(a grid over two section coordinates) and :func:`basin_fraction` (uniform random starts in a
box, with the Wilson interval)."""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..arguments import check_count, check_scheduler
from ..errors import GaitoptInputError
from .checks import (
    LIMIT,
    MAX_CHUNK,
    MAX_POINTS,
    MAX_SAMPLES,
    Setup,
    check_setup,
    chosen_coordinates,
    window_box,
)
from .classify import run_tasks, starts_task
from .results import BasinFraction, BasinSlice, wilson_interval

__all__ = ["basin_fraction", "basin_slice", "classify_starts"]


def outcomes_of(setup: Setup, starts: np.ndarray, chunk: int, scheduler: str | None) -> list[str]:
    points = [setup.point(starts=[start]) for start in starts.tolist()]
    return [o for r in run_tasks(starts_task, points, scheduler, chunk) for o in r["outcomes"]]


def classify_starts(
    gait: Any,
    starts: Any,
    *,
    steps: int = 40,
    hold: int = 5,
    tol: float = 1e-4,
    scale: Any = None,
    chunk: int = 20,
    scheduler: str | None = None,
) -> list[str]:
    """Simulate each start and say whether it converges to the gait: ``"converged"`` or why not
    (``"fell"``, ``"standing"``, ``"timeout"``, ``"not converged"``, ``"invalid start"``).

    Parameters
    ----------
    gait : LimitCycle
        A successful gait.
    starts : array_like
        Rows of section coordinates (every coordinate, in the section's order; their units).
    steps, hold, tol, scale, chunk, scheduler
        As in :func:`basin_fraction`.

    Returns
    -------
    list of str
    """
    setup = check_setup(gait, steps, hold, tol, scale)
    chunk = check_count("chunk", chunk, 1, MAX_CHUNK, LIMIT)
    check_scheduler(scheduler, serial=True)
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    if starts.shape[1] != len(setup.coordinates) or not np.all(np.isfinite(starts)):
        raise GaitoptInputError(
            f"`starts` must be finite rows of {len(setup.coordinates)} section coordinates "
            f"({', '.join(setup.coordinates)}), got shape {starts.shape}"
        )
    return outcomes_of(setup, starts, chunk, scheduler)


def basin_slice(
    gait: Any,
    coordinates: Sequence[str],
    *,
    points: int = 21,
    window: Any = 1.0,
    steps: int = 40,
    hold: int = 5,
    tol: float = 1e-4,
    scale: Any = None,
    chunk: int = 20,
    scheduler: str | None = None,
) -> BasinSlice:
    """Every start of a grid over two section coordinates simulated (the others at the fixed
    point): which converge to the gait.

    Parameters
    ----------
    gait : LimitCycle
        A successful gait.
    coordinates : (str, str)
        The two section coordinates varied.
    points : int
        Grid points per axis (the window's ends included).
    window : float, sequence or mapping
        Half widths (scaled: fractions of ``scale``) around the fixed point, or ``{name: (low,
        high)}`` in the coordinates' units.
    steps, hold, tol, scale
        As in :func:`basin`.
    chunk : int
        Starts per task of the sweep.
    scheduler : str, optional
        As in :func:`basin`.

    Returns
    -------
    BasinSlice
    """
    started = time.perf_counter()
    setup = check_setup(gait, steps, hold, tol, scale)
    points = check_count("points", points, 2, MAX_POINTS, LIMIT)
    chunk = check_count("chunk", chunk, 1, MAX_CHUNK, LIMIT)
    pair = chosen_coordinates("coordinates", coordinates, setup.coordinates, 2)
    check_scheduler(scheduler, serial=True)
    box = window_box(setup, window)
    values = tuple(np.linspace(*box[c], points) for c in pair)
    a, b = np.meshgrid(*values)
    starts = np.tile(np.asarray(setup.centre), (a.size, 1))
    starts[:, setup.coordinates.index(pair[0])] = a.ravel()
    starts[:, setup.coordinates.index(pair[1])] = b.ravel()
    outcomes = np.array(outcomes_of(setup, starts, chunk, scheduler)).reshape(a.shape)
    return BasinSlice(
        tuple(pair),
        values,
        outcomes == "converged",
        outcomes,
        dict(zip(setup.coordinates, setup.centre, strict=True)),
        gait.model,
        {"steps": setup.steps, "hold": setup.hold, "tol": setup.tol, "window": box},
        time.perf_counter() - started,
    )


def basin_fraction(
    gait: Any,
    *,
    samples: int = 200,
    window: Any = 1.0,
    steps: int = 40,
    hold: int = 5,
    tol: float = 1e-4,
    scale: Any = None,
    seed: int = 0,
    chunk: int = 20,
    scheduler: str | None = None,
) -> BasinFraction:
    """Fraction of a box on the section from which the gait converges, from uniform random
    starts (each simulated), with its 95 % Wilson interval.

    Parameters
    ----------
    gait : LimitCycle
        A successful gait.
    samples : int
        Starts drawn uniformly in the box (seeded).
    window : float, sequence or mapping
        Half widths (scaled) around the fixed point, or ``{name: (low, high)}`` for every
        section coordinate (their units).
    steps, hold, tol, scale
        As in :func:`basin`.
    seed : int
        Seed of the starts.
    chunk : int
        Starts per task of the sweep.
    scheduler : str, optional
        As in :func:`basin`.

    Returns
    -------
    BasinFraction
        For an unstable gait the starts are still simulated (none converges near it).
    """
    started = time.perf_counter()
    setup = check_setup(gait, steps, hold, tol, scale)
    samples = check_count("samples", samples, 1, MAX_SAMPLES, LIMIT)
    chunk = check_count("chunk", chunk, 1, MAX_CHUNK, LIMIT)
    check_scheduler(scheduler, serial=True)
    box = window_box(setup, window)
    low = np.array([box[c][0] for c in setup.coordinates])
    high = np.array([box[c][1] for c in setup.coordinates])
    starts = low + (high - low) * np.random.default_rng(seed).random((samples, len(low)))
    outcomes = outcomes_of(setup, starts, chunk, scheduler)
    k = sum(o == "converged" for o in outcomes)
    return BasinFraction(
        k / samples,
        wilson_interval(k, samples),
        0.95,
        samples,
        k,
        box,
        {"steps": setup.steps, "hold": setup.hold, "tol": setup.tol, "seed": seed},
        time.perf_counter() - started,
        starts,
        np.array(outcomes),
    )
