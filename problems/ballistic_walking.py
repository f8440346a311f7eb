"""Ballistic walking (Mochon & McMahon 1980): the step periods for which a passive swing exists.

Mochon & McMahon ("Ballistic walking", J. Biomech. 13:49–57, 1980) modelled the swing phase of
human walking with no muscle moments — the stance leg an inverted pendulum carrying the body, the
swing leg a free thigh–shank double pendulum — and asked, for each step length, which swing times
admit such a ballistic swing from toe-off to heel strike.  They found a bounded range of swing
times for each step length, and that normal walking lies in it.  This study computes that range
for :class:`gaitopt.models.ballistic_walker.BallisticWalker` (a 70 kg, 0.9 m-legged adult with
Winter's segment data; see the model's docstring for its simplifications against the paper):

* for each step length, the swing time is swept and the boundary-value problem (three toe-off
  rates so that heel strike comes at that time) solved by Newton's method, continued in the time;
* a solved swing is *ballistic* when its knee never hyperextends, its foot clears the ground and
  its stance leg pushes (the paper's conditions); the study also reports the sub-range where the
  knee's peak flexion stays below 70° (about the largest knee flexion of normal human swing), a
  physiological bound that is ours, not the paper's;
* the lower end of each range is set against a closed form: the shortest swing of the hip as a
  point mass on a massless inverted-pendulum leg (the swing leg's mass neglected), where the
  leg force m (g cos θ − l θ̇²) reaches zero at toe-off (its minimum over the step): θ̇₀² =
  (g/l) cos α and T_min = ∫_{−α}^{α} dθ / sqrt(θ̇₀² + 2 (g/l)(cos α − cos θ)), α = asin(d/2l).

The paper's own numbers (its figure of the shortest and longest swing time against step length,
and the measured swing times it compares with) were not found in the sources available to this
project, so no digit-by-digit comparison is made.

    python problems/ballistic_walking.py --out results [--fast]

Writes results/ballistic_walking/: summary.json, swings.csv, ballistic_walking.png.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.integrate import quad  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

PEAK_KNEE = math.radians(70)  # our physiological bound (normal swing peaks near 60–70°)


def point_mass_shortest_swing(step_length: float, leg_length: float, gravity: float) -> float:
    """The shortest swing time (s) of a point-mass hip on a massless straight stance leg from
    θ = −α to α, α = asin(d / 2l), with the leg still pushing: its force m (g cos θ − l θ̇²), by
    energy conservation θ̇² = θ̇₀² + 2 (g/l)(cos α − cos θ), is least at θ = ±α, so the leg pulls
    first at toe-off once θ̇₀² > (g/l) cos α; at that bound the time is the quadrature below."""
    alpha = math.asin(step_length / (2 * leg_length))
    w = gravity / leg_length
    rate0_sq = w * math.cos(alpha)
    time, _ = quad(
        lambda th: 1 / math.sqrt(rate0_sq + 2 * w * (math.cos(alpha) - math.cos(th))), -alpha,
        alpha, epsabs=1e-13, epsrel=1e-12,
    )  # fmt: skip
    return time


def shortest_ballistic_swing(model, swings: list) -> float | None:
    """The swing time (s) where the lower end's condition — the stance leg's least vertical
    ground force over the swing — crosses zero, located by Brent's method to 1e-4 s between the
    last grid time where the leg pulls and the first ballistic one (None without that bracket)."""
    from scipy.optimize import brentq

    first = next((k for k, sw in enumerate(swings) if sw.ballistic), None)
    if first is None or first == 0 or "pulls" not in swings[first - 1].reason:
        return None
    guess = swings[first].rates
    return brentq(
        lambda t: model.swing(t, guess).min_vertical_force, swings[first - 1].time,
        swings[first].time, xtol=1e-4,
    )  # fmt: skip


def sweep(model, times: np.ndarray) -> list:
    """Swings at each time, continued from the shortest ballistic-feasible start outward."""
    out = []
    guess = None
    for t in times:
        s = model.swing(float(t), guess)
        if s.success and np.all(np.isfinite(s.rates)):
            guess = s.rates
        out.append(s)
    return out


def ranges(times: np.ndarray, flags: list[bool]) -> list[list[float]]:
    """Maximal runs of True as [first, last] times."""
    runs, start = [], None
    for k, f in enumerate(flags):
        if f and start is None:
            start = k
        if (not f or k == len(flags) - 1) and start is not None:
            end = k if f else k - 1
            runs.append([float(times[start]), float(times[end])])
            start = None
    return runs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="coarse sweep for CI")
    parser.add_argument("--scheduler", default=None, help="unused (serial study)")
    parser.add_argument("--workers", type=int, default=2, help="unused (serial study)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "ballistic_walking"
    folder.mkdir(parents=True, exist_ok=True)
    steps = (0.6, 0.7) if args.fast else (0.6, 0.7, 0.8, 0.9)
    times = np.arange(0.2, 0.96, 0.05 if args.fast else 0.025)

    base = gaitopt.model("ballistic_walker")
    rows, table, swings_shown = [], {}, {}
    for d in steps:
        model = base.replace(step_length=d)
        swings = sweep(model, times)
        flags = [s.ballistic for s in swings]
        physio = [s.ballistic and s.max_knee_flexion <= PEAK_KNEE for s in swings]
        reasons = {}
        for s in swings:
            if not s.ballistic and s.reason:
                reasons.setdefault(s.reason, []).append(s.time)
        table[f"{d:g}"] = {
            "ballistic_ranges_s": ranges(times, flags),
            "ballistic_and_knee_below_70deg_s": ranges(times, physio),
            "failures": {k: [min(v), max(v)] for k, v in reasons.items()},
            "natural_swing_time_s": model.natural_swing_time(),
            "shortest_ballistic_swing_s": shortest_ballistic_swing(model, swings),
            "point_mass_shortest_swing_s": point_mass_shortest_swing(
                d, model.leg_length, model.gravity
            ),
        }
        for s in swings:
            rows.append(
                [d, s.time, s.success, s.ballistic, s.reason, *s.rates, s.min_knee_flexion,
                 s.max_knee_flexion, s.min_foot_height, s.min_vertical_force]
            )  # fmt: skip
        swings_shown[d] = swings
    write_csv(
        ["step_length", "swing_time", "solved", "ballistic", "reason", "stance_dot0",
         "thigh_dot0", "shank_dot0", "min_knee_flexion", "max_knee_flexion", "min_foot_height",
         "min_vertical_force"],
        rows,
        folder / "swings.csv",
    )  # fmt: skip
    summary = {
        "model": "ballistic_walker",
        "params": base.params,
        "source": "Mochon & McMahon 1980, J. Biomech. 13:49–57 (model and question); numbers "
        "computed here",
        "criteria": "ballistic = boundary conditions met to 1e-9 rad, knee flexion ≥ 0 "
        "throughout and extending at heel strike, swing foot above the ground, vertical ground "
        "force > 0 (the stance leg pushes), hip moving forward",
        "swing_time_grid_s": [float(times[0]), float(times[-1]), float(times[1] - times[0])],
        "by_step_length_m": table,
        "closed_form": "point_mass_shortest_swing_s: the hip a point mass on a massless "
        "inverted-pendulum leg (swing leg's mass neglected), the leg force zero at toe-off",
        "published_numbers": "not compared: Mochon & McMahon's figure of the swing-time range "
        "against step length was not available",
    }
    write_json(summary, folder / "summary.json")
    _figure(base, steps, times, swings_shown, table, folder / "ballistic_walking.png")
    for d, entry in table.items():
        print(
            f"step {d} m: ballistic swing times {entry['ballistic_ranges_s']} s; with peak knee "
            f"≤ 70°: {entry['ballistic_and_knee_below_70deg_s']} s; failures "
            f"{entry['failures']}; shortest ballistic swing "
            f"{entry['shortest_ballistic_swing_s']:.4f} s (point-mass hip, massless legs: "
            f"{entry['point_mass_shortest_swing_s']:.4f} s)"
        )
    print(f"wrote {folder}")
    return 0


def _figure(base, steps, times, swings, table, path: Path) -> None:
    fig, (left, mid, right) = plt.subplots(1, 3, figsize=(15, 4.8), layout="constrained")
    for d in steps:
        entry = table[f"{d:g}"]
        for lo, hi in entry["ballistic_ranges_s"]:
            left.plot([d, d], [lo, hi], color="C0", lw=8, solid_capstyle="butt")
        for lo, hi in entry["ballistic_and_knee_below_70deg_s"]:
            left.plot([d, d], [lo, hi], color="C2", lw=3, solid_capstyle="butt")
        fails = [s.time for s in swings[d] if not s.ballistic]
        left.plot([d] * len(fails), fails, "x", color="C3", ms=4)
    grid = np.linspace(min(steps) - 0.05, max(steps) + 0.05, 50)
    left.plot(grid, [point_mass_shortest_swing(x, base.leg_length, base.gravity) for x in grid],
              "-", color="C1", lw=1.2,
              label="point-mass hip on a massless leg: shortest swing (closed form)")  # fmt: skip
    located = [(d, table[f"{d:g}"]["shortest_ballistic_swing_s"]) for d in steps]
    located = [(d, t) for d, t in located if t is not None]
    if located:
        left.plot(*zip(*located, strict=True), "_", color="k", ms=18, mew=2,
                  label="shortest ballistic swing (located, 1e-4 s)")  # fmt: skip
    left.plot([], [], color="C0", lw=8, label="ballistic swing exists")
    left.plot([], [], color="C2", lw=3, label="… with peak knee flexion ≤ 70°")
    left.plot([], [], "x", color="C3", label="no ballistic swing")
    left.axhline(base.natural_swing_time(), color="k", lw=0.8, ls="--",
                 label="swing leg's pendulum half-period")  # fmt: skip
    left.set_xlabel("step length d (m)")
    left.set_ylabel("swing time T (s)")
    left.set_title("swing times with a ballistic swing (Mochon & McMahon's question)", fontsize=9)
    left.set_ylim(0.15, 1.3)  # room above the bars for the legend
    left.legend(fontsize=7.5, loc="upper left")
    left.grid(alpha=0.3)

    d = 0.7 if 0.7 in swings else steps[-1]
    shown = [s for s in swings[d] if s.ballistic]
    pick = shown[len(shown) // 3] if shown else None
    if pick is not None:
        model = base.replace(step_length=d)
        pts = model.phases[0].points
        for k in np.linspace(0, len(pick.t) - 1, 9).astype(int):
            P = np.asarray(pts(pick.x[:, k], model.p))
            shade = 0.2 + 0.6 * k / (len(pick.t) - 1)
            mid.plot(P[0], P[1], "-o", ms=2.5, lw=1.2, color=plt.cm.viridis(shade))
        mid.axhline(0, color="0.3", lw=1)
        mid.set_aspect("equal")
        mid.set_title(f"a ballistic swing: d = {d:g} m, T = {pick.time:.3g} s (toe-off → heel "
                      "strike)", fontsize=9)  # fmt: skip
    mid.set_xlabel("horizontal position x (m)")
    mid.set_ylabel("height y (m)")
    mid.grid(alpha=0.3)

    for s in swings[d][:: max(len(swings[d]) // 6, 1)]:
        if not s.success:
            continue
        style = "-" if s.ballistic else ":"
        label = f"T = {s.time:.3g} s" + ("" if s.ballistic else " (not ballistic)")
        right.plot(s.t / s.time, np.degrees(s.x[1] - s.x[2]), style, lw=1.2, label=label)
    right.axhline(0, color="k", lw=0.8)
    right.set_xlabel("fraction of the swing t/T (dimensionless)")
    right.set_ylabel("knee flexion thigh − shank (deg)")
    right.set_title(f"knee flexion through the swing, d = {d:g} m", fontsize=9)
    right.legend(fontsize=7)
    right.grid(alpha=0.3)
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
