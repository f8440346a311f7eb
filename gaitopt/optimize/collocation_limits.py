"""The state bounds and selected limits of a collocation (issue 11's joint limits): their rows
while the transcription is built (:func:`add_limits`; a limit a guard's rows keep already is
skipped, :func:`kept_by_guard`) and their checks on a solution — on dense samples of its
polynomials (:func:`check_limits`), where they bind (:func:`active_limits`) and the
certificate's part for them (:func:`certify_limits`).  Methods of
:class:`~gaitopt.optimize.collocation.Collocation` (``col`` is the transcription)."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..orbit.certificate import CONSTRAINT_TOL

__all__ = [
    "LIMIT_SAMPLES",
    "LIMIT_TOL",
    "active_limits",
    "add_limits",
    "certify_limits",
    "check_limits",
    "kept_by_guard",
    "limit_values",
    "phase_label",
]

#: Uniform samples per mesh interval of the dense check of state bounds and limits
#: (:meth:`Collocation.check_limits`): not the nodes, where they are imposed.
LIMIT_SAMPLES = 64
#: A state bound or limit counts as violated on the dense samples where
#: ``c < −LIMIT_TOL · (1 + max |c|)``: the certificate's one rule for unilateral constraints
#: (:data:`gaitopt.orbit.certificate.CONSTRAINT_TOL`).
LIMIT_TOL = CONSTRAINT_TOL


def add_limits(
    col, add: Any, k: int, i: int, label: str, Xk: Any, Uk: Any, u_start: Any, p: Any
) -> None:
    """Rows of phase ``k`` (model phase ``i``) for the selected limits and, at the section,
    the bounds of the states ``lift`` computes (the other nodes' bounds are variable bounds)."""
    problem, phase = col.problem, col.model.phases[i]
    if k == 0:
        lo, hi = problem.state_bounds_of(i)
        rows = [
            j
            for j in range(phase.n)
            if j not in col.section_index and (np.isfinite(lo[j]) or np.isfinite(hi[j]))
        ]
        for j in rows:
            name = f"bound on '{phase.states[j]}' at the section"
            add(name, Xk[j, 0], lo[j], hi[j])
            col.limit_groups.append(name)
    for c in problem.limits_of(i):
        if kept_by_guard(col, i, c):
            col.guard_limits.append((i, c.name))
            continue
        first = 1 if c.at_start else 0
        last = Xk.shape[1] - 1 if c.at_end else Xk.shape[1]
        nodes = Xk[:, first:last]
        # The input at a node: the start's extrapolated value, then the Radau points'.
        unodes = ca.horzcat(u_start, Uk)[:, first:last]
        if nodes.shape[1]:
            name = f"limit '{c.name}' ({label})"
            add(name, c.function.map(nodes.shape[1])(nodes, unodes, p), 0.0, np.inf)
            col.limit_groups.append(name)


def kept_by_guard(col, i: int, c: Any) -> bool:
    """Whether limit ``c`` of phase ``i`` is ``direction · g ≤ 0`` of its cycle transition's
    guard without admissibility test, ``c = −direction · g`` (checked at random states),
    which the transcription keeps at the interior nodes anyway (with the problem's
    guard margin, never less)."""
    tr = col.model.phases[i].transitions[0]
    if tr.admissible is not None:
        return False
    rng = np.random.default_rng(0)
    n, n_u = col.model.phases[i].n, len(col.model.inputs)
    for _ in range(4):
        x, u = rng.normal(size=n), rng.normal(size=n_u)
        value = float(c.function(x, u, col.model.p))
        guard = float(tr.guard(x, u, col.model.p))
        if abs(value + tr.direction * guard) > 1e-12 * (1 + abs(value)):
            return False
    return True


# -- joint limits on the solution ---------------------------------------------------------


def limit_values(
    col, sol: dict[str, Any], k: int, X: np.ndarray, U: np.ndarray
) -> list[tuple[str, np.ndarray, bool, bool]]:
    """``(label, c, at_start, at_end)`` of every state bound side (``x − low``,
    ``high − x``) and selected limit of phase ``k`` at the samples ``X``, ``U`` (``c ≥ 0``
    wanted)."""
    problem = col.problem
    i = col.chain[k]
    phase = col.model.phases[i]
    out = []
    lo, hi = problem.state_bounds_of(i)
    for j, state in enumerate(phase.states):
        if np.isfinite(lo[j]):
            out.append((f"{state} >= {lo[j]:g}", X[j] - lo[j], False, False))
        if np.isfinite(hi[j]):
            out.append((f"{state} <= {hi[j]:g}", hi[j] - X[j], False, False))
    for c in problem.limits_of(i):
        values = np.asarray(c.function.map(X.shape[1])(X, U, sol["p"]), dtype=float).ravel()
        out.append((f"{c.name} >= 0", values, c.at_start, c.at_end))
    return out


def phase_label(col, k: int) -> str:
    """The phase's name (with its place in the orbit when the orbit has several phases)."""
    phase = col.model.phases[col.chain[k]]
    return phase.name if len(col.chain) == 1 else f"{phase.name} #{k + 1}"


def check_limits(col: Any, sol: dict[str, Any], samples: int = LIMIT_SAMPLES) -> str | None:
    """None if every state bound and selected limit holds on ``samples`` uniform samples per
    mesh interval of each phase's polynomials, ``c ≥ −1e-9 · (1 + max |c|)`` (the rule of
    :func:`gaitopt.shooting.certify`'s unilateral constraints); else the first failure."""
    tn = np.linspace(0.0, 1.0, col.N * samples + 1)
    t0 = 0.0
    for k in range(len(col.chain)):
        X, U = col.evaluate(sol["X"][k], sol["U"][k], tn, sol["breaks"][k])
        for label, c, at_start, at_end in limit_values(col, sol, k, X, U):
            inner = c[1 if at_start else 0 : c.size - 1 if at_end else c.size]
            scale = LIMIT_TOL * (1 + float(np.max(np.abs(c))))
            bad = np.nonzero(inner < -scale)[0]
            if bad.size:
                j = int(bad[0]) + (1 if at_start else 0)
                return (
                    f"the limit '{label}' fails between the nodes of phase "
                    f"'{phase_label(col, k)}' at t = {t0 + tn[j] * sol['T'][k]:.4g} s (by "
                    f"{-float(np.min(inner)):.3g}; dense samples, tolerance {scale:.2g})"
                )
        t0 += sol["T"][k]
    return None


def active_limits(col, sol: dict[str, Any]) -> dict[str, list[list[float]]]:
    """The state bounds and selected limits active at the nodes (within 1e-6 of their bound,
    relative to 1 + the largest |c|): ``{"LABEL (phase)": [[t_first, t_last], ...]}``, the
    times (s since the orbit's section) of each run of consecutive active nodes."""
    out: dict[str, list[list[float]]] = {}
    t0 = 0.0
    for k in range(len(col.chain)):
        X, U = sol["X"][k], sol["U"][k]
        times = t0 + col.node_times(sol["breaks"][k]) * sol["T"][k]
        U = np.hstack([col.u_start_of(U), U])
        for label, c, at_start, at_end in limit_values(col, sol, k, X, U):
            hit = np.abs(c) <= 1e-6 * (1 + float(np.max(np.abs(c))))
            if at_start:
                hit[0] = False
            if at_end:
                hit[-1] = False
            if not hit.any():
                continue
            spans, j = [], 0
            while j < hit.size:
                if hit[j]:
                    e = j
                    while e + 1 < hit.size and hit[e + 1]:
                        e += 1
                    spans.append([float(times[j]), float(times[e])])
                    j = e + 1
                else:
                    j += 1
            out.setdefault(f"{label} ({phase_label(col, k)})", []).extend(spans)
        t0 += sol["T"][k]
    return out


def certify_limits(col, w: np.ndarray, result: Any) -> None:
    """The certificate's part for the state bounds and selected limits of an optimum
    ``result`` (an :class:`~gaitopt.optimize.result.OptimalGait` from ``w``): its
    ``active_constraints`` name each active bound or limit with its phase (``active_spans``:
    the time spans), and a gait whose dense samples violate one (:meth:`check_limits`) is
    no gait (``success`` False, the message says which, where and by how much)."""
    problem = col.problem
    if not problem.state_bounds and not problem.path_constraints:
        return
    sol = col.unpack(w, col.model.p)
    spans = col.active_limits(sol)
    generic = {f"{lo:g} <= {n} <= {hi:g}" for n, (lo, hi) in problem.state_bounds.items()}
    drop = generic | set(col.limit_groups)
    kept = [a for a in result.active_constraints if a not in drop]
    result.active_constraints = kept + list(spans)
    result.active_spans = spans
    if result.cost is None or result.message.startswith("not a gait"):
        return
    failure = col.check_limits(sol)
    if failure is not None:
        result.success, result.stable, result.status = False, None, "not_a_gait"
        result.message = "not a gait: " + failure
