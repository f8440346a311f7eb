"""The minimal biped (Srinivasan & Ruina 2006): its contract, its transitions against closed
forms, bad input, and a certified walking optimum whose simulated orbit balances its work and
energy (gaitopt/models/minimal_biped.py, problems/walk_run_cot.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import load_study

import gaitopt
from gaitopt import testing
from gaitopt.errors import GaitoptInputError, ParameterError
from gaitopt.models.minimal_biped import MinimalBipedRun, MinimalBipedWalk

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"


@pytest.mark.parametrize("cls", [MinimalBipedWalk, MinimalBipedRun])
def test_minimal_biped_keeps_the_model_contract(cls):
    # The public contract suite (structure, units, bad parameters); no passive gait to check.
    report = testing.check_model(cls)
    assert report["gait"] is None and not cls.passive_gait


def _cartesian(x):
    """Hip position and velocity about the stance foot from the polar stance state."""
    r, th, rd, thd = x
    pos = r * np.array([np.sin(th), np.cos(th)])
    vel = rd * np.array([np.sin(th), np.cos(th)]) + r * thd * np.array([np.cos(th), -np.sin(th)])
    return pos, vel


def test_heel_strike_is_a_plastic_impulse_along_the_new_leg():
    # Independent of the model's closed form: the hip's velocity after the heel strike is its
    # velocity before minus its component along the new leg (foot at x = d), computed here by
    # vector projection; the angular momentum about the new foot is then unchanged (the impulse
    # passes through it; Goswami et al. 1996).  Tolerance 1e-12 (rounding).
    model = gaitopt.model("minimal_biped_walk", step_length=0.7)
    d = model.step_length
    th = np.arcsin(d / (2 * 0.95))
    x_minus = np.array([0.95, th, 0.3, 1.4])  # on the guard 2 r sin θ = d, leg extending
    tr = model.phases[0].transitions[0]
    assert abs(float(tr.guard(x_minus, [0.0], model.p))) < 1e-12
    x_plus = np.asarray(tr.reset(x_minus, [0.0], model.p), dtype=float).ravel()
    pos, vel = _cartesian(x_minus)
    rel = pos - np.array([d, 0.0])  # hip from the new foot
    e = rel / np.linalg.norm(rel)
    expected = vel - (vel @ e) * e
    pos_plus, vel_plus = _cartesian(x_plus)
    np.testing.assert_allclose(pos_plus, rel, atol=1e-12)
    np.testing.assert_allclose(vel_plus, expected, atol=1e-12)
    cross = lambda a, b: a[0] * b[1] - a[1] * b[0]  # noqa: E731
    assert cross(rel, vel_plus) == pytest.approx(cross(rel, vel), abs=1e-12)
    # The impulse pushes (admissible > 0) when the hip moves towards the new foot.
    assert float(tr.admissible(x_minus, [0.0], model.p)) == pytest.approx(-(vel @ e), abs=1e-12)
    # The section lift lands on the reset's image.
    s = model.section_coordinates_of(x_plus)
    np.testing.assert_allclose(model.lift(s), x_plus, atol=1e-12)


def test_running_touchdown_and_liftoff_only_reexpress_the_velocity():
    # A massless leg changes no velocity (impact=False): the flight state at touchdown and the
    # polar state after it describe the same hip position and velocity relative to the new foot
    # (x = d); lift-off back to Cartesian is the inverse.  Tolerance 1e-12 (rounding).
    model = gaitopt.model("minimal_biped_run")
    d = model.step_length
    stance, flight = model.phases
    z = 0.9
    x_f = np.array([d - np.sqrt(1 - z**2), z, 3.1, -0.7])  # on the touchdown guard
    td = flight.transitions[0]
    assert abs(float(td.guard(x_f, [0.0], model.p))) < 1e-12
    x_s = np.asarray(td.reset(x_f, [0.0], model.p), dtype=float).ravel()
    pos, vel = _cartesian(x_s)
    np.testing.assert_allclose(pos, x_f[:2] - [d, 0.0], atol=1e-12)
    np.testing.assert_allclose(vel, x_f[2:], atol=1e-12)
    lo = stance.transitions[0]
    back = np.asarray(lo.reset(x_s, [0.0], model.p), dtype=float).ravel()
    np.testing.assert_allclose(back, np.r_[pos, vel], atol=1e-12)


def test_minimal_biped_bad_input_is_one_line():
    with pytest.raises(ParameterError, match="step_length"):
        gaitopt.model("minimal_biped_walk", step_length=2.5)  # longer than two legs
    with pytest.raises(ParameterError, match="mass"):
        gaitopt.model("minimal_biped_run", mass=-1.0)
    with pytest.raises(GaitoptInputError, match="speed"):
        gaitopt.optimize_gait(
            gaitopt.model("minimal_biped_walk"), "cot", speed=-1.0, bounds={"leg_force": (0, 30)}
        )
    with pytest.raises(GaitoptInputError, match="leg_force"):  # positive work needs a bound
        gaitopt.optimize_gait(gaitopt.model("minimal_biped_walk"), "cot", speed=1.0)


@pytest.mark.slow  # 24 s on the loaded 2-core machine: run by `make test-slow`
def test_walking_optimum_is_certified_and_its_work_balances_its_energy():
    # A certified walking optimum (1 m/s, d = 0.6 m, 0 <= F <= 30 N; the study's statement):
    # the independent simulation's orbit satisfies the work-energy theorem over one period,
    # W+ + W- + ΔE_heel_strike = 0 (periodic orbit), to 1e-9 J (the simulation's rtol 1e-12 and
    # the quadrature), with a heel strike that dissipates (ΔE < 0) and a positive work that is
    # the cost: cot · M g d, to the certificate's simulation rule (1e-6 relative; measured 3e-8).
    study = load_study("walk_run_cot")
    gait = gaitopt.optimize.solve_problem(
        study.problem_at("walk", 1.0), mesh=study.MESHES["walk"][0]
    )
    assert gait.success and gait.verified, gait.message
    balance = study.energy_balance(gait)
    assert balance["impact_energy"] < 0
    assert abs(balance["residual"]) < 1e-9
    weight_distance = gait.model.mass * gait.model.gravity * study.STEP
    assert balance["positive_work"] == pytest.approx(gait.cost * weight_distance, rel=1e-6)


def test_impossible_speed_is_an_honest_failure():
    # 30 m/s with a 0.6 m step: a stance of 0.02 s cannot redirect the hip with F <= 30 N.  The
    # optimiser returns success False with a reason, never a gait.
    model = gaitopt.model("minimal_biped_walk")
    gait = gaitopt.optimize_gait(model, "cot", speed=30.0, step_length=0.6,
                                 bounds={"leg_force": (0, 30)})  # fmt: skip
    assert not gait.success and gait.message


@pytest.mark.slow  # a walk and a run, cold: ~30-60 s on the shared machine
def test_walk_run_cot_fast_mode(tmp_path):
    # Fast mode: one cold start of the walk at 1 m/s and of the run at 4 m/s.  Every certified
    # row is verified by simulation (return error below 1e-8), balances its work and energy to
    # 1e-9 J, and the walk's cost is the committed full run's at 1 m/s (the certificate's 1e-8
    # relative) when that row came from the same cold start.
    study = load_study("walk_run_cot")
    assert study.main(["--out", str(tmp_path), "--fast"]) == 0
    data = json.loads((tmp_path / "walk_run_cot" / "cot.json").read_text(encoding="utf-8"))
    rows = {(r["gait"], r["speed_m_s"]): r for r in data["rows"]}
    walk = rows["walk", 1.0]
    assert walk["certified"], walk["failures"]
    for row in data["rows"]:
        if row["certified"]:
            assert row["return_error"] < 1e-8
            assert abs(row["energy_residual_J"]) < 1e-9
    assert (tmp_path / "walk_run_cot" / "cot.png").exists()


def _readme_rows(header: str) -> list[list[str]]:
    readme = (PROBLEMS.parent / "README.md").read_text(encoding="utf-8")
    table = readme[readme.index(header) :].split("\n\n", 1)[0]
    return [
        [c.strip() for c in line.strip("|").split("|")]
        for line in table.splitlines()[2:]
        if line.startswith("|")
    ]


def _printed(text: str, value: float) -> bool:
    """``text`` is ``value`` rounded to the significant digits ``text`` shows."""
    mantissa = text.split("e")[0]
    digits = len(mantissa.replace(".", "").lstrip("0"))
    return float(text) == float(f"{value:.{digits}g}")


def test_readme_walk_run_table_is_the_committed_study_output():
    # Every row of the README's walk-or-run table is results/walk_run_cot/cot.csv (written by the
    # full run) at the digits printed: each sequence's least certified cost of transport (or a
    # dash where none is certified), the running sequence's kind and flight, the optimal gait.
    import csv

    path = PROBLEMS.parent / "results" / "walk_run_cot" / "cot.csv"
    with open(path, encoding="utf-8") as f:
        rows = {(r["gait"], float(r["speed_m_s"])): r for r in csv.DictReader(f)}
    table = _readme_rows("| speed v (m/s) | v/√(g l) | walk: least cost")
    assert len(table) == len({v for _, v in rows}) == 11
    for speed, froude, walk, run, kind, optimal in table:
        v = float(speed)
        assert _printed(froude, float(rows["walk", v]["froude_speed"])), speed
        best = {}
        for gait, printed in (("walk", walk), ("run", run)):
            row = rows[gait, v]
            if printed.startswith("—"):
                assert row["certified"] == "False" and row["failures"], speed
                continue
            assert row["certified"] == "True", speed
            assert _printed(printed, float(row["cot"])), speed
            best[gait] = (float(row["cot"]), row["kind"])
        r = rows["run", v]
        if r["kind"] == "run, flight at floor":
            assert kind == "flight at the 1 ms floor", speed
        else:
            assert kind.startswith(r["kind"] + ", flight "), speed
            flight = kind.split("flight ")[1].split(" s")[0]
            assert _printed(flight, float(r["flight_s"])), speed
        cheapest = min(best.values())[1]
        named = {"walk": "walk", "pendular run": "pendular run", "run": "run"}
        expected = named.get(cheapest, "run sequence, flight at the floor (a walk)")
        assert optimal == expected, speed
    # The README's bounds over the certified rows: returns within 4e-11, discretisation error
    # <= 4.3e-9, work-energy residual <= 4.9e-11 J (each the largest, as printed).
    good = [r for r in rows.values() if r["certified"] == "True"]
    assert _printed("4e-11", max(float(r["return_error"]) for r in good))
    assert _printed("4.3e-9", max(float(r["discretisation_error"]) for r in good))
    assert _printed("4.9e-11", max(abs(float(r["energy_residual_J"])) for r in good))
