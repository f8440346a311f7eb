"""One phase of a simulation in one compiled call: :func:`integrate_arc`.

The same integration as :func:`gaitopt.simulation.phase.integrate_phase` with SciPy's DOP853
(each step one call of the compiled step), moved into C: the adaptive steps, error control,
dense output, the strict directional event checks at each step's check points, the root on the
dense output and the admissibility of a crossing all run inside ``gaitopt_arc``
(:mod:`gaitopt.kernels.arc_driver`), one ``ctypes`` call per arc instead of some 300 µs of
Python per step.  Python builds the arc's :class:`scipy.integrate.OdeSolution` from the steps'
dense-output coefficients afterwards (SciPy's own ``Dop853DenseOutput``), so an arc is the
same object either way.  Only for a constant input over the phase (no feedforward or feedback:
those stay in the Python loop).
"""

from __future__ import annotations

import numpy as np

from ..kernels.arcs import ArcLibrary, address
from .phase import _ARM, PhaseFunctions, _held

__all__ = ["integrate_arc", "rests_on_guard"]

#: Steps recorded per call before the driver returns to have its buffers emptied.
_CAPACITY = 512


def integrate_arc(
    funcs: PhaseFunctions,
    library: ArcLibrary,
    index: int,
    t0: float,
    x0: np.ndarray,
    rtol: float,
    atol: float,
    max_time: float,
):
    """Integrate phase ``index`` from ``(t0, x0)`` until an admissible directional crossing.

    Parameters
    ----------
    funcs : PhaseFunctions
        The phase's functions at its input and parameters (their values and event layout).
    library : ArcLibrary
        The model class's compiled arc library.
    index : int
        The phase's index in the model.
    t0 : float
        Start time (s).
    x0 : numpy.ndarray
        Start state.
    rtol, atol : float
        Integrator tolerances.
    max_time : float
        The phase's timeout (s after ``t0``).

    Returns
    -------
    tuple
        ``(solution, event, x_minus, status)`` as :func:`~gaitopt.simulation.phase
        .integrate_phase`: the arc's ``OdeSolution``, the index of the event that fired and the
        state there (None, None with a status ``"timeout"`` or ``"failed"``).
    """
    from scipy.integrate import OdeSolution
    from scipy.integrate._ivp.rk import Dop853DenseOutput

    x0 = np.ascontiguousarray(x0, dtype=float).ravel()
    n, m, n_tr = x0.size, funcs.events, len(funcs.phase.transitions)
    constraints = funcs._compiled_key[2]
    u = np.ascontiguousarray(funcs.u, dtype=float).ravel()
    p = np.ascontiguousarray(funcs.p, dtype=float).ravel()
    dims = np.array([n, m, n_tr], dtype=np.int32)
    dirs = np.asarray(funcs._directions, dtype=float)
    at_end = np.array([0] * n_tr + [int(c.at_end) for c in funcs.constraints], dtype=np.int32)
    opts = np.array([rtol, atol, t0, t0 + max_time], dtype=float)
    state = np.zeros(4 + 2 * n + 2 * m)
    state[0], state[1] = t0, -1.0  # h_abs < 0: the driver starts the arc
    state[4 : 4 + n] = x0
    cap = _CAPACITY
    stamps, ends = np.zeros(cap), np.zeros(cap)
    yold, F = np.zeros(cap * n), np.zeros(cap * 7 * n)
    count, event = np.zeros(1, dtype=np.int32), np.zeros(1, dtype=np.int32)
    hit = np.zeros(1 + n)
    table = library.pointers(index, constraints)
    ts, interpolants = [t0], []
    while True:
        code = library.arc(
            table, address(dims), address(u), address(p), address(dirs), address(at_end),
            address(opts), address(state), cap, address(stamps), address(ends),
            address(yold), address(F), address(count), address(hit), address(event),
        )  # fmt: skip
        if code < 0:
            raise RuntimeError(f"the compiled arc of phase {index} failed (code {code})")
        k = int(count[0])
        Y, Fs = yold[: k * n].reshape(k, n), F[: k * 7 * n].reshape(k, 7, n)
        for i in range(k):
            t_old = ts[-1]
            interpolants.append(Dop853DenseOutput(t_old, ends[i], Y[i].copy(), Fs[i].copy()))
            ts.append(float(stamps[i]))
        if code == 3:  # buffers full: go on from the driver's state
            continue
        if code == 0:
            return OdeSolution(ts, interpolants), int(event[0]), hit[1:].copy(), None
        if code == 1:
            return OdeSolution(ts, interpolants), None, None, "timeout"
        if not interpolants:  # the first step failed
            return _held(t0, x0), None, None, "failed"
        return OdeSolution(ts, interpolants), None, None, "failed"


def rests_on_guard(funcs: PhaseFunctions, library: ArcLibrary, index: int, x0: np.ndarray):
    """:func:`gaitopt.simulation.phase._rests_on_guard` with the guards' signed rates and
    curvatures along the flow from the compiled library (``excursion_<phase>``): the transition
    whose guard the state rests on, pressing into it, or None."""
    rates = None
    for k, tr in enumerate(funcs.phase.transitions):
        if tr.terminal or abs(funcs.signed_guard(k, x0)) > _ARM:
            continue
        if rates is None:
            rates = library.call(f"excursion_{index}", x0, funcs.u, funcs.p)
        g1, g2 = float(rates[0][k]), float(rates[1][k])
        if abs(g1) <= _ARM and g2 > 0:
            return tr.name
    return None
