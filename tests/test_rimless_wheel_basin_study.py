"""problems/rimless_wheel_basin.py --fast: its grids in basin.npz are the CSVs' rows (exact), and
the simulated fates agree with the closed-form ones (Tedrake's three-branch map) at every
simulated point."""

from __future__ import annotations

import csv

import numpy as np

from tests.helpers import run_study


def test_basin_npz_holds_the_csv_grids(tmp_path):
    folder = run_study("rimless_wheel_basin", tmp_path)
    with np.load(folder / "basin.npz") as data:
        col = {k: data[k] for k in data.files}
    with open(folder / "section_basin.csv", newline="") as fh:
        section = list(csv.DictReader(fh))
    assert [float(r["theta_dot"]) for r in section] == col["section_theta_dot"].tolist()
    assert [int(r["fate_simulated"]) for r in section] == col["section_fate_simulated"].tolist()
    np.testing.assert_array_equal(col["section_fate_simulated"], col["section_fate_closed_form"])
    with open(folder / "plane_basin.csv", newline="") as fh:
        plane = list(csv.DictReader(fh))
    fates = col["plane_fate_simulated"]  # rows by θ̇, columns by θ, as the CSV's order
    assert fates.shape == (col["plane_theta_dot"].size, col["plane_theta"].size)
    assert [int(r["fate_simulated"]) for r in plane] == fates.ravel().tolist()
    assert [float(r["theta"]) for r in plane[: fates.shape[1]]] == col["plane_theta"].tolist()
    np.testing.assert_array_equal(fates, col["plane_fate_closed_form"])
    assert col["closed_form_fate"].size == col["closed_form_theta_dot"].size
