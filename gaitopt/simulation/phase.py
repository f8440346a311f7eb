"""One phase of a simulation: the phase's functions at fixed inputs and parameters
(:class:`PhaseFunctions`: the right-hand side, guards, admissibility, unilateral constraints as
events) and the integration of one phase until an admissible directional crossing, located on
the step's dense output (SciPy's ``solve_ivp`` event logic, step by step)."""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

from ..hybrid import Phase, rate_along
from ..kernels.verify import CHECKS_PER_STEP

__all__ = ["PhaseFunctions", "integrate_phase", "locate_crossing"]

# A guard must have been below -_ARM (in units of the guard) before it can fire.
_ARM = 1e-10


class _Buffered:
    """A CasADi function evaluated through preallocated buffers (``Function.buffer``): about
    50× less call overhead than ``f(x, u, p)``, which dominates small right-hand sides."""

    def __init__(self, f: ca.Function, u: np.ndarray, p: np.ndarray):
        self._x = np.zeros(f.size1_in(0))
        self._u = np.array(u, dtype=float)  # its own copy: a feedforward rewrites it
        self._p = np.array(p, dtype=float)
        self._out = np.zeros(f.numel_out(0))
        self._buffer, self._trigger = f.buffer()
        for i, a in enumerate((self._x, self._u, self._p)):
            self._buffer.set_arg(i, memoryview(a))
        self._buffer.set_res(0, memoryview(self._out))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        self._x[:] = x
        self._trigger()
        return self._out.copy()


class PhaseFunctions:
    """Numerical callables of one phase, for fixed ``u`` and ``p``.

    Events are numbered: the phase's transitions first, then its unilateral constraints, each of
    which is a terminal event where ``c`` falls through zero (a trip, a leg that pulls)."""

    def __init__(
        self,
        phase: Phase,
        u: np.ndarray,
        p: np.ndarray,
        constraints: bool = True,
        model_cls: type | None = None,
        index: int | None = None,
    ):
        self.phase = phase
        self._compiled_key = (model_cls, index, bool(constraints))
        self.u, self.p = u, p
        self.constraints = phase.constraints if constraints else ()
        self._flow = _Buffered(phase.flow, u, p)
        self._guards = [_Buffered(tr.guard, u, p) for tr in phase.transitions]
        self._guards += [_Buffered(c.function, u, p) for c in self.constraints]
        self._directions = [tr.direction for tr in phase.transitions]
        self._directions += [-1] * len(self.constraints)
        self._admissible = [
            _Buffered(tr.admissible, u, p) if tr.admissible is not None else None
            for tr in phase.transitions
        ] + [None] * len(self.constraints)
        self._jac = None
        self._events = [tr.guard for tr in phase.transitions]
        self._events += [c.function for c in self.constraints]

    def step_function(self, varying: bool = False) -> ca.Function:
        """One DOP853 step with this phase's event functions (:mod:`gaitopt.dop853`): compiled
        with the model class's kernels (:mod:`gaitopt.kernels.verify`) where known.  With
        ``varying``, the input is given at each stage time and check point (a feedforward):
        CasADi's interpreter, built once per phase (no compiled kernel)."""
        from ..dop853 import step_function

        if varying:
            return step_function(self.phase.flow, self._events, _CHECKS_PER_STEP, varying=True)
        model_cls, index, constraints = self._compiled_key
        if model_cls is not None:
            from ..kernels.verify import verification_steps

            steps = verification_steps(model_cls)
            if steps is not None:
                return steps[(index, constraints)]
        return step_function(self.phase.flow, self._events, _CHECKS_PER_STEP)

    @property
    def events(self) -> int:
        """Number of events (transitions and constraints)."""
        return len(self._guards)

    _drive = None  # (feedforward, section time, step) for a time-varying input
    _feedback = None  # (feedback, section time, step, phase) for a state-feedback input
    _last_feedback = None  # (t, x, u) of the last call

    def feedback_input(self, t: float, x: np.ndarray) -> np.ndarray:
        """The state feedback's input ``feedback(t − t_section, x, phase, step)`` at time ``t``
        (s) and state ``x`` (input units)."""
        last = self._last_feedback
        if last is not None and last[0] == t and np.array_equal(last[1], x):
            return last[2]  # the event functions at one instant and state share one call
        feedback, t_section, step, phase = self._feedback
        u = np.asarray(feedback(t - t_section, x, phase, step), dtype=float).ravel()
        self._last_feedback = (t, np.array(x, dtype=float), u)
        return u

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        if self._feedback is not None:  # state feedback u(t − t_section, x, phase, step)
            self._flow._u[:] = self.feedback_input(t, x)
        elif self._drive is not None:  # feedforward u(t − t_section, step) in the flow
            feedforward, t_section, step = self._drive
            self._flow._u[:] = feedforward(t - t_section, step)
        return self._flow(x)

    def vectorised_drive(self) -> dict | None:
        """The feedforward for :class:`gaitopt.dop853.CompiledDOP853` (keywords ``drive``,
        ``stops``, ``rate``) when it evaluates many times at once, else None (a plain callable:
        one time per call, SciPy's stepper).

        A feedforward qualifies with a method ``vectorised(t, step)`` (inputs × ``len(t)``, ``t``
        an array of times since the section, equal to calling it at each); with ``breaks(step)``
        too (times since the section where the input or a derivative may jump, as an optimal
        gait's piecewise-polynomial profile has at its mesh points and its end), no step crosses
        one: each step integrates one smooth piece, and the input's limit from before a break
        drives the step that ends there, while the event functions at the break see the value
        from the break on (the input at that instant, as everywhere)."""
        if self._drive is None:
            return None
        feedforward, t_section, step = self._drive
        vectorised = getattr(feedforward, "vectorised", None)
        if not callable(vectorised):
            return None
        n_u = self._flow._u.size
        breaks = getattr(feedforward, "breaks", None)
        local = np.zeros(0)
        if callable(breaks):
            local = np.sort(np.asarray(breaks(step), dtype=float).ravel())
            # the distinct breaks after 0 (np.unique's values, without its import of numpy.ma)
            local = local[(local > 0) & np.append(True, local[1:] != local[:-1])]
        before = np.nextafter(local, -np.inf)  # the last time before each break

        def drive(times: np.ndarray, stop: int | None) -> np.ndarray:
            t = np.asarray(times, dtype=float) - t_section
            if stop is not None:  # a step ending at a break: the limit from before it
                np.minimum(t, before[stop], out=t)
                t[-1] = local[stop]  # ... but the events there see the value from it on
            u = np.asarray(vectorised(t, step), dtype=float)
            return u.reshape(n_u, t.size)

        flow = self._flow

        def rate(x: np.ndarray, u: np.ndarray) -> np.ndarray:
            flow._u[:] = u
            return flow(x)

        return {"drive": drive, "stops": t_section + local, "rate": rate}

    def jac(self, t: float, x: np.ndarray) -> np.ndarray:
        if self._jac is None:
            self._jac = self.phase.flow.factory("jac", ["x", "u", "p"], ["jac:flow:x"])
        return np.asarray(self._jac(x, self.u, self.p))

    def at(self, t: float | None, x: np.ndarray | None = None) -> None:
        """Set the event functions' input to the feedforward's value at time ``t`` (s), or the
        state feedback's at ``t`` and state ``x``: guards, admissibility and unilateral
        constraints see the input the flow sees (a stance foot's normal force depends on the
        torque applied at that instant).  No-op without either."""
        if t is None:
            return
        if self._feedback is not None:
            if x is None:
                return
            u = self.feedback_input(t, x)
        elif self._drive is not None:
            feedforward, t_section, step = self._drive
            u = feedforward(t - t_section, step)
        else:
            return
        for f in (*self._guards, *(a for a in self._admissible if a is not None)):
            f._u[:] = u

    def signed_guard(self, k: int, x: np.ndarray, t: float | None = None) -> float:
        self.at(t, x)
        return self._directions[k] * float(self._guards[k](x)[0])

    def admissible(self, k: int, x: np.ndarray, t: float | None = None) -> bool:
        self.at(t, x)
        n_tr = len(self.phase.transitions)
        if k >= n_tr and self.constraints[k - n_tr].at_end:
            # A constraint that vanishes where the phase ends (a foot touching down) reaches 0
            # with the cycle's guard: that is the touchdown, not a violation.
            return abs(float(self._guards[0](x)[0])) > _CONSTRAINT_START
        a = self._admissible[k]
        return a is None or float(a(x)[0]) > 0

    def violated_at_start(self, x: np.ndarray, t: float | None = None) -> tuple[int, str] | None:
        """A constraint that fails where the phase begins (at time ``t``): one that starts active
        (``at_start``) and does not rise (a trailing foot that does not lift off), or one already
        negative."""
        self.at(t, x)
        varying = self._drive is not None or self._feedback is not None
        u = self._guards[0]._u if varying else self.u
        n_tr = len(self.phase.transitions)
        for j, c in enumerate(self.constraints):
            value = float(self._guards[n_tr + j](x)[0])
            unit = f" {c.unit}" if c.unit else ""
            if c.at_start:
                rate = float(rate_along(self.phase.flow, c.function)(x, u, self.p))
                if not rate > _CONSTRAINT_RATE:
                    return (
                        n_tr + j,
                        f"'{c.name}' starts at 0 and does not rise (rate {rate:.3g}{unit}/s)",
                    )
            elif value < -_CONSTRAINT_START:
                return n_tr + j, f"'{c.name}' fails at the start ({value:.3g}{unit})"
        return None


# A constraint that starts active must rise faster than this (its unit per second); one that does
# not must not start below -_CONSTRAINT_START (its unit).  The certificate of both front doors
# (gaitopt.orbit.certificate.CONSTRAINT_TOL) uses the same.
_CONSTRAINT_RATE = 1e-9
_CONSTRAINT_START = 1e-9


def _short_excursion(
    funcs: PhaseFunctions, x0: np.ndarray, armed: np.ndarray, values: np.ndarray
) -> float | None:
    """A step bound that lets the guard checks see a short excursion at the phase start.

    A phase that starts on a guard (a rimless wheel rocking onto a spoke at a few mm/s) may leave
    it to the armed side and come back within a fraction of one adaptive step: the checks at
    the step's interior points would miss it, and the wheel would sink through the ground.  For
    each transition that starts unarmed and moves to its armed side (signed rate ``ġ < 0``) with
    a curvature that brings it back (``g̈ > 0``), the excursion lasts about ``τ = 2|ġ|/g̈``
    (second-order Taylor); the returned bound ``τ/4`` holds until every guard is armed.  An
    excursion that cannot arm its guard is left out: from the signed value ``v₀`` (``values``)
    it reaches ``v₀ − ġ²/(2 g̈)``, and unless that passes half the arming depth ``_ARM`` (a factor
    2 of margin on the Taylor estimate) the guard can neither arm nor fire on it.  (A phase that
    starts at an apex with ``ż ≈ 1e-16`` otherwise gets a bound near 1e-17 s, below the smallest
    step SciPy's solvers take at ``t ≈ 5 s``, 10 ulp of ``t``: the integrator stopped there.)
    None if no such excursion."""
    bound = np.inf
    for k, tr in enumerate(funcs.phase.transitions):
        if armed[k]:
            continue
        rate = rate_along(funcs.phase.flow, tr.guard)
        g1 = tr.direction * float(rate(x0, funcs.u, funcs.p))
        g2 = tr.direction * float(rate_along(funcs.phase.flow, rate)(x0, funcs.u, funcs.p))
        if g1 < 0 < g2 and values[k] - 0.5 * g1 * g1 / g2 < -0.5 * _ARM:
            bound = min(bound, 0.5 * abs(g1) / g2)
    return float(bound) if np.isfinite(bound) and bound > 0 else None


def _rests_on_guard(funcs: PhaseFunctions, x0: np.ndarray) -> str | None:
    """The transition whose guard the state rests on, pressing into it, or None.

    A state exactly on a guard (signed value 0), with zero rate (``ġ = 0``) and an acceleration
    toward the firing side (``g̈ > 0``), is held there by the contact the guard describes (the
    rimless wheel at rest on two spokes): the limit of the accumulating impacts, reached."""
    for k, tr in enumerate(funcs.phase.transitions):
        if tr.terminal or abs(funcs.signed_guard(k, x0)) > _ARM:
            continue
        rate = rate_along(funcs.phase.flow, tr.guard)
        g1 = tr.direction * float(rate(x0, funcs.u, funcs.p))
        g2 = tr.direction * float(rate_along(funcs.phase.flow, rate)(x0, funcs.u, funcs.p))
        if abs(g1) <= _ARM and g2 > 0:
            return tr.name
    return None


def locate_crossing(g: Callable[[float], float], a: float, b: float) -> float:
    """The time in ``(a, b]`` where the signed guard ``g`` goes from negative to non-negative.

    The caller has found ``g < 0`` at ``a`` and ``g >= 0`` at ``b`` (an integrator step's check
    points, ``a`` at least the arc's last time stamp); ``g`` is evaluated on the step's dense
    output.  The root is located by ``brentq`` (``xtol`` 1e-15, ``rtol`` 4 eps; SciPy's,
    restated in :func:`gaitopt.brent.brentq` to the bit without importing SciPy), with three
    cases at the ends, where floating point decides:

    * brentq's answer may be ``a`` itself: its tolerance (a few ulps) admits the end with the
      smaller ``|g|``, which is ``a`` when the sign change lies within a few ulps after it.
      That happens where a converged closed loop's event falls on an input profile's last
      break (the step stops at the break with ``g`` at -3e-15, the crossing one ulp later: the
      level compass optimum stabilised, after 20 orbits).  ``a`` is not the crossing
      (``g(a) < 0``), and returning it would repeat the arc's last time stamp (an
      ``OdeSolution`` with a zero-length piece: a ``ValueError``); the first float after ``a``
      with ``g >= 0`` is found by bisection in floating point instead.
    * ``g(b) < 0`` on the dense output although the caller's value at ``b`` (from the step's
      end state, or the compiled event values) is non-negative: the sign change lies in the
      last bits of the step, and ``b`` is the crossing.
    * ``g(a) >= 0`` on the dense output although the caller's value there is negative: the
      sign change lies in the first bits, and the first float after ``a`` is the crossing.

    Parameters
    ----------
    g : callable
        ``g(t) -> float``, the signed guard on the step's dense output.
    a, b : float
        The bracket, ``a < b``.

    Returns
    -------
    float
        The crossing time, ``a < t <= b``.
    """
    from ..brent import brentq

    if not g(b) >= 0:
        return b
    after = float(np.nextafter(a, np.inf))
    if not g(a) < 0:
        return min(after, b)
    t = brentq(g, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    if t > a:
        return float(t)
    lo, hi = a, b  # g(lo) < 0 <= g(hi); halve until they are adjacent floats
    while True:
        mid = lo + 0.5 * (hi - lo)
        if not lo < mid < hi:
            return float(hi)
        if g(mid) >= 0:
            hi = mid
        else:
            lo = mid


def _held(t0: float, x0: np.ndarray):
    """A zero-length arc at ``t0`` holding ``x0`` (a phase whose first step failed)."""
    from .dense import ConstantPiece, Pieces

    return Pieces([t0, t0], [ConstantPiece(t0, t0, np.asarray(x0, dtype=float))])


# Interior points per integrator step where the guards are also checked (see
# gaitopt.kernels.verify.CHECKS_PER_STEP).
_CHECKS_PER_STEP = CHECKS_PER_STEP


def integrate_phase(funcs: PhaseFunctions, solver_cls, t0, x0, rtol, atol, max_time, method):
    """Integrate one phase until an admissible directional crossing; locate it.

    A guard fires where its signed value goes from negative to non-negative after having been
    below ``-_ARM`` in this phase (strict crossings); signs are checked at the step ends and at
    ``_CHECKS_PER_STEP - 1`` interior points of each step, roots located by ``brentq`` on the
    step's dense output (:func:`locate_crossing`: a time after the bracket's start, so an arc's
    time stamps increase strictly).  An integrator failure is returned as the status
    ``"failed"`` with the arc integrated so far.

    ``solver_cls`` is SciPy's ``OdeSolver`` class of ``method``, or None: imported here only
    where it runs (another method than DOP853, or a state feedback or plain-callable
    feedforward); DOP853 with a constant or vectorised input runs
    :class:`gaitopt.dop853.CompiledDOP853`, which needs no :mod:`scipy.integrate`.  The arc is
    an ``OdeSolution`` of the steps' interpolants (:class:`gaitopt.simulation.dense.Pieces`)."""
    from .dense import Pieces as OdeSolution  # SciPy's OdeSolution for increasing stamps

    n_tr = funcs.events
    drive = funcs.vectorised_drive()  # a feedforward evaluated at a step's times at once
    if (
        method == "DOP853"
        and funcs._feedback is None
        and (funcs._drive is None or drive is not None)
    ):
        # one CasADi call per step (same method); with a feedforward, its values at the step's
        # stage times and check points are the call's input
        from ..dop853 import CompiledDOP853

        step = funcs.step_function(varying=drive is not None)
        solver = CompiledDOP853(funcs.rhs, step, funcs.u, funcs.p, t0, x0, t0 + max_time,
                                rtol=rtol, atol=atol, **(drive or {}))  # fmt: skip
    else:
        if solver_cls is None:  # SciPy's stepper (scipy.integrate: 0.3–0.5 s on first use)
            import scipy.integrate

            solver_cls = getattr(scipy.integrate, method)
        kwargs = {"jac": funcs.jac} if method in ("Radau", "LSODA") else {}
        solver = solver_cls(funcs.rhs, t0, x0, t0 + max_time, rtol=rtol, atol=atol, **kwargs)
    directions = np.array(funcs._directions, dtype=float)[:, None]
    values = np.array([funcs.signed_guard(k, x0, t0) for k in range(n_tr)], dtype=float)
    armed = values < -_ARM
    short = _short_excursion(funcs, x0, armed, values)
    if short is not None:
        solver.max_step = short
    ts = [t0]
    interpolants = []
    while True:
        solver.step()
        if solver.status == "failed":
            # The arc up to the last step that succeeded (its time stamps and interpolants pair
            # up); without one, a zero-length arc holding the start state, so that the failure
            # is a result (status "failed") whose arc can still be sampled, not an exception.
            if not interpolants:
                return _held(t0, x0), None, None, "failed"
            return OdeSolution(ts, interpolants), None, None, "failed"
        t_old, t_new = solver.t_old, solver.t
        dense = solver.dense_output()
        grid = np.linspace(t_old, t_new, _CHECKS_PER_STEP + 1)
        compiled = getattr(solver, "event_values", None)
        if compiled is not None:  # the event functions at the check points, from the step call
            signed = directions * compiled
        else:
            states = [dense(tt) for tt in grid[1:-1]] + [solver.y]
            signed = np.array(
                [
                    [funcs.signed_guard(k, x, tt) for x, tt in zip(states, grid[1:], strict=True)]
                    for k in range(n_tr)
                ]
            )
        best = None
        signed = np.reshape(signed, (n_tr, _CHECKS_PER_STEP))
        before = np.concatenate([values[:, None], signed[:, :-1]], axis=1)
        crossing = bool(np.any((before < 0) & (signed >= 0)))
        if not crossing:  # no sign change in this step: only the arming and the last values
            armed |= np.any(signed < -_ARM, axis=1)
            values[:] = signed[:, -1]
        for k in range(n_tr if crossing else 0):
            previous, was_armed = values[k], armed[k]
            for j in range(1, _CHECKS_PER_STEP + 1):
                current = float(signed[k, j - 1])
                if was_armed and previous < 0 <= current and compiled is not None:
                    # confirm on the dense output itself (the bracket brentq is given)
                    end = dense(grid[j]) if j < _CHECKS_PER_STEP else solver.y
                    ends = [
                        funcs.signed_guard(k, dense(grid[j - 1]), grid[j - 1]),
                        funcs.signed_guard(k, end, grid[j]),
                    ]
                    previous, current = ends
                if was_armed and previous < 0 <= current:
                    t_hit = locate_crossing(
                        lambda tt, k=k, dense=dense: funcs.signed_guard(k, dense(tt), tt),
                        grid[j - 1],
                        grid[j],
                    )
                    x_hit = dense(t_hit)
                    if funcs.admissible(k, x_hit, t_hit):
                        if best is None or t_hit < best[0]:
                            best = (t_hit, k, x_hit)
                        break
                was_armed = was_armed or current < -_ARM
                previous = current
            armed[k] = was_armed
            values[k] = previous
        interpolants.append(dense)
        if short is not None and (
            np.all(armed[: len(funcs.phase.transitions)]) or t_new - t0 > 8 * short
        ):
            solver.max_step, short = np.inf, None  # the excursion is over: full steps
        if best is not None:
            ts.append(best[0])
            return OdeSolution(ts, interpolants), best[1], best[2], None
        ts.append(t_new)
        if solver.status == "finished":
            return OdeSolution(ts, interpolants), None, None, "timeout"
