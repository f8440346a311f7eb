"""Transverse LQR against step-to-step LQR on the same optimal gait: closed-loop multipliers, the
largest perturbation survived along each section coordinate (both signs), peak input.

The largest survived perturbation along a direction is found by bisection on its size ``a``
in ``(0, a_max]``: a start ``s* + a d`` survives if the controlled simulation completes its
orbits and ends within ``a / 10`` of the fixed point (section units, max norm).  Every
start the bisection classifies is simulated (the classification *is* the simulation); the
bisection assumes that the surviving sizes along a direction form an interval from 0 (the
basin star-shaped along it), which it does not check between its probes.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..optimize.stabilisation.closed_loop import dense_check, run
from .design import trial

__all__ = [
    "Survival",
    "survived",
    "survived_along",
    "compare",
    "basin_rays",
    "sphere_directions",
    "transverse_runner",
    "step_to_step_runner",
]

Runner = Callable[[np.ndarray], tuple[bool, list[float], str]]


@dataclass
class Survival:
    """The largest survived perturbation along one signed section direction.

    Attributes
    ----------
    coordinate : str
        The section coordinate displaced.
    sign : float
        +1 or −1.
    survived : float
        Largest size found to survive (section units); 0 if none did.
    failed : float or None
        Smallest size found to fail (None: ``a_max`` survived, the search was capped).
    probes : list of tuple
        ``(size, survived, message)`` of every simulated start, in order.
    peak : list of float
        Largest ``|u|`` per input in the run from the largest survived size.
    """

    coordinate: str
    sign: float
    survived: float = 0.0
    failed: float | None = None
    probes: list[tuple[float, bool, str]] = field(default_factory=list)
    peak: list[float] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {
            "coordinate": self.coordinate,
            "sign": self.sign,
            "survived": self.survived,
            "failed": self.failed,
            "capped": self.failed is None,
            "probes": [list(p) for p in self.probes],
            "peak_input": self.peak,
        }


def transverse_runner(gait: Any, law: Any, orbits: int) -> Runner:
    """``runner(s0) -> (survived, peak |u|, message)`` for a transverse law."""

    def runner(s0: np.ndarray) -> tuple[bool, list[float], str]:
        tr = trial(gait, law, s0, orbits)
        return _survives(tr.status, tr.errors), list(tr.peak_applied), tr.message

    return runner


def step_to_step_runner(gait: Any, gain: np.ndarray, orbits: int) -> Runner:
    """``runner(s0) -> (survived, peak |u|, message)`` for the per-step offset law
    ``δₖ = −K (sₖ − s*)`` of :func:`gaitopt.optimize.stabilise`."""
    from ..errors import StateError

    def runner(s0: np.ndarray) -> tuple[bool, list[float], str]:
        try:
            sim, offsets, errors = run(gait, s0, gain, orbits)
        except StateError as exc:
            return False, [], str(exc)
        _, peak = dense_check(gait, sim, offsets) if sim.arcs else (None, np.zeros(0))
        return _survives(sim.status, errors), peak.tolist(), sim.message

    return runner


def _survives(status: str, errors: list[float]) -> bool:
    """Completed every orbit and ended within a tenth of the start's distance: a criterion
    that a slowly converging controller can meet in the same number of orbits as a fast one
    (|λ| 0.69 after 12 orbits: 0.012)."""
    return status == "completed" and len(errors) > 1 and errors[-1] <= 0.1 * errors[0]


def survived(
    runner: Runner,
    s_star: np.ndarray,
    coordinate: int,
    name: str,
    sign: float,
    a_max: float,
    iterations: int,
) -> Survival:
    """Bisection for the largest surviving size along ``sign · e_coordinate``."""
    direction = np.zeros(s_star.size)
    direction[coordinate] = sign
    return survived_along(runner, s_star, direction, Survival(name, sign), a_max, iterations)


def survived_along(
    runner: Runner,
    s_star: np.ndarray,
    direction: np.ndarray,
    result: Survival,
    a_max: float,
    iterations: int,
) -> Survival:
    """Bisection for the largest surviving size ``a`` of ``s* + a · direction`` (section units),
    recorded in ``result``; every classified start is simulated by ``runner``."""
    direction = np.asarray(direction, dtype=float)

    def probe(a: float) -> bool:
        ok, peak, message = runner(s_star + a * direction)
        result.probes.append((float(a), bool(ok), message))
        if ok and a >= result.survived:
            result.survived, result.peak = float(a), peak
        return ok

    if probe(a_max):
        return result
    lo, hi = 0.0, a_max
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if probe(mid):
            lo = mid
        else:
            hi = mid
    result.failed = hi
    return result


def sphere_directions(count: int, dimension: int) -> np.ndarray:
    """``count`` unit directions spread over the sphere of ``dimension`` (section units):
    a Fibonacci lattice in 3-D (deterministic), ± the axes in other dimensions."""
    if dimension != 3:
        eye = np.eye(dimension)
        return np.vstack([eye, -eye])[:count]
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = np.pi * (1.0 + 5.0**0.5) * k
    r = np.sqrt(1.0 - z**2)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def basin_rays(
    gait: Any,
    controllers: dict[str, Runner],
    directions: np.ndarray,
    *,
    a_max: float = 0.2,
    iterations: int = 3,
) -> dict[str, list[dict[str, Any]]]:
    """A star-shaped inner estimate of each closed loop's basin on the section: the largest
    surviving size along each of ``directions`` (bisection, every probe simulated; the same
    assumption as :func:`survived`: surviving sizes form an interval from 0 along a ray)."""
    model = gait.model
    s_star = np.asarray(model.section_coordinates_of(model.state_vector(gait.fixed_point)))
    out: dict[str, list[dict[str, Any]]] = {}
    for label, runner in controllers.items():
        rays = []
        for i, d in enumerate(np.asarray(directions, dtype=float)):
            result = survived_along(runner, s_star, d, Survival(f"ray {i}", 1.0), a_max, iterations)
            rays.append({"direction": d.tolist(), **result.to_json()})
        out[label] = rays
    return out


def compare(
    gait: Any,
    controllers: dict[str, tuple[Runner, np.ndarray]],
    *,
    a_max: float = 0.2,
    iterations: int = 6,
    coordinates: Sequence[str] | None = None,
) -> list[dict[str, Any]]:
    """One row per controller: its closed-loop multipliers (given), the largest survived
    perturbation along each section coordinate and sign, the peak input over those runs."""
    model = gait.model
    s_star = np.asarray(model.section_coordinates_of(model.state_vector(gait.fixed_point)))
    names = list(model.section.coordinates)
    chosen = names if coordinates is None else list(coordinates)
    rows = []
    for label, (runner, multipliers) in controllers.items():
        survivals = [
            survived(runner, s_star, names.index(c), c, sign, a_max, iterations)
            for c in chosen
            for sign in (1.0, -1.0)
        ]
        peaks = [s.peak for s in survivals if s.peak]
        rows.append(
            {
                "controller": label,
                "closed_loop_multipliers": [
                    [float(np.real(z)), float(np.imag(z))] for z in np.asarray(multipliers, complex)
                ],
                "largest_modulus": float(np.max(np.abs(multipliers))) if len(multipliers) else None,
                "survived": [s.to_json() for s in survivals],
                "peak_input": np.max(np.array(peaks), axis=0).tolist() if peaks else [],
            }
        )
    return rows
