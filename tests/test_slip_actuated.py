"""The SLIP with a leg actuator (gaitopt/models/slip_actuated.py): its contract, its exact
reduction to the SLIP with no actuator force, the actuator's power against the energy change, and
bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import load_study

import gaitopt
from gaitopt import testing
from gaitopt.errors import ParameterError
from gaitopt.models.slip_actuated import SLIP_STRIDE, SlipActuated

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"


def test_slip_actuated_keeps_the_model_contract():
    # The public contract suite, including its passive gait (F ≡ 0) found and verified.
    report = testing.check_model(SlipActuated)
    assert report["gait"] is not None and report["gait"].success


@pytest.mark.parametrize(("angle", "apex"), [(np.pi / 6, 0.87), (0.5, 1.0)])
def test_passive_gait_is_the_slip_gait(angle, apex):
    # Exact reduction (module docstring): with F ≡ 0 the stance is the SLIP's (Tedrake's stance
    # equations) and the flight ballistic, so the gait whose foothold is the SLIP gait's stride
    # is the SLIP gait seen from its touchdown.  Two independent shooting problems (three
    # phases from the apex in gaitopt.models.slip; two from touchdown here), each solved to a
    # residual ≤ 1e-11; tolerance 1e-10 (the issue's) on the touchdown state and the period.
    slip = gaitopt.find_limit_cycle(gaitopt.model("slip", touchdown_angle=angle), {"z": apex})
    assert slip.success and slip.verified, slip.message
    descent, stance, ascent = (np.asarray(a.x) for a in slip.orbit)
    # stride: apex → touchdown, the hip's travel over the foot in stance, lift-off → apex
    stride = descent[0, -1] + np.sin(-stance[1, 0]) + np.sin(stance[1, -1]) + (
        ascent[0, -1] - ascent[0, 0]
    )  # fmt: skip
    model = gaitopt.model("slip_actuated", step_length=float(stride))
    start = {"theta": float(stance[1, 0]), "r_dot": float(stance[2, 0]) + 1e-3}
    gait = gaitopt.find_limit_cycle(model, start)
    assert gait.success and gait.verified, gait.message
    assert gait.residual <= 1e-11 and slip.residual <= 1e-11
    for name, k in (("r", 0), ("theta", 1), ("r_dot", 2), ("theta_dot", 3)):
        assert gait.fixed_point[name] == pytest.approx(float(stance[k, 0]), abs=1e-10)
    assert gait.period == pytest.approx(slip.period, abs=1e-10)
    if angle == np.pi / 6:  # the model's default stride is this gait's (to the digits stored)
        assert SLIP_STRIDE == pytest.approx(stride, abs=1e-12)


def test_actuator_power_is_the_energy_rate():
    # Work–energy theorem: along the stance flow with a constant force F the stance energy
    # E = ½ m |v|² + m g z + ½ k (l0 − r)² changes at the rate F ṙ (input_rates).  Independent:
    # finite difference of E along the flow (central, step 1e-6 s; error O(h²) ≈ 1e-8 W, tolerance
    # 1e-5 W against powers of ~100 W).
    model = gaitopt.model("slip_actuated")
    phase = model.phases[0]
    x = np.array([0.93, -0.2, -1.1, 3.2])
    force = np.array([150.0])
    f = np.asarray(phase.flow(x, force, model.p), dtype=float).ravel()
    energy = phase.conserved["energy"]
    h = 1e-6
    rate = (float(energy(x + h * f, model.p)) - float(energy(x - h * f, model.p))) / (2 * h)
    power = float(model.input_rates(0)(x, model.p)) * force[0]
    assert rate == pytest.approx(power, abs=1e-5)
    assert float(model.input_rates(1)(x, model.p)) == 0.0  # no actuator work in flight


def test_slip_actuated_bad_input_is_one_line():
    with pytest.raises(ParameterError, match="energy"):
        gaitopt.model("slip_actuated", energy=100.0)  # E/(m g) = 0.13 m: cannot run


def test_slip_running_optima_fast_mode(tmp_path):
    # Fast mode (~5 s): the passive SLIP's own speed, energy and stride.  The least-effort
    # optimum there is the passive SLIP gait (F ≡ 0 is feasible, so the least effort is 0):
    # touchdown angle 30° (Tedrake's θ_td, the model's default stride) to 1e-8 deg (the shooting
    # gait's 1e-10 rad, through the collocation's discretisation error ≤ 1e-8), no force above
    # 1e-6 N, and its cost of transport, from the independent simulation's work, 0 to 1e-12.
    # The positive-work statement, whose zero-cost optima are not isolated (a held leg does no
    # work), is recorded certified or with a reason, never as an uncertified cost.
    study = load_study("slip_running_optima")
    assert study.main(["--fast", "--out", str(tmp_path)]) == 0
    folder = tmp_path / "slip_running_optima"
    data = json.loads((folder / "optima.json").read_text(encoding="utf-8"))
    rows = {r["cost"]: r for r in data["rows"]}
    effort = rows["effort"]
    assert effort["certified"] and effort["speed_m_s"] == study.V_PASSIVE
    assert effort["touchdown_angle_deg"] == pytest.approx(30.0, abs=1e-8)
    assert effort["peak_force_N"] < 1e-6
    assert abs(effort["cot_simulated"]) < 1e-12
    assert abs(effort["energy_residual_J"]) < 1e-9  # work–energy balance of the orbit
    cot = rows["cot"]
    assert cot["certified"] == (cot["optimal_cost"] is not None)
    assert cot["certified"] or cot["failures"]
    if cot["certified"]:
        assert cot["optimal_cost"] < 1e-9  # the passive gait is free
    assert (folder / "optima.png").exists() and (folder / "optima.csv").exists()


def test_readme_slip_optima_table_is_the_committed_study_output():
    # Every certified row of results/slip_running_optima/optima.csv (written by
    # problems/slip_running_optima.py) appears in the README's table with its touchdown angle, and
    # the table quotes no other row; the angles to the digits printed (1e-4 deg, 1e-9 deg).
    import csv

    path = PROBLEMS.parent / "results" / "slip_running_optima" / "optima.csv"
    with open(path, encoding="utf-8") as f:
        rows = [r for r in csv.DictReader(f) if r["certified"] == "True"]
    readme = (PROBLEMS.parent / "README.md").read_text(encoding="utf-8")
    start = readme.index("| cost | speed (m/s) | optimum | touchdown angle (deg)")
    table = []
    for line in readme[start:].splitlines()[2:]:
        if not line.startswith("|"):
            break
        table.append([c.strip() for c in line.strip("|").split("|")])
    assert len(table) == len(rows)
    for row in rows:
        speed = float(row["speed_m_s"])
        match = [c for c in table if c[0] == row["cost"] and abs(float(c[1]) - speed) < 1e-5]
        assert len(match) == 1, (row["cost"], speed)
        assert float(match[0][3]) == pytest.approx(float(row["touchdown_angle_deg"]), abs=1e-4)
