"""The kneed walker's least cost of transport with hip and knee torques
(problems/optimal_kneed_knee.py, issue 24 item 5a): the fast mode, and the README table against
the committed study output."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
from helpers import load_study, rows_by_speed

ROOT = Path(__file__).resolve().parents[1]


def _committed() -> dict[float, dict[str, str]]:
    return rows_by_speed(ROOT / "results" / "optimal_kneed_knee" / "knee.csv")


@pytest.mark.slow
def test_fast_mode_certifies_the_knee_powered_optimum(tmp_path):
    # The certificate (dense checks, the positive work between the nodes, the independent
    # simulation with both torques as feedforward, discretisation error ≤ 1e-8); then two
    # checks the study makes against independent numbers: the passive-knee optimum of the same
    # statement (feasible here, so the knee-powered cost must be no higher, to 1e-8) and the
    # work–energy balance on the simulated orbit (impact losses + negative work = positive
    # work, to 1e-8 relative; 5e-13 measured).  The same statement from the same start as the
    # full run, so the same cost as the committed row, to the 1e-8 target.  About 2 min on the
    # loaded 2-core machine: slow.
    study = load_study("optimal_kneed_knee")
    assert study.main(["--out", str(tmp_path), "--fast"]) == 0
    with open(tmp_path / "optimal_kneed_knee" / "knee.csv", encoding="utf-8") as f:
        (row,) = list(csv.DictReader(f))
    assert round(float(row["speed_m_per_s"]), 2) == 0.84
    assert row["success"] == "True", row["message"]
    assert float(row["discretisation_error"]) <= 1e-8
    assert float(row["energy_balance_gap"]) <= 1e-8
    assert row["at_most_passive"] == "True"
    assert float(row["cost_of_transport"]) < float(row["cot_passive_knee"])
    assert row["boundary_arcs"].startswith("knee_torque holds the 'knee strike' guard on [0, ")
    assert "clearance margin" in row["touch_points"]
    committed = _committed()[0.84]
    assert float(row["cost_of_transport"]) == pytest.approx(
        float(committed["cost_of_transport"]), rel=1e-8
    )


def test_readme_table_is_the_committed_study_output():
    # Every row of the README's table is results/optimal_kneed_knee/knee.csv (written by the
    # full run) rounded to the digits the README prints; a failed speed says so in both.
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    header = "| speed v (m/s) | least cost of transport, hip and knee (1)"
    table = readme[readme.index(header) :].split("\n\n", 1)[0]
    rows = [
        [c.strip() for c in line.strip("|").split("|")]
        for line in table.splitlines()[2:]
        if line.startswith("|")
    ]
    committed = _committed()
    assert len(rows) == len(committed)
    for speed, cot, passive, error, gap, held, touch, mu in rows:
        row = committed[round(float(speed), 2)]
        if cot.startswith("—"):
            assert row["success"] != "True"
            continue
        assert row["success"] == "True"
        assert row["at_most_passive"] == "True"
        assert float(cot) == float(f"{float(row['cost_of_transport']):.10g}")
        assert float(passive) == float(f"{float(row['cot_passive_knee']):.10g}")
        assert float(error) == float(f"{float(row['discretisation_error']):.1e}")
        assert float(gap) == float(f"{float(row['energy_balance_gap']):.1e}")
        end = row["boundary_arcs"].split(", ")[1].split("]")[0]
        assert held == f"0–{float(end):.4f}"
        assert float(touch) == round(float(row["touch_points"].split(" at ")[1].split()[0]), 4)
        assert float(mu) == round(float(row["max_abs_multiplier"]), 2)
