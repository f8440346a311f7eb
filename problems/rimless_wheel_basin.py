"""Rimless wheel: rolling vs standing — the basins, and the chapter's staircase with every branch.

Tedrake (*Underactuated Robotics*, ch. "Simple models of walking and running", §rimless wheel)
writes the wheel's step-to-step map on the post-impact rate θ̇⁺ with three branches: vaulting
forward above ω₁, rocking back between ω₂ and ω₁ (``θ̇⁺ₙ₊₁ = −cos 2α θ̇⁺ₙ``), vaulting backward
below ω₂; for γ > α the thresholds take their second form (ω₁ = 0, ω₂ = −sqrt(4 g/l sin α sin γ)).
Its fixed points are rolling, ``ω* = cot 2α sqrt(4 g/l sin α sin γ)`` (multiplier cos² 2α), and
standing, ``ω = 0`` (multiplier −cos 2α per impact): a wheel that rocks strikes spoke after spoke
with intervals shrinking by a constant factor, so it stands still after infinitely many impacts
in finite time — the simulator recognises the accumulation (Zeno) and ends in ``"standing"``.

This study computes, at Drake's default slope 0.08 rad (bistable: 0.0682 < γ < π/8), which
starts end rolling and which end standing, twice and independently:

* by the closed forms: energy to the first impact, then Tedrake's map iterated until the rate is
  within 1e-9 rad/s of ω* (rolling) or of 0 (standing);
* by hybrid simulation (:func:`gaitopt.simulate`, adaptive DOP853 with located events), whose
  outcome is ``"completed"`` near ω* or ``"standing"``.

The basins are drawn in the (θ, θ̇) plane (the stance spoke's angle between the two contact
configurations γ ∓ α) and on the section (θ̇⁺ after an impact), next to the staircase of the map
with every branch at γ = 0.08 and at γ = 0.5 > α (where standing is impossible).

    python problems/rimless_wheel_basin.py --out results [--fast]

Writes results/rimless_wheel_basin/: summary.json, section_basin.csv, plane_basin.csv,
basin.npz (the simulated and closed-form grids of both charts, columnar: rows of the plane's
fates by θ̇, columns by θ), basin.png, staircase.png.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import replaced_atomically, write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402
from gaitopt.returnmap import return_map  # noqa: E402

ROLLING, STANDING, UNDECIDED = 1, 0, -1
_RATE_RANGE = 4.0  # rad/s: the basins are charted for |θ̇| ≤ 4
_SIM_STEPS = 40  # impacts simulated before a start is called undecided
_CONVERGED = 1e-9  # rad/s: the closed-form iteration has reached ω* or 0


def first_impact(model, theta: float, theta_dot: float) -> float:
    """Post-impact rate (rad/s) at the first impact from a stance state, by energy: the hub
    reaches a contact configuration (γ + α ahead, γ − α behind) if its energy clears every point
    in between, else it turns back toward the other one."""
    g, a, gamma = model.gravity / model.length, model.alpha, model.slope
    energy = theta_dot**2 + 2 * g * math.cos(theta)  # θ̇² + 2 g/l cos θ is conserved

    def clears(lo: float, hi: float) -> bool:
        top = 1.0 if lo <= 0.0 <= hi else max(math.cos(lo), math.cos(hi))
        return energy > 2 * g * top

    ahead, behind = gamma + a, gamma - a
    forward = clears(theta, ahead) if theta_dot >= 0 else not clears(behind, theta)
    end = ahead if forward else behind
    rate = math.sqrt(max(energy - 2 * g * math.cos(end), 0.0))
    return math.cos(2 * a) * (rate if forward else -rate)


def fate_closed_form(model, omega: float, limit: int = 400) -> int:
    """ROLLING or STANDING: Tedrake's map iterated from the post-impact rate ω."""
    rolling = model.rolling_speed()
    for _ in range(limit):
        if not math.isfinite(omega):
            return UNDECIDED
        if abs(omega - rolling) < _CONVERGED:
            return ROLLING
        if abs(omega) < _CONVERGED:
            return STANDING
        omega = model.closed_form_map(omega)
    return UNDECIDED


def fate_simulated(model, state) -> int:
    """ROLLING (``_SIM_STEPS`` impacts, ending within 1e-4 rad/s of ω*), STANDING (the
    simulator's Zeno outcome) or UNDECIDED."""
    sim = gaitopt.simulate(model, state, steps=_SIM_STEPS)
    if sim.status == "standing":
        return STANDING
    if sim.success and abs(sim.section_states[-1][1] - model.rolling_speed()) < 1e-4:
        return ROLLING
    return UNDECIDED


def fates_simulated(model, rows, full_state: bool = False) -> np.ndarray:
    """:func:`fate_simulated` of many starts at once (rows of section coordinates, or with
    ``full_state`` of phase-0 states): the batch simulation, the same simulations and rule."""
    from gaitopt.simulation.batch import simulate_batch

    batch = simulate_batch(model, rows, steps=_SIM_STEPS, full_state=full_state)
    last = batch.section_states[:, -1, 1]  # NaN where the steps were not completed
    rolling = batch.success & (np.abs(last - model.rolling_speed()) < 1e-4)
    return np.where(batch.status == "standing", STANDING, np.where(rolling, ROLLING, UNDECIDED))


def intervals(grid: np.ndarray, fate: np.ndarray, value: int) -> list[list[float]]:
    """Maximal runs of ``fate == value`` on the grid, as [first, last] grid points."""
    runs, start = [], None
    for k, f in enumerate(fate):
        if f == value and start is None:
            start = k
        if (f != value or k == len(fate) - 1) and start is not None:
            end = k if f == value else k - 1
            runs.append([float(grid[start]), float(grid[end])])
            start = None
    return runs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small grids for CI")
    parser.add_argument("--scheduler", default=None, help="unused (serial study)")
    parser.add_argument("--workers", type=int, default=2, help="unused (serial study)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "rimless_wheel_basin"
    folder.mkdir(parents=True, exist_ok=True)
    n_sec_sim, n_plane_sim = (21, 8) if args.fast else (41, 16)
    n_sec_cf, n_plane_cf = (801, 100) if args.fast else (4001, 200)

    model = gaitopt.model("rimless_wheel")  # 8 spokes, slope 0.08: bistable
    a, gamma = model.alpha, model.slope
    w1, w2, ws = model.vaulting_speed(), model.backward_vaulting_speed(), model.rolling_speed()
    t0 = time.perf_counter()

    # -- the section: θ̇⁺ just after an impact -------------------------------------------------
    sec_cf = np.linspace(-_RATE_RANGE, _RATE_RANGE, n_sec_cf)
    fate_cf = np.array([fate_closed_form(model, w) for w in sec_cf])
    sec_sim = np.linspace(-_RATE_RANGE, _RATE_RANGE, n_sec_sim)
    fate_sec_sim = fates_simulated(model, sec_sim[:, None])
    fate_sec_ref = np.array([fate_closed_form(model, w) for w in sec_sim])
    write_csv(
        ["theta_dot", "fate_simulated", "fate_closed_form"],
        [[w, int(s), int(c)] for w, s, c in zip(sec_sim, fate_sec_sim, fate_sec_ref, strict=True)],
        folder / "section_basin.csv",
    )
    step = sec_cf[1] - sec_cf[0]
    rolling_measure = float(np.sum(fate_cf == ROLLING) * step)

    # -- the (θ, θ̇) plane: stance on one spoke, between the two contact configurations --------
    def plane(n: int) -> tuple[np.ndarray, np.ndarray]:
        thetas = gamma - a + 2 * a * (np.arange(n) + 0.5) / n  # cell centres, open interval
        rates = -_RATE_RANGE + 2 * _RATE_RANGE * (np.arange(n) + 0.5) / n
        return thetas, rates

    th_cf, rt_cf = plane(n_plane_cf)
    plane_cf = np.array(
        [[fate_closed_form(model, first_impact(model, th, w)) for th in th_cf] for w in rt_cf]
    )
    th_sim, rt_sim = plane(n_plane_sim)
    plane_rows = np.array([[th, w] for w in rt_sim for th in th_sim])  # phase-0 states
    plane_sim = fates_simulated(model, plane_rows, full_state=True).reshape(len(rt_sim), -1)
    plane_ref = np.array(
        [[fate_closed_form(model, first_impact(model, th, w)) for th in th_sim] for w in rt_sim]
    )
    write_csv(
        ["theta", "theta_dot", "fate_simulated", "fate_closed_form"],
        [
            [th, w, int(plane_sim[i, j]), int(plane_ref[i, j])]
            for i, w in enumerate(rt_sim)
            for j, th in enumerate(th_sim)
        ],
        folder / "plane_basin.csv",
    )
    elapsed = time.perf_counter() - t0

    steep = model.replace(slope=0.5)
    summary = {
        "model": "rimless_wheel",
        "params": model.params,
        "source": "Tedrake, Underactuated Robotics, rimless wheel (closed-form map, 3 branches)",
        "alpha": a,
        "omega_1": w1,
        "omega_2": w2,
        "rolling": {"omega_star": ws, "multiplier": math.cos(2 * a) ** 2},
        "standing": {
            "omega": 0.0,
            "multiplier_per_impact": model.standing_multiplier(),
            "stable": abs(model.standing_multiplier()) < 1,
            "note": model.standing_note(),
        },
        "section_basin": {
            "range": [-_RATE_RANGE, _RATE_RANGE],
            "rolling_intervals_closed_form": intervals(sec_cf, fate_cf, ROLLING),
            "rolling_measure_closed_form": rolling_measure,
            "rolling_fraction_closed_form": float(np.mean(fate_cf == ROLLING)),
            "standing_fraction_closed_form": float(np.mean(fate_cf == STANDING)),
            "simulated_points": int(len(sec_sim)),
            "simulation_agrees": int(np.sum(fate_sec_sim == fate_sec_ref)),
            "simulation_undecided": int(np.sum(fate_sec_sim == UNDECIDED)),
        },
        "plane_basin": {
            "theta_range": [gamma - a, gamma + a],
            "theta_dot_range": [-_RATE_RANGE, _RATE_RANGE],
            "rolling_fraction_closed_form": float(np.mean(plane_cf == ROLLING)),
            "standing_fraction_closed_form": float(np.mean(plane_cf == STANDING)),
            "simulated_points": int(plane_sim.size),
            "rolling_fraction_simulated": float(np.mean(plane_sim == ROLLING)),
            "simulation_agrees": int(np.sum(plane_sim == plane_ref)),
            "simulation_undecided": int(np.sum(plane_sim == UNDECIDED)),
        },
        "steep_slope": {
            "slope": 0.5,
            "omega_1": steep.vaulting_speed(),
            "omega_2": steep.backward_vaulting_speed(),
            "omega_star": steep.rolling_speed(),
            "standing_exists": steep.standing_exists(),
            "note": steep.standing_note(),
        },
        "timing_s": elapsed,
    }
    write_json(summary, folder / "summary.json")
    # the grids, columnar (NumPy's own format; the fates as ROLLING 1, STANDING 0, UNDECIDED -1)
    with replaced_atomically(folder / "basin.npz") as tmp, open(tmp, "xb") as fh:
        np.savez_compressed(
            fh,
            section_theta_dot=sec_sim,
            section_fate_simulated=fate_sec_sim.astype(int),
            section_fate_closed_form=fate_sec_ref.astype(int),
            closed_form_theta_dot=sec_cf,
            closed_form_fate=fate_cf.astype(int),
            plane_theta=th_sim,
            plane_theta_dot=rt_sim,
            plane_fate_simulated=plane_sim.astype(int),
            plane_fate_closed_form=plane_ref.astype(int),
            plane_closed_form_theta=th_cf,
            plane_closed_form_theta_dot=rt_cf,
            plane_closed_form_fate=plane_cf.astype(int),
        )
    _basin_figure(model, sec_cf, fate_cf, th_cf, rt_cf, plane_cf, th_sim, rt_sim, plane_sim, folder)
    _staircase_figure(model, steep, folder / "staircase.png")

    sb, pb = summary["section_basin"], summary["plane_basin"]
    print(
        f"rimless wheel, slope {gamma:g}: ω₁ = {w1:.6f}, ω₂ = {w2:.6f}, ω* = {ws:.6f} rad/s; "
        f"standing multiplier {model.standing_multiplier():.6f} per impact"
    )
    print(
        f"section |θ̇⁺| ≤ {_RATE_RANGE:g}: rolling on {sb['rolling_fraction_closed_form']:.4f} "
        f"(intervals {[[round(x, 4) for x in r] for r in sb['rolling_intervals_closed_form']]}); "
        f"simulation agrees at {sb['simulation_agrees']}/{sb['simulated_points']}"
    )
    print(
        f"plane: rolling {pb['rolling_fraction_closed_form']:.4f} (closed form), "
        f"{pb['rolling_fraction_simulated']:.4f} (simulated); agreement "
        f"{pb['simulation_agrees']}/{pb['simulated_points']}; {elapsed:.1f} s; wrote {folder}"
    )
    return 0


_FATE_COLOURS = ListedColormap(["#c6dbef", "#fdd0a2"])  # standing, rolling


def _basin_figure(model, sec, fate, th, rt, plane_cf, th_sim, rt_sim, plane_sim, folder) -> None:
    gamma = model.slope
    fig, (left, right) = plt.subplots(
        1, 2, figsize=(11, 4.8), layout="constrained", gridspec_kw={"width_ratios": [1.3, 1]}
    )
    extent = (th[0], th[-1], rt[0], rt[-1])
    left.imshow(
        np.where(plane_cf == UNDECIDED, np.nan, plane_cf),
        origin="lower",
        extent=extent,
        aspect="auto",
        cmap=_FATE_COLOURS,
        vmin=0,
        vmax=1,
        interpolation="nearest",
    )
    TH, RT = np.meshgrid(th_sim, rt_sim)
    for value, marker, label in ((ROLLING, "o", "rolls"), (STANDING, "x", "stands")):
        mask = plane_sim == value
        left.plot(
            TH[mask], RT[mask], marker, ms=3, color="k", ls="none", label=f"simulation: {label}"
        )
    left.axvline(0.0, color="0.3", lw=0.8, ls=":")
    left.set_xlabel(r"stance spoke angle $\theta$ (rad)")
    left.set_ylabel(r"stance spoke rate $\dot\theta$ (rad/s)")
    left.set_title(
        f"basin in the (θ, θ̇) plane, γ = {gamma:g} rad: orange rolls, blue stands\n"
        "(shading: closed form; markers: hybrid simulation)",
        fontsize=9,
    )
    left.legend(fontsize=8, loc="lower right")

    right.fill_between(sec, 0, 1, where=fate == ROLLING, color="#fdd0a2", step="mid")
    right.fill_between(sec, 0, 1, where=fate == STANDING, color="#c6dbef", step="mid")
    for w, name in (
        (model.vaulting_speed(), r"$\omega_1$"),
        (model.backward_vaulting_speed(), r"$\omega_2$"),
        (model.rolling_speed(), r"$\omega^*$"),
        (0.0, "0"),
    ):
        right.axvline(w, color="k", lw=0.8, ls="--")
        right.text(
            w,
            1.02,
            name,
            ha="right" if w == model.vaulting_speed() else "left",
            va="bottom",
            fontsize=9,
        )
    right.set_ylim(0, 1.12)
    right.set_yticks([0.25, 0.75], ["", ""])
    right.set_xlabel(r"post-impact rate $\dot\theta^+$ on the section (rad/s)")
    right.set_ylabel("fate (orange rolls, blue stands) (no unit)")
    right.set_title("basin on the section (closed-form map iterated)", fontsize=9)
    save_figure(fig, folder / "basin.png")


def _staircase(ax, model, start: float, colour: str, steps: int = 40) -> None:
    xs, ys, w = [start], [start], start
    for _ in range(steps):
        nxt = model.closed_form_map(w)
        if not math.isfinite(nxt):
            break
        xs += [w, nxt]
        ys += [nxt, nxt]
        w = nxt
    ax.plot(xs, ys, color=colour, lw=0.9, label=f"staircase from {start:g} rad/s")
    ax.plot([start], [start], "s", color=colour, ms=4)


def _map_panel(ax, model, lo: float, hi: float, starts: list[tuple[float, str]]) -> None:
    a = model.alpha
    w1, w2 = model.vaulting_speed(), model.backward_vaulting_speed()
    fine = np.linspace(lo, hi, 3000)
    values = np.array([model.closed_form_map(w) for w in fine])
    # Break the curve at the jumps (ω₁ and ω₂), where the map is discontinuous.
    jumps = np.abs(np.diff(values)) > 0.2
    values_broken = values.copy()
    values_broken[1:][jumps] = np.nan
    ax.plot(fine, values_broken, color="C0", lw=1.8, label="closed-form map (Tedrake)")
    coarse = np.linspace(lo, hi, 23)
    simulated = [return_map(model, w)[0] for w in coarse]
    ax.plot(coarse, simulated, "o", ms=3.5, mfc="none", color="k", label="simulated (one impact)")
    ax.plot([lo, hi], [lo, hi], color="k", lw=0.7, ls=":", label="diagonal")
    for w, name in ((w1, r"$\omega_1$"), (w2, r"$\omega_2$")):
        ax.axvline(w, color="0.5", lw=0.8, ls="--")
        ax.annotate(name, (w, hi), xytext=(2, -12), textcoords="offset points", fontsize=9)
    for start, colour in starts:
        _staircase(ax, model, start, colour)
    ws = model.rolling_speed()
    ax.plot([ws], [ws], "o", color="k", ms=7, zorder=5)
    ax.annotate(
        f"rolling ω* = {ws:.4g} rad/s\nλ = cos²2α = {math.cos(2 * a) ** 2:.3g}",
        (ws, ws),
        xytext=(-120, 18),
        textcoords="offset points",
        fontsize=8,
        arrowprops={"arrowstyle": "->", "lw": 0.6},
    )
    if model.standing_exists():
        ax.plot([0], [0], "o", color="k", ms=7, zorder=5)
        ax.annotate(
            f"standing ω = 0\nλ = −cos2α = {model.standing_multiplier():.3g} per impact\n"
            "(reached after infinitely many impacts)",
            (0, 0),
            xytext=(12, -52),
            textcoords="offset points",
            fontsize=8,
            arrowprops={"arrowstyle": "->", "lw": 0.6},
        )
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal")
    ax.set_xlabel(r"post-impact rate $\dot\theta^+_n$ (rad/s)")
    ax.set_ylabel(r"next post-impact rate $\dot\theta^+_{n+1}$ (rad/s)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")


def _staircase_figure(model, steep, path: Path) -> None:
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 6), layout="constrained")
    _map_panel(left, model, -4.0, 3.0, [(-2.0, "C3"), (-1.42, "C2"), (2.8, "C1")])
    left.set_title(
        f"γ = {model.slope:g} rad < α = π/{model.spokes}: three branches; "
        "rolling and standing both stable",
        fontsize=9,
    )
    _map_panel(right, steep, -4.5, 4.0, [(-4.2, "C3"), (0.2, "C1")])
    right.set_title(
        f"γ = {steep.slope:g} rad > α: the γ > α form (ω₁ = 0); standing impossible", fontsize=9
    )
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
