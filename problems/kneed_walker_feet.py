"""What curved feet buy the kneed walker: basin of attraction, local stability and slope range.

Claim under test (Tedrake, *Underactuated Robotics*, ch. "Simple models of walking and running",
on the kneed walker; curved feet after McGeer 1990, "Passive walking with knees", Proc. IEEE ICRA):
the region of attraction improves considerably with curved feet.  The point-foot model and its
parameters are Hsu Chen 2007 ("Passive dynamic walking with knees: a point foot model", MIT);
the curved feet are circular arcs of radius R centred on the leg axis R above the foot, rolling
without slipping (``gaitopt/models/kneed_walker.py``).

For each foot radius (0, 0.1, 0.2, 0.3 m; valid range [0, a1 + b1 = 0.5] m) this script measures

1. the gait and its largest |Floquet multiplier| at the default slope 0.0504 rad and at 0.07 rad
   (R = 0.3 m has no gait at 0.0504 rad: the branch in R folds at R ≈ 0.299 m there);
2. the basin of attraction in a 2-D slice of the Poincaré section: the post-heel-strike velocities
   ``(q1_dot, q2_dot)`` on a grid around the fixed point (``q1`` at its fixed-point value; a push
   just after heel strike), each point simulated (SciPy, ``gaitopt.simulate``) until it is within
   1e-3 of the fixed point (converged), falls, trips, or runs out of steps; reported as the
   converging fraction and area of the window and the *push margin*, the distance (rad/s) from the
   fixed point to the nearest grid point that does not converge;
3. the slope range with a stable gait: a plain loop over slopes with warm starts
   (``find_limit_cycle(model.replace(slope=s), previous)``) up and down from 0.07 rad until the
   gait is lost or a multiplier leaves the unit circle (located by bisection).

Usage::

    python problems/kneed_walker_feet.py --out results [--fast] [--workers 2]

Writes ``OUT/kneed_walker_feet/``: ``summary.json`` (everything below, with settings and
sources), ``gaits.csv``, ``slopes.csv``, ``basins.csv`` and ``feet.png`` (basins and multipliers
against slope).  ``--fast`` (CI): radii 0 and 0.2 m, the default slope only, a 7×7 grid and a
coarse slope step.  Full mode: 2 × 4 grids of 25×25 simulations and four slope scans, about a
minute on 2 cores.  Never shows a figure.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

MODEL = "kneed_walker"
DEFAULT_SLOPE = 0.0504  # rad, Hsu Chen 2007
ANCHOR_SLOPE = 0.07  # rad: every radius studied has a stable gait here (start of the scans)
SOURCES = [
    "Hsu Chen 2007, Passive dynamic walking with knees: a point foot model (MIT thesis)",
    "McGeer 1990, Passive walking with knees (Proc. IEEE ICRA), curved feet",
    "Tedrake, Underactuated Robotics, ch. Simple models of walking and running (kneed walker)",
]
OUTCOMES = ("converged", "fell", "tripped", "no lift-off", "undecided")


@dataclass(frozen=True)
class Settings:
    """What is computed (full mode by default)."""

    radii: tuple[float, ...] = (0.0, 0.1, 0.2, 0.3)
    basin_slopes: tuple[float, ...] = (DEFAULT_SLOPE, ANCHOR_SLOPE)
    grid: int = 25  # points per axis (odd: the fixed point is a grid node)
    window: tuple[float, float] = (0.5, 1.5)  # ± rad/s around (q1_dot*, q2_dot*)
    converged_within: float = 1e-3  # max-norm distance to the fixed point on the section
    max_steps: int = 100
    margin_directions: int = 8  # rays in the velocity slice for the push margin
    margin_step: float = 0.05  # rad/s between samples along a ray (then bisection)
    margin_max: float = 1.0  # rad/s: rays stop here
    slope_step: float = 0.002  # rad, first step of the slope scans
    slope_resolution: float = 2.5e-4  # rad, boundaries located to this
    rtol: float = 1e-8  # basin simulations (the gaits themselves are verified at 1e-11)

    @classmethod
    def fast(cls) -> Settings:
        return cls(
            radii=(0.0, 0.2),
            basin_slopes=(DEFAULT_SLOPE,),
            grid=7,
            max_steps=60,
            margin_directions=4,
            slope_step=0.005,
            slope_resolution=1e-3,
        )


# -- gaits and continuation in one parameter ----------------------------------------------------


_LAST_FAILURE: dict[str, str] = {"message": ""}


def _solve(model, guess) -> gaitopt.LimitCycle | None:
    """``find_limit_cycle``, or None if it fails (its message kept in ``_LAST_FAILURE``)."""
    try:
        cycle = gaitopt.find_limit_cycle(model, guess)
    except np.linalg.LinAlgError as exc:
        # gaitopt issue: a Newton run that "converges" to a singular point makes the
        # discretisation-error estimate raise instead of returning success=False.
        _LAST_FAILURE["message"] = f"LinAlgError in find_limit_cycle: {exc}"
        return None
    if not cycle.success:
        _LAST_FAILURE["message"] = cycle.message
        return None
    return cycle


def follow(cycle, param: str, target: float, step: float, smallest: float = 1e-4):
    """Warm-started steps of ``param`` towards ``target`` (halving the step on failure).

    Returns the cycle at ``target``, or None with the last value reached.
    """
    value = getattr(cycle.model, param)
    step = math.copysign(step, target - value)
    while abs(target - value) > 1e-12:
        nxt = target if abs(target - value) <= abs(step) * (1 + 1e-9) else value + step
        new = _solve(cycle.model.replace(**{param: nxt}), cycle)
        if new is None:
            step /= 2
            if abs(step) < smallest:
                return None, value
            continue
        cycle, value = new, nxt
    return cycle, value


def largest(cycle) -> float:
    return float(np.max(np.abs(cycle.multipliers)))


def kind_of_loss(cycle) -> str:
    """How the dominant multiplier leaves the unit circle."""
    lam = complex(cycle.multipliers[0])
    if abs(lam.imag) > 1e-9:
        return "complex pair (Neimark-Sacker)"
    return "-1 (period doubling)" if lam.real < 0 else "+1"


def scan_slopes(radius: float, section_point: list[float], settings: Settings) -> dict:
    """Slope range with a stable gait, from the anchor slope down and up (one radius)."""
    model = gaitopt.model(MODEL, foot_radius=radius, slope=ANCHOR_SLOPE)
    start = _solve(model, dict(zip(model.section.coordinates, section_point, strict=True)))
    if start is None:
        return {"foot_radius": radius, "points": [], "error": "no gait at the anchor slope"}
    points = [_row(start)]
    ends = {}
    for direction, name in ((-1, "low"), (+1, "high")):
        cycle, step = start, settings.slope_step
        while True:
            s = cycle.model.slope + direction * step
            new = _solve(cycle.model.replace(slope=s), cycle) if 0 < s <= 0.3 else None
            if new is None:
                step /= 2
                if step < settings.slope_resolution:
                    beyond = _LAST_FAILURE["message"].split(";")[0]
                    ends[name] = {
                        "slope": cycle.model.slope,
                        "why": f"the branch ends (last max|multiplier| {largest(cycle):.3f}); "
                        f"one step beyond: {beyond}",
                    }
                    break
                continue
            points.append(_row(new))
            if new.stable:
                cycle = new
                continue
            # A multiplier left the unit circle between cycle and new: bisect.
            stable, unstable = cycle, new
            while abs(unstable.model.slope - stable.model.slope) > settings.slope_resolution:
                mid = 0.5 * (stable.model.slope + unstable.model.slope)
                probe = _solve(stable.model.replace(slope=mid), stable)
                if probe is None:
                    break
                points.append(_row(probe))
                stable, unstable = (probe, unstable) if probe.stable else (stable, probe)
            ends[name] = {
                "slope": stable.model.slope,
                "why": f"loses stability: {kind_of_loss(unstable)} at slope "
                f"{unstable.model.slope:.5f}",
            }
            break
    points.sort(key=lambda r: r["slope"])
    return {
        "foot_radius": radius,
        "stable_range": [ends["low"]["slope"], ends["high"]["slope"]],
        "ends": ends,
        "points": points,
    }


def _row(cycle) -> dict:
    return {
        "slope": cycle.model.slope,
        "foot_radius": cycle.model.foot_radius,
        "period": cycle.period,
        "max_abs_multiplier": largest(cycle),
        "stable": bool(cycle.stable),
        **{k: cycle.fixed_point[k] for k in cycle.section_coordinates},
    }


# -- basins -------------------------------------------------------------------------------------


def basin_row(
    params: dict, fixed: list[float], q1_dots: list[float], q2_dot: float, settings: Settings
) -> list[tuple[str, int]]:
    """Outcome and steps of each grid point of one row (runs in a worker process)."""
    model = gaitopt.model(MODEL, **params)
    star = np.asarray(fixed)
    return [_outcome(model, np.array([star[0], v, q2_dot]), star, settings) for v in q1_dots]


@lru_cache(maxsize=1)
def _release_check() -> ca.Function:
    """``(ḣ, ẅ)`` of a phase-0 state: the trailing foot's rate of rise from the slope and the
    knee's flexion acceleration ``q̈3 − q̈2``.  Just after heel strike both must be positive for
    the model's phase sequence to hold (the foot lifts off, the released knee flexes)."""
    phase = gaitopt.model(MODEL).phases[0]
    x = ca.SX.sym("x", phase.n)
    u = ca.SX.sym("u", 0)
    p = ca.SX.sym("p", phase.flow.size1_in(2))
    f = phase.flow(x, u, p)
    clearance = next(c for c in phase.constraints if c.outcome == "trip")
    rise = ca.jtimes(clearance.function(x, u, p), x, f)
    return ca.Function("release", [x, p], [ca.vertcat(rise, f[5] - f[4])])


def _releases(model, x) -> bool:
    rise, flex = np.asarray(_release_check()(x, model.p), dtype=float).ravel()
    return rise > 0 and flex > 0


def _outcome(model, s, star, settings: Settings) -> tuple[str, int]:
    """Simulate from section point ``s`` until it converges to ``star`` or fails.

    ``no lift-off``: at some return (or the start) the trailing foot would not leave the slope or
    its knee would not flex, which leaves the model's phase sequence (no double support, no
    locked-knee swing); counted as a failure.
    """
    x, done, chunk = model.lift(s), 0, 5
    if not _releases(model, x):
        return "no lift-off", 0
    while done < settings.max_steps:
        sim = gaitopt.simulate(model, x, steps=chunk, rtol=settings.rtol, atol=settings.rtol / 10)
        for k, state in enumerate(sim.section_states[1:], start=1):
            if not _releases(model, state):
                return "no lift-off", done + k
            distance = np.max(np.abs(model.section_coordinates_of(state) - star))
            if distance < settings.converged_within:
                return "converged", done + k
        if not sim.success:
            last = sim.events[-1].transition if sim.events else ""
            return ("tripped" if last == "trip" else "fell"), done + sim.steps
        done += chunk
        x = sim.section_states[-1]
    return "undecided", done


def push_margin(params: dict, fixed: list[float], angle: float, settings: Settings) -> dict:
    """Smallest velocity perturbation along one ray of the (q1_dot, q2_dot) slice that is not
    recovered: samples every ``margin_step`` rad/s, then bisection to 2e-3 rad/s."""
    model = gaitopt.model(MODEL, **params)
    star = np.asarray(fixed)
    direction = np.array([0.0, math.cos(angle), math.sin(angle)])

    def recovers(r: float) -> bool:
        return _outcome(model, star + r * direction, star, settings)[0] == "converged"

    inside, r = 0.0, settings.margin_step
    while r <= settings.margin_max + 1e-12 and recovers(r):
        inside, r = r, r + settings.margin_step
    if r > settings.margin_max + 1e-12:
        return {"angle": angle, "margin": float("inf")}
    outside = r
    while outside - inside > 2e-3:
        mid = 0.5 * (inside + outside)
        inside, outside = (mid, outside) if recovers(mid) else (inside, mid)
    return {"angle": angle, "margin": inside}


def _margin_summary(rays: list[dict]) -> dict:
    """Smallest unrecovered push over the rays, and along ±q1_dot (speed added / removed)."""
    by_angle = {round(r["angle"], 9): r["margin"] for r in rays}
    return {
        "min_rad_per_s": min(by_angle.values()),
        "faster_rad_per_s": by_angle.get(0.0),
        "slower_rad_per_s": by_angle.get(round(math.pi, 9)),
        "rays": rays,
    }


def basin_metrics(q1_dots, q2_dots, outcomes, star) -> dict:
    grid = np.array([[o == "converged" for o, _ in row] for row in outcomes])
    cell = (q1_dots[1] - q1_dots[0]) * (q2_dots[1] - q2_dots[0])
    A, B = np.meshgrid(q1_dots, q2_dots)
    distance = np.hypot(A - star[1], B - star[2])
    failing = distance[~grid]
    steps = [n for row in outcomes for o, n in row if o == "converged"]
    counts = {k: int(sum(o == k for row in outcomes for o, _ in row)) for k in OUTCOMES}
    return {
        "fraction": float(grid.mean()),
        "area_rad2_per_s2": float(grid.sum() * cell),
        "grid_margin_rad_per_s": float(failing.min()) if failing.size else float("inf"),
        "mean_steps_to_converge": float(np.mean(steps)) if steps else float("nan"),
        "counts": counts,
    }


# -- the study ----------------------------------------------------------------------------------


def run(out: Path, settings: Settings, workers: int) -> dict:
    t0 = time.perf_counter()
    folder = out / "kneed_walker_feet"
    folder.mkdir(parents=True, exist_ok=True)
    default = gaitopt.find_limit_cycle(gaitopt.model(MODEL))
    if not default.success:
        raise RuntimeError(f"no gait at the defaults: {default.message}")
    anchor0, _ = follow(default, "slope", ANCHOR_SLOPE, 0.005)

    # 1. Gaits: each radius at the anchor slope, then at each basin slope.
    gaits: dict[tuple[float, float], gaitopt.LimitCycle | None] = {}
    anchors = {}
    notes = []
    for R in settings.radii:
        anchor, reached = follow(anchor0, "foot_radius", R, 0.025)
        if anchor is None:
            raise RuntimeError(
                f"no gait at R = {R} m, slope {ANCHOR_SLOPE} (reached R = {reached})"
            )
        anchors[R] = anchor
        for slope in settings.basin_slopes:
            cycle, reached = follow(anchor, "slope", slope, 0.005)
            if cycle is None:
                # Which limit: follow R at this slope from the point foot to locate the fold.
                base, _ = follow(default, "slope", slope, 0.005)
                _, r_end = follow(base, "foot_radius", R, 0.0125, smallest=1e-3)
                notes.append(
                    f"R = {R} m has no gait at slope {slope} rad (followed from slope "
                    f"{ANCHOR_SLOPE} it ends near {reached:.4f} rad; the branch in R at this "
                    f"slope ends near R = {r_end:.4f} m, a fold)"
                )
            gaits[(slope, R)] = cycle
    print(f"gaits solved ({time.perf_counter() - t0:.1f} s)", flush=True)

    # 2 + 3. Slope scans and basin rows, all in one pool.
    n, (w1, w2) = settings.grid, settings.window
    basin_jobs, margin_jobs = {}, {}
    with ProcessPoolExecutor(max_workers=workers) as pool:
        scans = {
            R: pool.submit(scan_slopes, R, anchors[R].section_point.tolist(), settings)
            for R in settings.radii
        }
        for (slope, R), cycle in gaits.items():
            if cycle is None:
                continue
            star = cycle.section_point
            q1_dots = star[1] + np.linspace(-w1, w1, n)
            q2_dots = star[2] + np.linspace(-w2, w2, n)
            params = cycle.model.params
            rows = [
                pool.submit(basin_row, params, star.tolist(), q1_dots.tolist(), b, settings)
                for b in q2_dots
            ]
            basin_jobs[(slope, R)] = (star, q1_dots, q2_dots, rows)
            angles = 2 * np.pi * np.arange(settings.margin_directions) / settings.margin_directions
            margin_jobs[(slope, R)] = [
                pool.submit(push_margin, params, star.tolist(), float(t), settings) for t in angles
            ]
        scan_results = {R: f.result() for R, f in scans.items()}
        margins = {key: [f.result() for f in jobs] for key, jobs in margin_jobs.items()}
        basins = {
            key: (star, a, b, [r.result() for r in rows])
            for key, (star, a, b, rows) in basin_jobs.items()
        }
    print(f"basins and slope scans done ({time.perf_counter() - t0:.1f} s)", flush=True)

    # -- collect ---------------------------------------------------------------------------------
    table = []
    for R in settings.radii:
        scan = scan_results[R]
        entry = {
            "foot_radius": R,
            "stable_slope_range": scan.get("stable_range"),
            "slope_range_ends": scan.get("ends"),
            "at_slope": {},
        }
        for slope in settings.basin_slopes:
            cycle = gaits[(slope, R)]
            if cycle is None:
                entry["at_slope"][str(slope)] = {"gait": False}
                continue
            star, a, b, outcomes = basins[(slope, R)]
            entry["at_slope"][str(slope)] = {
                "gait": True,
                "fixed_point": cycle.fixed_point,
                "period": cycle.period,
                "multipliers": [[m.real, m.imag] for m in cycle.multipliers],
                "max_abs_multiplier": largest(cycle),
                "basin": basin_metrics(a, b, outcomes, star),
                "push_margin": _margin_summary(margins[(slope, R)]),
            }
        table.append(entry)
    summary = {
        "study": "kneed_walker_feet",
        "sources": SOURCES,
        "settings": asdict(settings),
        "slice": "post-heel-strike velocities (q1_dot, q2_dot) with q1 = q1*; window "
        f"±{w1} × ±{w2} rad/s around the fixed point, {n}×{n} grid",
        "push_margin": f"{settings.margin_directions} rays from the fixed point in the same slice; "
        "the smallest perturbation (rad/s) not recovered along each (samples every "
        f"{settings.margin_step} rad/s up to {settings.margin_max}, then bisection to 2e-3)",
        "results": table,
        "notes": notes,
        "runtime_s": time.perf_counter() - t0,
        "workers": workers,
    }
    write_json(summary, folder / "summary.json")
    _write_csv(
        folder / "gaits.csv",
        [
            "foot_radius",
            "slope",
            "period",
            "max_abs_multiplier",
            "stable",
            "q1",
            "q1_dot",
            "q2_dot",
        ],
        [_row(c) for c in gaits.values() if c is not None],
    )
    _write_csv(
        folder / "slopes.csv",
        [
            "foot_radius",
            "slope",
            "period",
            "max_abs_multiplier",
            "stable",
            "q1",
            "q1_dot",
            "q2_dot",
        ],
        [p for R in settings.radii for p in scan_results[R]["points"]],
    )
    _write_csv(
        folder / "basins.csv",
        ["slope", "foot_radius", "q1", "q1_dot", "q2_dot", "outcome", "steps"],
        [
            {
                "slope": slope,
                "foot_radius": R,
                "q1": star[0],
                "q1_dot": a[j],
                "q2_dot": b[i],
                "outcome": outcomes[i][j][0],
                "steps": outcomes[i][j][1],
            }
            for (slope, R), (star, a, b, outcomes) in basins.items()
            for i in range(len(b))
            for j in range(len(a))
        ],
    )
    _figure(folder / "feet.png", settings, table, basins, scan_results)
    _print_table(table, settings)
    return summary


def _write_csv(path: Path, fields: list[str], rows: list[dict]) -> None:
    write_csv(fields, ([row.get(k) for k in fields] for row in rows), path)


def _figure(path, settings, table, basins, scans) -> None:
    radii, slopes = settings.radii, settings.basin_slopes
    fig = plt.figure(
        figsize=(3.0 * len(radii), 2.9 * (len(slopes) + 1) + 0.4), layout="constrained"
    )
    grid = fig.add_gridspec(len(slopes) + 1, len(radii))
    colours = ListedColormap(["#4c9a2a", "#d9d9d9", "#f4a582", "#b2abd2", "#92c5de"])
    codes = {k: i for i, k in enumerate(OUTCOMES)}
    for i, slope in enumerate(slopes):
        for j, R in enumerate(radii):
            ax = fig.add_subplot(grid[i, j])
            entry = table[j]["at_slope"][str(slope)]
            if not entry["gait"]:
                ax.text(0.5, 0.5, "no gait", ha="center", va="center", transform=ax.transAxes)
                ax.set_title(f"R = {R:g} m, slope {slope:g}", fontsize=8)
                ax.set_xticks([])
                ax.set_yticks([])
                continue
            star, a, b, outcomes = basins[(slope, R)]
            image = np.array([[codes[o] for o, _ in row] for row in outcomes])
            ax.imshow(
                image,
                origin="lower",
                extent=(a[0], a[-1], b[0], b[-1]),
                aspect="auto",
                cmap=colours,
                vmin=-0.5,
                vmax=len(OUTCOMES) - 0.5,
                interpolation="nearest",
            )
            ax.plot(star[1], star[2], "k+", ms=9, mew=1.5)
            ax.set_xlim(a[0], a[-1])
            ax.set_ylim(b[0], b[-1])
            ax.set_autoscale_on(False)  # margins beyond the window are not drawn
            rays = entry["push_margin"]["rays"]
            finite = [(r["angle"], r["margin"]) for r in rays if math.isfinite(r["margin"])]
            if finite:
                ax.plot(
                    [star[1] + m * math.cos(t) for t, m in finite],
                    [star[2] + m * math.sin(t) for t, m in finite],
                    "k.",
                    ms=3,
                )
            ax.set_title(
                f"R = {R:g} m, slope {slope:g}: {100 * entry['basin']['fraction']:.0f}% recover\n"
                f"push margin {entry['push_margin']['min_rad_per_s']:.3f} rad/s, "
                f"max|λ| {entry['max_abs_multiplier']:.2f}",
                fontsize=8,
            )
            ax.set_xlabel("q1_dot after heel strike (rad/s)", fontsize=8)
            if j == 0:
                ax.set_ylabel("q2_dot after heel strike (rad/s)", fontsize=8)
            ax.tick_params(labelsize=7)
    ax = fig.add_subplot(grid[len(slopes), :])
    for k, R in enumerate(radii):
        pts = scans[R]["points"]
        (line,) = ax.plot(
            [p["slope"] for p in pts],
            [p["max_abs_multiplier"] for p in pts],
            ".-",
            ms=3,
            lw=1,
            label=f"R = {R:g} m",
        )
        if scans[R].get("stable_range"):
            lo, hi = scans[R]["stable_range"]
            ax.plot([lo, hi], [0.08 + 0.08 * k] * 2, color=line.get_color(), lw=4)
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    for slope in slopes:
        ax.axvline(slope, color="0.5", lw=0.6, ls="--")
    ax.set_ylim(0, 1.6)
    ax.set_xlabel("slope (rad)")
    ax.set_ylabel("max |Floquet multiplier|")
    ax.set_title(
        "Gaits against slope; bars: slope range with a stable gait; dashed: basin slopes",
        fontsize=9,
    )
    ax.legend(fontsize=8, ncol=len(radii), loc="upper center")
    handles = [plt.Rectangle((0, 0), 1, 1, color=colours(k)) for k in range(len(OUTCOMES))]
    fig.legend(handles, OUTCOMES, loc="outside lower center", ncol=len(OUTCOMES), fontsize=8)
    fig.suptitle(
        "Kneed walker, curved feet of radius R: basins of a push just after heel strike "
        "(+ gait, · push margin along 8 rays)",
        fontsize=10,
    )
    save_figure(fig, path)


def _print_table(table, settings) -> None:
    print()
    head = f"{'R (m)':>6}  {'stable slopes (rad)':>17}"
    for slope in settings.basin_slopes:
        head += f" | γ={slope:<6g} {'max|λ|':>6} {'basin':>6} {'margin':>6} {'+/- q1_dot':>11}"
    print(head)
    for e in table:
        rng = e["stable_slope_range"]
        line = f"{e['foot_radius']:6.2f}  " + (
            f"{rng[0]:.4f} – {rng[1]:.4f}" if rng else f"{'—':>17}"
        )
        for slope in settings.basin_slopes:
            d = e["at_slope"][str(slope)]
            if not d["gait"]:
                line += f" | {'no gait':>41}"
                continue
            b, m = d["basin"], d["push_margin"]
            pushes = f"{m['faster_rad_per_s']:5.3f}/{m['slower_rad_per_s']:5.3f}"
            line += (
                f" | {'':8} {d['max_abs_multiplier']:6.3f} {100 * b['fraction']:5.1f}% "
                f"{m['min_rad_per_s']:6.3f} {pushes}"
            )
        print(line)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="output directory (default: results)")
    parser.add_argument("--fast", action="store_true", help="small CI-sized run")
    parser.add_argument("--workers", type=int, default=2, help="processes (default: 2)")
    args = parser.parse_args(argv)
    if args.workers < 1:
        parser.error(f"--workers must be a positive integer, got {args.workers}")
    settings = Settings.fast() if args.fast else Settings()
    summary = run(Path(args.out), settings, args.workers)
    print(f"\nwrote {Path(args.out) / 'kneed_walker_feet'} in {summary['runtime_s']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
