"""The printed report of ``make bench``: the table of models and methods (also kept in the JSON
record), its legend, the goals, and the sections' own tables."""

from __future__ import annotations

from typing import Any

from . import branches as _bench_branches
from . import curves as _bench_curves
from . import first_call as _bench_first_call
from . import goals as _bench_goals
from . import optimize as _bench_optimize
from . import simulate as _bench_simulate
from . import speed as _bench_speed
from .common import _median, _ms, _sci
from .control import _control_lines

__all__ = ["rows", "format_table"]


def _mults(z: list[list[float]] | None) -> str:
    if not z:
        return "—"
    parts, seen = [], set()
    for re_, im in z:
        if im < 0 and (re_, -im) in seen:
            continue
        seen.add((re_, im))
        parts.append(f"{re_:.4g}±{abs(im):.4g}i" if abs(im) > 1e-12 else f"{re_:.4g}")
    return ", ".join(parts)


def rows(record: dict[str, Any]) -> list[list[str]]:
    """The table: model | method | first call | once built | × vs baseline | errors | mults."""
    out = []
    for name, e in record["models"].items():
        base = e.get("baseline", {}).get("median_s")

        def speed(t: float | None, base: float | None = base) -> str:
            if base is None or t is None or not t > 0:
                return "—"
            return f"{base / t:.3g}×"

        for key, label in (
            ("verify_false", "gaitopt verify=False"),
            ("verify_true", "gaitopt verify=True"),
        ):
            first, built = e["first_call"][key], e["once_built"][key]
            out.append(
                [
                    name,
                    label,
                    _ms(first.get("median_s")),
                    _ms(built["median_s"]),
                    speed(built["median_s"]),
                    "(ref)",
                    _sci(e["gaitopt"].get("error_vs_reference")),
                    _mults(e["gaitopt"]["multipliers"]) if key == "verify_false" else "",
                ]
            )
        b = e.get("baseline", {})
        if "skipped" in b:
            out.append([name, "hand-written baseline", "—", "—", "—", "—", "—", b["skipped"]])
        elif b:
            out.append(
                [
                    name,
                    "solve_ivp + fsolve (by hand)",
                    "—",
                    _ms(b["median_s"]),
                    "1×",
                    _sci(b.get("error_vs_gaitopt")),
                    _sci(b.get("error_vs_reference")),
                    _mults(b["multipliers"]),
                ]
            )
        for label, r in e.get("drake", {}).get("runs", {}).items():
            unmet = ", not converged" if label.startswith("converge") else ", not settled"
            note = f"{r['steps']} steps" + ("" if r["settled"] else unmet)
            out.append(
                [
                    name,
                    f"Drake {label}, {note}",
                    "—",
                    _ms(r["median_s"]),
                    speed(r["median_s"]),
                    _sci(r.get("error_vs_gaitopt")),
                    _sci(r.get("error_vs_reference")),
                    "—",
                ]
            )
    return out


_HEAD = [
    "model",
    "method",
    "first call ms",
    "once built ms",
    "× vs baseline",
    "|Δx| vs gaitopt",
    "err vs reference",
    "multipliers",
]


def format_table(record: dict[str, Any]) -> str:
    """The printed report: table, legend and the compass-gait goals."""
    table = [_HEAD, *rows(record)]
    widths = [max(len(r[i]) for r in table) for i in range(len(_HEAD))]
    lines = []
    for i, r in enumerate(table):
        lines.append("  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip())
        if i == 0:
            lines.append("  ".join("-" * w for w in widths))
    m = record["machine"]
    rep = record["repeats"]
    imports = [
        run_["import_s"]
        for e in record["models"].values()
        for first in e["first_call"].values()
        for run_ in first["runs"]
    ]
    lines += [
        "",
        f"Machine: {m['platform']}, {m['cpu_count']} CPUs, Python {m['python']}; "
        + ", ".join(f"{k} {v}" for k, v in m["versions"].items() if v),
        f"first call: gaitopt.model() + find_limit_cycle() in a fresh process, median of "
        f"{rep['first_call_processes']} (`import gaitopt` excluded: median "
        f"{_ms(_median(imports))} ms); once built: median of "
        f"{rep['once_built_calls']} calls (verify=False: cycle + multipliers) and "
        f"{rep['once_built_calls_verify']} (verify=True: + SciPy simulation check).",
        f"× vs baseline = baseline time / row time. Baseline and Drake: median of "
        f"{rep['baseline_runs']} runs (Drake at accuracy 1e-10: up to 3; 'converge': 1).",
        "Drake: fresh System + Simulator simulated, with no monitor, from the start to the "
        "time the gait was seen to settle (consecutive post-impact states within 1e-5; "
        "'converge': 1e-10 or 100 steps); the run that watches it (a Python monitor per "
        "integrator step) is slower: JSON `median_s_with_monitor`.",
        "|Δx| = max-norm difference of the post-impact (section) state from gaitopt's; "
        "err vs reference: "
        + "; ".join(
            f"{n}: {e['reference']}" for n, e in record["models"].items() if e.get("reference")
        ),
    ]
    if record["drake"]["available"]:
        lines.append(f"pydrake import: {_ms(record['drake']['import_s'])} ms (not in the times).")
    else:
        lines.append(f"Drake peers skipped: {record['drake']['reason']}")
    g = record.get("goals") or {}
    if g:

        def verdict(ok: bool | None) -> str:
            return "n/a" if ok is None else ("met" if ok else "NOT met")

        lines += [
            "",
            "Compass-gait goals:",
            f"  cycle with multipliers once built ≤ 2 ms: "
            f"{_ms(g['cycle_with_multipliers_once_built_s'])} ms — {verdict(g['at_most_2ms'])}",
        ]
        if "speedup_vs_drake_default_settle" in g:
            lines.append(
                f"  ≥ 20× faster than Drake's settle-by-simulation (default accuracy, "
                f"{_ms(g['drake_default_settle_s'])} ms; "
                f"{_ms(g['drake_default_settle_with_monitor_s'])} ms watched by a monitor): "
                f"{g['speedup_vs_drake_default_settle']:.3g}× — "
                f"{verdict(g['at_least_20x_vs_drake'])}"
            )
        if "exact_to_1e-10" in g:
            lines.append(
                f"  exact to 1e-10: |Δx| vs Drake converged at accuracy 1e-10 "
                f"{_sci(g['error_vs_drake_converged_1e-10'])}, vs the hand-written baseline "
                f"{_sci(g.get('error_vs_baseline'))}; Drake at default accuracy leaves "
                f"{_sci(g.get('drake_default_settled_error'))} when settled, "
                f"{_sci(g.get('drake_default_error_floor'))} run to convergence — "
                f"{verdict(g['exact_to_1e-10'])}"
            )
    if "control" in record:
        lines += _control_lines(record["control"])
    if "branches" in record:
        b = record["branches"]
        lines += ["", _bench_branches.table(b) if "skipped" not in b else f"branches: {b}"]
    if "curves" in record:
        c = record["curves"]
        lines += ["", _bench_curves.table(c) if "skipped" not in c else f"curves: {c}"]
    if "optimize" in record:
        o = record["optimize"]
        lines += ["", _bench_optimize.table(o) if "skipped" not in o else f"optimize: {o}"]
    if "speed" in record and "skipped" in record["speed"]:
        lines += ["", f"speed: {record['speed']}"]
    if "first_call" in record:
        lines += ["", _bench_first_call.table(record["first_call"])]
    if "simulate" in record:
        simulate = record["simulate"]
        lines += ["", str(simulate) if "skipped" in simulate else _bench_simulate.table(simulate)]
    lines += ["", _bench_speed.table(record)]
    lines += ["", _bench_goals.table(record)]
    lines.append(f"Total benchmark time: {record['elapsed_s']:.0f} s.")
    return "\n".join(lines)
