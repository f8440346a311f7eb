"""The kneed walker on level ground, hip torque and push-off, across speeds
(problems/optimal_kneed_level.py): the fast mode, and the README table against the committed
study output."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
from helpers import load_study, rows_by_speed

ROOT = Path(__file__).resolve().parents[1]


def _committed() -> dict[float, dict[str, str]]:
    return rows_by_speed(ROOT / "results" / "optimal_kneed_level" / "level.csv")


@pytest.mark.slow
def test_fast_mode_certifies_and_is_no_lower_than_the_full_library(tmp_path):
    # Each reported point is certified by the optimiser's certificate (dense checks, the
    # positive work between the nodes, simulation with the torque and push-off as feedforward,
    # discretisation error ≤ 1e-8) and its heel strike presses the new foot into the ground.
    # The full run keeps the lowest certified attempt of more starts (cold starts and chains
    # over more speeds), so a fast-mode optimum may be no lower than the committed one at the
    # same speed (beyond 1e-8 relative, the certificate's target): a lower one would mean the
    # full library missed a minimum.  Several minutes on the loaded 2-core machine: slow.
    study = load_study("optimal_kneed_level")
    assert study.main(["--out", str(tmp_path), "--fast"]) == 0
    with open(tmp_path / "optimal_kneed_level" / "level.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    committed = _committed()
    assert [round(float(r["speed_m_per_s"]), 2) for r in rows] == [0.8, 0.9]
    certified = [r for r in rows if r["verified"] == "True"]
    assert certified
    for r in certified:
        assert float(r["discretisation_error"]) <= 1e-8
        assert float(r["heel_strike_impulse_N_s"]) > 0
        full = committed[round(float(r["speed_m_per_s"]), 2)]
        if full["verified"] == "True":
            assert float(r["cost_of_transport"]) >= float(full["cost_of_transport"]) * (1 - 1e-8)


def test_readme_table_is_the_committed_study_output():
    # Every row of the README's level-ground table is results/optimal_kneed_level/level.csv
    # (written by the full run) rounded to the digits the README prints.
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    header = "| speed v (m/s) | step length L (m) | period T (s) | least cost of transport"
    table = readme[readme.index(header) :].split("\n\n", 1)[0]
    rows = [
        [c.strip() for c in line.strip("|").split("|")]
        for line in table.splitlines()[2:]
        if line.startswith("|")
    ]
    committed = _committed()
    assert len(rows) == len(committed)
    for speed, step, period, cot, push, mu, verified, error in rows:
        row = committed[round(float(speed), 2)]
        if verified != "yes":
            assert row["verified"] != "True"
            continue
        assert row["verified"] == "True"
        assert float(step) == round(float(row["step_length_m"]), 5)
        assert float(period) == round(float(row["period_s"]), 5)
        assert float(cot) == float(f"{float(row['cost_of_transport']):.10g}")
        assert float(push) == round(float(row["push_off_N_s"]), 5)
        assert float(mu) == round(float(row["max_abs_multiplier"]), 3)
        assert float(error) == float(f"{float(row['discretisation_error']):.1e}")
