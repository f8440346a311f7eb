"""Crossings of a batch simulation (:mod:`gaitopt.simulation.batch_phase`): the check points of
``integrate_phase`` scanned for every start whose step changed a guard's sign, each bracket
confirmed on the dense output, located by Brent's method and tested for admissibility — with
the dense output, the guard and Brent's iteration in compiled functions of all the rows at once.

Per event of a phase two CasADi functions are built (and compiled with the phase's other batch
functions): ``probe(F, y_old, t_old, h, t, u, p) -> (g, x, a)``, the signed guard ``g`` at the
dense output's state ``x`` at time ``t`` and the crossing's admissibility value ``a`` (> 0:
admissible), and ``brent(F, y_old, t_old, h, lo, hi, u, p) -> (root, converged)``, SciPy's
``brentq`` (its C code's iteration, step for step, ``xtol`` 1e-15, ``rtol`` 4 eps) unrolled
:data:`ITERATIONS` times with the rows that converge frozen; a row that needs more is finished
by :func:`gaitopt.simulation.vectorised.brentq` (the same iteration again, in NumPy).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from ..hybrid import rate_along
from ..kernels.verify import CHECKS_PER_STEP, phase_events
from .phase import _ARM, _CONSTRAINT_START
from .vectorised import brentq

__all__ = ["ITERATIONS", "compiled_functions", "event_functions", "scan_crossings", "staged_brent"]

#: Brent iterations unrolled in the compiled locator (the dense-output guards here mostly take
#: 6–10; a row that needs more is finished in NumPy).
ITERATIONS = 12
_XTOL, _RTOL = 1e-15, 4 * np.finfo(float).eps
_C = CHECKS_PER_STEP


def _dense(F, y_old, t_old, h, t):
    """Dop853DenseOutput at ``t``, the same operations in the same order (SX; NumPy's is
    :func:`gaitopt.simulation.vectorised.dense`)."""
    x = (t - t_old) / h
    y = F[:, 6]
    for i in range(7):
        if i:
            y = y + F[:, 6 - i]
        y = y * x if i % 2 == 0 else y * (1 - x)
    return y + y_old


def _layout(model_cls) -> list[dict[str, list]]:
    """Per phase, the functions the batch evaluates besides the step, by role (None where a
    transition has none): flow, events (guards, then constraints), admissibility, resets, the
    guards' first and second rates along the flow, the constraints' rates."""
    out = []
    for phase in model_cls.structure().phases:
        rates = [rate_along(phase.flow, t.guard) for t in phase.transitions]
        out.append(
            {
                "flow": [phase.flow],
                "events": phase_events(phase, True),
                "admissible": [t.admissible for t in phase.transitions],
                "resets": [t.reset for t in phase.transitions],
                "rates": rates,
                "curvatures": [rate_along(phase.flow, r) for r in rates],
                "constraint_rates": [rate_along(phase.flow, c.function) for c in phase.constraints],
            }
        )
        probes, brents = event_functions(
            phase, phase.n, len(model_cls.inputs), len(model_cls.parameter_specs())
        )
        out[-1].update(probes=probes, brents=brents)
    return out


@lru_cache(maxsize=64)
def compiled_functions(model_cls) -> list[dict[str, list]]:
    """:func:`_layout` compiled into one library per model class (cached like the other
    kernels, :mod:`gaitopt.kernels.cache`): a guard, rate or reset mapped over many starts is
    then one C loop, not CasADi's interpreter per start.  The interpreted functions where there
    is no compiler."""
    import casadi as ca

    from ..kernels.cache import load, source_key

    layout = _layout(model_cls)
    slots = [(i, role, j) for i, roles in enumerate(layout) for role, fs in roles.items()
             for j, f in enumerate(fs) if f is not None]  # fmt: skip

    def build() -> list:
        functions = []
        for i, role, j in slots:
            f = layout[i][role][j]
            if role == "brents" and f.is_a("SXFunction"):  # one iteration's code, called 12×
                probe = layout[i]["probes"][j]
                g = ca.Function("g", probe.sx_in(), probe.call(probe.sx_in())[:1])
                f = staged_brent(f, g)
            args = f.sx_in() if f.is_a("SXFunction") else f.mx_in()
            functions.append(ca.Function(f"batch_{i}_{role}_{j}", args, f.call(args),
                                         f.name_in(), f.name_out()))  # fmt: skip
        return functions

    name = f"gaitopt_{model_cls.__name__.lower()}_batch"
    try:
        functions, _ = load(name, build, key=source_key(name, model_cls))
    except (RuntimeError, TypeError, NotImplementedError):
        return layout
    for (i, role, j), f in zip(slots, functions, strict=True):
        layout[i][role][j] = f
    return layout


def event_functions(phase, flow_n: int, n_u: int, n_p: int) -> tuple[list, list]:
    """``(probes, brents)``: one of each per event of ``phase`` (transitions, then constraints),
    see the module."""
    n_tr = len(phase.transitions)
    guards = [tr.guard for tr in phase.transitions] + [c.function for c in phase.constraints]
    rules = [tr.admissible for tr in phase.transitions if tr.admissible is not None]
    S = ca.SX if all(f.is_a("SXFunction") for f in guards + rules) else ca.MX
    F = S.sym("F", flow_n, 7)
    y_old = S.sym("y_old", flow_n)
    t_old, h, t = S.sym("t_old"), S.sym("h"), S.sym("t")
    lo, hi = S.sym("lo"), S.sym("hi")
    u, p = S.sym("u", n_u), S.sym("p", n_p)
    directions = [tr.direction for tr in phase.transitions] + [-1] * len(phase.constraints)
    probes, brents = [], []
    for ev, (guard, direction) in enumerate(zip(guards, directions, strict=True)):

        def g(time, guard=guard, direction=direction):
            return float(direction) * guard(_dense(F, y_old, t_old, h, time), u, p)[0]

        x = _dense(F, y_old, t_old, h, t)
        if ev < n_tr:
            rule = phase.transitions[ev].admissible
            a = rule(x, u, p)[0] if rule is not None else S(1.0)
        elif phase.constraints[ev - n_tr].at_end:  # touchdown, not a violation
            a = ca.fabs(guards[0](x, u, p)[0]) - _CONSTRAINT_START
        else:
            a = S(1.0)
        probes.append(
            ca.Function("probe", [F, y_old, t_old, h, t, u, p], [g(t), x, a],
                        ["F", "y_old", "t_old", "h", "t", "u", "p"], ["g", "x", "a"])
        )  # fmt: skip
        root, converged = _brent(g, lo, hi, S)
        brents.append(
            ca.Function("brent", [F, y_old, t_old, h, lo, hi, u, p], [root, converged],
                        ["F", "y_old", "t_old", "h", "lo", "hi", "u", "p"],
                        ["root", "converged"])
        )  # fmt: skip
    return probes, brents


def _brent_start(g, a, b, S) -> list:
    """The state of SciPy's ``brentq`` before its first iteration on ``g`` over ``[a, b]``:
    ``[xpre, xcur, xblk, fpre, fcur, fblk, spre, scur, root, done]``."""
    fpre, fcur = g(a), g(b)
    zero = S(0.0)
    done = (fpre == 0) + (fcur == 0) > 0
    return [a, b, zero, fpre, fcur, zero, zero, zero, ca.if_else(fpre == 0, a, b), done]


def _brent_iteration(g, state: list) -> list:
    """One iteration of SciPy's ``brentq`` C code (its ``scipy/optimize/Zeros/brentq.c``) on
    ``g``: the state after it (see :func:`_brent_start`)."""
    sel = ca.if_else
    xpre, xcur, xblk, fpre, fcur, fblk, spre, scur, root, done = state
    new = ((fpre != 0) * (fcur != 0) * ((fpre < 0) != (fcur < 0))) > 0
    xblk, fblk = sel(new, xpre, xblk), sel(new, fpre, fblk)
    spre, scur = sel(new, xcur - xpre, spre), sel(new, xcur - xpre, scur)
    swap = ca.fabs(fblk) < ca.fabs(fcur)
    xpre, xcur, xblk = sel(swap, xcur, xpre), sel(swap, xblk, xcur), sel(swap, xcur, xblk)
    fpre, fcur, fblk = sel(swap, fcur, fpre), sel(swap, fblk, fcur), sel(swap, fcur, fblk)
    delta = (_XTOL + _RTOL * ca.fabs(xcur)) / 2
    sbis = (xblk - xcur) / 2
    conv = ((fcur == 0) + (ca.fabs(sbis) < delta)) > 0
    root = sel((1 - done) * conv > 0, xcur, root)
    done = (done + conv) > 0
    stry_i = -fcur * (xcur - xpre) / (fcur - fpre)
    dpre = (fpre - fcur) / (xpre - xcur)
    dblk = (fblk - fcur) / (xblk - xcur)
    stry_e = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
    stry = sel(xpre == xblk, stry_i, stry_e)
    tried = (ca.fabs(spre) > delta) * (ca.fabs(fcur) < ca.fabs(fpre))
    good = (tried * (2 * ca.fabs(stry) < ca.fmin(ca.fabs(spre), 3 * ca.fabs(sbis) - delta))) > 0
    spre, scur = sel(good, scur, sbis), sel(good, stry, sbis)
    xpre, fpre = xcur, fcur
    xcur = sel(ca.fabs(scur) > delta, xcur + scur, xcur + sel(sbis > 0, delta, -delta))
    fcur = g(xcur)
    return [xpre, xcur, xblk, fpre, fcur, fblk, spre, scur, root, done]


def _brent(g, a, b, S):
    """SciPy's ``brentq`` C iteration on ``g`` over ``[a, b]``, unrolled (``S``: SX or MX)."""
    state = _brent_start(g, a, b, S)
    for _ in range(ITERATIONS):
        state = _brent_iteration(g, state)
    return state[8], state[9]


def staged_brent(brent: ca.Function, g: ca.Function) -> ca.Function:
    """``brent`` (an SX function of :func:`event_functions`) for compiling: one iteration an SX
    function called :data:`ITERATIONS` times (MX) rather than the iterations inlined.

    The same operations in the same order, so the same numbers; the generated C holds one
    iteration instead of 12 (the locators were most of the batch library's code and of its
    compile time).  ``g``: ``g(F, y_old, t_old, h, t, u, p)``, the signed event function on
    the dense output."""
    F, y_old, t_old, h, t, u, p = g.sx_in()
    state = ca.SX.sym("state", 10)

    def g_sx(time):
        return g(F, y_old, t_old, h, time, u, p)

    after = _brent_iteration(g_sx, ca.vertsplit(state))
    step = ca.Function("brent_iteration", [state, F, y_old, t_old, h, u, p], [ca.vertcat(*after)])
    args = brent.mx_in()  # F, y_old, t_old, h, lo, hi, u, p
    Fm, yom, tom, hm, lo, hi, um, pm = args

    def g_mx(time):
        return g(Fm, yom, tom, hm, time, um, pm)

    x = ca.vertcat(*_brent_start(g_mx, lo, hi, ca.MX))
    for _ in range(ITERATIONS):
        x = step(x, Fm, yom, tom, hm, um, pm)
    return ca.Function(brent.name(), args, [x[8], x[9]], brent.name_in(), brent.name_out())


def scan_crossings(run, ph, i, c, t_old, t_new, y_old, y_new, F, signed, best):
    """The starts ``c`` (rows of the accepted starts ``i``) whose step changed a sign: each
    event's check points in order, as ``integrate_phase`` scans them (a bracket confirmed on the
    dense output, located, admissible or not), all rows at once (``F``: their dense-output
    coefficients, rows ``c`` only).  ``best`` = ``(t, event, x)``
    arrays over the accepted starts, updated with each start's earliest admissible crossing."""
    best_t, best_k, best_x = best
    u, p = run.u[i[c]], run.p[i[c]]
    to, tn, yn, Fc = t_old[c], t_new[c], y_new[c], F  # F: the rows c already
    yo, hc = y_old[c], tn - to
    step = (tn - to) / _C
    grid = np.arange(_C + 1)[None, :] * step[:, None] + to[:, None]
    grid[:, -1] = tn

    def probe(ev, rows, times):
        return ph.probes[ev](rows.size, Fc[rows], yo[rows], to[rows], hc[rows], times, u[rows],
                             p[rows])  # fmt: skip

    for ev in range(len(ph.events)):
        previous = run.values[i[c], ev].copy()
        was_armed = run.armed[i[c], ev].copy()
        changes = signed[c, ev]
        before = np.concatenate([previous[:, None], changes[:, :-1]], axis=1)
        if not np.any((before < 0) & (changes >= 0)):  # no sign change of this event: as a
            run.armed[i[c], ev] = was_armed | np.any(changes < -_ARM, axis=1)  # quiet step
            run.values[i[c], ev] = changes[:, -1]
            continue
        done = np.zeros(c.size, bool)
        for j in range(1, _C + 1):
            current = signed[c, ev, j - 1].copy()
            cand = np.flatnonzero(~done & was_armed & (previous < 0) & (current >= 0))
            if cand.size:  # confirm on the dense output itself
                start = probe(ev, cand, grid[cand, j - 1])[0][:, 0]
                at_b = probe(ev, cand, grid[cand, j])[0][:, 0]  # locate_crossing's g(b)
                if j < _C:
                    end = at_b
                else:  # the step's end state itself
                    guard = ph.guards[ev](cand.size, yn[cand], u[cand], p[cand])[0][:, 0]
                    end = ph.directions[ev] * guard
                previous[cand], current[cand] = start, end
                ok = (start < 0) & (end >= 0)
                hit = cand[ok]
                if hit.size:
                    t_hit = _locate(ph, ev, hit, grid[hit, j - 1], grid[hit, j], at_b[ok], probe,
                                    (Fc, yo, to, hc, u, p))  # fmt: skip
                    _, x_hit, rule = probe(ev, hit, t_hit)
                    adm = rule[:, 0] > 0
                    take = hit[adm]
                    better = t_hit[adm] < best_t[c[take]]
                    rows = c[take[better]]
                    best_t[rows], best_k[rows] = t_hit[adm][better], ev
                    best_x[rows] = x_hit[adm][better]
                    done[take] = True
            live = ~done
            was_armed[live] |= current[live] < -_ARM
            previous[live] = current[live]
        run.armed[i[c], ev] = was_armed
        run.values[i[c], ev] = previous


def _locate(ph, ev, rows, a, b, g_b, probe, data):
    """``locate_crossing`` for many brackets whose ``g(a) < 0`` is confirmed: ``b`` where the
    dense output's ``g(b)`` is not non-negative, else Brent's root (compiled, the rare rows it
    does not finish continued in NumPy), or the first float after ``a`` found by halving where
    Brent's answer is ``a`` itself."""
    t = np.array(b, dtype=float)
    rest = np.flatnonzero(g_b >= 0)
    if not rest.size:
        return t
    Fc, yo, to, hc, u, p = data
    r = rows[rest]
    root, converged = ph.brents[ev](r.size, Fc[r], yo[r], to[r], hc[r], a[rest], b[rest], u[r],
                                    p[r])  # fmt: skip
    root, converged = root[:, 0], converged[:, 0] > 0
    slow = np.flatnonzero(~converged)
    if slow.size:  # the same iteration from the start, in NumPy, for the rows still going
        rs = r[slow]

        def g(k, x):
            return probe(ev, rs[k], x)[0][:, 0]

        root[slow] = brentq(g, a[rest][slow], b[rest][slow], _XTOL, _RTOL)  # type: ignore
    t[rest] = root
    for q in np.flatnonzero(root <= a[rest]):  # brentq ended on a: halve in floats
        lo, hi = a[rest[q]], b[rest[q]]
        row = r[q : q + 1]
        while True:
            mid = lo + 0.5 * (hi - lo)
            if not lo < mid < hi:
                break
            if probe(ev, row, np.array([mid]))[0][0, 0] >= 0:
                hi = mid
            else:
                lo = mid
        t[rest[q]] = hi
    return t
