"""The compiled arcs' dense output (:mod:`gaitopt.simulation.dense`) against SciPy's own classes.

Source: SciPy's ``OdeSolution`` and ``Dop853DenseOutput`` (``scipy/integrate/_ivp``), which
:mod:`gaitopt.simulation.dense` restates so that a solve need not import ``scipy.integrate``.
Same operations in the same order, so the values must agree to the bit (tolerance 0), at times
inside the pieces, on their stamps (a stamp belongs to the piece before it) and outside the arc.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import OdeSolution
from scipy.integrate._ivp.rk import Dop853DenseOutput

from gaitopt.simulation.compiled import DenseArc


def _arc(seed: int = 0, steps: int = 6, n: int = 4):
    rng = np.random.default_rng(seed)
    ts = np.concatenate([[0.3], 0.3 + np.cumsum(rng.uniform(0.01, 0.1, steps))])
    ends = ts[1:].copy()
    ends[-1] += 0.02  # the last step's own end lies past the arc's end (the crossing)
    y_old = rng.normal(size=(steps, n))
    F = rng.normal(size=(steps, 7, n))
    ours = DenseArc(ts, ends, y_old, F)
    pieces = [
        Dop853DenseOutput(a, b, y, f) for a, b, y, f in zip(ts[:-1], ends, y_old, F, strict=True)
    ]
    return ours, OdeSolution(ts, pieces), ts


def test_dense_arc_equals_scipy_to_the_bit():
    ours, scipy_solution, ts = _arc()
    rng = np.random.default_rng(1)
    times = np.concatenate([rng.uniform(ts[0] - 0.05, ts[-1] + 0.05, 50), ts])
    rng.shuffle(times)
    assert np.array_equal(ours(times), scipy_solution(times))  # vector of times, unsorted
    for t in times[:20]:  # one time at a time (SciPy's _call_single)
        assert np.array_equal(ours(t), scipy_solution(t))
    assert np.array_equal(ours(ts[2]), scipy_solution(ts[2]))  # on a stamp: the piece before


def test_dense_arc_pieces_and_attributes():
    ours, scipy_solution, ts = _arc(seed=2, steps=3)
    assert len(ours.interpolants) == len(scipy_solution.interpolants) == 3
    assert (ours.t_min, ours.t_max) == (scipy_solution.t_min, scipy_solution.t_max)
    assert np.array_equal(ours.ts, scipy_solution.ts)
