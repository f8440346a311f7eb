"""The rows of a collocation, phase by phase (the equations of
:class:`~gaitopt.optimize.collocation.Collocation`): its unknowns (:func:`unknowns`: the named
blocks of ``w`` with their bounds), the row list (:class:`Rows`: ``g`` with its bounds, named in
:class:`~gaitopt.optimize.radau.Group` s), each phase's dynamics, guard, crossing direction,
admissibility, unilateral constraints, limits, reset and periodicity (:func:`phase_rows`), and
the orbit's rows and objective (:func:`finish`).  The running cost's rows are
:mod:`gaitopt.optimize.collocation_cost`'s; ``col`` is the transcription being built."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..errors import GaitoptInputError
from ..hybrid import rate_along
from .boundary_arcs import boundary_nodes
from .collocation_kernels import defect_block, node_block
from .collocation_limits import add_limits
from .nodes import substitute
from .radau import Group, _Blocks
from .spectral import add_spectral_bound

__all__ = [
    "Phase",
    "Rows",
    "Terms",
    "Unknowns",
    "check_structure",
    "clearance_margin",
    "finish",
    "phase_margin",
    "phase_rows",
    "unknowns",
]


@dataclass
class Rows:
    """The constraint rows ``g`` with their bounds; each :meth:`add` is a named group."""

    groups: list[Group]
    g: list[Any] = field(default_factory=list)
    lbg: list[np.ndarray] = field(default_factory=list)
    ubg: list[np.ndarray] = field(default_factory=list)

    def add(self, name: str, expr: ca.MX, low: float = 0.0, high: float = 0.0) -> None:
        """Rows ``low ≤ expr ≤ high`` (an equation where equal), as the group ``name``."""
        expr = ca.vec(expr)
        start = sum(e.shape[0] for e in self.g)
        self.g.append(expr)
        self.lbg.append(np.full(expr.shape[0], low))
        self.ubg.append(np.full(expr.shape[0], high))
        self.groups.append(Group(name, start, expr.shape[0], low == high))


@dataclass
class Unknowns:
    """The symbols of the unknowns: ``s``, ``free``, the parameter vector ``p_in`` and ``p``
    (with the free entries replaced), per phase ``X`` (the first lifted), ``U``, ``T``, ``A``
    (accelerations of implicit dynamics), ``Th`` (arc fractions), ``Pp``, ``Pm`` (slack
    powers)."""

    s: Any
    free: Any
    p_in: Any
    p: Any
    X: list[Any] = field(default_factory=list)
    U: list[Any] = field(default_factory=list)
    T: list[Any] = field(default_factory=list)
    A: list[Any] = field(default_factory=list)
    Th: list[Any] = field(default_factory=list)
    Pp: list[Any] = field(default_factory=list)
    Pm: list[Any] = field(default_factory=list)


@dataclass
class Terms:
    """The cost's terms as the phases add them."""

    cost: list[Any] = field(default_factory=list)
    work: list[Any] = field(default_factory=list)
    effort: list[Any] = field(default_factory=list)
    distance: list[Any] = field(default_factory=list)
    brake: list[Any] = field(default_factory=list)  # ∫uᵢ² dt on braking arcs
    step_vectors: list[Any] = field(default_factory=list)


@dataclass
class Phase:
    """What the cost rows of phase ``k`` read of its transcription: interval lengths ``hs``,
    the collocation points' states ``Xc``, its inputs ``Uk``, duration ``Tk``, end state and
    input and its label."""

    hs: list[Any]
    Xc: Any
    Uk: Any
    Tk: Any
    Xk: Any
    x_end: Any
    u_end: Any
    label: str


def check_structure(col: Any, structure: list | None, work: bool) -> None:
    """A structure (arcs per phase) fits the orbit and the mesh, and has a reason to be."""
    if structure is None:
        return
    N = col.N
    if len(structure) != len(col.chain):
        raise GaitoptInputError("Collocation: a structure needs arcs for every phase")
    if not work and not any(any(a.bounds) or a.touches for arcs in structure for a in arcs):
        raise GaitoptInputError(
            "Collocation: the arcs of a cost without powers are those of input bounds "
            "or of touch points"
        )
    for arcs in structure:
        if sum(a.intervals for a in arcs) != N:
            raise GaitoptInputError(
                f"Collocation: the arcs of a phase must share its {N} mesh intervals"
            )


def unknowns(col: Any, structure: list | None, slack: bool) -> Unknowns:
    """The named blocks of ``w`` with their bounds (``col.blocks``), in order: ``s``, ``free``,
    then per phase ``X``, ``U``, ``T`` and, where used, ``A``, ``Theta``, ``Pplus``,
    ``Pminus``."""
    problem, model = col.problem, col.model
    phases, section = model.phases, model.section
    N, d, m = col.N, col.d, col.m
    n_u = len(model.inputs)
    n_p = len(model.parameter_specs())
    B = _Blocks()
    col.blocks = B
    lo0, hi0 = problem.state_bounds_of(0)
    s = B.add("s", m, 1, lo0[col.section_index], hi0[col.section_index])
    flo, fhi = problem.free_bounds()
    free = B.add("free", len(problem.free), 1, flo, fhi)
    p_in = ca.MX.sym("p", n_p)
    entries = [p_in[i] for i in range(n_p)]
    for j, i in enumerate(problem.free_index):
        entries[i] = free[j]
    p = ca.vertcat(*entries) if entries else p_in
    ulo, uhi = problem.input_bounds()
    v = Unknowns(s, free, p_in, p)
    for k, i in enumerate(col.chain):
        n = phases[i].n
        lo, hi = problem.state_bounds_of(i)
        cols = N * d if k == 0 else N * d + 1
        Xk = B.add(f"X{k}", n, cols, lo, hi)
        if k == 0:
            Xk = ca.horzcat(section.lift(s, p), Xk)
        v.X.append(Xk)
        v.U.append(B.add(f"U{k}", n_u, N * d, ulo, uhi))
        v.T.append(B.add(f"T{k}", 1, 1, 1e-3, problem.max_phase_time))
        v.A.append(B.add(f"A{k}", n // 2, N * d) if col.implicit is not None else None)
        if structure is not None:
            v.Th.append(B.add(f"Theta{k}", len(structure[k]), 1, 1e-6, 1.0))
        if slack:
            v.Pp.append(B.add(f"Pplus{k}", n_u, N * d, 0.0, np.inf))
            v.Pm.append(B.add(f"Pminus{k}", n_u, N * d, 0.0, np.inf))
    return v


def phase_rows(col: Any, add: Any, v: Unknowns, terms: Terms, k: int, i: int) -> Phase:
    """The rows of phase ``k`` (model phase ``i``) but its running cost's: arc fractions, held
    impulses, dynamics (collocation defects; the equations of motion of implicit dynamics),
    the guard at the end, not crossed before, its direction and admissibility, the unilateral
    constraints at the nodes and the start, the limits, the reset to the next phase, and
    continuous inputs or periodicity; the step's distance into ``terms``."""
    problem, model, structure = col.problem, col.model, col.structure
    N, d = col.N, col.d
    ulo, uhi = problem.input_bounds()
    p, X, U, T, Th = v.p, v.X, v.U, v.T, v.Th
    phase = model.phases[i]
    tr = phase.transitions[0]
    label = phase.name if len(col.chain) == 1 else f"{phase.name} #{k + 1}"
    Xk, Uk, Tk = X[k], U[k], T[k]
    if structure is None:
        hs = [Tk / N] * N
    else:  # interval lengths from the arc fractions
        add(f"arc fractions ({label})", ca.sum1(Th[k]) - 1.0)
        hs = [
            Tk * Th[k][a] / arc.intervals
            for a, arc in enumerate(structure[k])
            for _ in range(arc.intervals)
        ]
    Xc = Xk[:, 1:]
    for r in problem.impulsive_index:  # an impulse: one value per step, held
        if ulo[r] == uhi[r]:  # switched off by its bounds: already constant
            continue
        name = model.inputs[r]
        add(f"impulse '{name}' held over {label}", Uk[r, :-1] - Uk[r, -1])
    Ak = v.A[k]
    Yk = node_block(col, i, Xc, Uk, Ak, p)
    _dynamics_rows(col, add, phase, label, Xk, Uk, Ak, Yk, hs, p)
    x_end, u_end = Xk[:, -1], Uk[:, -1]
    _guard_rows(col, add, phase, label, Xc, Uk, Tk, hs, x_end, u_end, p, k)
    u_start = ca.mtimes(Uk[:, :d], ca.DM(col.u_at_start))
    _constraint_rows(col, add, phase, label, T, hs, k, Xk, Uk, Yk, u_start, p)
    add_limits(col, add, k, i, label, Xk, Uk, u_start, p)
    x_next = tr.reset(x_end, u_end, p)
    if k + 1 < len(col.chain):
        add(f"reset after {label}", X[k + 1][:, 0] - x_next)
    smooth = [r for r in range(len(model.inputs)) if r not in problem.impulsive_index]
    if problem.continuous_inputs and smooth and (k + 1) % len(model.phases):
        # The profile has no jump inside a step (GaitProblem.continuous_inputs): the next
        # phase's input polynomial starts where this one ends.
        u_next = ca.mtimes(U[k + 1][:, :d], ca.DM(col.u_at_start))
        add(f"inputs continuous after {label}", u_next[smooth] - u_end[smooth])
    else:
        add("periodicity", x_next[col.section_index] - v.s)
    step = problem.step_vector(i, x_end, p)
    if step is not None:
        terms.step_vectors.append(step)
        terms.distance.append(ca.norm_2(step))
    return Phase(hs, Xc, Uk, Tk, Xk, x_end, u_end, label)


def _dynamics_rows(
    col: Any, add: Any, phase: Any, label: str, Xk: Any, Uk: Any, Ak: Any, Yk: Any, hs: list,
    p: Any,
) -> None:  # fmt: skip
    """The collocation equations ``X_j C − h_j f`` of each interval (and, for implicit
    dynamics, ``M(q) a − rhs`` at the points, the equations of motion)."""
    N, d = col.N, col.d
    Xc = Xk[:, 1:]
    if col.implicit is None:
        F = phase.flow.map(N * d)(Xc, Uk, p) if Yk is None else Yk[: phase.n, :]
    else:  # ẋ = (q̇, a) with M(q) a = rhs(q, q̇, u) as constraints
        nq = phase.n // 2
        if Yk is None:
            M, rhs = col.implicit.map(N * d)(Xc[:nq, :], Xc[nq:, :], Uk, p)
            Ms = ca.horzsplit(M, nq)
            balance = ca.horzcat(*[ca.mtimes(Ms[c], Ak[:, c]) - rhs[:, c] for c in range(N * d)])
        else:
            balance = Yk[:nq, :]
        add(f"equations of motion ({label})", balance)
        F = ca.vertcat(Xc[nq:, :], Ak)
    if Yk is not None and col.implicit is not None:
        # Every defect is a function of its interval's own variables: one more block
        # of kernels (the interval's defects, compiled), not differentiated per mesh.
        add(f"dynamics ({label})", defect_block(col, Xk, Ak, hs))
    else:
        defects = []
        for j in range(N):
            Xi = Xk[:, j * d : j * d + d + 1]
            F_j = F[:, j * d : (j + 1) * d]
            defects.append(ca.mtimes(Xi, ca.DM(col.C)) - hs[j] * F_j)
        add(f"dynamics ({label})", ca.horzcat(*defects))


def _guard_rows(
    col: Any, add: Any, phase: Any, label: str, Xc: Any, Uk: Any, Tk: Any, hs: list,
    x_end: Any, u_end: Any, p: Any, k: int,
) -> None:  # fmt: skip
    """The phase ends on its guard, crossing it in its direction, admissibly (and, without
    an admissibility test, not before, except on phase ``k``'s boundary arcs of the guard)."""
    tr = phase.transitions[0]
    add(f"guard '{tr.name}' at the end of {label}", tr.guard(x_end, u_end, p))
    if tr.admissible is None and Xc.shape[1] > 1:
        # A guard without an admissibility test ends the phase wherever it is crossed
        # (the simulator's event): it keeps its side, direction · g ≤ 0, at the
        # interior nodes (the kneed walker's knee must not straighten early).
        inner = tr.guard.map(Xc.shape[1] - 1)(Xc[:, :-1], Uk[:, :-1], p)
        inner = tr.direction * inner + phase_margin(col, hs, Tk)[:, :-1]
        on_guard = boundary_nodes(col, k)  # boundary arcs hold the guard at 0 by equalities
        if on_guard is not None:
            inner = inner[:, [j for j in range(Xc.shape[1] - 1) if not on_guard[j]]]
        add(f"'{tr.name}' not before the end of {label}", inner, -np.inf)
    rate = rate_along(phase.flow, tr.guard)(x_end, u_end, p)
    add(
        f"crossing direction of '{tr.name}' ({label})",
        tr.direction * rate,
        col.problem.min_crossing_rate,
        np.inf,
    )
    if tr.admissible is not None:
        add(
            f"admissibility of '{tr.name}' ({label})",
            tr.admissible(x_end, u_end, p),
            0.0,
            np.inf,
        )


def _constraint_rows(
    col: Any, add: Any, phase: Any, label: str, T: list, hs: list, k: int, Xk: Any, Uk: Any,
    Yk: Any, u_start: Any, p: Any,
) -> None:  # fmt: skip
    """The phase's unilateral constraints ``c ≥ 0`` at its nodes (a length keeps the
    clearance margin) and at its start (rising there where it starts at zero)."""
    N, d = col.N, col.d
    margin, margin0 = clearance_margin(col, T, hs, k)
    first_row = phase.n // 2 if col.implicit is not None else phase.n
    for r, c in enumerate(phase.constraints):
        nodes = Xk[:, 1:-1] if c.at_end else Xk[:, 1:]
        unodes = Uk[:, :-1] if c.at_end else Uk
        # A length (a foot's height) keeps the problem's clearance margin.
        lift = margin if c.unit == "m" else ca.MX.zeros(1, N * d)
        if nodes.shape[1]:
            if Yk is None:
                values = c.function.map(nodes.shape[1])(nodes, unodes, p)
            else:  # the node kernel's row of this constraint
                values = Yk[first_row + r, : nodes.shape[1]]
            values = values - (lift[:, :-1] if c.at_end else lift)
            add(f"'{c.name}' ({label})", values, 0.0, np.inf)
        if c.at_start:
            rate_c = rate_along(phase.flow, c.function)(Xk[:, 0], u_start, p)
            add(f"'{c.name}' rising at the start of {label}", rate_c, 0.0, np.inf)
        else:
            add(
                f"'{c.name}' at the start of {label}",
                c.function(Xk[:, 0], u_start, p) - (margin0 if c.unit == "m" else 0.0),
                0.0,
                np.inf,
            )


def clearance_margin(col, T: list[ca.MX], hs: list[Any], k: int) -> tuple[Any, Any]:
    """The clearance margin ``c · sin(π t / T_step)`` (m) at the collocation nodes of phase
    ``k`` (a 1 × N·d row) and at its start, ``t`` the time since its step's section
    (:attr:`GaitProblem.clearance`; zeros when it is 0)."""
    c = col.problem.clearance
    if not c:
        return ca.MX.zeros(1, col.N * col.d), 0.0
    n_cycle = len(col.model.phases)
    first = n_cycle * (k // n_cycle)
    before = ca.sum1(ca.vertcat(*T[first:k])) if k > first else ca.MX(0)
    step = ca.sum1(ca.vertcat(*T[first : first + n_cycle]))
    times, edge = [], before
    for h in hs:
        times.extend(edge + h * tau for tau in col.tau[1:])
        edge = edge + h
    row = ca.horzcat(*times)
    return c * ca.sin(np.pi * row / step), c * ca.sin(np.pi * before / step)


def phase_margin(col, hs: list[Any], Tk: ca.MX) -> Any:
    """``m · sin(π t / T)`` at the collocation nodes of a phase (a 1 × N·d row), ``t`` the
    time since the phase began (:attr:`GaitProblem.guard_margin`; zeros when it is 0)."""
    m = col.problem.guard_margin
    if not m:
        return ca.MX.zeros(1, col.N * col.d)
    times, edge = [], ca.MX(0)
    for h in hs:
        times.extend(edge + h * tau for tau in col.tau[1:])
        edge = edge + h
    return m * ca.sin(np.pi * ca.horzcat(*times) / Tk)


# -- evaluation ---------------------------------------------------------------------------


def finish(col: Any, rows: Rows, v: Unknowns, terms: Terms) -> None:
    """The orbit's rows (fixed period, step length, speed), the spectral bound's, the cost and
    objective, and the NLP (``col.nlp``, ``col.outer``, bounds, outputs)."""
    problem, B = col.problem, col.blocks
    add, T, p, p_in = rows.add, v.T, v.p, v.p_in
    work = problem.cost_kind in ("work", "cot")
    slack = work and col.structure is None
    period = ca.sum1(ca.vertcat(*T))
    total = ca.sum1(ca.vertcat(*terms.distance)) if terms.distance else ca.MX(0)
    # The fixed period, step length and speed are the bounds of their rows, not constants in
    # the graph: problems that differ only in them (a library's points) share one compiled
    # NLP.  The speed row is distance / period (the period is a sum of durations bounded
    # away from 0); with the period and step length both fixed it is implied (the statement
    # checks they agree) and left out, so the rows stay independent.
    if problem.period is not None:
        add("period", period, problem.period, problem.period)
    if problem.step_length is not None:
        add("step length", total / problem.steps, problem.step_length, problem.step_length)
    if problem.speed is not None and (problem.period is None or problem.step_length is None):
        add("speed", total / period, problem.speed, problem.speed)
    if work:
        positive_work = ca.sum1(ca.vertcat(*terms.work))
        if problem.cost_kind == "cot":
            weight = problem.total_mass(p) * problem.gravity(p)
            J = positive_work / (weight * total)
        else:
            J = positive_work
    else:
        J = ca.sum1(ca.vertcat(*terms.cost))
    # ρ(A) ≤ R: the variational equations, A and the Schur–Cohn–Jury rows (spectral.py).
    col.spectral = (
        None
        if problem.max_multiplier is None
        else add_spectral_bound(col, B, add, v.X, v.U, T, v.Th, p, p_in)
    )
    w = B.vector()
    col._w, col._p = w, p_in
    objective = J
    if slack and problem.regularisation > 0:
        # Positive work alone leaves singular arcs (inputs that chatter between the nodes);
        # a small effort term selects a smooth optimum.  The reported cost is J alone.
        objective = J + problem.regularisation * ca.sum1(ca.vertcat(*terms.effort))
    braking = ca.sum1(ca.vertcat(*terms.brake)) if terms.brake else ca.MX(0)
    if terms.brake:  # the singular braking arcs' least-effort torque; reported apart
        objective = J + problem.braking_effort * braking
    g_all = ca.vertcat(*rows.g)
    positive_work = ca.sum1(ca.vertcat(*terms.work)) if work else ca.MX(np.nan)
    # The node outputs Y stand for the node function at the nodes (gaitopt.optimize.nodes):
    # the solver assembles its derivatives from compiled kernels; everyone else sees the
    # ordinary graph.
    col.outer = (objective, g_all)
    objective, g_all, J, positive_work, braking = substitute(
        col.node_blocks, [objective, g_all, J, positive_work, braking]
    )
    col.nlp = {"x": w, "p": p_in, "f": objective, "g": g_all}
    col.lbx = np.concatenate(B.lb)
    col.ubx = np.concatenate(B.ub)
    col.lbg = np.concatenate(rows.lbg)
    col.ubg = np.concatenate(rows.ubg)
    col._outputs = {
        "cost": J,
        "period": period,
        "distance": total,
        "p_used": p,
        "positive_work": positive_work,
        "braking_effort": braking,
    }
    col._X, col._U, col._T = v.X, v.U, T
    col._theta = v.Th
