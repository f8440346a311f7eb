"""One phase of a simulation in one compiled call: :func:`integrate_arc`.

The same integration as :func:`gaitopt.simulation.phase.integrate_phase` with SciPy's DOP853
(each step one call of the compiled step), moved into C: the adaptive steps, error control,
dense output, the strict directional event checks at each step's check points, the root on the
dense output and the admissibility of a crossing all run inside ``gaitopt_arc``
(:mod:`gaitopt.kernels.arc_driver`), one ``ctypes`` call per arc instead of some 300 µs of
Python per step.  Python builds the arc's dense solution from the steps' dense-output
coefficients afterwards (SciPy's ``OdeSolution`` and ``Dop853DenseOutput`` as
:mod:`gaitopt.simulation.dense` restates them, so that a solve need not import
``scipy.integrate``, 0.3–0.5 s: the same values to the bit), so an arc evaluates the same either
way.  Only for a constant input over the phase (no feedforward or feedback: those stay in the
Python loop).  Imported on a simulation's first compiled arc.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..kernels.arcs import ArcLibrary, address
from .dense import Dop853Piece, PiecewiseSolution
from .phase import _ARM, _CONSTRAINT_RATE, _CONSTRAINT_START, PhaseFunctions, _held

__all__ = [
    "ArcPlan", "DenseArc", "arc_plan", "integrate_arc", "rests_on_guard", "violated_at_start"
]  # fmt: skip

#: Steps recorded per call before the driver returns to have its buffers emptied.
_CAPACITY = 512


class ArcPlan:
    """One phase's compiled calls at fixed input and parameters, with their buffers: built once
    per :class:`PhaseFunctions` (which a simulation keeps per phase, input and parameters), so
    that an arc costs one ``ctypes`` call and no allocation of its arguments."""

    def __init__(self, funcs: PhaseFunctions, library: ArcLibrary, index: int):
        self.library, self.index = library, index
        self.n = n = funcs.phase.flow.size1_in(0)
        self.m = m = funcs.events
        n_tr = len(funcs.phase.transitions)
        self.u = np.array(funcs.u, dtype=float).ravel()
        self.p = np.array(funcs.p, dtype=float).ravel()
        self.dims = np.array([n, m, n_tr], dtype=np.int32)
        self.dirs = np.asarray(funcs._directions, dtype=float).copy()
        ends = [int(c.at_end) for c in funcs.constraints]
        self.at_end = np.array([0] * n_tr + ends, dtype=np.int32)
        self.opts = np.zeros(4)
        self.state = np.zeros(4 + 2 * n + 2 * m)
        cap = self.capacity = _CAPACITY
        self.stamps, self.ends = np.zeros(cap), np.zeros(cap)
        self.yold, self.F = np.zeros(cap * n), np.zeros(cap * 7 * n)
        self.count, self.event = np.zeros(1, dtype=np.int32), np.zeros(1, dtype=np.int32)
        self.hit = np.zeros(1 + n)
        table = library.pointers(index, funcs._compiled_key[2])
        self.args = (
            table, *map(address, (self.dims, self.u, self.p, self.dirs, self.at_end, self.opts,
                                  self.state)),
            cap, *map(address, (self.stamps, self.ends, self.yold, self.F, self.count,
                                self.hit, self.event)),
        )  # fmt: skip
        self._table = table  # kept alive with its address
        self._functions: dict[str, object] = {}

    def function(self, name: str):
        """The library's function ``name`` at this phase's input and parameters (built once)."""
        f = self._functions.get(name)
        if f is None:
            f = self._functions[name] = self.library.function(name, self.u, self.p)
        return f

    def reset(self, transition: int, x: np.ndarray) -> np.ndarray:
        """Transition ``transition``'s reset of the state ``x``, compiled."""
        return self.function(f"reset_{self.index}_{transition}")(x)[0]


def arc_plan(funcs: PhaseFunctions, library: ArcLibrary, index: int) -> ArcPlan:
    """The phase's :class:`ArcPlan`, built on first use and kept with ``funcs``."""
    plan = getattr(funcs, "_arc_plan", None)
    if plan is None or plan.library is not library:
        plan = funcs._arc_plan = ArcPlan(funcs, library, index)
    return plan


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
    plan = arc_plan(funcs, library, index)
    n = plan.n
    x0 = np.asarray(x0, dtype=float).ravel()
    # SciPy's solvers raise rtol to 100 eps (with a warning: scipy.integrate._ivp.common
    # .validate_tol); so does the driver, to take the same steps
    rtol = max(float(rtol), 100 * np.finfo(float).eps)
    plan.opts[:] = (rtol, atol, t0, t0 + max_time)
    state = plan.state
    state[:] = 0.0
    state[0], state[1] = t0, -1.0  # h_abs < 0: the driver starts the arc
    state[4 : 4 + n] = x0
    stamps, ends, Y, F = [np.array([t0])], [], [], []
    while True:
        code = library.arc(*plan.args)
        if code < 0:
            raise RuntimeError(f"the compiled arc of phase {index} failed (code {code})")
        k = int(plan.count[0])
        stamps.append(plan.stamps[:k].copy())
        ends.append(plan.ends[:k].copy())
        Y.append(plan.yold[: k * n].reshape(k, n).copy())
        F.append(plan.F[: k * 7 * n].reshape(k, 7, n).copy())
        if code == 3:  # buffers full: go on from the driver's state
            continue
        steps = sum(len(e) for e in ends)
        if code == 2 and not steps:  # the first step failed
            return _held(t0, x0), None, None, "failed"
        arc = DenseArc(*map(np.concatenate, (stamps, ends, Y, F)))
        if code == 0:
            return arc, int(plan.event[0]), plan.hit[1:].copy(), None
        return arc, None, None, "timeout" if code == 1 else "failed"


class DenseArc(PiecewiseSolution):
    """An arc's dense solution (as :class:`scipy.integrate.OdeSolution`) from the compiled steps'
    dense-output coefficients: its pieces (:class:`~gaitopt.simulation.dense.Dop853Piece`, SciPy's
    ``Dop853DenseOutput``, one per step) are built when first evaluated, not per step as the arc
    is integrated.

    Parameters
    ----------
    ts : numpy.ndarray
        The arc's time stamps (s): its start, then each step's end (the last: the crossing).
    ends : numpy.ndarray
        Each step's own end (s; the last step's may lie past the crossing).
    y_old : numpy.ndarray
        Each step's start state (rows).
    F : numpy.ndarray
        Each step's 7 dense-output coefficient vectors (steps × 7 × n, SciPy's ``F``).
    """

    def __init__(self, ts: np.ndarray, ends: np.ndarray, y_old: np.ndarray, F: np.ndarray):
        # OdeSolution's attributes for increasing, strictly ordered time stamps (the driver's
        # crossings lie strictly after a step's start: locate_crossing)
        self.ts = ts
        self.n_segments = ends.size
        self.t_min, self.t_max = ts[0], ts[-1]
        self._steps = (ends, y_old, F)
        self._interpolants = None

    def __call__(self, t) -> np.ndarray:
        """The state at ``t`` (n) or at each time of a 1-D ``t`` (n × len(t)): each time on its
        step's interpolant (:class:`~gaitopt.simulation.dense.Dop853Piece`'s operations, element
        by element the same, for all times at once)."""
        t = np.asarray(t)
        if t.ndim > 1:
            raise ValueError("`t` must be a float or a 1-D array.")
        ends, y_old, F = self._steps
        index = np.clip(np.searchsorted(self.ts, t, side="left") - 1, 0, self.n_segments - 1)
        t_old = self.ts[index]
        x = (t - t_old) / (ends[index] - t_old)
        y = np.zeros(y_old.shape[1:] if t.ndim == 0 else (t.size, y_old.shape[1]))
        x = x if t.ndim == 0 else x[:, None]
        for i in range(7):  # reversed(F), as Dop853Piece
            y += F[index, 6 - i]
            if i % 2 == 0:
                y *= x
            else:
                y *= 1 - x
        y += y_old[index]
        return y.T

    @property
    def interpolants(self) -> Sequence:
        """The steps' DOP853 interpolants (each built when first evaluated: a solve reads a
        few of an arc's steps, not all)."""
        if self._interpolants is None:
            self._interpolants = _Pieces(self.ts, *self._steps)
        return self._interpolants


class _Pieces(Sequence):
    """Each step's :class:`~gaitopt.simulation.dense.Dop853Piece`, built on first access."""

    def __init__(self, ts: np.ndarray, ends: np.ndarray, y_old: np.ndarray, F: np.ndarray):
        self._ts, self._ends, self._y_old, self._F = ts, ends, y_old, F
        self._built: dict[int, Dop853Piece] = {}

    def __len__(self) -> int:
        return self._ends.size

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        i = int(i)
        i = i + len(self) if i < 0 else i
        if not 0 <= i < len(self):
            raise IndexError(i)
        piece = self._built.get(i)
        if piece is None:
            piece = self._built[i] = Dop853Piece(
                float(self._ts[i]), float(self._ends[i]), self._y_old[i], self._F[i]
            )
        return piece


def rests_on_guard(funcs: PhaseFunctions, library: ArcLibrary, index: int, x0: np.ndarray):
    """:func:`gaitopt.simulation.phase._rests_on_guard` with the guards' signed rates and
    curvatures along the flow from the compiled library (``excursion_<phase>``): the transition
    whose guard the state rests on, pressing into it, or None."""
    rates = None
    for k, tr in enumerate(funcs.phase.transitions):
        if tr.terminal or abs(funcs.signed_guard(k, x0)) > _ARM:
            continue
        if rates is None:
            rates = arc_plan(funcs, library, index).function(f"excursion_{index}")(x0)
        g1, g2 = float(rates[0][k]), float(rates[1][k])
        if abs(g1) <= _ARM and g2 > 0:
            return tr.name
    return None


def violated_at_start(funcs: PhaseFunctions, library: ArcLibrary, index: int, x: np.ndarray):
    """:meth:`PhaseFunctions.violated_at_start` with the constraints' values and rates from the
    compiled library (``start_<phase>``): ``(event, reason)`` of a constraint that fails where
    the phase begins, or None."""
    if not funcs.constraints:
        return None
    values, rates = arc_plan(funcs, library, index).function(f"start_{index}")(x)
    n_tr = len(funcs.phase.transitions)
    for j, c in enumerate(funcs.constraints):
        unit = f" {c.unit}" if c.unit else ""
        if c.at_start:
            rate = float(rates[j])
            if not rate > _CONSTRAINT_RATE:
                return (
                    n_tr + j,
                    f"'{c.name}' starts at 0 and does not rise (rate {rate:.3g}{unit}/s)",
                )
        elif float(values[j]) < -_CONSTRAINT_START:
            return n_tr + j, f"'{c.name}' fails at the start ({float(values[j]):.3g}{unit})"
    return None
