"""SciPy's DOP853 with each step evaluated in one CasADi call: the stepper of the verification.

:class:`scipy.integrate.DOP853` (Dormand & Prince's 8(5,3) pair; Hairer, Nørsett & Wanner,
*Solving ODEs I*, §II.10) spends most of a short simulation in Python: 12 right-hand-side calls
per step, 3 more for the dense output, each through several Python frames.  :class:`CompiledDOP853`
keeps SciPy's class — its initial step, error norm and step-size control, its
``Dop853DenseOutput``, restated without importing :mod:`scipy.integrate` (0.3–0.5 s at
start-up) in :mod:`gaitopt.dop853_base` and :mod:`gaitopt.simulation.dense`, the same operations
in the same order — and replaces only the arithmetic of one step by one call of a CasADi
function built from the phase's flow with SciPy's own coefficients: the new state and rate, both
error estimates, the dense-output coefficients, and the phase's event functions (guards and
unilateral constraints) at the step's interior check points and its end.  Same method, same
steps, same results to rounding (at rtol 1e-12 the error estimate is itself a difference of
nearly equal numbers, so step sizes may differ from SciPy's in their 8th digit: results agree
within the tolerance, not bit for bit); about 4× less time per step.

The flow must be autonomous (``ẋ = f(x, u, p)``, as every phase's is) with ``p`` constant over
the phase; ``u`` is either constant too or, for a feedforward ``u(t)`` known in advance (an optimal
gait's input profile), given at each of the step's times: its stages ``t + cᵢh``, its check
points and its end (``varying=True``; the caller evaluates ``u`` there, vectorised, before the
call: the SX interpreter, about 100 µs per step for the five-link biped against some 20 µs per
right-hand side through Python).  Where such an input may jump (a profile's breakpoints: the
collocation's input polynomials do not join), steps end at the jump rather than straddle it
(``stops``): a step across a jump has an error estimate of the jump's size, so SciPy rejects
and shrinks it again and again there (half of all tries on the five-link biped's optimum), and
the results then vary, at the tolerance's level, with where the steps happen to fall.
Functions are built once per phase and kept (about 10–40 ms each).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from .dop853_base import Dop853Frame, coefficients
from .simulation.dense import Dop853Piece

__all__ = ["CompiledDOP853", "STAGE_FRACTIONS", "step_function"]

# SciPy's step-size control (scipy/integrate/_ivp/rk.py)
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_dc = coefficients()  # SciPy's, read without importing scipy.integrate
_N = _dc.N_STAGES  # 12

_CACHE: dict[tuple[int, int, int, bool], tuple[object, ca.Function]] = {}

#: Times of a step's stages 1…15 as fractions of the step (SciPy's ``C``; stage 12, at 1, is the
#: rate at the new state): with ``varying``, the first 15 columns of ``u``, in this order.
STAGE_FRACTIONS = np.asarray(_dc.C[1:], dtype=float)


def step_function(
    flow: ca.Function, events: list[ca.Function], checks: int, varying: bool = False
) -> ca.Function:
    """One DOP853 step of ``ẋ = flow(x, u, p)`` with ``events`` at ``checks`` points.

    Inputs ``(y, f, h, fractions, u, p, tol)``: the state, its rate, the step (s), the interior
    check points as fractions of the step (``checks − 1`` of them), ``tol = (rtol, atol)``.
    Outputs ``(y_new, f_new, error_norm, F, G)``: SciPy's error norm of the step (accepted below
    1), ``F`` the dense-output coefficients (n × 7, SciPy's ``F`` transposed), ``G`` the event
    functions (rows) at the interior points and at ``y_new`` (columns).

    With ``varying``, ``u`` is a matrix (inputs × ``15 + checks``): its columns the input at
    the stage times ``t + STAGE_FRACTIONS·h`` (stage 12 at ``t + h``: the new state's rate), at
    the interior check points ``t + fractions·h``, and the input the event functions see at the
    step's end (the same as stage 12's unless the input jumps there); the flow and the event
    functions at each of those times see that column, as SciPy's ``fun(t, y)`` with a
    time-dependent right-hand side does.  ``f`` is then the rate at ``t`` with ``u(t)``.
    """
    key = (id(flow), hash(tuple(id(e) for e in events)), checks, bool(varying))
    hit = _CACHE.get(key)
    if hit is not None:
        return hit[1]
    fn = None
    if varying:  # built in SX at once (10× faster than MX then expand; no kernel is made of it)
        try:
            fn = _step(ca.SX, flow, events, checks, varying)
        except (RuntimeError, NotImplementedError):  # a flow that does not expand
            fn = None
    if fn is None:  # the constant step in MX, the graph its compiled kernels are made from
        fn = _step(ca.MX, flow, events, checks, varying)
        try:
            fn = fn.expand()  # SX: a flat instruction list, several times faster to evaluate
        except RuntimeError:
            pass
    _CACHE[key] = ((flow, events), fn)  # keep the keyed objects alive (ids stay unique)
    return fn


def _step(S, flow: ca.Function, events: list[ca.Function], checks: int, varying: bool):
    """:func:`step_function`'s graph in ``S`` (``casadi.SX`` or ``casadi.MX``)."""
    n = flow.size1_in(0)
    y, f0 = S.sym("y", n), S.sym("f", n)
    h = S.sym("h")
    frac = S.sym("fractions", checks - 1)
    n_u = flow.size1_in(1)
    columns = STAGE_FRACTIONS.size + checks
    u = S.sym("u", n_u, columns) if varying else S.sym("u", n_u)
    p = S.sym("p", flow.size1_in(2))

    def u_stage(s: int):  # the input at stage s (1…15)
        return u[:, s - 1] if varying else u

    def u_check(i: int):  # the input at check point i (checks − 1: the end)
        return u[:, STAGE_FRACTIONS.size + i] if varying else u

    A, B = _dc.A, _dc.B
    K = [f0]
    for s in range(1, _N):  # rk_step
        dy = sum((A[s, j] * K[j] for j in range(s) if A[s, j] != 0), S.zeros(n))
        K.append(flow(y + h * dy, u_stage(s), p))
    y_new = y + h * sum((B[j] * K[j] for j in range(_N) if B[j] != 0), S.zeros(n))
    f_new = flow(y_new, u_stage(_N), p)
    K.append(f_new)
    e5 = sum((_dc.E5[j] * K[j] for j in range(_N + 1) if _dc.E5[j] != 0), S.zeros(n))
    e3 = sum((_dc.E3[j] * K[j] for j in range(_N + 1) if _dc.E3[j] != 0), S.zeros(n))
    for s in range(_N + 1, _dc.N_STAGES_EXTENDED):  # DOP853._dense_output_impl
        dy = sum((A[s, j] * K[j] for j in range(s) if A[s, j] != 0), S.zeros(n))
        K.append(flow(y + h * dy, u_stage(s), p))
    delta = y_new - y
    F = [delta, h * f0 - delta, 2 * delta - h * (f_new + f0)]
    for row in _dc.D:
        F.append(h * sum((row[j] * K[j] for j in range(len(K)) if row[j] != 0), S.zeros(n)))
    G = []
    for i in range(checks - 1):  # Dop853DenseOutput._call_impl at each fraction
        x = frac[i]
        z = S.zeros(n)
        for k, Fk in enumerate(reversed(F)):
            z = (z + Fk) * (x if k % 2 == 0 else 1 - x)
        state = z + y
        G.append(ca.vertcat(*(e(state, u_check(i), p)[0] for e in events)))
    G.append(ca.vertcat(*(e(y_new, u_check(checks - 1), p)[0] for e in events)))
    # DOP853._estimate_error_norm, scaled by atol + max(|y|, |y_new|)·rtol
    tol = S.sym("tol", 2)  # rtol, atol
    scale = tol[1] + ca.fmax(ca.fabs(y), ca.fabs(y_new)) * tol[0]
    n5, n3 = ca.sumsqr(e5 / scale), ca.sumsqr(e3 / scale)
    denominator = ca.fmax(n5 + 0.01 * n3, 1e-300)  # both 0: the norm is 0
    error_norm = ca.fabs(h) * n5 / ca.sqrt(denominator * n)
    return ca.Function(
        "dop853_step",
        [y, f0, h, frac, u, p, tol],
        [y_new, f_new, error_norm, ca.horzcat(*F), ca.horzcat(*G)],
    )


class _Call:
    """``step_function``'s evaluation through preallocated buffers (``Function.buffer``)."""

    def __init__(self, fn: ca.Function, u: np.ndarray, p: np.ndarray, rtol, atol):
        n, m, c = fn.size1_in(0), fn.size1_out(4), fn.size2_out(4)
        self.y, self.f = np.zeros(n), np.zeros(n)
        self.h, self.frac = np.zeros(1), np.zeros(c - 1)
        self.u = np.zeros(fn.numel_in(4))  # column-major: inputs × times with a drive
        self.u[:] = np.ascontiguousarray(u, dtype=float).ravel() if u is not None else 0.0
        self.p = np.ascontiguousarray(p, dtype=float).ravel().copy()
        self.tol = np.array([rtol, atol], dtype=float)
        self.y_new, self.f_new, self.norm = np.zeros(n), np.zeros(n), np.zeros(1)
        self.F = np.zeros(n * 7)  # column-major n × 7
        self.G = np.zeros(max(m * c, 1))  # column-major m × c
        self.m, self.c, self.n = m, c, n
        self._buffer, self._trigger = fn.buffer()
        for i, a in enumerate((self.y, self.f, self.h, self.frac, self.u, self.p, self.tol)):
            self._buffer.set_arg(i, memoryview(a))
        for i, a in enumerate((self.y_new, self.f_new, self.norm, self.F, self.G)):
            self._buffer.set_res(i, memoryview(a))

    def __call__(self, y, f, h) -> float:
        self.y[:] = y
        self.f[:] = f
        self.h[0] = h
        self._trigger()
        return float(self.norm[0])


class CompiledDOP853(Dop853Frame):
    """:class:`scipy.integrate.DOP853` (its frame: :class:`~gaitopt.dop853_base.Dop853Frame`)
    with each step (and its dense output and the event functions at the check points) evaluated
    in one CasADi call.

    Parameters
    ----------
    fun : callable
        ``fun(t, x)``, the flow for SciPy's start-up (initial step selection).
    step : casadi.Function
        From :func:`step_function` for the same flow.
    u, p : numpy.ndarray
        The phase's input and parameters, constant over the phase (``u`` unused with ``drive``).
    t0, y0, t_bound, rtol, atol, max_step
        As for :class:`scipy.integrate.DOP853`.
    drive : callable, optional
        ``drive(times, stop) -> u`` (inputs × ``len(times)``): a time-varying input, for a
        ``step`` built with ``varying=True``, evaluated once per step try at the step's absolute
        times (s; :func:`step_function`'s columns, the last the step's end).  ``stop`` is None,
        or the index in ``stops`` of the time where the step ends: the drive then gives the
        input's limit from before that time in every column but the last, and the value from
        that time on in the last (what the event functions see there).  ``fun`` must use the
        same input.
    stops : array_like, optional
        Increasing times (s) where the drive's input may jump (an input profile's breakpoints):
        no step crosses one (a step that would ends there), so the error estimate and the dense
        output never straddle a jump, as in any integration of a piecewise-smooth
        right-hand side; after a stop the rate is ``rate(y, u)`` with the input from the stop on.
    rate : callable, optional
        ``rate(y, u)``, the flow at state ``y`` with input ``u`` (needed with ``stops``).

    After each step, :attr:`event_values` holds the event functions (rows) at the interior
    check points ``t_old + (t − t_old)·k/checks`` and at ``t`` (columns).
    """

    def __init__(
        self, fun, step: ca.Function, u, p, t0, y0, t_bound, drive=None, stops=(), rate=None,
        **options,
    ):  # fmt: skip
        super().__init__(fun, t0, y0, t_bound, **options)
        self._call = _Call(step, None if drive is not None else u, p, self.rtol, self.atol)
        self._call.frac[:] = np.arange(1, self._call.c) / self._call.c
        self._drive, self._rate = drive, rate
        self._stops = np.asarray(stops, dtype=float) if drive is not None else np.zeros(0)
        if self._stops.size and (rate is None or self.direction < 0):
            raise ValueError("stops need `rate` and a forward integration")
        # the fractions of a step at which the drive is evaluated (step_function's columns;
        # the last, the step's end, is set to t_new itself)
        self._times = np.concatenate([STAGE_FRACTIONS, self._call.frac, [1.0]])
        self._F = None
        self.event_values = None

    def _step_impl(self):  # scipy.integrate._ivp.rk.RungeKutta._step_impl, one call per try
        t, y = self.t, self.y
        min_step = 10 * np.abs(np.nextafter(t, self.direction * np.inf) - t)
        h_abs = min(max(self.h_abs, min_step), self.max_step)
        call, exponent = self._call, self.error_exponent
        step_rejected = False
        stop_index = int(np.searchsorted(self._stops, t, side="right"))  # the next stop after t
        stop = self._stops[stop_index] if stop_index < self._stops.size else np.inf
        while True:
            if h_abs < min_step:
                return False, self.TOO_SMALL_STEP
            h = h_abs * self.direction
            t_new = t + h
            if self.direction * (t_new - self.t_bound) > 0:
                t_new = self.t_bound
            wanted, landing = h_abs, t_new >= stop  # a step that would cross a stop ends there
            if landing:
                t_new = stop
            h = t_new - t
            h_abs = np.abs(h)
            if self._drive is not None:  # the input at the stage times and the check points
                times = t + h * self._times
                times[-1] = t_new
                drive = self._drive(times, stop_index if landing else None)
                call.u[:] = np.ravel(drive, order="F")
            error_norm = call(y, self.f, h)
            if error_norm < 1:
                factor = (
                    _MAX_FACTOR
                    if error_norm == 0
                    else min(_MAX_FACTOR, _SAFETY * error_norm**exponent)
                )
                if step_rejected:
                    factor = min(1, factor)
                h_abs *= factor
                if landing:  # a step shortened to a stop: the controller's size goes on
                    h_abs = max(h_abs, wanted)
                break
            h_abs *= max(_MIN_FACTOR, _SAFETY * error_norm**exponent)
            step_rejected = True
        self.h_previous = h
        self.y_old = y
        self.t = t_new
        self.y = call.y_new.copy()
        self.h_abs = h_abs
        self.f = call.f_new.copy()
        if self._drive is not None and landing:  # the rate with the input after the stop
            self.f = np.asarray(self._rate(self.y, drive[:, -1]), dtype=float).ravel()
        self._F = call.F.reshape(7, call.n).copy()  # column-major n × 7 = row-major 7 × n
        self.event_values = call.G[: call.m * call.c].reshape(call.c, call.m).T.copy()
        return True, None

    def _dense_output_impl(self):
        return Dop853Piece(self.t_old, self.t, self.y_old, self._F)  # SciPy's, restated
