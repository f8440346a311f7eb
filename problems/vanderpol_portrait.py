"""Van der Pol: the chapter's opening figures — orbital convergence to a limit cycle.

Tedrake (*Underactuated Robotics*, ch. "Simple models of walking and running", limit cycles) opens
with ``q̈ + μ (q² − 1) q̇ + q = 0`` at μ = 0.2: from almost every start the trajectory settles on
the same closed orbit (the origin, the one equilibrium, repels), but in the time domain the
trajectories do not synchronise — each keeps its own phase.  Convergence is *orbital*.  This study
draws, at μ = 0.2:

* the phase portrait from many initial conditions, inside and outside the cycle, with the origin;
* the time-domain panel: q(t) of the same starts, converging to the cycle's amplitude with
  different phases;
* the orbital distance ``min_τ ‖x(t) − x*(τ)‖`` (:func:`gaitopt.orbital_distance`) against time on
  a log axis, with the decay the nontrivial Floquet multiplier predicts, ``|λ|^(t/T)``, where
  ``λ = exp(∮ μ (1 − q²) dt)`` (Liouville's formula);
* the return map on the section ``q = 0, q̇ > 0`` with its staircase and both fixed points: the
  cycle (stable) and the origin — an equilibrium, so ``P(0) = 0`` with return time zero (it is
  there at once), unstable and one-sided (only ``q̇ > 0`` is on the section), with slope
  ``P'(0⁺) = exp(π μ / ω_d)``, ``ω_d = sqrt(1 − μ²/4)``, from the linearisation about the origin.

    python problems/vanderpol_portrait.py --out results [--fast]

Writes results/vanderpol_portrait/: summary.json, distance.csv, portrait.png.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.orbits import OrbitSampler  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402
from gaitopt.returnmap import return_map  # noqa: E402

MU = 0.2  # Tedrake's figure


def liouville_multiplier(cycle) -> float:
    """``exp(∮ μ (1 − q²) dt)`` along the orbit: the trace of the flow's Jacobian integrated over
    one period (Liouville), the nontrivial multiplier of a planar limit cycle."""
    mu = cycle.model.mu
    sim = gaitopt.simulate(cycle.model, cycle.x, steps=1, rtol=1e-12)
    total = 0.0
    for arc in sim.arcs:
        t = np.linspace(arc.t0, arc.t1, 4001)
        q = arc.solution(t)[0]
        total += np.trapezoid(mu * (1 - q**2), t)
    return math.exp(total)


def origin_slope(mu: float) -> float:
    """``P'(0⁺) = exp(π μ/ω_d)``: the linearisation about the origin, ``q̈ − μ q̇ + q = 0``, turns
    once in ``2π/ω_d`` and grows by ``exp(μ/2 · 2π/ω_d)`` meanwhile (ω_d = sqrt(1 − μ²/4))."""
    return math.exp(math.pi * mu / math.sqrt(1 - mu**2 / 4))


def _flow(mu: float):
    return lambda t, x: [x[1], mu * (1 - x[0] ** 2) * x[1] - x[0]]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="fewer starts for CI")
    parser.add_argument("--scheduler", default=None, help="unused (serial study)")
    parser.add_argument("--workers", type=int, default=2, help="unused (serial study)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "vanderpol_portrait"
    folder.mkdir(parents=True, exist_ok=True)

    model = gaitopt.model("vanderpol", mu=MU)
    cycle = gaitopt.find_limit_cycle(model)
    if not cycle.success:
        print(f"no limit cycle: {cycle.message}")
        return 1
    period = cycle.period
    lam = complex(cycle.multipliers[0]).real
    lam_liouville = liouville_multiplier(cycle)
    sampler = OrbitSampler(cycle)

    # -- many starts: inside (near the origin) and outside the cycle ---------------------------
    angles = np.linspace(0, 2 * np.pi, 6 if args.fast else 12, endpoint=False)
    starts = [(r * math.cos(a), r * math.sin(a)) for r in (0.1, 3.5) for a in angles]
    horizon = 8 * period
    t_eval = np.linspace(0, horizon, 1600 if args.fast else 4000)
    runs = [
        solve_ivp(_flow(MU), (0, horizon), s, t_eval=t_eval, rtol=1e-11, atol=1e-12) for s in starts
    ]

    # -- orbital distance along a few of them ---------------------------------------------------
    tracked = [0, len(angles)]  # one start inside, one outside
    every = 10 if args.fast else 5
    rows, decay = [], {}
    for k in tracked:
        t = runs[k].t[::every]
        d = np.array([sampler.distance(x) for x in runs[k].y[:, ::every].T])
        decay[k] = (t, d)
        rows += [[k, float(tt), float(dd)] for tt, dd in zip(t, d, strict=True)]
    write_csv(["start", "t", "orbital_distance"], rows, folder / "distance.csv")
    # Measured decay per period: successive returns to the section, from simulation.
    ratios = []
    for s0 in (0.5, 3.5):
        sim = gaitopt.simulate(model, {"q_dot": s0}, steps=14)
        d = np.array([sampler.distance(x) for x in sim.section_states])
        ratios.append(d[1:] / d[:-1])

    # -- the return map and the origin ---------------------------------------------------------
    small = 1e-5
    slope_simulated = float(return_map(model, small)[0]) / small
    summary = {
        "model": "vanderpol",
        "mu": MU,
        "source": "Tedrake, Underactuated Robotics, limit cycles (Van der Pol, μ = 0.2)",
        "period": period,
        "fixed_point_q_dot": float(cycle.section_point[0]),
        "multiplier_shooting": lam,
        "multiplier_liouville": lam_liouville,
        "distance_ratio_per_period_last": [float(r[-1]) for r in ratios],
        "origin": {
            "return_map_value": 0.0,
            "return_time": 0.0,
            "slope_closed_form": origin_slope(MU),
            "slope_simulated": slope_simulated,
            "stable": False,
            "one_sided": True,
        },
    }
    write_json(summary, folder / "summary.json")
    _figure(model, cycle, starts, runs, decay, lam, period, folder / "portrait.png", args.fast)
    print(
        f"Van der Pol μ = {MU}: period {period:.10f}, multiplier {lam:.8f} (Liouville "
        f"{lam_liouville:.8f}); orbital distance ratio per period → "
        f"{', '.join(f'{r[-1]:.6f}' for r in ratios)}; origin P'(0+) {slope_simulated:.6f} "
        f"(closed form {origin_slope(MU):.6f}); wrote {folder}"
    )
    return 0


def _figure(model, cycle, starts, runs, decay, lam, period, path: Path, fast: bool) -> None:
    fig, axes = plt.subplots(2, 2, figsize=(12, 9.5), layout="constrained")
    (ax_pp, ax_t), (ax_d, ax_map) = axes
    orbit = gaitopt.simulate(model, cycle.x, steps=1, rtol=1e-12).arcs[0]
    _, X = orbit.sample(600)

    for k, run in enumerate(runs):
        ax_pp.plot(run.y[0], run.y[1], color=f"C{k % 10}", lw=0.6, alpha=0.8)
        ax_pp.plot(*starts[k], "o", ms=3, color=f"C{k % 10}")
    ax_pp.plot(X[0], X[1], color="k", lw=2.2, label="limit cycle")
    ax_pp.plot([0], [0], "o", ms=8, mfc="white", color="k", label="origin (unstable equilibrium)")
    ax_pp.set_xlabel("position q (dimensionless)")
    ax_pp.set_ylabel("velocity q̇ (dimensionless)")
    ax_pp.set_title(f"phase portrait, μ = {model.mu:g}: every start converges to the cycle")
    ax_pp.legend(fontsize=8, loc="upper left")
    ax_pp.grid(alpha=0.3)

    n_angles = len(starts) // 2
    for k in (0, n_angles // 2, n_angles, n_angles + n_angles // 2):
        ax_t.plot(runs[k].t, runs[k].y[0], lw=1.0, color=f"C{k % 10}", label=f"start {k}")
    ax_t.axhline(X[0].max(), color="k", lw=0.7, ls="--", label="cycle amplitude")
    ax_t.axhline(X[0].min(), color="k", lw=0.7, ls="--")
    ax_t.set_xlabel("time t (dimensionless)")
    ax_t.set_ylabel("position q (dimensionless)")
    ax_t.set_title("time domain: one amplitude, different phases")
    ax_t.legend(fontsize=8, loc="lower right", ncol=2)
    ax_t.grid(alpha=0.3)

    for k, (t, d) in decay.items():
        where = "inside" if k == 0 else "outside"
        ax_d.semilogy(t, d, lw=1.2, label=f"start {k} ({where} the cycle)")
        # The Floquet prediction through the point where the distance first falls below 0.1.
        j = int(np.argmax(d < 0.1))
        pred = d[j] * abs(lam) ** ((t - t[j]) / period)
        ax_d.semilogy(t[j:], pred[j:], "k--", lw=0.8)
    ax_d.plot([], [], "k--", lw=0.8, label=f"|λ|^(t/T), λ = {lam:.4f}, T = {period:.4f}")
    ax_d.set_ylim(1e-6, 10)
    ax_d.set_xlabel("time t (dimensionless)")
    ax_d.set_ylabel("orbital distance min_τ ‖x(t) − x*(τ)‖ (dimensionless)")
    ax_d.set_title("orbital distance decays by |λ| per period")
    ax_d.legend(fontsize=8, loc="upper right")
    ax_d.grid(alpha=0.3, which="both")

    s_star = float(cycle.section_point[0])
    grid = np.linspace(0.0, 3.6, 25 if fast else 60)
    values = [0.0] + [float(return_map(model, s)[0]) for s in grid[1:]]
    ax_map.plot(grid, values, color="C0", lw=1.8, label="return map P(q̇) (simulated)")
    ax_map.plot([0, 3.6], [0, 3.6], "k:", lw=0.8, label="diagonal")
    for start, colour in ((0.05, "C1"), (3.5, "C2")):
        xs, ys, s = [start], [start], start
        for _ in range(12):
            nxt = float(return_map(model, s)[0])
            xs += [s, nxt]
            ys += [nxt, nxt]
            s = nxt
        ax_map.plot(xs, ys, color=colour, lw=0.9, label=f"staircase from q̇ = {start:g}")
    ax_map.plot(
        [s_star], [s_star], "o", color="k", ms=8, label=f"limit cycle (stable, λ = {lam:.3f})"
    )
    ax_map.plot([0], [0], "o", ms=8, mfc="white", color="k")
    ax_map.annotate(
        "origin: an equilibrium, P(0) = 0 with\nreturn time 0; one-sided (q̇ > 0 only),\n"
        f"unstable: P'(0⁺) = exp(πμ/ω_d) = {origin_slope(model.mu):.3f}",
        (0, 0),
        xytext=(40, 25),
        textcoords="offset points",
        fontsize=8,
        arrowprops={"arrowstyle": "->", "lw": 0.6},
    )
    ax_map.set_xlim(-0.05, 3.6)
    ax_map.set_ylim(-0.05, 3.6)
    ax_map.set_xlabel("q̇ at crossing n of q = 0 upward (dimensionless)")
    ax_map.set_ylabel("q̇ at crossing n + 1 (dimensionless)")
    ax_map.set_title("return map on the section q = 0, q̇ > 0")
    ax_map.legend(fontsize=8, loc="lower right")
    ax_map.grid(alpha=0.3)
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
