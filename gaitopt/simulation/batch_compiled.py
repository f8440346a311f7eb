"""The batch simulation in one compiled call: :func:`run_compiled`.

Every start of a batch is simulated to its end inside ``gaitopt_batch``
(:mod:`gaitopt.kernels.batch_driver`): per start the loop of :func:`gaitopt.simulate` with each
phase one arc of the compiled simulation's driver (:mod:`gaitopt.kernels.arc_driver`, the arcs
of ``gaitopt.simulate``'s compiled backend, step for step), the constraint checks where a phase
begins, a state resting on a guard, the resets, the returns to the section and an accumulation
of impacts.  Python only lifts the starts, lays out the model's function addresses and reads the
columns back; there is no Python per step try, per arc or per start.  Used by
:func:`gaitopt.simulation.batch.simulate_batch` where the model class has a compiled arc library
and a C compiler is present (else the NumPy batch, :mod:`gaitopt.simulation.batch_phase`).
"""

from __future__ import annotations

import ctypes
import threading
from functools import lru_cache

import numpy as np

from ..kernels.arcs import ArcLibrary, address
from ..kernels.batch_driver import STATUS_CODES
from .vectorised import Mapped

__all__ = ["run_compiled"]

#: Events kept per start and step (and per phase of the model) before a start's buffer
#: overflows and it runs again with four times the room.
EVENTS_PER_STEP = 4
_OVERFLOW = STATUS_CODES.index("overflow")
#: The mapped lift and flow write their shared buffers: one thread at a time (a Dask worker's
#: threads may run two batches at once; the C call itself shares nothing).
_LOCK = threading.Lock()
_INVALID = STATUS_CODES.index("invalid start")


class _Layout:
    """A model's phases as ``gaitopt_batch`` reads them (addresses and flags, kept alive here)."""

    def __init__(self, structure, library: ArcLibrary, constraints: bool):
        phases = structure.phases
        P = len(phases)
        self.E = E = max(len(ph.transitions) + len(ph.constraints) for ph in phases)
        self.nmax = max(ph.n for ph in phases)
        self.names: list[str] = []  # an event's name by code phase * E + index
        self.phase_dims = np.zeros((P, 4), dtype=np.int32)
        self.trans = np.zeros((P, E, 3), dtype=np.int32)
        self.flags = np.zeros((P, E, 2), dtype=np.int32)
        self.dirs = np.zeros((P, E))
        self.fns = (ctypes.c_void_p * (10 * P))()
        self.resets = (ctypes.c_void_p * (2 * P * E))()
        self.starts = (ctypes.c_void_p * (2 * P))()
        cycle_end = (P - 1, 0)
        for i, ph in enumerate(phases):
            cons = ph.constraints if constraints else ()
            n_tr = len(ph.transitions)
            self.phase_dims[i] = (ph.n, n_tr + len(cons), n_tr, len(cons))
            names = [tr.name for tr in ph.transitions] + [c.outcome for c in cons]
            self.names += names + [""] * (E - len(names))
            for k, tr in enumerate(ph.transitions):
                closes = (i, k) == cycle_end or tr.returns_to_section
                target = tr.target if tr.target is not None else 0  # none for a terminal one
                self.trans[i, k] = (target, int(tr.terminal), int(closes))
                self.dirs[i, k] = tr.direction
                found = library.addresses(f"reset_{i}_{k}")
                if found is not None:
                    self.resets[2 * (i * E + k)], self.resets[2 * (i * E + k) + 1] = found
            for j, c in enumerate(cons):
                self.flags[i, j, 0] = int(c.at_start)
                self.flags[i, n_tr + j, 1] = int(c.at_end)
                self.dirs[i, n_tr + j] = -1.0
            table = library.pointers(i, bool(constraints))
            for j in range(10):
                self.fns[10 * i + j] = table[j]
            found = library.addresses(f"start_{i}") if cons else None
            if found is not None:
                self.starts[2 * i], self.starts[2 * i + 1] = found


@lru_cache(maxsize=64)
def _prepared(model_cls, library: ArcLibrary, constraints: bool):
    """A model class's layout and its section lift and phase-0 flow mapped over starts, with
    one parameter vector for all (shared) and with one per start (built once: they are the fixed
    cost of a call)."""
    structure = model_cls.structure()
    lift, flow = structure.section.lift, structure.phases[0].flow
    return (_Layout(structure, library, constraints),
            Mapped(lift, shared=(1,)), Mapped(flow, shared=(2,)),
            Mapped(lift), Mapped(flow))  # fmt: skip


def _starts(prepared, rows: np.ndarray, u: np.ndarray, p: np.ndarray, full_state: bool):
    """Phase-0 states of the rows and which are states of the model (finite, finite rate);
    ``p`` one parameter vector for all rows, or a row per start."""
    m = rows.shape[0]
    lift, flow = (prepared[1], prepared[2]) if p.ndim == 1 else (prepared[3], prepared[4])
    with np.errstate(all="ignore"), _LOCK:
        x = rows.copy() if full_state else lift(m, rows, p)[0]
        rate = flow(m, x, u, p)[0]
    valid = np.all(np.isfinite(x), axis=1) & np.all(np.isfinite(rate), axis=1)
    return np.ascontiguousarray(np.where(valid[:, None], x, 0.0)), valid


def _lanes(model_cls, constraints: bool, n_p: int):
    """``(gaitopt_lanes, its vector step table)`` where the model class has vector steps whose
    parameter vector has ``n_p`` entries (:mod:`gaitopt.kernels.lane_driver`), else None."""
    from ..kernels.batch_driver import lanes_library
    from ..kernels.vector_step import vector_steps

    steps = vector_steps(model_cls)
    run = lanes_library() if steps is not None else None
    if run is None:
        return None
    phases = model_cls.structure().phases
    if any(steps.n_p(i, constraints) != n_p for i in range(len(phases))):
        return None
    table = (ctypes.c_void_p * len(phases))(
        *(steps.address(i, constraints) for i in range(len(phases)))
    )
    return run, table, steps


def run_compiled(run, model, library: ArcLibrary, rows, u, p, full_state, steps, rtol, atol,
                 max_phase_time, constraints, record_events) -> dict:  # fmt: skip
    """Simulate every row in ``gaitopt_batch`` (``run``, the batch library's function): the
    columns of :class:`gaitopt.simulation.batch.BatchSimulation` (see there).  ``u``: a row per
    start; ``p``: one parameter vector for all starts, or a row per start (``dims[8]``, the
    parameter stride, 0 or n_p).  Where the model class has vector steps the starts run in
    ``gaitopt_lanes`` (the same outcomes to the bit, :data:`~gaitopt.kernels.vector_step.LANES`
    starts per step call)."""
    prepared = _prepared(type(model), library, bool(constraints))
    lay = prepared[0]
    N, n0 = rows.shape[0], model.phases[0].n
    u = np.ascontiguousarray(u, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    x0, valid = _starts(prepared, rows, u, p, full_state)
    shared_p = p.ndim == 1
    n_p = p.shape[-1]
    shared_u = u.shape[0] > 0 and bool(np.all(u == u[:1]))
    u_in = np.ascontiguousarray(u[:1] if shared_u else u).ravel()
    u_in = u_in if u_in.size else np.zeros(1)
    lanes = _lanes(type(model), bool(constraints), n_p) if N >= 2 else None
    # SciPy's solvers raise rtol to 100 eps (compiled.py: integrate_arc does the same)
    opts = np.array([max(float(rtol), 100 * np.finfo(float).eps), atol, max_phase_time])
    status = np.where(valid, 0, _INVALID).astype(np.int32)
    last = np.full(N, -1, dtype=np.int32)
    returns = np.zeros(N, dtype=np.int32)
    t_end, acc = np.zeros(N), np.full(N, np.nan)
    phase_end = np.zeros(N, dtype=np.int32)
    sec_t = np.full((N, steps + 1), np.nan)
    sec_x = np.full((N, steps + 1, n0), np.nan)
    cap = (EVENTS_PER_STEP * (steps + 1) * len(model.phases) + 8) if record_events else 0
    todo = np.arange(N)
    events = None
    while True:  # once, or again for the starts whose events overflowed their buffer
        k = todo.size
        n_u = len(model.inputs)
        u_stride, p_stride = 0 if shared_u else n_u, 0 if shared_p else n_p
        dims = [k, len(model.phases), lay.E, steps, n_u, u_stride, lay.nmax, cap, p_stride]
        dims = np.array(dims, dtype=np.int32)
        st, la, re, te, pe, ac = (
            a[todo].copy() for a in (status, last, returns, t_end, phase_end, acc)
        )
        sx = np.full((k, steps + 1, n0), np.nan)
        stt = np.full((k, steps + 1), np.nan)
        counts = np.zeros(max(k, 1), dtype=np.int32)
        ev_t = np.zeros(max(k * cap, 1))
        ev_code = np.zeros(max(k * cap, 1), dtype=np.int32)
        ev_b = np.zeros(max(k * cap * lay.nmax, 1))
        ev_a = np.zeros(max(k * cap * lay.nmax, 1))
        ui = u_in if shared_u else np.ascontiguousarray(u[todo]).ravel()
        xi = np.ascontiguousarray(x0[todo])
        pi = p if shared_p else np.ascontiguousarray(p[todo]).ravel()
        pi = pi if pi.size else np.zeros(1)
        call = (*map(address, (dims, lay.phase_dims, lay.trans, lay.flags, lay.dirs)),
                ctypes.addressof(lay.fns), ctypes.addressof(lay.resets),
                ctypes.addressof(lay.starts),
                *map(address, (ui, pi, opts, xi, st, la, re, te, pe, ac, stt, sx, counts,
                               ev_t, ev_code, ev_b, ev_a)))  # fmt: skip
        if lanes is not None and k >= 2:
            extra = np.array([n_p, dims.size], dtype=np.int32)
            code = lanes[0](*call, ctypes.addressof(lanes[1]), address(extra))
        else:
            code = run(*call)
        if code:
            raise RuntimeError(f"the compiled batch simulation of {model.name} failed")
        status[todo], last[todo], returns[todo] = st, la, re
        t_end[todo], phase_end[todo], acc[todo] = te, pe, ac
        sec_t[todo], sec_x[todo] = stt, sx
        if record_events:
            got = _events(lay, todo, counts[:k], cap, ev_t, ev_code, ev_b, ev_a, st)
            events = got if events is None else _merge(events, got)
        again = np.flatnonzero(st == _OVERFLOW)
        if not again.size:
            break
        todo, cap = todo[again], 4 * cap
        status[todo] = 0
    fell = status == STATUS_CODES.index("fell")
    names = np.array(lay.names, dtype=object)
    outcome = np.where(fell, names[np.maximum(last, 0)], "").astype(str)
    if record_events:
        order = np.lexsort((events["t"], events["start"]))
        events = {key: v[order] for key, v in events.items()}
    return {
        "status": np.array(STATUS_CODES, dtype=object)[status].astype(str),
        "outcome": outcome,
        "steps": returns.astype(int),
        "section_times": sec_t,
        "section_states": sec_x,
        "t_end": t_end,
        "phase_end": phase_end.astype(int),
        "accumulation_time": acc,
        "events": events,
    }


def _events(lay, todo, counts, cap, ev_t, ev_code, ev_b, ev_a, st) -> dict:
    """The events of one call as columns (starts that overflowed left out: they run again)."""
    keep = st != _OVERFLOW
    counts = np.where(keep, counts, 0)
    first = np.repeat(np.arange(counts.size) * cap - np.cumsum(counts) + counts, counts)
    rows = (first + np.arange(first.size)).astype(int)  # start i's events: i * cap + 0, 1, …
    codes = ev_code[rows] if rows.size else np.zeros(0, dtype=np.int32)
    names = np.array(lay.names, dtype=object)
    return {
        "start": np.repeat(todo, counts).astype(int),
        "t": ev_t[rows] if rows.size else np.zeros(0),
        "phase": (codes // lay.E).astype(int),
        "transition": names[codes].astype(str) if rows.size else np.zeros(0, dtype=str),
        "before": ev_b.reshape(-1, lay.nmax)[rows] if rows.size else np.zeros((0, lay.nmax)),
        "after": ev_a.reshape(-1, lay.nmax)[rows] if rows.size else np.zeros((0, lay.nmax)),
    }


def _merge(a: dict, b: dict) -> dict:
    return {key: np.concatenate([a[key], b[key]]) for key in a}
