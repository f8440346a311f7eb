"""The Strandbeest: Jansen's leg linkage, its foot path and ride height, and the machine walking.

Sources: Theo Jansen's holy numbers (*The Great Pretender*, 2007; Wikipedia, "Jansen's linkage")
at Robin Deits' scale, 0.01 m per unit, with his PVC links (0.476 kg/m) and six leg pairs on one
crank at phases 0, 2π/3, 4π/3, π/3, π, 5π/3 (Drake, ``examples/multibody/strandbeest``);
Tedrake, *Underactuated Robotics*, "Simple models of walking and running" (the rimless wheel,
which the machine generalises).

* Kinematics (:mod:`gaitopt.linkage`): loop closure by CasADi's Newton rootfinder continued in
  the crank angle; foot path, width, height, the share of a turn within 5 mm of the lowest
  point, the ride-height ripple of six pairs and of one pair; the mechanical advantage
  ``dr_foot/dθ`` (crank torque per unit foot force) by AD.
* Dynamics (:mod:`gaitopt.models.strandbeest`): passively down a slope the rolling gait from
  the energy-plus-impact closed form, checked by simulation (and, without ``--fast``, by
  multiple shooting); its existence range in slope (the closed form's lowest θ̇² crosses 0);
  driven by a crank torque on level ground, the least torque that walks and a driven gait.

    python problems/strandbeest.py --out results [--fast]

Writes results/strandbeest/: numbers.json, foot_path.png, ride_height.png,
mechanical_advantage.png.
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
from scipy.optimize import brentq  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_json  # noqa: E402
from gaitopt.linkage import GROUND_BAND, SIX_PAIR_PHASES, JansenLinkage  # noqa: E402
from gaitopt.models.strandbeest import Strandbeest  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402


def _kinematics(folder: Path, samples: int) -> dict:
    turn = JansenLinkage().turn(samples)
    numbers = turn.numbers()
    foot = turn.foot
    y_low = numbers["lowest_point"][1]

    fig, ax = plt.subplots(figsize=(6.4, 3.6), constrained_layout=True)
    ax.plot(foot[:, 0], foot[:, 1], color="C0", label="foot path")
    band = foot[:, 1] <= y_low + GROUND_BAND
    ax.plot(foot[band, 0], foot[band, 1], ".", ms=2, color="C3",
            label=f"within {GROUND_BAND * 1e3:g} mm of the lowest point")  # fmt: skip
    ax.plot([0], [0], "k+", ms=10, label="crank axle")
    ax.set_aspect("equal")
    ax.set_xlabel("foot position x (m)")
    ax.set_ylabel("foot height y (m)")
    ax.set_title(
        f"Jansen's leg: width {numbers['width']:.4f} m, height {numbers['height']:.4f} m, "
        f"on the ground {100 * numbers['ground_fraction']:.1f} % of a turn",
        fontsize=9,
    )
    ax.legend(fontsize=8, loc="upper left")
    save_figure(fig, folder / "foot_path.png")

    thetas = np.linspace(0, 2 * math.pi, 4 * samples)
    fig, ax = plt.subplots(figsize=(6.4, 3.6), constrained_layout=True)
    one = turn.ride_height((0.0,), thetas)
    six = turn.ride_height(SIX_PAIR_PHASES, thetas)
    ax.plot(
        thetas,
        1e3 * (one - one.max()),
        label=f"one pair (ripple {1e3 * numbers['ripple_one_pair']:.2f} mm)",
    )
    ax.plot(
        thetas,
        1e3 * (six - six.max()),
        label=f"six pairs (ripple {1e3 * numbers['ripple_six_pairs']:.3f} mm)",
    )
    ax.set_xlabel("crank angle θ (rad)")
    ax.set_ylabel("ride height H − H_max (mm)")
    ax.set_title(f"crank axle above the lowest foot; H_max = {-y_low:.4f} m", fontsize=9)
    ax.legend(fontsize=8)
    save_figure(fig, folder / "ride_height.png")

    fig, ax = plt.subplots(figsize=(6.4, 3.6), constrained_layout=True)
    ax.plot(turn.thetas, turn.foot_velocity[:, 0], label="τ/F_x = dx/dθ (horizontal force)")
    ax.plot(turn.thetas, turn.foot_velocity[:, 1], label="τ/F_y = dy/dθ (vertical force)")
    on = turn.foot[:, 1] <= y_low + GROUND_BAND
    ax.fill_between(turn.thetas, -0.4, 0.4, where=on, color="0.9", label="foot on the ground")
    ax.set_xlabel("crank angle θ (rad)")
    ax.set_ylabel("crank torque per unit foot force τ/F (N·m/N)")
    ax.set_title("mechanical advantage (inverse): virtual work τ δθ = F · δr_foot", fontsize=9)
    ax.legend(fontsize=8)
    save_figure(fig, folder / "mechanical_advantage.png")
    return numbers


def _existence_low(model: Strandbeest, name: str, lo: float, hi: float) -> float:
    """Where the closed form's lowest θ̇² over the cycle crosses zero (parameter ``name``)."""

    def lowest(value: float) -> float:
        cf = model.replace(**{name: value}).closed_form()
        return cf.get("min_theta_dot_squared", -1.0)

    return brentq(lowest, lo, hi, xtol=1e-7)


def _dynamics(fast: bool) -> dict:
    model = Strandbeest()
    out: dict = {"model": model.params}
    cf = model.closed_form()
    sim = gaitopt.simulate(model, {"theta_dot": cf["theta_dot"]}, steps=1)
    out["passive"] = {
        "slope": model.slope,
        "closed_form": {k: cf[k] for k in ("theta_dot", "multiplier", "period", "min_theta_dot")},
        "simulation_return": float(sim.section_states[-1][1]),
        "simulation_period": float(sim.section_times[-1] - sim.section_times[0]),
        "handover_ratios": [float(r) for r in cf["ratios"]],
    }
    out["passive"]["slope_min"] = _existence_low(model, "slope", 0.0, model.slope)
    if not fast:
        t0 = time.perf_counter()
        cycle = gaitopt.find_limit_cycle(model)
        out["passive"]["shooting"] = {
            "success": cycle.success,
            "message": cycle.message,
            "theta_dot": float(cycle.section_point[0]) if cycle.success else None,
            "multiplier": float(abs(cycle.multipliers[0])) if cycle.success else None,
            "period": cycle.period if cycle.success else None,
            "seconds": time.perf_counter() - t0,
        }
    # Driven on level ground: the least torque that walks, and the gait at 1 N·m.
    level = model.replace(slope=0.0)
    tau_min = _existence_low(level, "torque", 0.0, 50.0)
    driven = level.replace(torque=1.0)
    dcf = driven.closed_form()
    dsim = gaitopt.simulate(driven, {"theta_dot": dcf["theta_dot"]}, steps=1)
    out["driven"] = {
        "torque_min": tau_min,
        "torque": driven.torque,
        "closed_form": {k: dcf[k] for k in ("theta_dot", "multiplier", "period", "min_theta_dot")},
        "simulation_return": float(dsim.section_states[-1][1]),
        "stable": bool(abs(dcf["multiplier"]) < 1),
    }
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes; no multiple shooting")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "strandbeest"
    folder.mkdir(parents=True, exist_ok=True)
    numbers = _kinematics(folder, 360 if args.fast else 1440)
    dynamics = _dynamics(args.fast)
    write_json({"linkage": numbers, "walker": dynamics}, folder / "numbers.json")
    print(
        f"width {numbers['width']:.6f} m, height {numbers['height']:.6f} m, ground fraction "
        f"{numbers['ground_fraction']:.6f}, ripple six pairs {numbers['ripple_six_pairs']:.3e} m, "
        f"one pair {numbers['ripple_one_pair']:.6f} m"
    )
    p = dynamics["passive"]
    print(
        f"passive gait at slope {p['slope']}: θ̇* = {p['closed_form']['theta_dot']:.8f} rad/s, "
        f"multiplier {p['closed_form']['multiplier']:.8f}, exists for slope > {p['slope_min']:.6f}"
    )
    if "shooting" in p:
        print(f"shooting: {p['shooting']}")
    d = dynamics["driven"]
    dc = d["closed_form"]
    print(
        f"driven on level ground: τ_min = {d['torque_min']:.6f} N·m; at τ = {d['torque']:.4f}: "
        f"θ̇* = {dc['theta_dot']:.6f}, multiplier {dc['multiplier']:.6f}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
