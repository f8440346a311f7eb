"""``make gaits``: the gait of every registered model at its defaults, with its pictures.

Usage::

    python -m gaitopt.gaits --out results [--models rimless_wheel,compass_gait]

For each model (every entry of :data:`gaitopt.REGISTRY`, or those named): find the limit cycle
from the model's default start and write, under ``OUT/<model>/``,

* ``cycle.json`` — :meth:`LimitCycle.as_dict` (the object of ``gaitopt solve --json``), also
  when the search failed (``"success": false``, with the message); without ``solve_time``, so
  that rerunning leaves the tracked files unchanged (timings are measured by ``make bench``);
* ``phase_portrait.png`` — the orbit's phase portrait with a simulated transient from the
  model's default start;
* ``walking.gif`` — for models with a drawable geometry, ~4 simulated steps from the fixed point
  (``animation.gif`` for a scene without ground: the bouncing ball, the jugglers;
  :func:`gaitopt.animation.gif_name`);
* ``return_map.png`` — for 1-D sections, the staircase plot of the return map (the rimless
  wheel's closed-form map overlaid).

``cycle.json`` is stored to the digits the gait is certified to (:func:`certified_record`), so
that a rebuild elsewhere leaves the tracked files unchanged.  A GIF takes most of the run's time;
``animation.key`` beside it records what it was drawn from (the stored gait, the sources of the
model, the simulator and the drawing code, the matplotlib and Pillow versions), and a run whose
key matches keeps the GIF instead of drawing it again.

When the search fails only ``cycle.json`` is written (and figures of an earlier run removed).
An actuated-only model (``passive_gait`` False: the five-link biped) has no passive gait to
search for; it is skipped, with the reason, and does not count as a failure.

Each model's folder is written whole or not at all (:func:`gaitopt.files.folder_written_whole`):
its files go into a hidden ``OUT/.<model>.<random>.partial`` folder, which then replaces
``OUT/<model>/`` in one step.  Files that other tools keep there (the Strandbeest study's
``numbers.json`` and figures) are carried over; of the files named above, only those this run
wrote are kept.  So a run stopped with Ctrl-C leaves every model's folder either as the last
complete run left it or complete from this one (never a ``cycle.json`` without its figures),
prints ``gaitopt.gaits: interrupted`` and exits with status 130.  A summary table ends a
complete run.  Exit status: 0 when every model was solved and drawn, 1 when a model failed to
solve or a figure failed (the error is printed; the other models go on), 2 for bad arguments,
130 interrupted.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import re
import shutil
import sys
import time
import traceback
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .errors import GaitoptInputError
from .files import check_output_folder, folder_written_whole, write_json
from .hybrid import HybridModel
from .interrupts import caused_by_interrupt, interrupts_outside_casadi
from .models import REGISTRY
from .models import model as make_model
from .result import LimitCycle
from .shooting import find_limit_cycle
from .simulation import simulate

__all__ = ["main", "run_model", "return_map_interval"]

WALK_STEPS = 4  # simulated steps in walking.gif
TRANSIENT_STEPS = 8  # simulated steps overlaid on the phase portrait
FIGURES = ("phase_portrait.png", "return_map.png", "walking.gif", "animation.gif")
#: The key of the animation last drawn in a folder (see :func:`_animation_key`).
ANIMATION_KEY = "animation.key"
#: The entries of ``OUT/<model>/`` this runner owns: a run replaces them (the others stay).
OWNED = ("cycle.json", *FIGURES, ANIMATION_KEY)

#: Diagnostic fields stored as the power of ten above them (bounds, not run-to-run noise).
_DIAGNOSTICS = ("residual", "discretisation_error", "verification_error")
#: A diagnostic number in a message (``residual 3.9e-13``).
_SMALL_NUMBER = re.compile(r"(?<![\w.])(\d(?:\.\d+)?e-\d+)")


def _up_to_power_of_ten(value: float) -> float:
    """The power of ten at or above ``value`` > 0 (``3.9e-13`` → ``1e-12``)."""
    return float(f"1e{math.ceil(math.log10(value) - 1e-12)}")


def certified_record(record: dict) -> dict:
    """``cycle.json`` as stored by ``make gaits``: the numbers to the digits the gait is
    certified to, so that a rebuild on another machine (another BLAS, another compiler) writes
    the same file.

    The fixed point, period, durations and section coordinates are rounded at one digit below
    the certificate's accuracy ``e = max(discretisation error, residual)`` (e = 9e-12: to 1e-11);
    the multipliers, derivatives of the orbit, two digits coarser; the diagnostics themselves
    (residual, discretisation and verification errors, in the fields and in the message) are
    stored as the power of ten above them (``residual 3.9e-13`` → ``residual < 1e-12``).  A
    failed search is stored as it is.
    """
    if not record.get("success"):
        return record
    errors = [record.get(k) for k in ("discretisation_error", "residual")]
    accuracy = max([e for e in errors if isinstance(e, float) and math.isfinite(e)] + [1e-14])
    decimals = max(0, -math.floor(math.log10(accuracy)) - 1)

    def rounded(value, places):
        if isinstance(value, float) and math.isfinite(value):
            return round(value, places) + 0.0  # + 0.0: no "-0.0"
        if isinstance(value, dict):
            return {k: rounded(v, places) for k, v in value.items()}
        if isinstance(value, list):
            return [rounded(v, places) for v in value]
        return value

    out = dict(record)
    for key in ("period", "fixed_point", "durations", "inputs"):
        if key in out:
            out[key] = rounded(out[key], decimals)
    if "multipliers" in out:
        out["multipliers"] = rounded(out["multipliers"], max(0, decimals - 2))
    for key in _DIAGNOSTICS:
        value = out.get(key)
        if isinstance(value, float) and math.isfinite(value) and value > 0:
            out[key] = _up_to_power_of_ten(value)
    out["message"] = _SMALL_NUMBER.sub(
        lambda m: f"< {_up_to_power_of_ten(float(m.group(1))):g}", out.get("message", "")
    )
    return out


def _animation_key(model: HybridModel, record: dict) -> str:
    """What an animation is drawn from: the stored gait, the model's and the drawing code's
    sources and the library versions.  A folder whose ``animation.key`` matches keeps its GIF
    (drawing one takes most of ``make gaits``' time) instead of drawing it again."""
    import inspect

    import matplotlib
    import PIL

    from . import animation, simulation

    digest = hashlib.sha256(json.dumps(record, sort_keys=True).encode())
    sources = [
        Path(inspect.getfile(animation)),
        *sorted(Path(inspect.getfile(simulation)).parent.glob("*.py")),
        Path(inspect.getfile(type(model))),
    ]
    for source in sources:
        digest.update(source.read_bytes())
    digest.update(f"{matplotlib.__version__} {PIL.__version__}".encode())
    return digest.hexdigest()


def return_map_interval(cycle: LimitCycle) -> tuple[float, float]:
    """Interval of the staircase plot: the model's map domain if it states one, else from 0 to
    twice the fixed point's section coordinate."""
    domain = cycle.model.map_domain()
    if domain is not None:
        return domain
    s = float(cycle.section_point[0])
    if s == 0.0:
        return (-1.0, 1.0)
    return (min(0.0, 2 * s), max(0.0, 2 * s))


def _drawable(model: HybridModel) -> bool:
    return all(phase.points is not None for phase in model.phases)


def run_model(name: str, out: Path) -> tuple[LimitCycle, list[str], list[str]]:
    """Solve one model at its defaults and write its files under ``out/name``.

    The folder is written whole (:func:`gaitopt.files.folder_written_whole`): the files of
    :data:`OWNED` that this run writes replace the folder's, those it does not write (the
    figures of a failed search) are removed, the other files in the folder stay.  If anything
    raises before the end (Ctrl-C), ``out/name`` is left as it was.

    Returns
    -------
    cycle : LimitCycle
    written : list of str
        Files written.
    errors : list of str
        Figures that failed, each with its error (or the folder, if it could not be written).
    """
    model = make_model(name)
    cycle = find_limit_cycle(model)
    try:
        with folder_written_whole(out / name, replaces=OWNED) as folder:
            written, errors = _write_model(model, cycle, folder, previous=out / name)
    except OSError as exc:  # the solve is kept (its row in the summary); the folder as it was
        return cycle, [], [f"{out / name}: cannot write there ({exc}); nothing was written"]
    return cycle, written, errors


def _write_model(
    model: HybridModel, cycle: LimitCycle, folder: Path, previous: Path | None = None
) -> tuple[list[str], list[str]]:
    """``cycle.json`` and, for a gait found, its figures in ``folder``; returns the files
    written and the figures that failed.  ``previous``, the folder of the last run, lends its
    GIF where its :data:`ANIMATION_KEY` matches this run's."""
    from . import animation, plotting  # matplotlib only when drawing

    # No solve_time: a tracked result must not change from run to run (timings: `make bench`).
    record = certified_record(cycle.as_dict(timing=False))
    write_json(record, folder / "cycle.json")
    written, errors = ["cycle.json"], []
    if not cycle.success:  # no figures: those of an earlier run would contradict cycle.json
        return written, errors

    def attempt(filename: str, draw) -> None:
        try:
            draw(folder / filename)
            written.append(filename)
        except Exception as exc:  # a figure must not stop the run; it is reported
            if caused_by_interrupt(exc):
                raise
            errors.append(f"{filename}: {type(exc).__name__}: {exc}")
            traceback.print_exc(file=sys.stderr)

    def portrait(path: Path) -> None:
        transient = simulate(model, steps=TRANSIENT_STEPS, inputs=cycle.inputs)
        fig, _ = plotting.plot_phase_portrait(cycle, simulation=transient)
        plotting.save_figure(fig, path)

    def staircase(path: Path) -> None:
        lo, hi = return_map_interval(cycle)
        closed_form = model.closed_form_map if model.closed_form_map(lo) is not None else None
        # Where the model states its map's domain the staircase starts from its default start
        # (inside the domain); otherwise near the top of (0, 2 s*).
        start = None if model.map_domain() is not None else lo + 0.9 * (hi - lo)
        fig, _ = plotting.plot_return_map(model, (lo, hi), start=start, closed_form=closed_form)
        plotting.save_figure(fig, path)

    def walking(path: Path) -> None:
        key = _animation_key(model, record)
        old = previous / path.name if previous is not None else None
        old_key = previous / ANIMATION_KEY if previous is not None else None
        if old is not None and old.is_file() and old_key.is_file():
            if old_key.read_text(encoding="utf-8").strip() == key:
                shutil.copy2(old, path)  # the same gait drawn by the same code: kept
                (folder / ANIMATION_KEY).write_text(key + "\n", encoding="utf-8")
                return
        sim = simulate(model, cycle.x, steps=WALK_STEPS, inputs=cycle.inputs)
        if not sim.arcs:
            raise RuntimeError(f"simulation from the fixed point failed: {sim.message}")
        animation.animate_walker(model, sim, path)
        (folder / ANIMATION_KEY).write_text(key + "\n", encoding="utf-8")

    attempt("phase_portrait.png", portrait)
    if len(model.section.coordinates) == 1:
        attempt("return_map.png", staircase)
    if _drawable(model):
        attempt(animation.gif_name(model), walking)
        if (folder / ANIMATION_KEY).is_file():
            written.append(ANIMATION_KEY)
    return written, errors


def _fmt(value: float, spec: str) -> str:
    return "—" if value is None or not math.isfinite(value) else format(value, spec)


def _summary(rows: list[tuple[str, LimitCycle | str | None]]) -> str:
    header = ("model", "period", "max |mult|", "stable", "verified", "solve (ms)")
    lines = [header]
    for name, c in rows:
        if isinstance(c, str):  # skipped, with the reason
            lines.append((name, "skipped", "—", "—", "—", "—"))
            continue
        if c is None:
            lines.append((name, "error", "—", "—", "—", "—"))
            continue
        mods = np.abs(c.multipliers)
        lines.append(
            (
                name,
                _fmt(c.period, ".10g") if c.success else "failed",
                _fmt(float(mods.max()) if mods.size else float("nan"), ".4g"),
                "—" if c.stable is None else str(c.stable),
                str(bool(c.verified)),
                _fmt(1e3 * c.solve_time, ".1f"),
            )
        )
    widths = [max(len(row[i]) for row in lines) for i in range(len(header))]
    text = [
        "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip()
        for row in lines
    ]
    text.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(text)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``python -m gaitopt.gaits``; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m gaitopt.gaits",
        description="Find the gait of every model at its defaults; write JSON, PNG and GIF files.",
    )
    parser.add_argument("--out", default="results", help="output directory (default: results)")
    parser.add_argument(
        "--models",
        default=None,
        help=f"comma-separated model names (default: all of {', '.join(REGISTRY)})",
    )
    args = parser.parse_args(argv)
    try:
        with interrupts_outside_casadi():  # else CasADi may turn Ctrl-C into another error
            return _run(args)
    except BaseException as exc:
        if not caused_by_interrupt(exc):
            raise
    # Ctrl-C: every folder is as the last complete write left it.
    sys.stdout.flush()
    print("gaitopt.gaits: interrupted", file=sys.stderr, flush=True)
    return 130


def _run(args: argparse.Namespace) -> int:
    """:func:`main` after its arguments are parsed (and without its handling of Ctrl-C)."""
    names = (
        list(REGISTRY)
        if args.models is None
        else [n.strip() for n in args.models.split(",") if n.strip()]
    )
    try:
        if not names:
            raise GaitoptInputError(f"`--models` names no model, got {args.models!r}")
        for name in names:
            make_model(name)  # unknown names fail here, before any work
    except GaitoptInputError as exc:
        print(f"gaitopt.gaits: error: {exc}", file=sys.stderr)
        return 2
    try:
        check_output_folder(args.out)  # an unusable --out fails now, not after the solves
    except GaitoptInputError as exc:
        print(f"gaitopt.gaits: error: --out {args.out}: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out)

    rows: list[tuple[str, LimitCycle | str | None]] = []
    failed = False
    for k, name in enumerate(names, 1):
        if not REGISTRY[name].passive_gait:
            reason = make_model(name).existence_note() or "no passive gait"
            print(f"[{k}/{len(names)}] {name}: skipped (actuated-only: {reason})", flush=True)
            rows.append((name, reason))
            continue
        print(f"[{k}/{len(names)}] {name}: solving ...", flush=True)
        start = time.perf_counter()
        try:
            cycle, written, errors = run_model(name, out)
        except Exception as exc:
            if caused_by_interrupt(exc):
                raise
            traceback.print_exc(file=sys.stderr)
            print(f"[{k}/{len(names)}] {name}: ERROR {type(exc).__name__}: {exc}", flush=True)
            rows.append((name, None))
            failed = True
            continue
        rows.append((name, cycle))
        status = "solved" if cycle.success else f"NOT SOLVED ({cycle.message})"
        print(
            f"[{k}/{len(names)}] {name}: {status}; wrote {', '.join(written)} "
            f"to {out / name} in {time.perf_counter() - start:.1f} s",
            flush=True,
        )
        for error in errors:
            print(f"[{k}/{len(names)}] {name}: FAILED {error}", flush=True)
        failed |= not cycle.success or bool(errors)
    print()
    print(_summary(rows))
    return 1 if failed else 0


if __name__ == "__main__":
    _status = main()
    if _status == 130:
        # Interrupted, and every folder already as its last complete write left it: a second
        # Ctrl-C while the interpreter shuts down (Python then puts SIGINT back to its default
        # action) would end the process by the signal, status -2 instead of 130.
        import signal

        signal.signal(signal.SIGINT, signal.SIG_IGN)
    sys.exit(_status)
