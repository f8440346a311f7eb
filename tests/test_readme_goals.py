"""The README's goals table says what the last ``make bench`` measured.

``make bench`` writes every goal of issue 23 with its measured ratio into ``results/bench.json``
(``goals_issue_23``, :mod:`bench.goals`); the README quotes them in the table after "Every goal in
one table".  Each row of that table must begin with the bench's headline figure (the measured
value up to its first space, e.g. ``19.3×`` or ``4.65 ms``) and carry its verdict, in the bench's
order, so a new bench run that is not carried into the README (or a README edit that no bench
run measured) fails here.  Exact string comparison: the README copies the bench's rounding.
"""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _readme_rows() -> list[list[str]]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    start = text.index("**Every goal in one table.**")
    lines = text[start:].splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("| goal |"))
    rows = []
    for line in lines[first + 2 :]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip().strip("|").split("|")])
    return rows


def test_readme_goals_table_is_the_last_bench_run():
    goals = json.loads((ROOT / "results" / "bench.json").read_text(encoding="utf-8"))
    goals = goals["goals_issue_23"]
    rows = _readme_rows()
    assert len(rows) == len(goals), "README goals table and results/bench.json differ in rows"
    for row, goal in zip(rows, goals, strict=True):
        headline = goal["measured"].split(" ")[0]
        assert row[1].startswith(headline), (goal["goal"], row[1], goal["measured"])
        assert row[-1] == ("yes" if goal["met"] else "no"), (goal["goal"], row[-1])
