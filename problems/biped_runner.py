"""The biped runner's gaits: the symmetric run (= the SLIP run twice) and the limps of unequal legs.

Raibert's biped run (Raibert, *Legged Robots That Balance*, MIT Press 1986, ch. 4) as a point
mass on two massless spring legs that take turns (gaitopt/models/biped_runner.py).  With equal
legs and touchdown angles each stride is two SLIP steps (Blickhan 1989; Tedrake, *Underactuated
Robotics*, SLIP), so the stride's fixed point is the SLIP's and its one multiplier is the SLIP
multiplier squared.  Unequal legs make the two steps differ: Merker, Kaiser, Seyfarth & Hermann
(2015, "Stable running with asymmetric legs: a bifurcation approach", Int. J. Bifurcation Chaos)
follow such asymmetric runs; Minetti (1998) and Andrada et al. (2016) call a run with one aerial
phase much shorter than the other a *skip*.

This study

* compares the symmetric run with the `slip` gait (apex, speed, period = 2 × the SLIP's,
  multiplier = the SLIP's squared) at three touchdown angles (0.51, 0.52 and π/6 rad);
* follows the gait by pseudo-arclength continuation in leg B's touchdown angle θ_b over
  0.45–0.62 rad, both ways: with equal legs from the symmetric run (θ_b = θ_a = π/6), and with
  leg B softer (7500 N/m instead of 8397.36 N/m) from the limp of tests/test_biped_runner.py at
  θ_b = 0.56 rad, classifying every gait (`classify`: symmetric run, limp, skip) with
  its apex heights, aerial phases, multiplier and stability.

    python problems/biped_runner.py --out results [--fast]

Writes results/biped_runner/: symmetric.csv/json (the SLIP comparison), branch_equal.csv,
branch_soft_b.csv (θ_b, apex heights, aerial phases, period, multiplier, stable, gait),
summary.json and gaits.png.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.models.biped_runner import classify  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402

#: Leg B softer than leg A (N/m), as the limp of tests/test_biped_runner.py.
SOFT_B = 7500.0
COLUMNS = (
    "touchdown_angle_b_rad", "apex_a_m", "apex_b_m", "aerial_a_s", "aerial_b_s", "stance_a_s",
    "stance_b_s", "period_s", "multiplier", "stable", "gait",
)  # fmt: skip


def symmetric_rows(angles: list[float]) -> list[dict]:
    """The symmetric run and the SLIP at each touchdown angle (rad)."""
    rows = []
    for angle in angles:
        slip = gaitopt.find_limit_cycle(gaitopt.model("slip", touchdown_angle=angle))
        if not slip.success:
            raise RuntimeError(f"no SLIP gait at θ = {angle}: {slip.message}")
        runner = gaitopt.find_limit_cycle(
            gaitopt.model("biped_runner", touchdown_angle_a=angle, touchdown_angle_b=angle),
            {"z": slip.fixed_point["z"]},
        )
        if not runner.success:
            raise RuntimeError(f"no symmetric run at θ = {angle}: {runner.message}")
        mu_slip = complex(slip.multipliers[0])
        mu_run = complex(runner.multipliers[0])
        rows.append(
            {
                "touchdown_angle_rad": angle,
                "apex_m": runner.fixed_point["z"],
                "slip_apex_m": slip.fixed_point["z"],
                "speed_m_s": runner.fixed_point["x_dot"],
                "period_s": runner.period,
                "twice_slip_period_s": 2 * slip.period,
                "multiplier": mu_run.real,
                "slip_multiplier_squared": (mu_slip**2).real,
                "verified": bool(runner.verified and slip.verified),
            }
        )
    return rows


def branch_rows(branch) -> list[dict]:
    """One row per gait of a branch in θ_b, classified."""
    rows = []
    for cycle in branch.cycles:
        if not cycle.success:
            continue
        c = classify(cycle)
        mu = complex(cycle.multipliers[0])
        rows.append(
            {
                "touchdown_angle_b_rad": float(cycle.model.touchdown_angle_b),
                "apex_a_m": c["apex_a"],
                "apex_b_m": c["apex_b"],
                "aerial_a_s": c["aerial_a"],
                "aerial_b_s": c["aerial_b"],
                "stance_a_s": c["stance_a"],
                "stance_b_s": c["stance_b"],
                "period_s": float(cycle.period),
                "multiplier": mu.real if abs(mu.imag) < 1e-12 else abs(mu),
                "stable": bool(cycle.stable),
                "gait": c["gait"],
            }
        )
    return rows  # in the branch's order (arclength): through a fold θ_b turns back


def follow(stiffness_b: float, theta_b: float, guess: dict, bounds: tuple, max_step: float):
    """The branch in θ_b, both ways from the gait at ``theta_b`` (rad, found from ``guess``),
    with leg B's stiffness (N/m), within ``bounds`` (rad)."""
    model = gaitopt.model("biped_runner", stiffness_b=stiffness_b, touchdown_angle_b=theta_b)
    start = gaitopt.find_limit_cycle(model, guess)
    if not start.success:
        raise RuntimeError(f"no gait with leg B at {stiffness_b} N/m: {start.message}")
    return gaitopt.continuation(
        model,
        "touchdown_angle_b",
        start=start,
        to=bounds[1],
        bounds=bounds,
        both_directions=True,
        cascade=False,
        options=gaitopt.PseudoArclength(step=max_step, max_step=max_step),
    )


def _figure(branches: dict[str, list[dict]]):
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    for label, rows in branches.items():
        th = [r["touchdown_angle_b_rad"] for r in rows]
        ax1.plot(th, [r["apex_a_m"] for r in rows], "-", label=f"{label}: apex before A")
        ax1.plot(th, [r["apex_b_m"] for r in rows], "--", label=f"{label}: apex before B")
        ax2.semilogy(th, [abs(r["multiplier"]) for r in rows], "-", label=label)
    ax1.set_ylabel("apex height z (m)")
    ax1.legend(fontsize=7)
    ax2.axhline(1.0, color="0.6", lw=0.8)  # stable below
    ax2.set_ylabel("stride multiplier |λ| (1)")
    ax2.set_xlabel("leg B's touchdown angle θ_b (rad)")
    ax2.legend(fontsize=7)
    fig.suptitle("Biped runner: symmetric run (θ_b = π/6) and limps")
    fig.tight_layout()
    return fig


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "biped_runner"
    folder.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    angles = [math.pi / 6] if args.fast else [0.51, 0.52, math.pi / 6]
    symmetric = symmetric_rows(angles)
    write_json(symmetric, folder / "symmetric.json")
    write_csv(list(symmetric[0]), [list(r.values()) for r in symmetric], folder / "symmetric.csv")
    step = 0.02 if args.fast else 0.004
    bounds = (0.50, 0.58) if args.fast else (0.45, 0.62)
    branches, specials = {}, {}
    # Equal legs from the symmetric run (θ_b = π/6); leg B softer from the limp at 0.56 rad (at
    # π/6 the soft leg's stride has no gait: its apex falls below the touchdown height).
    for name, k_b, theta_b, z in (
        ("equal", 8397.36, math.pi / 6, 0.8768),
        ("soft_b", SOFT_B, 0.56, 0.876),
    ):
        branch = follow(k_b, theta_b, {"z": z}, bounds, step)
        rows = branch_rows(branch)
        branches[name] = rows
        specials[name] = [
            {"kind": sp.kind, "touchdown_angle_b_rad": float(sp.param), "message": sp.message}
            for sp in branch.special_points
        ]
        write_csv(
            list(COLUMNS), [[r[c] for c in COLUMNS] for r in rows], folder / f"branch_{name}.csv"
        )
    summary = {
        "symmetric_equals_slip": max(
            max(
                abs(r["apex_m"] - r["slip_apex_m"]),
                abs(r["period_s"] - r["twice_slip_period_s"]),
                abs(r["multiplier"] - r["slip_multiplier_squared"]),
            )
            for r in symmetric
        ),  # fmt: skip
        "gaits": {name: sorted({r["gait"] for r in rows}) for name, rows in branches.items()},
        "stable_range_rad": {
            name: [
                min((r["touchdown_angle_b_rad"] for r in rows if r["stable"]), default=None),
                max((r["touchdown_angle_b_rad"] for r in rows if r["stable"]), default=None),
            ]
            for name, rows in branches.items()
        },
        "points": {name: len(rows) for name, rows in branches.items()},
        "special_points": specials,
        "fast": args.fast,
        "elapsed_s": time.perf_counter() - t0,
    }
    write_json(summary, folder / "summary.json")
    save_figure(_figure({"k_b = k_a": branches["equal"], "k_b = 7500 N/m": branches["soft_b"]}),
                folder / "gaits.png")  # fmt: skip
    print(
        f"symmetric run = SLIP twice to {summary['symmetric_equals_slip']:.2g}; gaits "
        f"{summary['gaits']}; stable θ_b {summary['stable_range_rad']} "
        f"({summary['elapsed_s']:.1f} s)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
