"""The compass gait's level-ground least-effort optimum stabilised by transverse LQR and by
step-to-step LQR, compared.

Sources: Manchester, Tobenkin, Levashov & Tedrake 2011, "Regions of attraction for hybrid limit
cycles of walking robots" (transverse LQR on the compass gait); Drake's MATLAB
``examples/CompassGait/runTransverseCycle.m`` (its weights, Q = diag(10, 5, 1, 0.5) over
(stance, swing, stance_dot, swing_dot), R = 0.1); Shiriaev, Freidovich & Manchester 2008
(transverse linearisation).

The gait: ``gaitopt.optimize_gait(compass_gait, slope=0, cost="effort", period=0.8,
step_length=0.3)``, open-loop multipliers −1.34, 0.43, −0.003 with its profile ``u*(t)`` on the
clock.  Three controllers on the same gait:

* transverse LQR (:func:`gaitopt.transverse.transverse_lqr`, Drake's weights): ``u = u*(τ) −
  K(τ) x⊥`` along the whole step, ``τ`` the phase of the nearest orbit point;
* step-to-step LQR (:func:`gaitopt.optimize.stabilise`) with its defaults Q = I, R = 1e-3 (the
  README's): an offset ``δₖ`` held over step ``k``, decided at each heel strike;
* step-to-step LQR with Drake's weights on the section coordinates, Q = diag(10, 1, 0.5) over
  (stance, stance_dot, swing_dot), R = 0.1.

For each: the closed-loop multipliers (the transverse monodromy's and the step map's), the
largest perturbation survived along each section coordinate and sign (bisection up to 0.2
section units, each probe simulated for ``orbits`` orbits: a survivor completes them and ends
within a/10 of the fixed point; 12 orbits, 3 bisection steps after the probe at
0.2) and the peak hip torque in those survivors' runs.

Writes ``OUT/compass_transverse_lqr/``: ``comparison.json`` (everything; its
``linearisation_checks``: the monodromy against the Floquet multipliers of the compass gait,
kneed walker and SLIP, and the optimum), ``table.md`` (the README's table), ``transverse.png``
(the gain along the step in state coordinates, and the error per step from one start for the
open loop and each controller).  ``--fast``: one start for the transverse checks (stance_dot +
0.005), 10 orbits, one coordinate (stance_dot), one bisection step, no Drake-weights
step-to-step row, no linearisation checks.

Usage::

    python problems/compass_transverse_lqr.py --out results [--fast]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import gaitopt
from gaitopt.files import write_json
from gaitopt.optimize import stabilise
from gaitopt.transverse import transverse_lqr
from gaitopt.transverse.compare import (
    basin_rays,
    compare,
    sphere_directions,
    step_to_step_runner,
    transverse_runner,
)
from gaitopt.transverse.design import trial

STUDY = "compass_transverse_lqr"
Q_DRAKE = [10.0, 5.0, 1.0, 0.5]  # runTransverseCycle.m, over (stance, swing, stance_dot, swing_dot)
R_DRAKE = 0.1


def _fmt_mu(mu: list[list[float]]) -> str:
    parts = []
    for re, im in mu:
        parts.append(f"{re:.4f}" if abs(im) < 1e-12 else f"{re:.4f}{im:+.4f}j")
    return ", ".join(parts)


def table(rows: list[dict], coordinates: list[str]) -> str:
    head = ["controller", "closed-loop multipliers", "\\|λ\\|max"]
    head += [f"{c} {'+' if s > 0 else '−'}" for c in coordinates for s in (1, -1)]
    head += ["peak \\|τ\\| (N·m)"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for row in rows:
        cells = [row["controller"], _fmt_mu(row["closed_loop_multipliers"])]
        cells.append(f"{row['largest_modulus']:.4f}")
        for s in row["survived"]:
            cells.append(f"{s['survived']:.4f}" + ("+" if s["capped"] else ""))
        cells.append(f"{row['peak_input'][0]:.3f}" if row["peak_input"] else "—")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def linearisation_checks(optimum) -> list[dict]:
    """The transverse monodromy's eigenvalues against each gait's Floquet multipliers (the
    shooting's or the collocation's AD): the compass gait, the kneed walker (its state changes
    dimension at the knee strike) and the SLIP at their defaults, and the optimum (its profile
    on the clock, as its multipliers are)."""
    from gaitopt.transverse import transverse_linearisation

    rows = []
    cases = [
        (n, gaitopt.find_limit_cycle(gaitopt.model(n)))
        for n in ("compass_gait", "kneed_walker", "slip")
    ]
    cases.append(("compass_gait optimum (clock)", optimum))
    for name, gait in cases:
        lin = transverse_linearisation(gait)
        mu = lin.clock_multipliers if "clock" in name else lin.multipliers
        rest = list(np.asarray(mu, complex))
        gap = 0.0
        for z in np.asarray(gait.multipliers, complex):
            j = int(np.argmin([abs(z - y) for y in rest]))
            gap = max(gap, abs(z - rest.pop(j)))
        rows.append(
            {
                "gait": name,
                "transverse_dimensions": lin.dimensions,
                "floquet": [[z.real, z.imag] for z in np.asarray(gait.multipliers, complex)],
                "monodromy": [[z.real, z.imag] for z in np.asarray(mu, complex)],
                "largest_gap": gap,
                "others": [[z.real, z.imag] for z in rest],
            }
        )
        print(f"{name}: monodromy vs Floquet multipliers {gap:.2g}; others {rest}")
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="one coordinate, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / STUDY
    folder.mkdir(parents=True, exist_ok=True)
    orbits = 10 if args.fast else 12
    iterations = 1 if args.fast else 3
    coordinates = ["stance_dot"] if args.fast else None
    timings: dict[str, float] = {}

    clock = time.perf_counter()
    gait = gaitopt.optimize_gait(
        gaitopt.model("compass_gait", slope=0.0), "effort", period=0.8, step_length=0.3
    )
    timings["optimize_s"] = time.perf_counter() - clock
    if not gait.success:
        print(gait.message, file=sys.stderr)
        return 1
    print(f"optimum: cost {gait.cost:.10g}, multipliers {gait.multipliers}")
    clock = time.perf_counter()
    checks = [] if args.fast else linearisation_checks(gait)
    timings["linearisation_checks_s"] = time.perf_counter() - clock
    clock = time.perf_counter()
    starts = [[0.0, 0.005, 0.0]] if args.fast else None
    tv = transverse_lqr(gait, Q=Q_DRAKE, R=R_DRAKE, orbits=orbits, starts=starts)
    timings["transverse_lqr_s"] = time.perf_counter() - clock
    print(tv.message)
    clock = time.perf_counter()
    s2s = stabilise(gait, orbits=orbits)
    print(s2s.message)
    s2s_drake = None if args.fast else stabilise(gait, Q=[10.0, 1.0, 0.5], R=R_DRAKE, orbits=orbits)
    timings["step_to_step_s"] = time.perf_counter() - clock
    if s2s_drake is not None:  # its |λ| 0.69 needs about 19 orbits for its own 1e-3 check
        print(s2s_drake.message)
    controllers = {
        "transverse LQR, Q = diag(10, 5, 1, 0.5), R = 0.1": (
            transverse_runner(gait, tv.law, orbits),
            tv.closed_loop_multipliers,
        ),
        "step-to-step LQR, Q = I, R = 1e-3": (
            step_to_step_runner(gait, s2s.gain, orbits),
            s2s.closed_loop_multipliers,
        ),
    }
    if s2s_drake is not None:
        controllers["step-to-step LQR, Q = diag(10, 1, 0.5), R = 0.1"] = (
            step_to_step_runner(gait, s2s_drake.gain, orbits),
            s2s_drake.closed_loop_multipliers,
        )
    clock = time.perf_counter()
    rows = compare(gait, controllers, a_max=0.2, iterations=iterations, coordinates=coordinates)
    timings["survival_s"] = time.perf_counter() - clock
    # Basins of both closed loops on the section: rays spread over the sphere (section units),
    # each bisected with every probe simulated (a star-shaped inner estimate).
    clock = time.perf_counter()
    directions = sphere_directions(2 if args.fast else 16, len(gait.model.section.coordinates))
    basins = basin_rays(
        gait,
        {label: runner for label, (runner, _) in list(controllers.items())[:2]},
        directions,
        a_max=0.2,
        iterations=iterations,
    )
    timings["basin_rays_s"] = time.perf_counter() - clock
    basin_rows = []
    for label, rays in basins.items():
        radii = np.array([r["survived"] for r in rays])
        basin_rows.append(
            {
                "controller": label,
                "rays": len(rays),
                "smallest_radius": float(radii.min()),
                "median_radius": float(np.median(radii)),
                "largest_radius": float(radii.max()),
                "capped_rays": int(sum(r["capped"] for r in rays)),
                "probes": int(sum(len(r["probes"]) for r in rays)),
            }
        )
        print(
            f"basin of {label}: radius {radii.min():.4g} to {radii.max():.4g} "
            f"(median {np.median(radii):.4g}) over {len(rays)} rays"
        )
    names = coordinates or list(gait.model.section.coordinates)
    text = table(rows, names)
    print(text)
    (folder / "table.md").write_text(text, encoding="utf-8")
    summary = {
        "gait": {
            "cost": gait.cost,
            "multipliers": [[z.real, z.imag] for z in np.asarray(gait.multipliers, complex)],
            "fixed_point": gait.fixed_point,
        },
        "transverse": tv.to_json(),
        "step_to_step": s2s.to_json(),
        "step_to_step_drake_weights": None if s2s_drake is None else s2s_drake.to_json(),
        "comparison": rows,
        "basins": {"directions": directions.tolist(), "rays": basins, "summary": basin_rows},
        "linearisation_checks": checks,
        "orbits": orbits,
        "bisection_iterations": iterations,
        "a_max": 0.2,
        "fast": args.fast,
        "timings": timings,
    }
    write_json(summary, folder / "comparison.json")
    _figure(gait, tv, s2s, folder / "transverse.png", orbits)
    ok = tv.success and s2s.success and bool(rows)
    return 0 if ok else 1


def _figure(gait, tv, s2s, path: Path, orbits: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gaitopt.optimize.stabilisation.closed_loop import run
    from gaitopt.plotting import save_figure
    from gaitopt.transverse.linearise import householder

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    frame = tv.linearisation.frames[0]
    taus = np.linspace(0.0, frame.stage.duration, 161)
    rows = []
    for tau in taus:
        K = tv.riccati.gain(0, tau)
        Pi = householder(frame.at(tau)["f"], frame.axis, frame.sign)
        rows.append((K @ Pi).ravel())  # δu = −K Π (x − x*): the gain on the state error
    G = np.array(rows)
    units = ["N·m/rad", "N·m/rad", "N·m·s/rad", "N·m·s/rad"]
    for j, name in enumerate(gait.model.state_names):
        ax1.plot(taus, G[:, j], label=f"{name} ({units[j]})")
    ax1.set_xlabel("phase along the step τ (s)")
    ax1.set_ylabel("gain K(τ)Π(τ), hip torque per state error")
    ax1.set_title("transverse LQR gain on x − x*(τ)")
    ax1.legend(fontsize=8)
    model = gait.model
    s_star = np.asarray(model.section_coordinates_of(model.state_vector(gait.fixed_point)))
    s0 = s_star + np.array([0.0, 0.05, 0.0])
    runs = {"transverse LQR": trial(gait, tv.law, s0, orbits).errors}
    runs["step-to-step LQR (Q = I, R = 1e-3)"] = run(gait, s0, s2s.gain, orbits)[2]
    runs["open loop u*(t)"] = run(gait, s0, None, orbits)[2]
    for label, errors in runs.items():
        ax2.semilogy(range(len(errors)), np.maximum(errors, 1e-16), "o-", ms=3, label=label)
    ax2.set_xlabel("step k")
    ax2.set_ylabel("section error max|s_k − s*| (rad, rad/s)")
    ax2.set_title("from stance_dot + 0.05 rad/s")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


if __name__ == "__main__":
    sys.exit(main())
