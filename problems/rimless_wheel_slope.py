"""Rimless wheel vs slope: its standing and rolling fixed points, and where each exists.

The rimless wheel (McGeer 1990; Coleman, Chatterjee & Ruina 1997) has two kinds of steady
motion on a slope γ (Tedrake, *Underactuated Robotics*, ch. "Simple models of walking and
running", §rimless wheel; α = π/spokes):

* **standing** — at rest with two spokes on the ground.  On the section (just after a forward
  impact) it is the fixed point ω = 0 of the rocking map ``P(ω) = cos²2α · ω`` (0 < ω < ω₁: the
  wheel rocks back onto the uphill spoke and forward again, losing a factor cos 2α at each
  impact; the chapter's every-impact map has −cos 2α per impact), with multiplier cos²2α.  The
  wheel can stand wherever the vertical lies between two
  spokes on the ground: for every slope below π/spokes;
* **rolling** — the fixed point ``ω* = cot 2α · sqrt(4 g/l · sin α · sin γ)`` of the vaulting map
  ``P(ω) = cos 2α · sqrt(ω² + 4 g/l · sin α · sin γ)``, with multiplier cos²2α.  It exists only
  where the wheel has the speed to vault over the stance spoke: ``ω* > ω₁ = sqrt(2 g/l (1 −
  cos(γ − α)))``, i.e. above the root γ_b of ``ω*(γ) = ω₁(γ)``, up to π/spokes.

Between γ_b and π/spokes both exist (bistable: which one the wheel ends in depends on its start).
Here the rolling branch comes from continuation (``gaitopt.continuation``) from the default slope
in both directions: downhill it ends at a ``boundary`` special point, where the gait ceases to
exist (its period diverges as ω* → ω₁), and that location is compared with the closed-form root
γ_b; uphill it runs to just below π/spokes, where standing ceases to exist (rolling goes on
beyond it: ``problems/rimless_wheel_basin.py`` has the γ > α form).  Every branch point
is compared with the closed-form ω* and cos²2α, and the standing point with the rocking map
sampled by simulation.

    python problems/rimless_wheel_slope.py --out results [--fast]

Writes results/rimless_wheel_slope/: branch.json, branch.csv, closed_form.csv, rocking_map.csv,
summary.json, existence.png.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402
from scipy.optimize import brentq  # noqa: E402

import gaitopt  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import save_figure  # noqa: E402
from gaitopt.returnmap import return_map  # noqa: E402

# The uphill end of the branch: just inside the open range slope < π/spokes.
_BELOW_RANGE_END = 1e-9


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    parser.add_argument("--scheduler", default=None, help="unused (no sweep in this study)")
    parser.add_argument("--workers", type=int, default=2, help="unused (no sweep in this study)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "rimless_wheel_slope"
    folder.mkdir(parents=True, exist_ok=True)
    n_rocking_slopes = 4 if args.fast else 12

    model = gaitopt.model("rimless_wheel")  # spokes 8, slope 0.08 (Drake's defaults)
    alpha = model.alpha
    top = alpha * (1 - _BELOW_RANGE_END)

    # -- rolling: continuation from the default slope, both directions ---------------------
    t0 = time.perf_counter()
    branch = gaitopt.continuation(model, "slope", to=top, both_directions=True)
    t_continuation = time.perf_counter() - t0
    write_json(branch.as_dict(), folder / "branch.json")
    write_csv(*branch.csv_rows(), folder / "branch.csv")

    # -- the closed form along the branch ------------------------------------------------------
    rows = []
    for c in branch.cycles:
        m = c.model
        rows.append(
            [
                m.slope,
                c.fixed_point["theta_dot"],
                m.rolling_speed(),
                c.fixed_point["theta_dot"] - m.rolling_speed(),
                m.vaulting_speed(),
                c.multipliers[0].real,
                math.cos(2 * alpha) ** 2,
                c.period,
            ]
        )
    write_csv(
        [
            "slope",
            "omega_continuation",
            "omega_closed_form",
            "difference",
            "omega_1",
            "multiplier",
            "multiplier_closed_form",
            "period",
        ],
        rows,
        folder / "closed_form.csv",
    )
    table = np.array(rows)

    # -- where rolling exists: the closed-form root of ω*(γ) = ω₁(γ) vs the located boundary --
    gamma_b = _closed_form_boundary(model)
    boundaries = [sp for sp in branch.special_points if sp.kind == "boundary"]
    located = boundaries[0].param if boundaries else None

    # -- standing: the rocking map, sampled by simulation, against cos²2α · ω ---------------
    rocking = []
    for slope in np.linspace(0.02, 0.3, n_rocking_slopes):
        m = model.replace(slope=float(slope))
        for fraction in (0.5, 0.9):
            omega = fraction * m.vaulting_speed()
            # Two impacts (back onto the uphill spoke, forward onto the downhill one): the
            # chapter's map counts each, −cos 2α per impact, cos² 2α per pair.
            after = float(return_map(m, omega, steps=2)[0])
            closed = m.closed_form_map(m.closed_form_map(omega))
            rocking.append([float(slope), omega, after, closed, after / omega])
    write_csv(
        ["slope", "omega", "map_simulated", "map_closed_form", "ratio"],
        rocking,
        folder / "rocking_map.csv",
    )
    ratios = np.array([r[4] for r in rocking])
    defined = np.isfinite(ratios)

    summary = {
        "model": "rimless_wheel",
        "params": model.params,
        "alpha": alpha,
        "source": "Tedrake, Underactuated Robotics, rimless wheel (closed forms)",
        "rolling": {
            "exists_from": gamma_b,
            "exists_to": alpha,
            "branch_from": float(branch.params.min()),
            "branch_to": float(branch.params.max()),
            "points": len(branch.cycles),
            "message": branch.message,
            "max_abs_difference_from_closed_form": float(np.max(np.abs(table[:, 3]))),
            "max_abs_multiplier_difference": float(np.max(np.abs(table[:, 5] - table[:, 6]))),
            "all_stable": bool(np.all(branch.stable)),
        },
        "boundary": {
            "located": located,
            "closed_form": gamma_b,
            "difference": located - gamma_b if located is not None else None,
            "message": boundaries[0].message if boundaries else None,
            "period_at_boundary": float(boundaries[0].cycle.period) if boundaries else None,
        },
        "range_end": {
            "last_point": float(branch.params.max()),
            "pi_over_spokes": alpha,
            "difference": alpha - float(branch.params.max()),
        },
        "standing": {
            "fixed_point": 0.0,
            "exists_from": 0.0,
            "exists_to": alpha,
            "multiplier_closed_form": math.cos(2 * alpha) ** 2,
            "rocking_map_samples": len(rocking),
            "rocking_map_defined": int(defined.sum()),
            "max_abs_ratio_error": float(np.max(np.abs(ratios[defined] - math.cos(2 * alpha) ** 2)))
            if defined.any()
            else None,
        },
        "bistable": [gamma_b, alpha],
        "timing_s": {"continuation": t_continuation},
    }
    write_json(summary, folder / "summary.json")

    # -- figure ------------------------------------------------------------------------------
    _figure(branch, model, gamma_b, boundaries[0] if boundaries else None, folder / "existence.png")

    print(
        f"rimless wheel (spokes {model.spokes}): rolling exists for {gamma_b:.10f} < slope < "
        f"π/spokes = {alpha:.10f}; standing for 0 < slope < {alpha:.10f}"
    )
    if located is not None:
        print(
            f"boundary located by continuation at {located:.12f}, closed form {gamma_b:.12f} "
            f"(difference {located - gamma_b:.2e})"
        )
    worst = summary["rolling"]["max_abs_difference_from_closed_form"]
    print(
        f"branch {branch.params.min():.10f}..{branch.params.max():.10f}, {len(branch.cycles)} "
        f"gaits; |ω − ω*closed form| ≤ {worst:.1e} rad/s; rocking map / ω = cos²2α to "
        f"{summary['standing']['max_abs_ratio_error']:.1e}"
    )
    print(f"continuation {t_continuation:.1f} s; wrote {folder}")
    return 0


def _closed_form_boundary(model) -> float:
    """Root of ω*(γ) = ω₁(γ) on (0, π/spokes): ω* grows and ω₁ shrinks with γ, so it is unique."""

    def gap(slope: float) -> float:
        m = model.replace(slope=slope)
        return m.rolling_speed() - m.vaulting_speed()

    return brentq(gap, 1e-6, model.alpha * (1 - _BELOW_RANGE_END), xtol=1e-15, rtol=1e-15)


def _figure(branch, model, gamma_b: float, boundary, path: Path) -> None:
    alpha = model.alpha
    fig, (ax, bottom) = plt.subplots(
        2,
        1,
        sharex=True,
        figsize=(8, 7),
        gridspec_kw={"height_ratios": [3, 1.3]},
        layout="constrained",
    )
    gammas = np.linspace(1e-4, alpha * (1 - _BELOW_RANGE_END), 600)
    closed = np.array([model.replace(slope=float(g)).rolling_speed() for g in gammas])
    omega1 = np.array([model.replace(slope=float(g)).vaulting_speed() for g in gammas])
    rolls = gammas > gamma_b

    ax.axvspan(0, gamma_b, color="tab:blue", alpha=0.07, lw=0)
    ax.axvspan(gamma_b, alpha, color="tab:purple", alpha=0.12, lw=0)
    ax.plot(
        gammas[rolls],
        closed[rolls],
        "-",
        color="tab:red",
        lw=1.5,
        label=r"rolling, closed form $\omega^* = \cot 2\alpha\,"
        r"\sqrt{4(g/l)\sin\alpha\sin\gamma}$",
    )
    ax.plot(
        gammas[~rolls],
        closed[~rolls],
        ":",
        color="tab:red",
        lw=1.2,
        label=r"closed-form $\omega^*$ where $\omega^* < \omega_1$ (no rolling)",
    )
    ax.plot(
        branch.params,
        branch.fixed_points[:, 1],
        "o",
        ms=3.5,
        color="k",
        zorder=5,
        label=f"rolling, continuation ({len(branch.cycles)} certified gaits, stable)",
    )
    ax.plot(
        gammas,
        omega1,
        "-.",
        color="0.35",
        lw=1.2,
        label=r"vaulting rate $\omega_1$ (below: rocks back, comes to rest)",
    )
    ax.plot(
        [0, alpha],
        [0, 0],
        "-",
        color="tab:blue",
        lw=4,
        solid_capstyle="butt",
        label=rf"standing, $\omega = 0$ (rocking map slope $\cos^2 2\alpha$ = "
        rf"{math.cos(2 * alpha) ** 2:.3g})",
    )
    ax.axvline(alpha, color="k", lw=0.8, ls="--")
    ax.axvline(gamma_b, color="tab:purple", lw=0.8, ls="--")
    top = 1.08 * max(np.max(closed), np.max(omega1))
    ax.text(gamma_b / 2, 0.93 * top, "standing only", ha="center", va="top", fontsize=9)
    ax.text(
        (gamma_b + alpha) / 2,
        0.93 * top,
        "bistable: standing and rolling",
        ha="center",
        va="top",
        fontsize=9,
        color="tab:purple",
    )
    ax.text(alpha, 0.99 * top, r"$\pi$/spokes ", ha="right", va="top", fontsize=9)
    if boundary is not None:
        b, located = boundary, boundary.param
        ax.plot(
            [located],
            [b.cycle.fixed_point["theta_dot"]],
            "s",
            ms=7,
            mfc="none",
            color="tab:purple",
            zorder=6,
        )
        ax.annotate(
            f"boundary (ω* = ω₁)\ncontinuation  {located:.10f}\nclosed form  {gamma_b:.10f}"
            f"\ndifference  {located - gamma_b:.1e}",
            (located, b.cycle.fixed_point["theta_dot"]),
            xytext=(30, -70),
            textcoords="offset points",
            fontsize=8,
            arrowprops={"arrowstyle": "->", "lw": 0.8},
        )
    ax.set_ylim(-0.1, top)
    ax.set_xlim(0, alpha * 1.02)
    ax.set_ylabel(r"$\dot\theta$ just after impact (rad/s)")
    ax.set_title(
        f"Rimless wheel ({model.spokes} spokes, l = {model.length:g} m): fixed points vs slope",
        fontsize=11,
    )
    ax.legend(fontsize=7.5, loc="center right", bbox_to_anchor=(0.99, 0.47))
    ax.grid(alpha=0.3)

    bottom.semilogy(branch.params, branch.periods, "o-", ms=3, color="k", lw=1)
    bottom.axvline(gamma_b, color="tab:purple", lw=0.8, ls="--")
    bottom.axvline(alpha, color="k", lw=0.8, ls="--")
    bottom.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    bottom.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    bottom.set_yticks([0.3, 0.5, 1, 2, 5])
    bottom.set_ylabel("rolling step period (s)")
    bottom.set_xlabel(r"slope $\gamma$ (rad)")
    bottom.grid(alpha=0.3, which="both")
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
