"""Batched simulation: many starts of one model stepped together, each with its own step size,
error control, events and phase.

:func:`simulate_batch` runs the algorithm of :func:`gaitopt.simulate` (SciPy's DOP853 step-size
control driving the verification's compiled DOP853 step, :mod:`gaitopt.kernels.verify`; strict,
directional, admissible guard crossings checked at the step's check points and located by Brent's
method on the step's dense output; unilateral constraints as named terminal events; resets into
the next phase; a state resting on a guard and an accumulation of impacts as ``"standing"``) on
N starts at once: every array of the integrator has a row per start, each row has its own step
size, rejections, armed guards and phase, and masks retire the starts that end.  One step try of
all the starts in a phase is one call of the compiled step ``map``-ped over them
(:class:`~gaitopt.simulation.vectorised.Mapped`); crossings are confirmed, located (compiled
probes of the dense output and SciPy's Brent iteration unrolled, for every bracket at once:
:mod:`gaitopt.simulation.batch_events`) and reset for all the starts that cross in that step at
once.  There is no Python per start and step.

It is the same method as :func:`gaitopt.simulate`, not a new one: its events agree with the
per-start simulation to rounding (the tests check 1e-10), and like it, it is a different method
from the shooting's fixed-step RK8 kernels (:mod:`gaitopt.shooting`), so it stays an independent
check of them.  Each start has its own constant input and its own parameters (``inputs``,
``params``: a row per start, or one for all); no feedforward, no input policy, no terrain
within a call — a step-to-step policy on rough ground is a sequence of one-step calls
(:func:`gaitopt.control.closed_loop_batch`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import GaitoptInputError, ParameterError
from .batch_phase import STATUS, BatchPhases

__all__ = ["simulate_batch", "BatchSimulation", "STATUS", "compiled_batch"]


@dataclass
class BatchSimulation:
    """What :func:`simulate_batch` returns: one row per start (columnar).

    Attributes
    ----------
    model : HybridModel
        The model.
    status : numpy.ndarray of str
        Per start, as :attr:`gaitopt.Simulation.status`: ``"completed"``, ``"fell"`` (a terminal
        transition or a unilateral constraint: :attr:`outcome` names it), ``"standing"`` (at rest
        on a guard, or impacts accumulating), ``"timeout"``, ``"failed"`` (integrator), or
        ``"invalid start"`` (not a finite state with a finite rate).
    outcome : numpy.ndarray of str
        The terminal event's name for ``"fell"`` (``"trip"``, ``"fall"``…), else ``""``.
    steps : numpy.ndarray of int
        Returns to the section completed.
    section_times : numpy.ndarray
        ``N × (steps + 1)`` times (s) of the returns (the start first), NaN after the last.
    section_states : numpy.ndarray
        ``N × (steps + 1) × n`` phase-0 states there, NaN after the last.
    t_end : numpy.ndarray
        Time (s) where each simulation ended.
    phase_end : numpy.ndarray of int
        Phase in which it ended.
    accumulation_time : numpy.ndarray
        For ``"standing"``: where the motion comes to rest (s); else NaN.
    events : dict of numpy.ndarray or None
        With ``record_events``: every event, columns ``start``, ``t``, ``phase``, ``transition``
        (its name), ``before``, ``after`` (states, NaN-padded to the largest phase; ``after`` NaN
        for a terminal event), in order of time per start.
    elapsed : float
        Wall-clock seconds.
    """

    model: Any
    status: np.ndarray
    outcome: np.ndarray
    steps: np.ndarray
    section_times: np.ndarray
    section_states: np.ndarray
    t_end: np.ndarray
    phase_end: np.ndarray
    accumulation_time: np.ndarray
    events: dict[str, np.ndarray] | None = None
    elapsed: float = 0.0
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def success(self) -> np.ndarray:
        """Per start: the simulation completed its steps."""
        return self.status == "completed"

    def __len__(self) -> int:
        return len(self.status)

    def message(self, i: int) -> str:
        """One start's outcome in words."""
        status, k = str(self.status[i]), int(self.steps[i])
        phase = self.model.phases[int(self.phase_end[i])].name
        t = float(self.t_end[i])
        if status == "fell":
            return f"{self.outcome[i]} at t = {t:.6g} s after {k} steps in phase '{phase}'"
        if status == "standing":
            return f"at rest (standing) by t = {self.accumulation_time[i]:.6g} s after {k} steps"
        return end_message(status, k, t, phase)

    def events_of(self, i: int) -> list[tuple[float, int, str, np.ndarray, np.ndarray | None]]:
        """One start's events as ``(t, phase, transition, before, after)`` (``after`` None for
        a terminal event); needs ``record_events``."""
        if self.events is None:
            raise GaitoptInputError("events were not recorded; use record_events=True")
        rows = np.flatnonzero(self.events["start"] == i)
        out = []
        for r in rows:
            phase = int(self.events["phase"][r])
            n = self.model.phases[phase].n
            after = self.events["after"][r]
            after = after[~np.isnan(after)] if not np.all(np.isnan(after)) else None
            out.append(
                (
                    float(self.events["t"][r]),
                    phase,
                    str(self.events["transition"][r]),
                    self.events["before"][r, :n].copy(),
                    after,
                )
            )
        return out


def end_message(status: str, steps: int, t: float, phase: str) -> str:
    """A batched run's end in words for the statuses every batch words alike: ``completed``
    after ``steps`` returns at ``t`` (s), ``timeout`` or ``failed`` in ``phase``, else an
    invalid start (``fell`` and ``standing`` are worded by each caller)."""
    if status == "completed":
        return f"{steps} steps in {t:.6g} s"
    if status == "timeout":
        return f"no transition within the phase time limit in phase '{phase}' (t = {t:.6g})"
    if status == "failed":
        return f"integrator failed in phase '{phase}' at t = {t:.6g}"
    return "not a state of the model (not finite, or its rate of change is not)"


def simulate_batch(
    model: Any,
    starts: Sequence[Sequence[float]] | np.ndarray,
    *,
    steps: int = 10,
    inputs: Sequence[float] | np.ndarray | None = None,
    params: Mapping[str, Any] | np.ndarray | None = None,
    full_state: bool = False,
    rtol: float = 1e-11,
    atol: float = 1e-12,
    max_phase_time: float = 30.0,
    constraints: bool = True,
    record_events: bool = False,
    backend: str = "auto",
) -> BatchSimulation:
    """Simulate many starts of a hybrid model together, each for ``steps`` returns to the
    section (the algorithm of :func:`gaitopt.simulate`, batched).

    Parameters
    ----------
    model : HybridModel or str
        The model.
    starts : array_like
        N rows: section coordinates (the section's order, their units), or with ``full_state``
        full phase-0 states.  Rows that are not a state of the model (not finite, or where the
        equations of motion overflow) end at once with the status ``"invalid start"``.
    steps : int
        Returns to the Poincaré section to simulate.
    inputs : array_like, optional
        The per-step input, constant: one vector for every start, or N rows (one per start).
        Default: the model's nominal (passive) input.
    params : mapping or array_like, optional
        Parameters per start: a mapping name → value (one for every start) or N values (one per
        start), the other parameters the model's; or an N × n_p array (every parameter, in
        :meth:`~gaitopt.HybridModel.parameter_specs` order, their units).  Each start is then
        simulated as ``gaitopt.simulate(model.replace(**its parameters), ...)`` would (a rough
        ground's height per start, a slope per start).  Every value is checked as the model's
        constructor checks it (its range and the model's own conditions).  Default: the
        model's parameters for every start.
    full_state : bool
        Whether ``starts`` are full phase-0 states rather than section coordinates.
    rtol, atol, max_phase_time, constraints
        As in :func:`gaitopt.simulate`.
    record_events : bool
        Keep every event (times, phases, states) in :attr:`BatchSimulation.events`.
    backend : str
        ``"compiled"``: every start run to its end in one compiled call
        (:mod:`gaitopt.simulation.batch_compiled`: the arcs of :func:`gaitopt.simulate`'s compiled
        backend, step for step, with the hybrid loop around them in C); ``"numpy"``: the starts
        stepped together from NumPy, one mapped call of the compiled step per step try
        (:mod:`gaitopt.simulation.batch_phase`); ``"auto"`` (default): compiled where the model
        class has a compiled arc library (a C compiler present, ``GAITOPT_COMPILE`` not 0), else
        NumPy.  Both give the events of :func:`gaitopt.simulate` (the tests: 1e-10).

    Returns
    -------
    BatchSimulation
    """
    import time

    from ..arguments import check_count, check_positive
    from ..errors import MAX_SIMULATION_STEPS
    from ..models import as_model

    started = time.perf_counter()
    model = as_model(model)
    steps = check_count(
        "steps", steps, 0, MAX_SIMULATION_STEPS, "time and memory grow with every step "
        "(gaitopt.errors.MAX_SIMULATION_STEPS); simulate in pieces, each from the last state"
    )  # fmt: skip
    rtol, atol = check_positive("rtol", rtol, "1e-11"), check_positive("atol", atol, "1e-12")
    max_phase_time = check_positive("max_phase_time", max_phase_time, "30")
    rows = np.asarray(starts, dtype=float)
    if rows.ndim == 1:
        rows = rows[None, :]
    width = model.phases[0].n if full_state else len(model.section.coordinates)
    if rows.ndim != 2 or rows.shape[1] != width or rows.shape[0] < 1:
        what = "phase-0 states" if full_state else "section coordinates"
        names = model.phases[0].states if full_state else model.section.coordinates
        raise GaitoptInputError(
            f"`starts` must be rows of {width} {what} ({', '.join(names)}), got shape "
            f"{np.shape(starts)}"
        )
    n_u = len(model.inputs)
    u = model.nominal_input() if inputs is None else np.asarray(inputs, dtype=float)
    u = np.broadcast_to(u, (rows.shape[0], n_u)) if u.ndim == 1 and u.size == n_u else u
    if u.shape != (rows.shape[0], n_u) or not np.all(np.isfinite(u)):
        raise GaitoptInputError(
            f"`inputs` must be {n_u} finite values ({', '.join(model.inputs) or 'none'}) or one "
            f"row of them per start, got shape {np.shape(inputs)}"
        )
    p = start_parameters(model, params, rows.shape[0])
    library = _compiled(model, backend)
    if library is not None:
        from .batch_compiled import run_compiled

        out = run_compiled(library[0], model, library[1], rows, u, p, full_state, steps, rtol,
                           atol, max_phase_time, constraints, record_events)  # fmt: skip
    else:
        p_rows = np.ascontiguousarray(np.broadcast_to(p, (rows.shape[0], p.shape[-1])))
        run = BatchPhases(model, np.ascontiguousarray(u, dtype=float), p_rows, rtol, atol,
                          max_phase_time, constraints, record_events)  # fmt: skip
        run.start(rows, full_state, steps)
        run.loop()
        out = run.result()
    return BatchSimulation(
        model=model,
        **out,
        elapsed=time.perf_counter() - started,
        settings={
            "steps": steps,
            "rtol": rtol,
            "atol": atol,
            "max_phase_time": max_phase_time,
            "backend": "compiled" if library is not None else "numpy",
        },  # fmt: skip
    )


_BACKENDS = ("auto", "compiled", "numpy")


def start_parameters(model: Any, params: Any, n: int) -> np.ndarray:
    """The parameter vectors of ``n`` starts from :func:`simulate_batch`'s ``params``: one
    vector (n_p,) where every start has the same, else n × n_p rows.

    Raises
    ------
    ParameterError
        An unknown name, a shape that is neither one value nor ``n``, a value that is not a
        finite number, outside its range or failing the model's own conditions (one line).
    """
    specs = model.parameter_specs()
    names = [spec.name for spec in specs]
    base = model.p
    if params is None:
        return base
    what = f"{len(names)} parameters ({', '.join(names)})"
    try:
        if isinstance(params, Mapping):
            rows = np.array(np.broadcast_to(base, (n, base.size)))
            for name, value in params.items():
                if name not in names:
                    raise ParameterError(
                        f"`params`: {model.name} has no parameter {name!r}; its parameters: "
                        f"{', '.join(names)}"
                    )
                column = np.asarray(value, dtype=float)
                if column.shape not in ((), (n,)):
                    raise ParameterError(
                        f"`params`[{name!r}] must be one number or {n} (one per start), got "
                        f"shape {column.shape}"
                    )
                rows[:, names.index(name)] = column
        else:
            rows = np.asarray(params, dtype=float)
            if rows.shape == (base.size,):
                rows = np.array(np.broadcast_to(rows, (n, base.size)))
            elif rows.shape != (n, base.size):
                raise ParameterError(
                    f"`params` must be a mapping name → value(s), or {n} rows (one per start) of "
                    f"{what}, got shape {rows.shape}"
                )
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ParameterError(
            f"`params` must be numbers: a mapping name → value(s) or rows of {what} ({exc})"
        ) from None
    for j, spec in enumerate(specs):  # ParameterSpec.contains, every start at once
        col = rows[:, j]
        with np.errstate(invalid="ignore"):
            above = col > spec.low if spec.low_open else col >= spec.low
            below = col < spec.high if spec.high_open else col <= spec.high
            ok = np.isfinite(col) & above & below
            if spec.integer:
                ok &= col == np.floor(col)
        if not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            unit = "" if spec.unit == "1" else f" {spec.unit}"
            raise ParameterError(
                f"`params`: {model.name}'s parameter `{spec.name}` = {col[i]:g} (start {i}) is "
                f"out of range; valid: {spec.range_text()}{unit}, default {spec.default:g}"
            )
    unique, first = np.unique(rows, axis=0, return_index=True)
    for row, i in zip(unique, first, strict=True):  # the model's own conditions (check())
        try:
            model.replace(**dict(zip(names, map(float, row), strict=True)))
        except ParameterError as exc:
            raise ParameterError(f"`params` (start {int(i)}): {exc}") from None
    if unique.shape[0] == 1:
        return unique[0].copy()
    return np.ascontiguousarray(rows)


def compiled_batch(model: Any) -> bool:
    """Whether :func:`simulate_batch` runs ``model``'s starts compiled (``backend="auto"``): then
    a start costs the same in a batch of one as in a batch of thousands."""
    return _compiled(model, "auto") is not None


def _compiled(model: Any, backend: str):
    """``(gaitopt_batch, the model class's arc library)`` where ``backend`` asks for the compiled
    batch and it is there, else None (the NumPy batch)."""
    if backend not in _BACKENDS:
        raise GaitoptInputError(f"`backend` must be one of {', '.join(_BACKENDS)}, got {backend!r}")
    if backend == "numpy":
        return None
    from ..kernels.arcs import arc_library
    from ..kernels.batch_driver import batch_library

    run = batch_library()
    library = arc_library(type(model)) if run is not None else None
    if library is None:
        if backend == "compiled":
            raise GaitoptInputError(
                f"`backend` 'compiled': no compiled batch for {model.name} (no C compiler: "
                f"$GAITOPT_CC, default gcc, or GAITOPT_COMPILE=0); use backend='auto' or 'numpy'"
            )
        return None
    return run, library
