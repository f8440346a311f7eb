"""The state of a batch simulation and its loop (:func:`gaitopt.simulation.batch.simulate_batch`).

Every quantity of :func:`gaitopt.simulation.phase.integrate_phase` and of the loop of
:func:`gaitopt.simulate` is an array with a row per start: the phase, time, state, rate, step size
(SciPy's DOP853 control: initial step, acceptance, growth and shrink factors, the smallest step),
the guards' last values and whether each is armed, the step bound of a short excursion.  Each
pass of :meth:`BatchPhases.loop` begins the phases of the starts that entered one (constraints
at the start, a state resting on a guard, the initial step), then makes one step try of every
running start, phase by phase: one mapped kernel call, the accepted rows checked for crossings
as ``integrate_phase`` checks them, the crossings located by Brent's method in lockstep, the
earliest admissible one per start fired (a reset into the next phase, or a terminal outcome).
"""

from __future__ import annotations

import numpy as np

from ..kernels.verify import CHECKS_PER_STEP, phase_events, verification_steps
from .batch_events import compiled_functions, scan_crossings
from .phase import _ARM, _CONSTRAINT_RATE, _CONSTRAINT_START
from .vectorised import Mapped
from .zeno import _ZENO_SPREAD, _ZENO_WINDOW

__all__ = ["BatchPhases", "STATUS", "RUNNING"]

STATUS = ("running", "completed", "fell", "standing", "timeout", "failed", "invalid start")
RUNNING, COMPLETED, FELL, STANDING, TIMEOUT, FAILED, INVALID = range(len(STATUS))
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0  # SciPy's (scipy/integrate/_ivp/rk.py)
_EXPONENT = -1 / 8  # DOP853's error exponent, -1/(order of the error estimator + 1)
_C = CHECKS_PER_STEP
_ZENO_KEEP = 2 * (_ZENO_WINDOW + 1) + 1  # impact times the accumulation test needs (lag 2)


def _rms(v: np.ndarray) -> np.ndarray:
    """SciPy's ``norm`` (RMS) of each row; the stacked product sums as ``np.linalg.norm``'s dot
    does (bit for bit: the step sizes then follow SciPy's exactly)."""
    v = np.ascontiguousarray(v)
    return np.sqrt((v[:, None, :] @ v[:, :, None])[:, 0, 0]) / v.shape[1] ** 0.5


class _Phase:
    """A phase's functions, each mapped over starts (an input and a parameter vector per
    start)."""

    def __init__(self, model, index: int, constraints: bool):
        phase = model.phases[index]
        self.phase, self.n = phase, phase.n
        self.n_tr = len(phase.transitions)
        self.constraints = phase.constraints if constraints else ()
        self.events = phase_events(phase, constraints)
        self.directions = np.array(
            [t.direction for t in phase.transitions] + [-1] * len(self.constraints), dtype=float
        )
        steps = verification_steps(type(model))
        if steps is not None:
            kernel = steps[(index, bool(constraints))]
        else:  # no kernel for this class: CasADi's interpreter, same function
            from ..dop853 import step_function

            kernel = step_function(phase.flow, self.events, _C)
        self.step = Mapped(kernel, shared=(3, 6))  # the check fractions and tolerances
        fs = compiled_functions(type(model))[index]

        def mapped(functions):
            return [Mapped(f) if f is not None else None for f in functions]

        self.flow = mapped(fs["flow"])[0]
        self.guards = mapped(fs["events"][: len(self.events)])
        self.admissible = mapped(fs["admissible"])
        self.resets = mapped(fs["resets"])
        self.rates = mapped(fs["rates"])
        self.curvatures = mapped(fs["curvatures"])
        self.constraint_rates = mapped(fs["constraint_rates"][: len(self.constraints)])
        self.probes = [Mapped(f) for f in fs["probes"][: len(self.events)]]
        self.brents = [Mapped(f) for f in fs["brents"][: len(self.events)]]


class BatchPhases:
    """Arrays of a batch simulation and the loop that advances them (see the module)."""

    def __init__(self, model, u, p, rtol, atol, max_phase_time, constraints, record_events):
        self.model, self.u, self.p = model, u, p  # a row per start each
        self.rtol, self.atol, self.max_time = rtol, atol, max_phase_time
        self.tol = np.array([rtol, atol])
        self.fractions = np.arange(1, _C) / _C
        self.phases = [_Phase(model, i, constraints) for i in range(len(model.phases))]
        self.n_max = max(ph.n for ph in self.phases)
        self.e_max = max(len(ph.events) for ph in self.phases)
        last = len(model.phases) - 1
        self.cycle_end = (last, 0)
        self.record = record_events
        self.log: list[tuple] = []

    # -- set-up and result ---------------------------------------------------------------------
    def start(self, rows: np.ndarray, full_state: bool, steps: int) -> None:
        m, model = rows.shape[0], self.model
        n0 = model.phases[0].n
        with np.errstate(all="ignore"):
            if full_state:
                x = rows.copy()
            else:
                lift = Mapped(model.section.lift)
                x = lift(m, rows, self.p)[0]
            rate = self.phases[0].flow(m, x, self.u, self.p)[0]
        valid = np.all(np.isfinite(x), axis=1) & np.all(np.isfinite(rate), axis=1)
        self.N, self.steps = m, steps
        self.status = np.where(valid, RUNNING, INVALID)
        self.outcome = np.full(m, "", dtype=object)
        self.phase = np.zeros(m, dtype=int)
        self.t = np.zeros(m)
        self.t0 = np.zeros(m)
        self.t_bound = np.zeros(m)
        self.y = np.zeros((m, self.n_max))
        self.y[:, :n0] = np.where(valid[:, None], x, 0.0)
        self.f = np.zeros((m, self.n_max))
        self.h_abs = np.zeros(m)
        self.max_step = np.full(m, np.inf)
        self.short = np.full(m, np.nan)
        self.new_step = np.ones(m, bool)
        self.rejected = np.zeros(m, bool)
        self.values = np.zeros((m, self.e_max))
        self.armed = np.zeros((m, self.e_max), bool)
        self.fresh = np.ones(m, bool)
        self.returns = np.zeros(m, dtype=int)
        self.sec_t = np.full((m, steps + 1), np.nan)
        self.sec_x = np.full((m, steps + 1, n0), np.nan)
        self.sec_t[:, 0] = 0.0
        self.sec_x[:, 0] = np.where(valid[:, None], x, np.nan)
        self.impacts = np.full((m, _ZENO_KEEP), np.nan)  # the last reset times, newest last
        self.n_impacts = np.zeros(m, dtype=int)
        self.accumulation = np.full(m, np.nan)
        if steps == 0:
            self.status[valid] = COMPLETED

    def result(self) -> dict:
        out = {
            "status": np.array(STATUS, dtype=object)[self.status].astype(str),
            "outcome": self.outcome.astype(str),
            "steps": self.returns.copy(),
            "section_times": self.sec_t,
            "section_states": self.sec_x,
            "t_end": self.t.copy(),
            "phase_end": self.phase.copy(),
            "accumulation_time": self.accumulation,
            "events": None,
        }
        if self.record:
            if self.log:
                cols = list(zip(*self.log, strict=True))
                out["events"] = {
                    "start": np.concatenate(cols[0]),
                    "t": np.concatenate(cols[1]),
                    "phase": np.concatenate(cols[2]),
                    "transition": np.concatenate(cols[3]).astype(str),
                    "before": np.concatenate(cols[4]),
                    "after": np.concatenate(cols[5]),
                }
                order = np.lexsort((out["events"]["t"], out["events"]["start"]))
                out["events"] = {k: v[order] for k, v in out["events"].items()}
            else:
                empty = np.zeros((0, self.n_max))
                out["events"] = {"start": np.zeros(0, int), "t": np.zeros(0),
                                 "phase": np.zeros(0, int), "transition": np.zeros(0, str),
                                 "before": empty, "after": empty}  # fmt: skip
        return out

    def _event(self, idx, t, phase, name, before, after) -> None:
        if not self.record:
            return
        pad = np.full((idx.size, self.n_max), np.nan)
        b, a = pad.copy(), pad.copy()
        b[:, : before.shape[1]] = before
        if after is not None:
            a[:, : after.shape[1]] = after
        names = np.broadcast_to(np.asarray(name, dtype=object), idx.shape)
        self.log.append((idx.copy(), np.asarray(t, float).copy(), np.full(idx.size, phase),
                         np.array(names, dtype=object), b, a))  # fmt: skip

    def _end(self, idx, status, outcome="") -> None:
        self.status[idx] = status
        if outcome:
            self.outcome[idx] = outcome

    # -- the loop ------------------------------------------------------------------------------
    def loop(self) -> None:
        while True:
            running = self.status == RUNNING
            if not running.any():
                return
            for k, ph in enumerate(self.phases):
                idx = np.flatnonzero(running & self.fresh & (self.phase == k))
                if idx.size:
                    self._begin(ph, k, idx)
            running = self.status == RUNNING
            for k, ph in enumerate(self.phases):
                idx = np.flatnonzero(running & ~self.fresh & (self.phase == k))
                if idx.size:
                    self._try(ph, k, idx)

    def _begin(self, ph: _Phase, k: int, idx: np.ndarray) -> None:
        """A phase begins (``simulate``'s checks, then ``integrate_phase``'s set-up)."""
        m, n, u, p = idx.size, ph.n, self.u[idx], self.p[idx]
        x, t = self.y[idx, :n], self.t[idx]
        keep = np.ones(m, bool)
        e, n_tr = len(ph.events), ph.n_tr
        raw = [ph.guards[j](m, x, u, p)[0][:, 0] for j in range(e)]  # each event where it begins
        known: dict[int, tuple[np.ndarray, np.ndarray]] = {}

        def rates(j: int, m=m, x=x, u=u, p=p) -> tuple[np.ndarray, np.ndarray]:
            """Signed ġ and g̈ of transition j at every start the phase began with."""
            if j not in known:
                d = ph.directions[j]
                known[j] = (d * ph.rates[j](m, x, u, p)[0][:, 0],
                            d * ph.curvatures[j](m, x, u, p)[0][:, 0])  # fmt: skip
            return known[j]

        # a constraint that fails where the phase begins (PhaseFunctions.violated_at_start)
        for j, c in enumerate(ph.constraints):
            if c.at_start:
                rate = ph.constraint_rates[j](m, x, u, p)[0][:, 0]
                bad = ~(rate > _CONSTRAINT_RATE)
            else:
                bad = raw[n_tr + j] < -_CONSTRAINT_START
            bad &= keep
            if bad.any():
                self._event(idx[bad], t[bad], k, c.outcome, x[bad], None)
                self._end(idx[bad], FELL, c.outcome)
                keep &= ~bad
        # at rest against a guard, pressing into it (_rests_on_guard)
        if self.steps:
            pending = keep & (self.returns[idx] < self.steps)
            for j, tr in enumerate(ph.phase.transitions):
                if tr.terminal or not pending.any():
                    continue
                on = pending & (np.abs(ph.directions[j] * raw[j]) <= _ARM)
                if not on.any():
                    continue
                g1, g2 = rates(j)
                rest = on & (np.abs(g1) <= _ARM) & (g2 > 0)
                self.accumulation[idx[rest]] = t[rest]
                self._end(idx[rest], STANDING)
                pending &= ~rest
                keep &= ~rest
        rows = keep
        idx, x, t, u, p, m = idx[keep], x[keep], t[keep], u[keep], p[keep], int(keep.sum())
        if not m:
            return
        # SciPy's RungeKutta.__init__: the rate and select_initial_step (Hairer et al., II.4)
        f0 = ph.flow(m, x, u, p)[0]
        t_bound = t + self.max_time
        interval = np.abs(t_bound - t)
        scale = self.atol + np.abs(x) * self.rtol
        d0, d1 = _rms(x / scale), _rms(f0 / scale)
        h0 = np.where((d0 < 1e-5) | (d1 < 1e-5), 1e-6, 0.01 * d0 / np.where(d1 > 0, d1, 1))
        h0 = np.minimum(h0, interval)
        f1 = ph.flow(m, x + h0[:, None] * f0, u, p)[0]
        d2 = _rms((f1 - f0) / scale) / h0
        with np.errstate(divide="ignore"):
            h1 = np.where(
                (d1 <= 1e-15) & (d2 <= 1e-15),
                np.maximum(1e-6, h0 * 1e-3),
                (0.01 / np.maximum(d1, d2)) ** (1 / 8),
            )
        self.h_abs[idx] = np.minimum(np.minimum(100 * h0, h1), interval)
        self.f[idx, :n] = f0
        self.t0[idx], self.t_bound[idx] = t, t_bound
        self.new_step[idx], self.rejected[idx] = True, False
        # the guards where the phase begins: armed if strictly on the pre-crossing side
        values = np.column_stack([ph.directions[j] * raw[j][rows] for j in range(e)])
        self.values[idx, :e] = values
        self.armed[idx] = False
        self.armed[idx, :e] = values < -_ARM
        # a short excursion to the armed side and back (_short_excursion): bound the steps
        bound = np.full(m, np.inf)
        for j in range(n_tr):
            unarmed = ~self.armed[idx, j]
            if not unarmed.any():
                continue
            g1, g2 = (r[rows] for r in rates(j))
            with np.errstate(all="ignore"):
                deep = values[:, j] - 0.5 * g1 * g1 / g2 < -0.5 * _ARM  # it can arm
                cand = unarmed & (g1 < 0) & (0 < g2) & deep
                bound = np.where(cand, np.minimum(bound, 0.5 * np.abs(g1) / g2), bound)
        short = np.isfinite(bound) & (bound > 0)
        self.short[idx] = np.where(short, bound, np.nan)
        self.max_step[idx] = np.where(short, bound, np.inf)
        self.fresh[idx] = False

    def _try(self, ph: _Phase, k: int, idx: np.ndarray) -> None:
        """One step try of each start in ``idx`` (CompiledDOP853._step_impl, one pass of its
        loop), then the accepted steps' events (integrate_phase)."""
        n, e, m = ph.n, len(ph.events), idx.size
        t, y, f = self.t[idx], self.y[idx, :n], self.f[idx, :n]
        min_step = 10 * np.abs(np.nextafter(t, np.inf) - t)
        h_abs = self.h_abs[idx]
        fresh = self.new_step[idx]
        h_abs = np.where(fresh, np.minimum(np.maximum(h_abs, min_step), self.max_step[idx]), h_abs)
        small = h_abs < min_step
        if small.any():
            self._end(idx[small], FAILED)
        t_new = t + h_abs
        t_new = np.where(t_new - self.t_bound[idx] > 0, self.t_bound[idx], t_new)
        h = t_new - t
        h_abs = np.abs(h)
        y_new, f_new, error, F, G = ph.step(m, y, f, h, self.fractions, self.u[idx],
                                            self.p[idx], self.tol)  # fmt: skip
        error = error[:, 0]
        accept = (error < 1) & ~small
        with np.errstate(all="ignore"):
            grow = _SAFETY * error**_EXPONENT
        factor = np.where(error == 0, _MAX_FACTOR, np.where(grow < _MAX_FACTOR, grow, _MAX_FACTOR))
        factor = np.where(self.rejected[idx] & ~(factor < 1), 1.0, factor)
        shrink = np.where(grow > _MIN_FACTOR, grow, _MIN_FACTOR)
        with np.errstate(all="ignore"):  # a failed start's step may be NaN: it has ended
            self.h_abs[idx] = np.where(accept, h_abs * factor, h_abs * shrink)
        self.rejected[idx] = ~accept
        self.new_step[idx] = accept
        if not accept.any():
            return
        a = np.flatnonzero(accept)
        i = idx[a]
        t_old, t_new, y_old, y_new = t[a], t_new[a], y[a], y_new[a]
        self.t[i], self.y[i, :n], self.f[i, :n] = t_new, y_new, f_new[a]
        signed = ph.directions[None, :, None] * G[a].reshape(-1, _C, e).transpose(0, 2, 1)
        values, armed = self.values[i, :e], self.armed[i, :e]
        before = np.concatenate([values[:, :, None], signed[:, :, :-1]], axis=2)
        crossing = np.any((before < 0) & (signed >= 0), axis=(1, 2))
        quiet = ~crossing
        self.armed[i[quiet], :e] = armed[quiet] | np.any(signed[quiet] < -_ARM, axis=2)
        self.values[i[quiet], :e] = signed[quiet, :, -1]
        best_t = np.full(a.size, np.inf)
        best_k = np.full(a.size, -1)
        best_x = np.zeros((a.size, n))
        c = np.flatnonzero(crossing)
        if c.size:
            F = F[a[c]].reshape(-1, 7, n)  # the dense output of the crossing rows only
            scan_crossings(self, ph, i, c, t_old, t_new, y_old, y_new, F, signed,
                           (best_t, best_k, best_x))  # fmt: skip
        short = ~np.isnan(self.short[i])
        if short.any():
            over = np.all(self.armed[i, : ph.n_tr], axis=1) | (
                t_new - self.t0[i] > 8 * self.short[i]
            )
            release = short & over
            self.max_step[i[release]], self.short[i[release]] = np.inf, np.nan
        fired = best_k >= 0
        if fired.any():
            self._fire(ph, k, i[fired], best_k[fired], best_t[fired], best_x[fired])
        ended = ~fired & (t_new - self.t_bound[i] >= 0)
        if ended.any():
            self._end(i[ended], TIMEOUT)

    def _fire(self, ph, k, idx, event, t, x_minus) -> None:
        """The located transitions: a terminal outcome, or the reset into the next phase."""
        self.t[idx] = t
        for ev in np.unique(event):
            rows = event == ev
            i, tt, xm = idx[rows], t[rows], x_minus[rows]
            if ev >= ph.n_tr:  # a unilateral constraint fails
                name = ph.constraints[ev - ph.n_tr].outcome
                self._event(i, tt, k, name, xm, None)
                self._end(i, FELL, name)
                continue
            tr = ph.phase.transitions[ev]
            if tr.terminal:
                self._event(i, tt, k, tr.name, xm, None)
                self._end(i, FELL, tr.name)
                continue
            x = ph.resets[ev](i.size, xm, self.u[i], self.p[i])[0]
            self._event(i, tt, k, tr.name, xm, x)
            target = tr.target
            self.phase[i] = target
            self.y[i, : x.shape[1]] = x
            self.fresh[i] = True
            if (k, int(ev)) == self.cycle_end or tr.returns_to_section:
                self.returns[i] += 1
                r = self.returns[i]
                self.sec_t[i, r] = tt
                self.sec_x[i, r] = x
            self._impact(i, tt)
            more = (self.returns[i] < self.steps) | ((self.phase[i] != 0) & (self.steps > 0))
            self._end(i[~more & (self.status[i] == RUNNING)], COMPLETED)

    def _impact(self, idx, t) -> None:
        """Record a reset's time; an accumulation of impacts ends the motion as standing
        (:func:`gaitopt.simulation.zeno.accumulation`, for every start at once)."""
        self.impacts[idx, :-1] = self.impacts[idx, 1:]
        self.impacts[idx, -1] = t
        self.n_impacts[idx] += 1
        count = self.n_impacts[idx]
        pending = self.returns[idx] < self.steps
        found = np.zeros(idx.size, bool)
        undecided = np.ones(idx.size, bool)
        for lag in (1, 2):
            needed = lag * (_ZENO_WINDOW + 1) + 1
            short = undecided & (count < needed)
            undecided &= ~short  # too few events: None (the lag-2 test is not tried)
            rows = np.flatnonzero(undecided)
            if not rows.size:
                break
            times = self.impacts[idx[rows], -needed:][:, ::-1][:, ::lag][:, ::-1]
            d = np.diff(times, axis=1)
            positive = np.all(d > 0, axis=1)
            with np.errstate(all="ignore"):
                r = d[:, 1:] / d[:, :-1]
                mean = np.mean(r, axis=1)
                hit = (
                    positive
                    & (mean < 1.0)
                    & np.all(
                        np.abs(r - mean[:, None]) <= _ZENO_SPREAD * (1.0 - mean[:, None]), axis=1
                    )
                )
                when = times[:, -1] + d[:, -1] * mean / (1.0 - mean)
            found[rows[hit]] = True
            self.accumulation[idx[rows[hit]]] = when[hit]
            undecided[rows[hit]] = False
        stop = found & pending & (self.status[idx] == RUNNING)
        self._end(idx[stop], STANDING)
        self.accumulation[idx[found & ~stop]] = np.nan
