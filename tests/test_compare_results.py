"""The drift check behind ``make studies-check`` (scripts/compare_results.py): it must see a number
that moved by more than 1e-8 relative, a flag that flipped, a field or a row that went missing,
and must let through what is exempt by its documented rules (times; finite-difference estimates
to 1e-3; fields new in the fresh run)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "compare_results.py"
spec = importlib.util.spec_from_file_location("compare_results", SCRIPT)
compare_results = importlib.util.module_from_spec(spec)
spec.loader.exec_module(compare_results)


def _write(root: Path, study: str, name: str, text: str) -> None:
    (root / study).mkdir(parents=True, exist_ok=True)
    (root / study / name).write_text(text, encoding="utf-8")


def _run(tmp_path: Path, fresh: dict, committed: dict, csv_pair=None) -> int:
    _write(tmp_path / "fresh", "s", "a.json", json.dumps(fresh))
    _write(tmp_path / "results", "s", "a.json", json.dumps(committed))
    if csv_pair:
        _write(tmp_path / "fresh", "s", "t.csv", csv_pair[0])
        _write(tmp_path / "results", "s", "t.csv", csv_pair[1])
    argv = [str(tmp_path / "fresh"), "--results", str(tmp_path / "results")]
    return compare_results.main(argv)


def test_identical_and_exempt_changes_are_not_drift(tmp_path, capsys):
    committed = {"cost": 6.668848535, "time_s": 3.0, "multipliers_fd": [0.5], "ok": True}
    fresh = {"cost": 6.668848535 * (1 + 5e-9), "time_s": 9.0, "multipliers_fd": [0.5001],
             "ok": True, "new_field": 1.0}  # fmt: skip
    assert _run(tmp_path, fresh, committed) == 0
    assert "1 new fields" in capsys.readouterr().out


def test_a_moved_number_a_flipped_flag_and_a_lost_field_are_drift(tmp_path, capsys):
    committed = {"cost": 1.0, "certified": False, "rows": [{"a": 1.0}], "gone": 2.0}
    assert _run(tmp_path, {**committed, "cost": 1.0 + 2e-8}, committed) == 1
    assert _run(tmp_path, {**committed, "certified": True}, committed) == 1
    assert _run(tmp_path, {k: v for k, v in committed.items() if k != "gone"}, committed) == 1
    assert _run(tmp_path, {**committed, "rows": []}, committed) == 1
    assert "DRIFT" in capsys.readouterr().out


def test_csv_cells_compared_by_column(tmp_path):
    same = {"x": 1.0}
    ok = ("speed,cot,message\n1.0,0.25,found\n", "speed,cot,message\n1.0,0.25,other words\n")
    assert _run(tmp_path, same, same, ok) == 0
    moved = ("speed,cot\n1.0,0.2500001\n", "speed,cot\n1.0,0.25\n")
    assert _run(tmp_path, same, same, moved) == 1
    filled = ("speed,cot\n1.0,0.25\n", "speed,cot\n1.0,\n")  # a failed row now certified
    assert _run(tmp_path, same, same, filled) == 1


def test_a_physical_duration_is_compared_and_a_work_time_is_not(tmp_path):
    # A gait's step time or period is a number of the gait (1e-8 like any other); the time a
    # solve or a continuation took (time_s, continuation_s, a "timing_s" block) measures the
    # machine.
    committed = {"step_time_s": 0.7344606213, "period_s": 1.5, "time_s": 1.0,
                 "continuation_s": 2.0, "timing_s": {"sweep": 3.0}}  # fmt: skip
    moved = {**committed, "time_s": 5.0, "continuation_s": 0.1, "timing_s": {"sweep": 0.2}}
    assert _run(tmp_path, moved, committed) == 0
    assert _run(tmp_path, {**committed, "step_time_s": 0.7344606213 * (1 + 1e-7)}, committed) == 1
    assert _run(tmp_path, {**committed, "period_s": 1.5 * (1 + 1e-7)}, committed) == 1
