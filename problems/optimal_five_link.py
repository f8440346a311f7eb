"""The five-link biped's least-effort gaits against OptimTraj's committed solver logs.

Kelly's OptimTraj (``demo/fiveLinkBiped``, commit 8c43235; Kelly 2017, SIAM Review 59(4)) solves
one step of 0.4 m in 0.6 s on level ground, minimising ∫Σu² dt with |u| ≤ 100 N·m,
|q| ≤ π/2 rad, |q̇| ≤ 10 rad/s and no knee limit; its GPOPS-II logs end at 263.69884582 (IPOPT)
and 302.25469438 (SNOPT), two local minima.  Here a seeded multi-start finds both, says which
starts reach which, refines the best to a discretisation error below 1e-8, re-simulates it and
reports its Floquet multipliers (AD and finite differences).

    python problems/optimal_five_link.py --out results [--starts N]

Writes results/optimal_five_link/: minima.csv, optimal.json, inputs.csv, inputs.png, orbit.png,
gait.gif.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import gaitopt  # noqa: E402
from gaitopt.cli.optimize_files import write_optimal  # noqa: E402
from gaitopt.files import write_csv  # noqa: E402

OPTIMTRAJ = {"GPOPS-IPOPT": 263.69884582, "GPOPS-SNOPT": 302.25469438}  # 8c43235 logs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--starts", type=int, default=8, help="seeded starts (default 8)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "optimal_five_link"
    folder.mkdir(parents=True, exist_ok=True)
    model = gaitopt.model("five_link_biped")
    t0 = time.perf_counter()
    gait = gaitopt.optimize_gait(
        model,
        period=0.6,
        step_length=0.4,
        bounds={name: high for name, (_, high) in model.input_bounds.items()},
        state_bounds=model.state_bounds,
        starts=args.starts,
        seed=0,
    )
    elapsed = time.perf_counter() - t0
    rows = []
    for m in gait.minima:
        ref, value = min(OPTIMTRAJ.items(), key=lambda kv: abs(kv[1] - m.cost))
        rows.append((m.cost, ref, value, (m.cost - value) / value, " ".join(map(str, m.starts))))
        print(f"minimum {m.cost:.10f}: {ref} {value} (rel {(m.cost - value) / value:.2e}), "
              f"starts {m.starts}")  # fmt: skip
    write_csv(["cost", "optimtraj_log", "optimtraj_cost", "relative_difference", "starts"],
              rows, folder / "minima.csv")  # fmt: skip
    report = gait.to_json(minima=True)
    report["time_s"] = elapsed
    write_optimal(gait, report, folder)
    print(f"best {gait.cost:.10f}, discretisation error {gait.discretisation_error:.2g}, "
          f"verified {gait.verified}, {elapsed:.1f} s for {args.starts} starts")  # fmt: skip
    return 0 if gait.success else 1


if __name__ == "__main__":
    raise SystemExit(main())
