"""Grizzle's three-link walker: how its step time depends on the integrator's tolerance.

Issue 20 quotes a step time of 2.2583406929 s and a dominant Floquet multiplier 0.5512805 for
Grizzle's three-link walker (Grizzle, Abba & Plestan 2001, IEEE TAC 46(1)) under the fixed
virtual constraints h = [θ3 − π/8, θ1 + θ2] with ω_n = 5, ζ = 1.1.  gaitopt finds 2.1677530383 s
and 0.6713863, and so do a NumPy referee (``tests/test_three_link_walker.py``) and the generic
Bézier closed loop.  The model's equations agree term by term with Grizzle's own course code for
this walker (D, C, G, B, the extended impact model and the relabelling; g = 9.8).

This study shows why ten digits of the step time can disagree: this gait barely passes
mid-stance (the zero dynamics start just above the energy needed to carry the stance leg over
the vertical), so the step time is extremely sensitive to the state after impact
(dT/dθ̇1⁺ of order −10² s per rad/s).  An integrator run at its default tolerance (SciPy's and
DifferentialEquations.jl's: rtol 1e-3, atol 1e-6) perturbs the state by about that much per
step, and its *discretised* return map — a smooth map wherever the accepted steps do not change
— has a fixed point of its own that iterating the simulation finds to 1e-13, with a step time
and multipliers that look exact and are not the ODE's.  The study computes, for SciPy's RK45,
LSODA and DOP853 at rtol = atol·10³ = 1e-3 (the defaults) and at tighter tolerances, the fixed
point of the discretised map (iterated to convergence from gaitopt's gait), its step time and
its finite-difference multipliers.  At the defaults the three methods give three different,
self-consistent "gaits" (0.07 s apart, dominant multipliers 0.22–0.73); as the tolerance
tightens all converge to gaitopt's 2.1677530383 s and 0.6713863.

    python problems/three_link_tolerance.py --out results [--fast]

Writes results/three_link_tolerance/: tolerance.csv, tolerance.json.  ``--fast`` runs RK45 only,
at the default and the tightest tolerance.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

import gaitopt
from gaitopt.files import write_csv, write_json

METHODS = ("RK45", "LSODA", "DOP853")
# (rtol, atol): SciPy's and DifferentialEquations.jl's defaults, then tighter.
TOLERANCES = ((1e-3, 1e-6), (1e-6, 1e-9), (1e-8, 1e-11), (1e-10, 1e-13), (1e-12, 1e-14))
ITERATIONS = 80  # map iterations toward the discretised fixed point (multiplier ≤ 0.73: 1e-11)
FD_STEP = 1e-7  # central differences of the discretised map (rad, rad/s)
HEADER = [
    "method",
    "rtol",
    "atol",
    "step_time_s",
    "fixed_point_drift",
    "mu1",
    "abs_mu2",
    "abs_mu3",
    "step_time_minus_gaitopt_s",
]


class _ScipyStep:
    """One step of the closed loop, integrated by SciPy's ``solve_ivp``: the model's own flow,
    guard and reset (CasADi functions evaluated numerically), the event located by SciPy."""

    def __init__(self, model: gaitopt.HybridModel) -> None:
        phase = model.phases[0]
        strike = phase.transitions[0]
        self._p = model.p
        self._u = np.zeros(0)
        self._flow, self._guard, self._reset = phase.flow, strike.guard, strike.reset
        self._direction = strike.direction

    def _rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        del t
        return np.asarray(self._flow(x, self._u, self._p), dtype=float).ravel()

    def __call__(self, x: np.ndarray, method: str, rtol: float, atol: float):
        """Return ``(x⁺ after the impact, the step time (s))`` from the post-impact state ``x``."""

        def event(t: float, y: np.ndarray) -> float:
            del t
            return float(self._guard(y, self._u, self._p))

        event.terminal, event.direction = True, self._direction
        sol = solve_ivp(self._rhs, (0.0, 10.0), x, method=method, events=event, rtol=rtol,
                        atol=atol)  # fmt: skip
        if not sol.t_events[0].size:
            raise RuntimeError(f"{method} at rtol {rtol:g}: no heel strike within 10 s")
        x_minus = sol.y_events[0][0]
        x_plus = np.asarray(self._reset(x_minus, self._u, self._p), dtype=float).ravel()
        return x_plus, float(sol.t_events[0][0])


def discretised_fixed_point(step, x0, method, rtol, atol, coordinates):
    """Iterate the discretised return map from ``x0`` and differentiate it at the limit.

    Returns
    -------
    dict
        ``step_time_s``, ``fixed_point_drift`` (max |P(x) − x| at the last iterate, its
        convergence), ``multipliers`` (eigenvalues of the central-difference Jacobian of the map on
        the section ``coordinates``, sorted by modulus).
    """
    x = np.array(x0, dtype=float)
    for _ in range(ITERATIONS):
        x, _ = step(x, method, rtol, atol)
    x_next, period = step(x, method, rtol, atol)
    J = np.empty((len(coordinates), len(coordinates)))
    for j, i in enumerate(coordinates):
        plus, minus = x.copy(), x.copy()
        plus[i] += FD_STEP
        minus[i] -= FD_STEP
        J[:, j] = (step(plus, method, rtol, atol)[0][coordinates]
                   - step(minus, method, rtol, atol)[0][coordinates]) / (2 * FD_STEP)  # fmt: skip
    mu = np.linalg.eigvals(J)
    mu = mu[np.argsort(-np.abs(mu))]
    return {
        "step_time_s": period,
        "fixed_point_drift": float(np.max(np.abs(x_next - x))),
        "multipliers": [[float(m.real), float(m.imag)] for m in mu],
    }


def run(fast: bool = False) -> dict:
    """The table: gaitopt's gait, then each method and tolerance (see the module docstring)."""
    model = gaitopt.model("three_link_walker")
    cycle = gaitopt.find_limit_cycle(model)
    if not cycle.success:
        raise RuntimeError(f"three_link_walker: {cycle.message}")
    names = list(model.state_names)
    coordinates = [names.index(c) for c in cycle.section_coordinates]
    step = _ScipyStep(model)
    methods = ("RK45",) if fast else METHODS
    tolerances = (TOLERANCES[0], TOLERANCES[-1]) if fast else TOLERANCES
    # The sensitivity of the step time to the stance leg's rate after impact (central
    # difference at tight tolerance): what makes the step time so fragile.
    i = names.index("stance_dot")
    plus, minus = np.array(cycle.x, dtype=float), np.array(cycle.x, dtype=float)
    plus[i] += 1e-6
    minus[i] -= 1e-6
    dT = (step(plus, "DOP853", 1e-12, 1e-14)[1] - step(minus, "DOP853", 1e-12, 1e-14)[1]) / 2e-6
    rows = []
    for method in methods:
        for rtol, atol in tolerances:
            r = discretised_fixed_point(step, cycle.x, method, rtol, atol, coordinates)
            mu = r["multipliers"]
            rows.append(
                {
                    "method": method,
                    "rtol": rtol,
                    "atol": atol,
                    "step_time_s": r["step_time_s"],
                    "fixed_point_drift": r["fixed_point_drift"],
                    "mu1": math.hypot(*mu[0]) * (1 if mu[0][0] >= 0 else -1),
                    "abs_mu2": math.hypot(*mu[1]),
                    "abs_mu3": math.hypot(*mu[2]),
                    "step_time_minus_gaitopt_s": r["step_time_s"] - cycle.period,
                }
            )
    return {
        "gaitopt": {
            "step_time_s": cycle.period,
            "mu1": float(abs(cycle.multipliers[0])),
            "abs_mu2": float(abs(cycle.multipliers[1])),
            "verified": bool(cycle.verified),
            "dT_dstance_dot_s_per_rad_s": dT,
        },
        "issue_20": {"step_time_s": 2.2583406929, "mu1": 0.5512805},
        "rows": rows,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("results"), help="results folder")
    parser.add_argument("--fast", action="store_true", help="RK45 at two tolerances only")
    args = parser.parse_args(argv)
    table = run(fast=args.fast)
    folder = args.out / "three_link_tolerance"
    folder.mkdir(parents=True, exist_ok=True)
    write_csv(HEADER, [[row[k] for k in HEADER] for row in table["rows"]], folder / "tolerance.csv")
    write_json(table, folder / "tolerance.json")
    g = table["gaitopt"]
    print(
        f"gaitopt: {g['step_time_s']:.10f} s, μ1 {g['mu1']:.7f}, "
        f"dT/dθ̇1⁺ {g['dT_dstance_dot_s_per_rad_s']:.1f} s/(rad/s)"
    )
    for row in table["rows"]:
        print(
            f"{row['method']:>6} rtol {row['rtol']:.0e}: T {row['step_time_s']:.10f} s "
            f"({row['step_time_minus_gaitopt_s']:+.2e}), μ1 {row['mu1']:.7f}, "
            f"|μ2| {row['abs_mu2']:.2e}, drift {row['fixed_point_drift']:.1e}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
