"""Simplest walker vs slope: the long- and short-step gaits, the period-doubling cascade, and
the γ^(1/3) scaling of the step angle (Garcia, Chatterjee, Ruina & Coleman 1998).

Garcia et al. ("The simplest walking model: stability, complexity, and scaling", J. Biomech.
Eng. 120:281–288, 1998) found two period-one gaits for every small slope γ: a long-step gait,
stable for 0 < γ < 0.015 rad (their abstract; the period doubling at γ ≈ 0.0151), and a
short-step gait that is always unstable; beyond the period doubling the stable walking motions
period-double again and "apparently become chaotic through a sequence of period doublings"
(abstract; their bifurcation diagram, quoted by Kurz & Stergiou 2007, J. NeuroEng. Rehabil. 4:30,
Fig. 1: chaotic gaits for 0.01839 < γ < 0.0189 and no stable gait above γ ≈ 0.019).  Their
small-γ analysis gives the step angle θ* ∝ γ^(1/3).

Here both families come from continuation (``gaitopt.continuation``), from Garcia's gaits at
γ = 0.009, up to the end of the slope range with ``cascade=True`` (the period-2, 4, 8, …
branches born at each period doubling), and down to small γ, where the log-log slope of θ*(γ)
is fitted and compared with 1/3.  Every period-doubled branch is recorded with whether it was
born at its period doubling (its first orbit next to the parent's and with a multiplier near
+1, the square of the crossing −1); the library's branch switching keeps only such orbits.

    python problems/simplest_walker_slope.py --out results [--fast]

Writes results/simplest_walker_slope/: branches.json, long.csv, short.csv, summary.json,
bifurcation.png, cascade.png, scaling.png.
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

import gaitopt  # noqa: E402
from gaitopt import Branch  # noqa: E402
from gaitopt.continuation.switching import born_at  # noqa: E402
from gaitopt.files import write_csv, write_json  # noqa: E402
from gaitopt.plotting import plot_branch, save_figure  # noqa: E402

START = 0.009  # Garcia et al.'s slope (rad)
# Garcia et al. 1998's gaits at γ = 0.009, rounded: the continuation's starting guesses.
GUESSES = {
    "long": {"theta": 0.2003, "theta_dot": -0.1998},
    "short": {"theta": 0.1939, "theta_dot": -0.2039},
}
# Garcia et al. 1998 (and docs/design.md): the gaits at γ = 0.009 to 14 digits.
GARCIA = {
    "long": {"theta": 0.20031090049483, "theta_dot": -0.19983247291764},
    "short": {"theta": 0.19393736960624, "theta_dot": -0.20386692731962},
}
GARCIA_PD = 0.0151  # first period doubling of the long gait (Garcia et al. 1998; abstract: 0.015)
# The overview follows the period-2 and period-4 branches to the range end; the cascade is
# resolved with fine steps from ZOOM_FROM (below the first PD) to CASCADE_TO (past its
# accumulation, γ ≈ 0.01829).
OVERVIEW_PERIOD = 4
ZOOM_FROM, CASCADE_TO = 0.0145, 0.0187
FIT_BELOW = 1e-3  # the small-γ part of the branches where θ* ∝ γ^p is fitted
FEIGENBAUM = 4.669201609


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="results", help="results folder")
    parser.add_argument("--fast", action="store_true", help="small sizes for CI")
    parser.add_argument("--scheduler", default=None, help="unused (no sweep in this study)")
    parser.add_argument("--workers", type=int, default=2, help="unused (no sweep in this study)")
    args = parser.parse_args(argv)
    folder = Path(args.out) / "simplest_walker_slope"
    folder.mkdir(parents=True, exist_ok=True)
    if args.fast:
        top, bottom, per_decade, zoom_step, zoom_period = 0.02, 1e-4, 3, 0.004, 8
    else:  # 0.05: the end of the slope's range
        top, bottom, per_decade, zoom_step, zoom_period = 0.05, 1e-5, 6, 0.002, 16
    options = gaitopt.PseudoArclength(step=0.02, max_step=0.05)
    fine = gaitopt.PseudoArclength(step=zoom_step, max_step=zoom_step, max_points=1000)

    model = gaitopt.model("simplest_walker", slope=START)
    t0 = time.perf_counter()
    starts = {name: gaitopt.find_limit_cycle(model, guess) for name, guess in GUESSES.items()}
    for name, cycle in starts.items():
        if not cycle.success:
            raise SystemExit(f"no {name}-step gait at γ = {START}: {cycle.message}")

    # -- up the slope to the range end, with the first doublings (overview) -----------------
    up_long, overview_log = _cascade(starts["long"], top, OVERVIEW_PERIOD, options)
    up_short, _ = _cascade(starts["short"], top, OVERVIEW_PERIOD, options)
    t_up = time.perf_counter() - t0

    # -- the cascade, resolved: fine steps from just below the first PD to CASCADE_TO --------
    t0 = time.perf_counter()
    below = [c for c in up_long.cycles if c.model.slope <= ZOOM_FROM]
    cascade, cascade_log = _cascade(below[-1], CASCADE_TO, zoom_period, fine)
    t_cascade = time.perf_counter() - t0

    # -- down the slope, in legs that land on log-spaced slopes (points for the fit) ----------
    t0 = time.perf_counter()
    n_legs = max(int(round(per_decade * math.log10(START / bottom))), 1)
    targets = np.logspace(math.log10(START), math.log10(bottom), n_legs + 1)[1:]
    families = {}
    for name, up in (("long", up_long), ("short", up_short)):
        down, cycle, message = [], starts[name], ""
        for target in targets:
            leg = gaitopt.continuation(
                cycle.model, "slope", to=float(target), start=cycle, cascade=False, options=options
            )
            down += leg.cycles[1:]
            cycle = leg.cycles[-1]
            if leg.params[-1] != target:  # the family ends (or the corrector gives up) here
                message = f"down: {leg.message}"
                break
        families[name] = _joined(
            down, up, message or f"down: reached slope = {cycle.model.slope:.6g}"
        )
    t_down = time.perf_counter() - t0

    # -- outputs ---------------------------------------------------------------------------------
    write_json(
        {**{name: b.as_dict() for name, b in families.items()}, "cascade": cascade.as_dict()},
        folder / "branches.json",
    )
    for name, b in (*families.items(), ("cascade", cascade)):
        write_csv(*b.csv_rows(), folder / f"{name}.csv")

    pds = _period_doublings(cascade)
    overview_pds = _period_doublings(families["long"])
    pd_slopes = [d["slope"] for d in pds]
    ratios = [
        (pd_slopes[i + 1] - pd_slopes[i]) / (pd_slopes[i + 2] - pd_slopes[i + 1])
        for i in range(len(pd_slopes) - 2)
    ]
    accumulation = (
        pd_slopes[-1] + (pd_slopes[-1] - pd_slopes[-2]) / (FEIGENBAUM - 1)
        if len(pd_slopes) >= 2
        else None
    )
    fits = {name: _scaling_fit(b) for name, b in families.items()}
    at_start = {}
    for name, c in starts.items():
        at_start[name] = {
            "theta": c.fixed_point["theta"],
            "theta_dot": c.fixed_point["theta_dot"],
            "garcia": GARCIA[name],
            "difference": max(abs(c.fixed_point[k] - v) for k, v in GARCIA[name].items()),
            "multipliers": c.multipliers,
            "stable": bool(c.stable),
        }
    ends = {}
    for name, b in families.items():
        ends[name] = {
            "from": float(b.params.min()),
            "to": float(b.params.max()),
            "folds": [
                sp.param for x in b.descendants() for sp in x.special_points if sp.kind == "LP"
            ],
            "boundaries": [
                {"period": x.steps, "slope": sp.param, "message": sp.message}
                for x in b.descendants()
                for sp in x.special_points
                if sp.kind == "boundary"
            ],
            "message": b.message,
            "stable_slopes": _stable_interval(b),
        }
    summary = {
        "model": "simplest_walker",
        "source": "Garcia, Chatterjee, Ruina & Coleman 1998, J. Biomech. Eng. 120:281-288",
        "slope_range": [float(bottom), float(top)],
        "gaits_at_0.009": at_start,
        "period_doublings": pds,
        "period_doublings_overview": overview_pds,
        "cascade_window": [float(cascade.params.min()), CASCADE_TO],
        "first_period_doubling": {
            "continuation": pd_slopes[0] if pd_slopes else None,
            "garcia": GARCIA_PD,
            "difference": pd_slopes[0] - GARCIA_PD if pd_slopes else None,
        },
        "feigenbaum_ratios": ratios,
        "accumulation_estimate": accumulation,
        "families": ends,
        "scaling": fits,
        "cascade": {
            "max_period": zoom_period,
            "overview_max_period": OVERVIEW_PERIOD,
            "overview": overview_log,
            "resolved": cascade_log,
        },
        "timing_s": {"up": t_up, "cascade": t_cascade, "down": t_down},
    }
    write_json(summary, folder / "summary.json")

    # -- figures ---------------------------------------------------------------------------------
    _bifurcation_figure(families, folder / "bifurcation.png")
    _cascade_figure(cascade, pds, accumulation, folder / "cascade.png")
    _scaling_figure(families, fits, folder / "scaling.png")

    print(
        "simplest walker at γ = 0.009: long gait "
        f"{'stable' if starts['long'].stable else 'UNSTABLE'} (|μ|max "
        f"{np.max(np.abs(starts['long'].multipliers)):.4f}), short gait "
        f"{'stable' if starts['short'].stable else 'unstable'} (|μ|max "
        f"{np.max(np.abs(starts['short'].multipliers)):.4f})"
    )
    print(
        "period doublings of the long gait: "
        + ", ".join(f"{d['slope']:.8f} ({d['period']}→{d['to_period']})" for d in pds)
        + f"; Garcia et al.: first at ≈ {GARCIA_PD}"
    )
    if ratios:
        print(f"Feigenbaum ratios {', '.join(f'{r:.3f}' for r in ratios)} (δ = {FEIGENBAUM:.3f})")
    for name, f in fits.items():
        print(
            f"{name}-step θ* ∝ γ^p on {f['range'][0]:.0e} ≤ γ ≤ {f['range'][1]:.0e}: "
            f"p = {f['exponent']:.5f} (1/3 to {100 * f['relative_error']:.2f} %), "
            f"θ* ≈ {f['prefactor']:.4f} γ^p"
        )
    for name, e in ends.items():
        print(f"{name}-step family: {e['message']}")
    for label, log in (("overview", overview_log), ("resolved cascade", cascade_log)):
        for child in log["children"]:
            if not child["born_at_pd"]:
                print(f"{label}: the period-{child['steps']} branch is not born at its PD")
    print(
        f"continuation up {t_up:.1f} s, cascade {t_cascade:.1f} s, down {t_down:.1f} s; "
        f"wrote {folder}"
    )
    return 0


# ---------------------------------------------------------------------------------------------
def _joined(down: list, up: Branch, down_message: str) -> Branch:
    """One branch from the downward legs (given from the start downwards) and the upward branch
    (starting at the shared start), in increasing slope."""
    cycles = down[::-1] + up.cycles
    n = len(down)
    specials = [
        gaitopt.SpecialPoint(sp.kind, sp.param, sp.index + n, sp.cycle, sp.message)
        for sp in up.special_points
    ]
    return Branch(
        up.model,
        up.param,
        up.steps,
        cycles=cycles,
        special_points=specials,
        children=up.children,
        message=f"{down_message}; up: {up.message}",
    )


def _cascade(start, to: float, max_period: int, options) -> tuple[Branch, dict]:
    """``continuation(..., cascade=True)`` from ``start`` to ``to``; returns the branch and, for
    each period-doubled branch, where it starts and whether it was born at its PD (next to the
    parent orbit with a multiplier near +1: :func:`gaitopt.continuation.switching.born_at`)."""
    branch = gaitopt.continuation(
        start.model,
        "slope",
        to=to,
        start=start,
        cascade=True,
        max_period=max_period,
        options=options,
    )
    children = []
    for parent in branch.descendants():
        pds = [sp for sp in parent.special_points if sp.kind == "PD"]
        for child in parent.children:
            sp = min(pds, key=lambda sp: abs(sp.param - float(child.params[0])))
            children.append(
                {
                    "steps": child.steps,
                    "pd": sp.param,
                    "first_param": float(child.params[0]),
                    "first_multipliers": child.cycles[0].multipliers,
                    "born_at_pd": born_at(child.cycles[0], sp.cycle),
                }
            )
    return branch, {"children": children}


def _period_doublings(branch: Branch) -> list[dict]:
    pds = [
        {"period": b.steps, "to_period": 2 * b.steps, "slope": sp.param}
        for b in branch.descendants()
        for sp in b.special_points
        if sp.kind == "PD"
    ]
    return sorted(pds, key=lambda d: d["period"])


def _stable_interval(branch: Branch) -> list[float] | None:
    """Slopes of the period-1 branch's stable points (first and last)."""
    stable = branch.params[branch.stable]
    return [float(stable.min()), float(stable.max())] if stable.size else None


def _scaling_fit(branch: Branch) -> dict:
    """Least-squares line through (log γ, log θ*) for γ ≤ FIT_BELOW, plus local slopes."""
    gamma, theta = branch.params, branch.fixed_points[:, 0]
    small = gamma <= FIT_BELOW * (1 + 1e-12)
    p, c = np.polyfit(np.log(gamma[small]), np.log(theta[small]), 1)
    local = []
    for lo in 10.0 ** np.arange(math.floor(math.log10(gamma.min()) + 1e-9), math.log10(0.01)):
        sel = (gamma >= lo * (1 - 1e-9)) & (gamma <= 10 * lo * (1 + 1e-9))
        if sel.sum() >= 3:
            slope = np.polyfit(np.log(gamma[sel]), np.log(theta[sel]), 1)[0]
            local.append({"from": float(lo), "to": float(10 * lo), "exponent": float(slope)})
    return {
        "exponent": float(p),
        "prefactor": float(math.exp(c)),
        "relative_error": float(abs(p - 1 / 3) * 3),
        "range": [float(gamma[small].min()), float(gamma[small].max())],
        "points": int(small.sum()),
        "by_decade": local,
    }


def _bifurcation_figure(families: dict, path: Path) -> None:
    """Both families over the whole slope range (the short one in grey)."""
    fig, (top, bottom) = plot_branch(families["long"], coordinate="theta")
    n_top, n_bottom = len(top.lines), len(bottom.lines)
    plot_branch(families["short"], coordinate="theta", axes=(top, bottom))
    for line in top.lines[n_top:] + bottom.lines[n_bottom:]:
        if line.get_color() != "k":  # the special points stay black
            line.set_color("0.45")
        if line.get_label().startswith("period"):
            line.set_label("short step, period 1")
    for line in top.lines[:n_top]:
        if line.get_label() == "period 1":
            line.set_label("long step, period 1")
    top.legend(fontsize=8, loc="upper left")
    top.set_ylabel(r"step angle $\theta^*$ just after heel strike (rad)")
    bottom.set_yscale("log")
    bottom.set_xlabel(r"slope $\gamma$ (rad)")
    top.set_title(
        "Simplest walker (Garcia et al. 1998): gaits vs slope (solid stable, dotted unstable)",
        fontsize=10,
    )
    save_figure(fig, path)


def _cascade_figure(cascade: Branch, pds: list, accumulation: float | None, path: Path) -> None:
    """The period-doubling cascade of the long gait, resolved, with its PDs tabulated."""
    fig, (top, bottom) = plt.subplots(
        2,
        1,
        sharex=True,
        figsize=(9, 8),
        gridspec_kw={"height_ratios": [2, 1]},
        layout="constrained",
    )
    plot_branch(cascade, coordinate="theta", axes=(top, bottom))
    bottom.set_yscale("log")
    bottom.set_ylim(0.1, 20)
    bottom.set_xlabel(r"slope $\gamma$ (rad)")
    top.set_ylabel(r"step angle $\theta$ just after each heel strike (rad)")
    top.set_title(
        "Simplest walker: the long gait's period-doubling cascade (solid stable, dotted unstable)",
        fontsize=10,
    )
    text = "\n".join(f"PD {d['period']}→{d['to_period']}: γ = {d['slope']:.8f}" for d in pds)
    if accumulation is not None:
        text += f"\naccumulation (Feigenbaum δ) ≈ {accumulation:.5f}"
    text += f"\nGarcia et al. 1998: first PD at γ ≈ {GARCIA_PD}"
    top.text(
        0.2,
        0.97,
        text,
        transform=top.transAxes,
        ha="left",
        va="top",
        fontsize=8,
        bbox={"fc": "white", "ec": "0.7", "alpha": 0.9},
    )
    top.legend(fontsize=8, loc="upper left")
    save_figure(fig, path)


def _scaling_figure(families: dict, fits: dict, path: Path) -> None:
    fig, (ax, local) = plt.subplots(
        2,
        1,
        sharex=True,
        figsize=(7, 7),
        gridspec_kw={"height_ratios": [3, 1.4]},
        layout="constrained",
    )
    colours = {"long": "tab:blue", "short": "tab:orange"}
    for name, b in families.items():
        gamma, theta = b.params, b.fixed_points[:, 0]
        f = fits[name]
        ax.loglog(gamma, theta, "o", ms=3, color=colours[name], label=f"{name}-step gait")
        g = np.array(f["range"])
        ax.loglog(
            g,
            f["prefactor"] * g ** f["exponent"],
            "-",
            lw=2,
            color="k",
            alpha=0.6,
            label=f"fit on γ ≤ {FIT_BELOW:g} ({name}): θ* = {f['prefactor']:.4f} "
            f"γ^{f['exponent']:.4f}",
        )
        # local log-log slope between neighbouring points
        mid = np.sqrt(gamma[1:] * gamma[:-1])
        slope = np.diff(np.log(theta)) / np.diff(np.log(gamma))
        ok = np.diff(gamma) > 0
        local.semilogx(mid[ok], slope[ok], "-", color=colours[name], label=name)
    local.axhline(1 / 3, color="k", ls="--", lw=0.8, label="1/3 (Garcia et al.)")
    local.axvline(FIT_BELOW, color="0.5", ls=":", lw=0.8)
    ax.axvline(FIT_BELOW, color="0.5", ls=":", lw=0.8)
    local.set_ylim(0.25, 0.36)
    local.set_ylabel(r"d ln $\theta^*$ / d ln $\gamma$")
    local.set_xlabel(r"slope $\gamma$ (rad)")
    local.legend(fontsize=8, loc="lower left")
    ax.set_ylabel(r"step angle $\theta^*$ (rad)")
    ax.set_title(r"Simplest walker: $\theta^* \propto \gamma^{1/3}$ at small slopes", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    for a in (ax, local):
        a.grid(alpha=0.3, which="both")
    save_figure(fig, path)


if __name__ == "__main__":
    raise SystemExit(main())
