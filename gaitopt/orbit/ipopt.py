"""IPOPT on any transcription (:class:`~gaitopt.orbit.transcription.Transcription`): the
nonlinear program ``min f(w)`` subject to ``lbg ≤ F(w) ≤ ubg`` and ``lbw ≤ w ≤ ubw`` (rule 3),
with the residual ``F`` and the objective written in the transcription's symbols (rule 7),
through :func:`casadi.nlpsol` (exact derivatives by CasADi's AD of the plain graph).

The front doors keep their own tuned solvers (``ShootingProblem.ipopt_solver``; the
collocation's, whose derivatives come from compiled node kernels); this one is the plain method
every transcription gets."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["IPOPT_OPTIONS", "IpoptResult", "solve_nlp"]

#: IPOPT's options here (quiet; tight tolerances, as the front doors').
IPOPT_OPTIONS = {
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "print_time": False,
    "ipopt.tol": 1e-12,
    "ipopt.constr_viol_tol": 1e-12,
    "ipopt.max_iter": 1000,
    "error_on_fail": False,
    "show_eval_warnings": False,
}


@dataclass(frozen=True)
class IpoptResult:
    """The last point ``w``, whether IPOPT reports success, its iterations, return status and
    the objective's value there."""

    w: np.ndarray
    converged: bool
    iterations: int
    return_status: str
    objective: float


def solve_nlp(
    transcription: Any,
    w0,
    *,
    objective: Any = None,
    options: dict[str, Any] | None = None,
) -> IpoptResult:
    """Solve ``transcription`` by IPOPT from ``w0``.

    Parameters
    ----------
    transcription : Transcription
        Any transcription (its :attr:`symbols`, :meth:`bounds`, ``u`` and ``p``).
    w0 : numpy.ndarray
        Start (clipped into the bounds).
    objective : casadi.MX, optional
        An expression of the transcription's symbols (``symbols.w``, ``u``, ``p``, the node
        states and inputs, the durations); default its own (0 for the shooting: a feasibility
        problem).
    options : dict, optional
        Options of :func:`casadi.nlpsol` merged over :data:`IPOPT_OPTIONS`.
    """
    sym = transcription.symbols
    f = sym.objective if objective is None else objective
    nlp = {"x": sym.w, "p": ca.vertcat(sym.u, sym.p), "f": f, "g": sym.F}
    solver = ca.nlpsol("orbit_ipopt", "ipopt", nlp, {**IPOPT_OPTIONS, **(options or {})})
    b = transcription.bounds()
    w0 = np.clip(np.asarray(w0, dtype=float).ravel(), b.lbw, b.ubw)
    par = np.concatenate([np.asarray(transcription.u, float).ravel(), transcription.p])
    sol = solver(x0=w0, p=par, lbx=b.lbw, ubx=b.ubw, lbg=b.lbg, ubg=b.ubg)
    stats = solver.stats()
    return IpoptResult(
        np.asarray(sol["x"], dtype=float).ravel(),
        bool(stats["success"]),
        int(stats["iter_count"]),
        str(stats.get("return_status", "")),
        float(sol["f"]),
    )
