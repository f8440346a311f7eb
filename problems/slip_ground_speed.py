"""Ground-speed matching: how fast the blind runner's foot moves over the ground at touchdown.

Animals and people running retract the swing leg before touchdown — the foot swings backward
relative to the hip — so that at touchdown it moves forward over the ground more slowly than the
body ("ground-speed matching"; Tedrake, *Underactuated Robotics*, ch. "Simple models of walking
and running", which cites the biomechanics of swing-leg retraction, e.g. Seyfarth, Geyer & Herr
2003, "Swing-leg retraction: a simple control model for stable running", J. Exp. Biol.
206:2547).  The blind swing-leg law of problems/slip_rough_terrain.py (Ernst/Geyer: a leg angle
θ(t) of the time since apex, deadbeat for every ground height it may meet;
:func:`gaitopt.terrain.blind_swing_law`) is computed with no reference to ground speed, so it is
a test of the observation: does deadbeat blind running retract the leg, and how much of the
body's speed does the foot keep at touchdown?

At touchdown the foot is ``x_f = x + l0 sin θ`` ahead of the hip (SLIP convention: the leg held at
θ from vertical, foot ahead), so its horizontal velocity over the ground is

    v_foot = ẋ + l0 cos θ · θ̇(t),

with ``ẋ`` the flight's constant forward speed and ``θ̇`` the law's derivative (Chebyshev series,
differentiated exactly).  ``v_foot / ẋ`` is 1 for a leg held fixed (no matching), 0 for perfect
matching, and below 1 for retraction (``θ̇ < 0``).  It is computed for laws from several apex
heights around the target, at every ground height the law covers.

    python problems/slip_ground_speed.py --out results [--fast]

Writes results/slip_ground_speed/: summary.json, touchdowns.csv, ground_speed.png.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.polynomial import chebyshev  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt import control as gc  # noqa: E402
from gaitopt import terrain as gt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

TARGET = 1.0  # m: the rough-terrain study's target apex height
HEIGHTS = (-0.1, 0.1)  # m: ground heights the law covers


def angle_rate(law: gt.SwingLaw, t: np.ndarray) -> np.ndarray:
    """``θ̇(t)`` (rad/s) of a swing-leg law: the Chebyshev series differentiated, times
    ``d ξ / d t = 1/t_halfwidth`` (zero outside the fitted window, where the angle is held)."""
    tc, tw = law.inputs[0], law.inputs[1]
    xi = (np.asarray(t, dtype=float) - tc) / tw
    rate = chebyshev.chebval(np.clip(xi, -1, 1), chebyshev.chebder(law.inputs[2:])) / tw
    return np.where(np.abs(xi) <= 1, rate, 0.0)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="fewer apex heights for CI")
    parser.add_argument("--scheduler", default=None, help="unused (serial study)")
    parser.add_argument("--workers", type=int, default=2, help="unused (serial study)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "slip_ground_speed"
    folder.mkdir(parents=True, exist_ok=True)

    slip = gaitopt.model("slip")
    deadbeat = gc.deadbeat(slip, target={"z": TARGET})
    apexes = (0.97, 1.0, 1.03) if args.fast else (0.95, 0.975, 1.0, 1.025, 1.05)
    l0 = slip.rest_length
    rows, curves = [], {}
    for z in apexes:
        law = gt.blind_swing_law(deadbeat.deadbeat_solver, z, target=TARGET, heights=HEIGHTS)
        ok = np.isfinite(law.times) & np.isfinite(law.angles)
        t, h = law.times[ok], law.heights[ok]
        theta = law.angle(t)
        rate = angle_rate(law, t)
        speed = slip.apex_speed(z)  # ẋ in flight: constant, from the energy at this apex
        v_foot = speed + l0 * np.cos(theta) * rate
        curves[z] = (h, t, theta, rate, v_foot / speed, speed)
        rows += [
            [z, float(hh), float(tt), float(th), float(r), speed, float(v), float(v / speed)]
            for hh, tt, th, r, v in zip(h, t, theta, rate, v_foot, strict=True)
        ]
    write_csv(
        ["apex_z", "ground_height", "touchdown_time", "angle", "angle_rate", "body_speed",
         "foot_speed", "foot_over_body"],
        rows,
        folder / "touchdowns.csv",
    )  # fmt: skip
    ratios = np.array([r[7] for r in rows])
    rates = np.array([r[4] for r in rows])
    summary = {
        "model": "slip",
        "params": slip.params,
        "target_apex_m": TARGET,
        "ground_heights_m": list(HEIGHTS),
        "apex_heights_m": list(apexes),
        "source": "blind swing-leg law (gaitopt.terrain.blind_swing_law, deadbeat at every ground "
        "height); ground-speed matching as in Seyfarth, Geyer & Herr 2003",
        "touchdowns": len(rows),
        "retracting_fraction": float(np.mean(rates < 0)),
        "foot_over_body_speed": {
            "min": float(ratios.min()),
            "median": float(np.median(ratios)),
            "max": float(ratios.max()),
        },
        "at_target_on_level_ground": _at(curves, TARGET, 0.0),
    }
    write_json(summary, folder / "summary.json")
    _figure(curves, folder / "ground_speed.png")
    r = summary["foot_over_body_speed"]
    print(
        f"blind law: the leg retracts at {100 * summary['retracting_fraction']:.0f} % of "
        f"{len(rows)} touchdowns; foot/body speed at touchdown {r['min']:.3f}–{r['max']:.3f} "
        f"(median {r['median']:.3f}); wrote {folder}"
    )
    return 0


def _at(curves, z: float, h: float) -> dict | None:
    if z not in curves:
        return None
    hs, t, theta, rate, ratio, speed = curves[z]
    k = int(np.argmin(np.abs(hs - h)))
    return {
        "ground_height": float(hs[k]),
        "touchdown_time_s": float(t[k]),
        "angle_rad": float(theta[k]),
        "angle_rate_rad_s": float(rate[k]),
        "body_speed_m_s": speed,
        "foot_over_body": float(ratio[k]),
    }


def _figure(curves, path: Path) -> None:
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5), layout="constrained")
    for k, (z, (h, t, _theta, rate, ratio, _)) in enumerate(sorted(curves.items())):
        order = np.argsort(h)
        left.plot(100 * h[order], ratio[order], "o-", ms=3, color=f"C{k}", label=f"apex {z:g} m")
        right.plot(t[order], np.degrees(rate[order]), "o-", ms=3, color=f"C{k}",
                   label=f"apex {z:g} m")  # fmt: skip
    left.axhline(1.0, color="k", lw=0.8, ls="--", label="leg held fixed (no matching)")
    left.set_xlabel("ground height at touchdown h (cm)")
    left.set_ylabel("foot speed / body speed at touchdown (dimensionless)")
    left.set_title(
        "blind swing-leg law: foot speed at touchdown\n(perfect ground-speed matching would be 0)",
        fontsize=10,
    )
    left.legend(fontsize=8)
    left.grid(alpha=0.3)
    right.axhline(0.0, color="k", lw=0.8)
    right.set_xlabel("touchdown time after apex t (s)")
    right.set_ylabel("leg angle rate θ̇ at touchdown (deg/s; < 0: retraction)")
    right.set_title("the law retracts the leg (θ̇ < 0) for late touchdowns", fontsize=10)
    right.legend(fontsize=8)
    right.grid(alpha=0.3)
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
