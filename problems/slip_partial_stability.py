"""SLIP's partial stability: the (z, ẋ) apex map has one stable and one neutral multiplier.

The spring-mass runner conserves energy, so its apex state (height ``z``, forward speed ``ẋ``)
lives on a level set ``E = ½ m ẋ² + m g z`` that no step can leave.  Tedrake (*Underactuated
Robotics*, ch. "Simple models of walking and running", SLIP) therefore draws the 1-D apex map on
one energy level, ``z[n+1] = P(z[n]; E)``, whose stable fixed point rejects height disturbances.
In the full apex state (z, ẋ) the map has two multipliers: ``P'(z*)`` along the level set, and
exactly 1 across it, the neutral direction of energy.  A disturbance that changes the energy is
therefore not rejected: the runner settles on the fixed point of the *new* energy level.

This study computes, at Tedrake's defaults (k̃ = 10.7, θ_td = 30°, Ẽ = 1.61):

* the 2×2 Jacobian of the (z, ẋ) apex map by central differences of simulated steps (each start's
  energy is its own: the model is re-parametrised with ``energy = ½ m ẋ² + m g z``), its
  eigenvalues, and the 1-D multiplier of the energy-level map from :func:`find_limit_cycle`;
* two disturbances at the fixed point, simulated for many steps: one along the level set (height
  traded for speed at the same energy) — rejected; one that adds energy (a push, +3 % speed) —
  not rejected: the apex converges to the fixed point of the new energy.

    python problems/slip_partial_stability.py --out results [--fast]

Writes results/slip_partial_stability/: summary.json, disturbances.csv, partial_stability.png.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

_H = 1e-4  # central-difference step (m, m/s): truncation O(h²) ~ 1e-8, rounding ~ 1e-11/h


def energy_of(model, z: float, xdot: float) -> float:
    """``E = ½ m ẋ² + m g z`` (J) at an apex."""
    return 0.5 * model.mass * xdot**2 + model.mass * model.gravity * z


def apex_step(model, z: float, xdot: float) -> tuple[float, float]:
    """One simulated apex-to-apex step from an apex (z, ẋ) at its own energy: (z', ẋ')."""
    m = model.replace(energy=energy_of(model, z, xdot))
    sim = gaitopt.simulate(m, {"z": z}, steps=1)
    if not sim.success:
        return math.nan, math.nan
    x = sim.section_states[-1]
    names = m.state_names
    return float(x[names.index("z")]), float(x[names.index("x_dot")])


def apex_jacobian(model, z: float, xdot: float, h: float = _H) -> np.ndarray:
    """The (z, ẋ) apex map's Jacobian by central differences of simulated steps."""
    J = np.zeros((2, 2))
    for j, (dz, dv) in enumerate(((h, 0.0), (0.0, h))):
        plus = np.array(apex_step(model, z + dz, xdot + dv))
        minus = np.array(apex_step(model, z - dz, xdot - dv))
        J[:, j] = (plus - minus) / (2 * h)
    return J


def run(model, z: float, xdot: float, steps: int) -> np.ndarray:
    """Apex states (z, ẋ, E) over ``steps`` steps from (z, ẋ) (its own energy)."""
    m = model.replace(energy=energy_of(model, z, xdot))
    sim = gaitopt.simulate(m, {"z": z}, steps=steps)
    names = m.state_names
    zs = sim.section_states[:, names.index("z")]
    vs = sim.section_states[:, names.index("x_dot")]
    return np.c_[zs, vs, [energy_of(model, a, b) for a, b in zip(zs, vs, strict=True)]]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="fewer steps for CI")
    parser.add_argument("--scheduler", default=None, help="unused (serial study)")
    parser.add_argument("--workers", type=int, default=2, help="unused (serial study)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "slip_partial_stability"
    folder.mkdir(parents=True, exist_ok=True)
    steps = 12 if args.fast else 25

    model = gaitopt.model("slip")
    cycle = gaitopt.find_limit_cycle(model)
    if not cycle.success:
        print(f"no SLIP gait: {cycle.message}")
        return 1
    z_star = float(cycle.fixed_point["z"])
    v_star = model.apex_speed(z_star)
    lam_1d = complex(cycle.multipliers[0]).real
    J = apex_jacobian(model, z_star, v_star)
    eig, vec = np.linalg.eig(J)
    order = np.argsort(np.abs(eig - 1.0))[::-1]  # the stable one first, the neutral one last
    eig, vec = eig[order].real, vec[:, order].real
    # The neutral direction should cross the level sets (change E); the stable one lie along it
    # (dE = m ẋ dẋ + m g dz = 0).
    grad_e = np.array([model.mass * model.gravity, model.mass * v_star])
    along = [float(abs(grad_e @ v) / np.linalg.norm(grad_e)) for v in vec.T]

    # -- disturbances ----------------------------------------------------------------------------
    dz = 0.02  # inside the basin: the unstable fixed point of the 1-D map is near 0.915 m
    same_energy = (z_star + dz, math.sqrt(v_star**2 - 2 * model.gravity * dz))
    push = (z_star, 1.03 * v_star)
    level = run(model, *same_energy, steps)
    pushed = run(model, *push, steps)
    new_model = model.replace(energy=energy_of(model, *push))
    new_cycle = gaitopt.find_limit_cycle(new_model)
    z_new = float(new_cycle.fixed_point["z"]) if new_cycle.success else math.nan
    write_csv(
        ["step", "kind", "z", "x_dot", "energy"],
        [[n, "same energy", *row] for n, row in enumerate(level)]
        + [[n, "push (+3 % speed)", *row] for n, row in enumerate(pushed)],
        folder / "disturbances.csv",
    )
    summary = {
        "model": "slip",
        "params": model.params,
        "source": "Tedrake, Underactuated Robotics, SLIP apex map (energy-level map); "
        "eigenvalues of the (z, ẋ) map by central differences of simulated steps",
        "fixed_point": {"z": z_star, "x_dot": v_star, "energy": model.energy},
        "multiplier_energy_level_map": lam_1d,
        "apex_map_jacobian": J.tolist(),
        "apex_map_multipliers": eig.tolist(),
        "neutral_multiplier_minus_one": float(eig[1] - 1.0),
        "stable_multiplier_minus_1d": float(eig[0] - lam_1d),
        "eigenvector_energy_change": along,
        "same_energy_disturbance": {
            "start": list(same_energy),
            "final_z": float(level[-1, 0]),
            "final_distance_to_fixed_point": float(abs(level[-1, 0] - z_star)),
        },
        "energy_disturbance": {
            "start": list(push),
            "energy_before": model.energy,
            "energy_after": float(pushed[0, 2]),
            "final_z": float(pushed[-1, 0]),
            "original_fixed_point_z": z_star,
            "new_energy_fixed_point_z": z_new,
            "final_distance_to_new_fixed_point": float(abs(pushed[-1, 0] - z_new)),
            "rejected": bool(abs(pushed[-1, 0] - z_star) < 1e-3),
        },
    }
    write_json(summary, folder / "summary.json")
    _figure(model, new_model, z_star, v_star, z_new, eig, vec, level, pushed, lam_1d, folder)
    print(
        f"SLIP apex map (z, ẋ) at z* = {z_star:.6f} m, ẋ* = {v_star:.6f} m/s: multipliers "
        f"{eig[0]:.8f} (1-D map {lam_1d:.8f}) and {eig[1]:.10f} (energy, neutral); a +3 % "
        f"push ends at z = {pushed[-1, 0]:.5f} m, the new level's fixed point {z_new:.5f} m, "
        f"not the old {z_star:.5f} m; wrote {folder}"
    )
    return 0


def _figure(model, new_model, z_star, v_star, z_new, eig, vec, level, pushed, lam, folder) -> None:
    fig, (ax_map, ax_plane, ax_n) = plt.subplots(1, 3, figsize=(15, 4.8), layout="constrained")
    lo, hi = 0.86, 0.93
    zs = np.linspace(lo, hi, 41)
    for m, colour, name in ((model, "C0", "E"), (new_model, "C3", "E + push")):
        values = [
            gaitopt.returnmap.return_map(m, z)[0] if m.apex_domain()[0] < z < m.apex_domain()[1]
            else np.nan
            for z in zs
        ]  # fmt: skip
        ax_map.plot(
            zs, values, color=colour, lw=1.6, label=f"apex map at {name} = {m.energy:.4g} J"
        )
    ax_map.plot([lo, hi], [lo, hi], "k:", lw=0.8, label="diagonal")
    ax_map.plot([z_star], [z_star], "o", color="C0", ms=7, label=f"fixed point, λ = {lam:.4f}")
    ax_map.plot([z_new], [z_new], "o", color="C3", ms=7, label="fixed point after the push")
    ax_map.set_xlabel("apex height z at step n (m)")
    ax_map.set_ylabel("apex height z at step n + 1 (m)")
    ax_map.set_title("1-D apex maps, one per energy level", fontsize=10)
    ax_map.legend(fontsize=7.5, loc="upper left")
    ax_map.grid(alpha=0.3)

    z_grid = np.linspace(0.86, 0.92, 50)
    for e, colour in ((model.energy, "C0"), (new_model.energy, "C3")):
        arg = 2 * (e / model.mass - model.gravity * z_grid)
        v = np.where(arg > 0, np.sqrt(np.abs(arg)), np.nan)
        ax_plane.plot(z_grid, v, color=colour, lw=0.8, ls="--", label=f"level set E = {e:.4g} J")
    ax_plane.plot(level[:, 0], level[:, 1], "o-", ms=3, lw=0.6, color="C2", label="height push")
    ax_plane.plot(pushed[:, 0], pushed[:, 1], "s-", ms=3, lw=0.6, color="C3", label="speed push")
    ax_plane.plot([z_star], [v_star], "o", color="k", ms=7, label="fixed point")
    for k, (name, style) in enumerate((("stable", "-"), ("neutral (energy)", ":"))):
        d = vec[:, k] / np.linalg.norm(vec[:, k]) * 0.05
        ax_plane.plot(
            [z_star - d[0], z_star + d[0]],
            [v_star - d[1], v_star + d[1]],
            "k",
            ls=style,
            lw=1.4,
            label=f"eigenvector, λ = {eig[k]:.4f} ({name})",
        )
    ax_plane.set_xlabel("apex height z (m)")
    ax_plane.set_ylabel("apex forward speed ẋ (m/s)")
    ax_plane.set_title("(z, ẋ) apex map: one stable, one neutral direction", fontsize=10)
    ax_plane.legend(fontsize=7, loc="upper right")
    ax_plane.grid(alpha=0.3)

    n = np.arange(len(level))
    ax_n.plot(n, level[:, 0], "o-", ms=3, color="C2", label="height push (same energy)")
    ax_n.plot(n, pushed[:, 0], "s-", ms=3, color="C3", label="speed push (+3 %: more energy)")
    ax_n.axhline(z_star, color="k", lw=0.8, ls="--", label=f"fixed point at E, {z_star:.4f} m")
    ax_n.axhline(
        z_new, color="C3", lw=0.8, ls="--", label=f"fixed point at E + push, {z_new:.4f} m"
    )
    ax_n.set_xlabel("apex count n (dimensionless)")
    ax_n.set_ylabel("apex height z (m)")
    ax_n.set_title("an energy disturbance is not rejected", fontsize=10)
    ax_n.legend(fontsize=7.5, loc="best")
    ax_n.grid(alpha=0.3)
    save_figure(fig, folder / "partial_stability.png")


if __name__ == "__main__":
    raise SystemExit(main())
