"""Compare a fresh run of studies against the committed ``results/``: every number to 1e-8.

``make studies-check`` runs the studies into a scratch folder and then this script, which reads
every JSON and CSV file a study wrote there and compares it with the file of the same name under
``results/``.  A number differs when ``|new − old| > rtol · |old| + atol`` (``atol`` 1e-12: a
relative test for every number a study prints, an absolute one only at rounding level); a flag
or word that differs, a list that changed length, or a field that disappeared is a difference
too.  Fields
new in the fresh run are listed but are not drift (the committed file predates them).

Exempt from the 1e-8 rule, because they are not reproducible to it by design:

* times and counts of work (``time_s``, ``seconds``, ``wall``, ``cpu``, ``timing``,
  ``iterations``, ``continuation_s``, …: :func:`_is_machine`): they measure the machine, not the
  gait (a physical duration such as ``step_time_s`` or ``period_s`` is compared);
* finite-difference estimates (fields named ``*_fd*``): their own accuracy is ~1e-6 … 1e-4
  (step-size noise), so they are compared to ``--fd-rtol`` (default 1e-3) instead;
* error sizes (fields named ``*error*``, ``*residual*``, ``*gap*``, ``*difference*``): a
  discretisation-error estimate, a return error or two methods' difference is the size of a
  rounding-level quantity, reproduced when it stays within a factor of 10 (or both are below
  ``atol``);
* numbers within 1e-6 of zero (a constraint's value at its touch point, a residual): compared
  absolutely, to 1e-9.

Exit status 0 when nothing drifted, 1 otherwise (2 for bad arguments).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from pathlib import Path

MACHINE_FIELDS = (
    "seconds",
    "elapsed",
    "wall",
    "cpu",
    "timing",
    "runtime",
    "iterations",
    "nfev",
    "commit",
    "date",
    "version",
    "load",
    "speedup",
)

#: Keys that time a piece of work (``time_s``: a solve's; ``continuation_s``, ``trials_s``, …):
#: a key ``<work>_s`` or ``<work>_time`` with ``<work>`` one of these, or ``time``/``time_s``
#: itself.  A physical duration (``step_time_s``, ``period_s``, ``touchdown_time_s``) is a
#: number of the gait and is compared like any other.
WORK = (
    "time", "solve", "total", "total_cpu", "continuation", "trials", "transverse_lqr", "build",
    "brute_force",
    "compile", "study", "sweep", "grid", "curve", "fraction", "slice", "rays", "map", "guesses",
)  # fmt: skip


def _is_machine(key: str) -> bool:
    key = key.lower()
    if any(word in key for word in MACHINE_FIELDS):
        return True
    for suffix in ("_s", "_time"):
        if key.endswith(suffix) and key[: -len(suffix)] in WORK:
            return True
    if "_over_" in key and key.endswith("time"):  # a ratio of two times (loop_over_batch_time)
        return True
    return key == "time"


def _is_fd(key: str) -> bool:
    return "_fd" in key.lower() or key.lower().startswith("fd_")


def _number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


ATOL = 1e-12  # absolute part of the test: rounding level (set by --atol)


NEAR_ZERO = 1e-6  # |old| below this: a residual-level number, compared absolutely
NEAR_ZERO_ATOL = 1e-9


def _is_error_size(key: str) -> bool:
    key = key.lower()
    return any(word in key for word in ("error", "residual", "gap", "difference"))


def _close(new: float, old: float, rtol: float, error_size: bool = False) -> bool:
    if math.isnan(new) and math.isnan(old):
        return True
    if math.isinf(new) or math.isinf(old):
        return new == old
    if error_size:
        if abs(new) <= ATOL and abs(old) <= ATOL:
            return True
        return abs(old) > 0 and 0.1 <= abs(new) / abs(old) <= 10.0
    if abs(old) < NEAR_ZERO:
        return abs(new - old) <= NEAR_ZERO_ATOL
    return abs(new - old) <= rtol * abs(old) + ATOL


def compare_json(
    new, old, path: str, rtol: float, fd_rtol: float, found: list, added: list, size=False
):
    """Walk two JSON values side by side; append ``(path, new, old)`` for each difference."""
    if isinstance(new, dict) and isinstance(old, dict):
        for key in sorted(set(new) | set(old)):
            where = f"{path}/{key}"
            if _is_machine(key):
                continue
            if key not in old:
                added.append(where)
            elif key not in new:
                found.append((where, "<missing>", old[key]))
            else:
                tol = fd_rtol if _is_fd(key) else rtol
                flag = size or _is_error_size(key)
                compare_json(new[key], old[key], where, tol, fd_rtol, found, added, flag)
    elif isinstance(new, list) and isinstance(old, list):
        if len(new) != len(old):
            found.append((path, f"{len(new)} items", f"{len(old)} items"))
            return
        for index, (a, b) in enumerate(zip(new, old, strict=True)):
            compare_json(a, b, f"{path}[{index}]", rtol, fd_rtol, found, added, size)
    elif isinstance(new, bool) or isinstance(old, bool) or new is None or old is None:
        if new != old:
            found.append((path, new, old))
    elif isinstance(new, (int, float)) and isinstance(old, (int, float)):
        if not _close(float(new), float(old), rtol, size):
            found.append((path, new, old))
    elif new != old and not (isinstance(new, str) and isinstance(old, str)):
        found.append((path, new, old))
    elif isinstance(new, str) and new != old and path.endswith(("status", "success")):
        found.append((path, new, old))


def compare_csv(new: Path, old: Path, rtol: float, fd_rtol: float, found: list, added: list):
    """Numeric cells to ``rtol`` by column name; other cells are free text (messages)."""
    with new.open(encoding="utf-8", newline="") as a, old.open(encoding="utf-8", newline="") as b:
        rows_new, rows_old = list(csv.reader(a)), list(csv.reader(b))
    if not rows_new or not rows_old:
        if bool(rows_new) != bool(rows_old):
            found.append(
                ("", "empty" if not rows_new else "rows", "empty" if not rows_old else "rows")
            )
        return
    head_new, head_old = rows_new[0], rows_old[0]
    added.extend(f"column {name}" for name in head_new if name not in head_old)
    found.extend((f"column {name}", "<missing>", "") for name in head_old if name not in head_new)
    if len(rows_new) != len(rows_old):
        found.append(("rows", len(rows_new) - 1, len(rows_old) - 1))
        return
    for number, (row_new, row_old) in enumerate(
        zip(rows_new[1:], rows_old[1:], strict=True), start=1
    ):
        cells_new = dict(zip(head_new, row_new, strict=False))
        for name, cell_old in zip(head_old, row_old, strict=False):
            if name not in cells_new or _is_machine(name):
                continue
            cell_new = cells_new[name]
            a, b = _number(cell_new), _number(cell_old)
            if a is None or b is None:
                if (a is None) != (b is None) or cell_new.lower() in ("true", "false"):
                    if cell_new != cell_old:
                        found.append((f"row {number} {name}", cell_new, cell_old))
                continue
            if not _close(a, b, fd_rtol if _is_fd(name) else rtol, _is_error_size(name)):
                found.append((f"row {number} {name}", a, b))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fresh", type=Path, help="folder the studies just wrote (study/…)")
    parser.add_argument("--results", type=Path, default=Path("results"), help="committed results")
    parser.add_argument("--rtol", type=float, default=1e-8, help="relative tolerance (1e-8)")
    parser.add_argument("--atol", type=float, default=1e-12, help="absolute part (1e-12)")
    parser.add_argument("--fd-rtol", type=float, default=1e-3, help="for *_fd* fields (1e-3)")
    parser.add_argument("--show", type=int, default=12, help="differences shown per file")
    args = parser.parse_args(argv)
    global ATOL
    ATOL = args.atol
    if not args.fresh.is_dir():
        print(f"compare_results: fresh={str(args.fresh)!r} is not a folder; run the studies "
              "into it first (make studies-check does)", file=sys.stderr)  # fmt: skip
        return 2
    drifted = 0
    files = sorted(p for p in args.fresh.rglob("*") if p.suffix in (".json", ".csv"))
    for path in files:
        relative = path.relative_to(args.fresh)
        old = args.results / relative
        if not old.exists():
            print(f"new     {relative} (no committed file to compare with)")
            continue
        found: list = []
        added: list = []
        if path.suffix == ".json":
            new_data = json.loads(path.read_text(encoding="utf-8"))
            old_data = json.loads(old.read_text(encoding="utf-8"))
            compare_json(new_data, old_data, "", args.rtol, args.fd_rtol, found, added)
        else:
            compare_csv(path, old, args.rtol, args.fd_rtol, found, added)
        state = "DRIFT  " if found else "same   "
        extra = f" ({len(added)} new fields)" if added else ""
        print(f"{state} {relative}: {len(found)} differences{extra}")
        for where, new, old_value in found[: args.show]:
            print(f"          {where}: now {new!r}, committed {old_value!r}")
        drifted += bool(found)
    print(f"{len(files)} files compared, {drifted} drifted (rtol {args.rtol:g})")
    return 1 if drifted else 0


if __name__ == "__main__":
    sys.exit(main())
