"""An optimal gait analysed as a found one: its open loop shot, continued and controlled.

The level least-effort compass gait (0.3 m in 0.8 s, slope 0) is an :class:`OptimalGait`
(Radau collocation, :func:`gaitopt.optimize_gait`).  Its open loop — the hip-torque profile
read on a clock since heel strike, the model's parameters still free (``gaitopt.orbit.
feedforward``) — is an autonomous hybrid model, whose limit cycle multiple shooting finds from
the optimum (:func:`gaitopt.open_loop.open_loop_cycle`).  Two independent transcriptions of the
same orbit are compared (period, fixed point, multipliers, the return map's Jacobians in state
and in a per-step torque offset); then the open loop is continued downhill in the slope with the
profile held fixed (every point certified and verified by simulation; the last one also by the
simulator driven by the optimum's own profile), and step-to-step LQR is designed on it and
simulated.

    python problems/optimal_open_loop.py --out results [--fast]

Writes results/optimal_open_loop/: summary.json, branch.csv, branch.png.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.continuation import PseudoArclength  # noqa: E402
from gaitopt.control import closed_loop, lqr  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.open_loop import open_loop_cycle  # noqa: E402
from gaitopt.optimize.stabilisation import offset_jacobian  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402


def _gap(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="slope to 0.001 only, for CI")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_open_loop"
    folder.mkdir(parents=True, exist_ok=True)

    gait = gaitopt.optimize_gait(
        gaitopt.model("compass_gait", slope=0.0), period=0.8, step_length=0.3
    )
    assert gait.success, gait.message
    clock = time.perf_counter()
    cycle = open_loop_cycle(gait)
    cycle_s = time.perf_counter() - clock
    names = list(gait.fixed_point)
    shooting = {
        "success": cycle.success,
        "message": cycle.message,
        "period": cycle.period,
        "period_gap": abs(cycle.period - gait.period),
        "fixed_point_gap": _gap([cycle.fixed_point[n] for n in names], gait.x),
        "multipliers": [complex(m) for m in cycle.multipliers],
        "multiplier_gap": _gap(
            np.sort_complex(cycle.multipliers), np.sort_complex(gait.multipliers)
        ),
        "segments": cycle.problem.disc.segments,
        "rk_steps": cycle.problem.disc.rk_steps,
        "seconds": cycle_s,
    }
    print(
        f"open loop by shooting: period {cycle.period:.12f} s ({shooting['period_gap']:.2g} from "
        f"the optimum's), fixed point {shooting['fixed_point_gap']:.2g}, multipliers "
        f"{shooting['multiplier_gap']:.2g} apart"
    )

    controller = lqr(gait, Q=1.0, R=1e-3)
    lin = controller.linearisation
    col, w = gait.transcription
    A_col, B_col = offset_jacobian(col, w, gait.model.p)
    s0 = controller.target + np.array([1e-3, -1e-3, 1e-3])
    start = dict(zip(cycle.model.section.coordinates, s0, strict=True))
    run = closed_loop(controller, controller.model, start, steps=8)
    free = closed_loop(None, controller.model, start, steps=8, target=controller.target)
    control = {
        "Q": 1.0,
        "R": 1e-3,
        "B": lin.B.ravel(),
        "A_gap_to_collocation": _gap(lin.A, A_col),
        "B_gap_to_collocation": _gap(lin.B, B_col),
        "gain": controller.gain.ravel(),
        "closed_loop_multipliers": [complex(m) for m in controller.closed_loop_multipliers],
        "controlled_errors": run.errors,
        "uncontrolled_errors": free.errors,
    }
    print(f"LQR gain {np.round(controller.gain.ravel(), 3)}, closed loop "
          f"{np.round(controller.closed_loop_multipliers.real, 5)}")  # fmt: skip

    to = 0.001 if args.fast else 0.01
    clock = time.perf_counter()
    branch = gaitopt.continuation(
        gait, "slope", to=to, cascade=False, options=PseudoArclength(step=0.05)
    )
    branch_s = time.perf_counter() - clock
    rows = [
        (float(c.model.slope), c.period, float(np.max(np.abs(c.multipliers))), c.stable,
         c.verified)
        for c in branch.cycles
    ]  # fmt: skip
    write_csv(["slope_rad", "period_s", "max_abs_multiplier", "stable", "verified"], rows,
              folder / "branch.csv")  # fmt: skip
    # The last point, checked by the simulator driven by the optimum's own (NumPy) profile.
    last = branch.cycles[-1]
    base = gait.model.replace(slope=float(last.model.slope))
    x0 = base.state_vector({k: last.fixed_point[k] for k in base.state_names})
    sim = gaitopt.simulate(base, x0, steps=1, feedforward=gait.feedforward, rtol=1e-12,
                           atol=1e-13)  # fmt: skip
    continuation = {
        "success": branch.success,
        "message": branch.message,
        "to": to,
        "points": len(branch.cycles),
        "all_verified": all(c.success and c.verified for c in branch.cycles),
        "period_at_end": last.period,
        "max_abs_multiplier_at_end": rows[-1][2],
        "special_points": [(sp.kind, sp.param) for sp in branch.special_points],
        "feedforward_return_error_at_end": (
            _gap(sim.section_states[-1], x0) if sim.success else None
        ),
        "seconds": branch_s,
    }
    print(f"continued to slope {to}: {len(rows)} certified points, period {last.period:.9f} s; "
          f"{branch.message}")  # fmt: skip
    write_json(
        {
            "optimum": {
                "cost": gait.cost,
                "period": gait.period,
                "fixed_point": gait.fixed_point,
                "multipliers": [complex(m) for m in gait.multipliers],
            },
            "shooting": shooting,
            "control": control,
            "continuation": continuation,
        },  # fmt: skip
        folder / "summary.json",
    )

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    slope = [r[0] for r in rows]
    ax1.plot(slope, [r[1] for r in rows], "o-", ms=3)
    ax1.set_xlabel("slope γ (rad)")
    ax1.set_ylabel("step period T (s)")
    ax1.set_title("Open loop of the level optimum, torque profile held")
    ax2.plot(slope, [r[2] for r in rows], "o-", ms=3)
    ax2.axhline(1.0, color="k", lw=0.8, ls="--")
    ax2.set_xlabel("slope γ (rad)")
    ax2.set_ylabel("largest multiplier modulus |λ|max (1)")
    ax2.set_title("Open-loop stability")
    fig.tight_layout()
    save_figure(fig, folder / "branch.png")
    plt.close(fig)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
