"""Distance to a periodic orbit: how far a state is from the gait, whatever its timing.

Convergence to a limit cycle is *orbital*: a perturbed trajectory approaches the orbit as a set,
not the periodic solution at the same time (Van der Pol's trajectories all reach the cycle, each
with its own phase; Tedrake, *Underactuated Robotics*, ch. "Simple models of walking and
running", limit cycles).  The orbital distance ``d(x) = min_τ ‖x − x*(τ)‖`` measures that; near a
stable orbit it shrinks by the nontrivial Floquet multiplier's modulus every period.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from .errors import GaitoptInputError
from .result import LimitCycle
from .simulation import simulate

__all__ = ["orbital_distance", "OrbitSampler"]

# Samples of the orbit per period for the coarse search (the minimum is then refined on the dense
# output, so this only needs to separate the local minima).
_SAMPLES = 2000


class OrbitSampler:
    """The orbit of a solved gait as dense output, for repeated distance queries.

    The orbit is re-simulated from the fixed point for one period (adaptive DOP853 at rtol 1e-12),
    giving a continuous ``x*(τ)`` on each phase-``phase`` arc.

    Parameters
    ----------
    cycle : LimitCycle
        A solved gait.
    phase : int
        The phase whose states the queried points are in (default 0).
    """

    def __init__(self, cycle: LimitCycle, phase: int = 0):
        if not cycle.success:
            raise GaitoptInputError(
                f"`cycle` must be a solved gait; got success=False ({cycle.message})"
            )
        sim = simulate(cycle.model, cycle.x, steps=cycle.steps, inputs=cycle.inputs, rtol=1e-12)
        if not sim.success:
            raise GaitoptInputError(f"the orbit could not be re-simulated: {sim.message}")
        self.arcs = [arc for arc in sim.arcs if arc.phase == phase]
        if not self.arcs:
            raise GaitoptInputError(f"the orbit never enters phase {phase}")
        self.n = cycle.model.phases[phase].n
        total = sum(arc.t1 - arc.t0 for arc in self.arcs)
        self._grid = []
        for arc in self.arcs:
            count = max(int(_SAMPLES * (arc.t1 - arc.t0) / total), 20)
            t = np.linspace(arc.t0, arc.t1, count)
            self._grid.append((arc, t, arc.solution(t)))

    def distance(self, x: np.ndarray) -> float:
        """``min_τ ‖x − x*(τ)‖`` (Euclidean, in the state's units) for one state ``x``."""
        x = np.asarray(x, dtype=float).ravel()
        if x.size != self.n:
            raise GaitoptInputError(f"`x` must have {self.n} entries, got {x.size}")
        best = (np.inf, None, 0)
        for arc, t, X in self._grid:
            d = np.linalg.norm(X - x[:, None], axis=0)
            k = int(np.argmin(d))
            if d[k] < best[0]:
                best = (float(d[k]), (arc, t), k)
        value, (arc, t), k = best
        lo, hi = t[max(k - 1, 0)], t[min(k + 1, len(t) - 1)]
        if hi > lo:
            # The nearest point makes x − x*(τ) orthogonal to the orbit's tangent: a root of
            # g(τ) = (x*(τ) − x)·ẋ*(τ) between the neighbours of the nearest sample (ẋ* by a
            # central difference on the dense output, error O(h²)).
            h = 1e-6 * (hi - lo)

            def g(tt: float) -> float:
                tangent = arc.solution(min(tt + h, arc.t1)) - arc.solution(max(tt - h, arc.t0))
                return float(np.dot(arc.solution(tt) - x, tangent))

            ga, gb = g(lo), g(hi)
            if ga * gb < 0:
                root = brentq(g, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
                value = min(value, float(np.linalg.norm(arc.solution(root) - x)))
        return value


def orbital_distance(cycle: LimitCycle, x: np.ndarray, *, phase: int = 0) -> float | np.ndarray:
    """Distance from a state to a gait's orbit, ``min_τ ‖x − x*(τ)‖``.

    Parameters
    ----------
    cycle : LimitCycle
        A solved gait (``cycle.success``).
    x : array_like
        One state of ``phase`` (shape ``(n,)``) or several (``(m, n)``), in the model's units.
    phase : int
        Phase of the states (default 0).

    Returns
    -------
    float or numpy.ndarray
        The Euclidean distance (the states' units; mixed units are added as they are), one per
        state.

    Examples
    --------
    >>> import gaitopt
    >>> cycle = gaitopt.find_limit_cycle(gaitopt.model("vanderpol"))
    >>> float(gaitopt.orbital_distance(cycle, cycle.x)) < 1e-9
    True
    """
    sampler = OrbitSampler(cycle, phase)
    arr = np.asarray(x, dtype=float)
    if arr.ndim == 1:
        return sampler.distance(arr)
    return np.array([sampler.distance(row) for row in arr])
