"""RABBIT on the five-link biped (gaitopt.hzd.rabbit), multi-start HZD design and the speed
library (gaitopt.hzd.multistart), bad input of the HZD front doors (issue 20).

Sources of the numbers: independent methods throughout — the closed loop's friction cone
against the plant's own ground reaction and against finite differences of the walker's
momentum; the design's quadrature against the restricted map's ODE integration; two grids of
one design; the design against the full-order closed loop (its period, its multipliers) and an
independent DOP853 integration of the effort (problems/rabbit_hzd.py).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.errors import GaitoptInputError
from gaitopt.hzd import virtual_constraint_model
from gaitopt.hzd.design import surface_gait
from gaitopt.hzd.multistart import design_problem, multistart_design, speed_library
from gaitopt.hzd.rabbit import RABBIT, rabbit_start
from gaitopt.hzd.zero_dynamics import restricted_map

RESULTS = Path(__file__).resolve().parent.parent / "results" / "rabbit_hzd"


@pytest.fixture(scope="module")
def plant():
    return gaitopt.model("five_link_biped")


def test_the_friction_cone_is_the_walkers_momentum_balance(plant):
    # The closed loop's friction constraints μN ∓ F_t (from the point masses' accelerations
    # along the closed loop) against (a) the plant's own declared normal force (its
    # contact_force with the closed loop's torques): (fwd + bwd)/(2μ) = N to 1e-9 relative, and
    # (b) F_t = d/dt Σ m_i v_i,x by central differences along the flow (h = 1e-6: error ~1e-8
    # of forces ~100 N; 1e-5 N asserted).
    model = virtual_constraint_model(plant, 5)(omega_n=8.0, friction_coefficient=0.6)
    phase = model.phases[0]
    c = {k.name: k.function for k in phase.constraints}
    rng = np.random.default_rng(3)
    for _ in range(3):
        x = np.r_[rng.uniform(-0.3, 0.3, 5), rng.normal(size=5)]
        fwd = float(c["stance foot does not slip forward"](x, [], model.p))
        bwd = float(c["stance foot does not slip backward"](x, [], model.p))
        normal = float(c["stance foot pushes on the ground"](x, [], model.p))
        assert (fwd + bwd) / 1.2 == pytest.approx(normal, rel=1e-9)
        f = np.asarray(phase.flow(x, [], model.p), dtype=float).ravel()

        def momentum(y):
            m, _, v = phase.bodies(y, model.p)
            return float(np.asarray(v, dtype=float)[0] @ np.asarray(m, dtype=float).ravel())

        tangential = (momentum(x + 1e-6 * f) - momentum(x - 1e-6 * f)) / 2e-6
        assert (bwd - fwd) / 2 == pytest.approx(tangential, abs=1e-5)


def test_rabbit_start_walks_and_the_quadrature_matches_the_restricted_map(plant):
    # θ = (q1 + q2)/2 decreases over a step.  The design's Simpson quadrature (401 phases)
    # against restricted_map's DOP853 integration of the zero dynamics (rtol 1e-12): the same
    # slope (both from the impact, 1e-12) and step time (1e-6 s, the quadrature's error); the
    # start walks, slower than RABBIT's 0.75 m/s.
    model = rabbit_start(plant)
    g = surface_gait(model, 401)
    rmap = restricted_map(g.model)
    assert g.walks and rmap.walks
    assert g.slope == pytest.approx(rmap.slope, abs=1e-12)
    assert g.step_time == pytest.approx(rmap.step_time, abs=1e-6)
    assert 0 < g.speed < RABBIT["speed"]
    assert set(g.conditions) == {
        "swing foot above the ground",
        "stance foot pushes on the ground",
        "stance foot does not slip forward",
        "stance foot does not slip backward",
    }


@pytest.mark.skipif(not (RESULTS / "rabbit_hzd.json").exists(), reason="study not run")
def test_the_committed_rabbit_optimum_meets_every_condition(plant):
    # The study's committed optimum (problems/rabbit_hzd.py) re-evaluated here by the design's
    # quadrature on a grid it was not optimised on (301 phases): RABBIT's conditions hold to the
    # quadrature's error (speed 1e-6 m/s, mid-step clearance 1e-6 m, |u| ≤ 100 N·m, N ≥ 0, the
    # friction cone), the effort agrees with the study's to 1e-5 relative and the restricted
    # map's slope to 1e-8.
    d = json.loads((RESULTS / "rabbit_hzd.json").read_text(encoding="utf-8"))
    model = rabbit_start(plant).with_alpha(
        {j: np.array(v) for j, v in d["bezier"].items()},
        theta_plus=d["theta_plus"],
        theta_minus=d["theta_minus"],
    )
    g = surface_gait(model, 301)
    assert g.walks
    assert g.speed == pytest.approx(RABBIT["speed"], abs=1e-6)
    assert g.foot[150] >= RABBIT["mid_clearance"] - 1e-6
    assert g.max_torque <= RABBIT["torque_limit"] + 1e-6
    for name in ("stance foot pushes on the ground", "stance foot does not slip forward",
                 "stance foot does not slip backward"):  # fmt: skip
        assert np.min(g.conditions[name]) > 0
    assert g.effort == pytest.approx(d["design"]["effort_N2m2s"], rel=1e-5)
    assert g.slope == pytest.approx(d["design"]["slope"], abs=1e-8)


def test_design_input_errors(plant):
    # One line naming the argument (issue 20, item 4).
    three = gaitopt.model("three_link_walker")
    with pytest.raises(GaitoptInputError, match="^starts: 0"):
        multistart_design(three, 4, starts=0)
    with pytest.raises(GaitoptInputError, match="^spread: "):
        multistart_design(three, 4, spread=-1.0)
    with pytest.raises(GaitoptInputError, match="^degree: 2"):
        multistart_design(three, 2)
    with pytest.raises(GaitoptInputError, match="^speed: "):
        design_problem(plant, 5, speed=0.0)
    with pytest.raises(GaitoptInputError, match="^speeds: "):
        speed_library(three, 4, [0.5, -1.0])
    with pytest.raises(GaitoptInputError, match="^model: 'compass_gait'"):
        multistart_design(gaitopt.model("compass_gait"), 4)
    with pytest.raises(GaitoptInputError, match="^model: "):
        design_problem(gaitopt.model("kneed_walker"), 4)


@pytest.mark.parametrize(
    "argv, option",
    [
        (["--degree", "0"], "--degree"),
        (["--degree", "40"], "--degree"),
        (["--omega-n", "0"], "--omega-n"),
        (["--zeta", "-1"], "--zeta"),
        (["--torque-limit", "0"], "--torque-limit"),
        (["--phase-variable", "torso=1"], "--phase-variable"),
        (["--speed", "0.5"], "--speed"),
        (["--design", "--starts", "100"], "--starts"),
        (["--design", "--spread", "0"], "--spread"),
        (["--design", "--speed", "-1"], "--speed"),
        (["--design", "--omega-n", "-3"], "--omega-n"),
    ],
)
def test_cli_bad_hzd_input_is_one_line_exit_2(capsys, argv, option):
    # Every bad argument: exit 2 and one line on stderr naming the option (item 4).
    code = main(["solve", "three_link_walker", "--controller", "hzd", *argv])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and option in err, err


@pytest.mark.parametrize("argv", [["--design"], ["--speed", "0.5"], ["--spread", "0.2"]])
def test_cli_design_options_need_the_hzd_controller(capsys, argv):
    code = main(["solve", "three_link_walker", *argv])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and argv[0] in err, err


def test_cli_design_refuses_an_unactuated_model(capsys):
    code = main(["solve", "compass_gait", "--controller", "hzd", "--design"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "MODEL" in err, err


@pytest.mark.slow  # ~2 min: eight SLSQP runs and three full-order certifications
def test_three_link_multistart_lists_every_distinct_minimum(capsys):
    # Multi-start from 8 seeded starts (seed 0): start 0 is the study's start, so its minimum is
    # problems/three_link_hzd_optimal.py's (928.3563 N²·m·s, 1e-4 relative: the same SLSQP
    # run); every listed minimum is distinct (costs differ by > 1e-6 relative), certified on the
    # full-order loop with μ₁ = δ² (1e-6, Minimum.verified) and listed cheapest first; the CLI
    # gives the same list (the same seed).
    result = multistart_design(gaitopt.model("three_link_walker"), 4, starts=8, seed=0)
    costs = [m.design.cost for m in result.minima]
    assert costs == sorted(costs) and len(result.starts) == 8
    assert np.all(np.diff(costs) > 1e-6 * costs[0])
    assert all(m.verified for m in result.minima)
    zero = result.minima[result.starts[0]["minimum"]]
    assert zero.design.cost == pytest.approx(928.3563, rel=1e-4)
    code = main(["solve", "three_link_walker", "--controller", "hzd", "--design", "--starts",
                 "8", "--seed", "0", "--json"])  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and [m["cost"] for m in out["minima"]] == pytest.approx(costs, rel=1e-9)


@pytest.mark.slow  # ~1 min
def test_three_link_speed_library_continues_the_optimum():
    # Natural-parameter continuation in speed: each point meets its speed (SLSQP's equality to
    # 1e-8 m/s); above the free optimum's speed (0.5247 m/s, 928.3563 N²·m·s,
    # problems/three_link_hzd_optimal.py) the cost rises with speed and is never below the free
    # optimum's (a constrained optimum of the same problem; 1e-6 relative).
    rows = speed_library(gaitopt.model("three_link_walker"), 4, [0.525, 0.6, 0.65])
    got = {v: g for v, g, _ in rows}
    assert all(g is not None for g in got.values())
    for v, g in got.items():
        assert g.speed == pytest.approx(v, abs=1e-8)
    assert 928.3563 * (1 - 1e-6) < got[0.525].cost < got[0.6].cost < got[0.65].cost


def _study(name: str, out: Path) -> Path:
    import importlib.util

    path = Path(__file__).resolve().parent.parent / "problems" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"study_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main(["--out", str(out), "--fast"]) == 0
    return out / name


@pytest.mark.slow  # ~3 min: one SLSQP design (101 phases) and a five-link full-order gait
def test_rabbit_hzd_study_fast(tmp_path):
    # Sources: independent methods.  The design (Simpson on 101 phases) against the full-order
    # closed loop at ω_n = 20: its period = the zero dynamics' step time (1e-5 s: the coarse
    # quadrature's error), one multiplier = δ² (1e-6), hybrid invariance (residual ≤ 1e-10,
    # Westervelt et al. 2007 eqs (6.37)); the effort by DOP853 along the closed loop against the
    # quadrature (1e-4 relative on 101 phases); RABBIT's conditions on the orbit's dense samples
    # (N > 0, the friction cone); perturbed runs approach the gait.
    folder = _study("rabbit_hzd", tmp_path)
    d = json.loads((folder / "rabbit_hzd.json").read_text(encoding="utf-8"))
    design = d["design"]
    assert design["speed_m_s"] == pytest.approx(0.75, abs=1e-6)
    assert design["mid_step_foot_m"] >= 0.1 - 1e-8 and design["max_abs_torque_Nm"] <= 100 + 1e-6
    assert d["invariance_residual"] < 1e-10
    assert d["simulated_effort"] == pytest.approx(design["effort_N2m2s"], rel=1e-4)
    import csv

    rows = list(csv.DictReader((folder / "rabbit_hzd.csv").open(encoding="utf-8")))
    row = rows[0]
    assert row["verified"] == "True"
    assert float(row["period_s"]) == pytest.approx(design["step_time_s"], abs=1e-5)
    assert float(row["mu_minus_slope"]) < 1e-6
    assert float(row["min_normal_force_N"]) > 0 and float(row["min_friction_margin_N"]) > 0
    # Perturbed runs (fast: 2 starts, 6 steps): none falls, each ends closer to the fixed point
    # than half its start (δ²⁶ ≈ 0.10; the full run's ratios after 6 steps are 0.005–0.29).
    runs: dict[str, dict[int, float]] = {}
    for r in csv.DictReader((folder / "perturbed.csv").open(encoding="utf-8")):
        runs.setdefault(r["start"], {})[int(r["step"])] = float(r["distance"])
    steps = d["perturbed"]["steps"]
    assert len(runs) == d["perturbed"]["starts"]
    for run in runs.values():
        assert -1 not in run and run[steps] < 0.5 * run[0]
    for name in ("outputs.png", "torques.png", "zero_dynamics.png", "perturbed.csv"):
        assert (folder / name).stat().st_size > 0


@pytest.mark.slow  # ~1 min: two three-link starts and a three-point speed library
def test_hzd_multistart_study_fast(tmp_path):
    # Start 0 is problems/three_link_hzd_optimal.py's SLSQP run (928.3563 N²·m·s, 1e-4
    # relative); every listed minimum verified on the full-order loop (μ = δ² to 1e-6); the
    # library's points meet their speeds (they are SLSQP's equality constraints, 1e-8 m/s).
    folder = _study("hzd_multistart", tmp_path)
    d = json.loads((folder / "hzd_multistart.json").read_text(encoding="utf-8"))
    three = d["three_link_walker"]
    assert all(m["verified"] for m in three["minima"])
    zero = three["minima"][three["starts"][0]["minimum"]]
    assert zero["cost"] == pytest.approx(928.3563, rel=1e-4)
    import csv

    for row in csv.DictReader((folder / "library.csv").open(encoding="utf-8")):
        assert row["success"] == "True"
        assert float(row["achieved_speed_m_s"]) == pytest.approx(float(row["speed_m_s"]), abs=1e-8)
    assert (folder / "library.png").stat().st_size > 0


def _readme_table(header: str) -> list[list[str]]:
    """The body rows of the README table whose header row begins with ``header``."""
    readme = (RESULTS.parent.parent / "README.md").read_text(encoding="utf-8")
    table = readme[readme.index(header) :].split("\n\n", 1)[0]
    rows = [line for line in table.splitlines()[2:] if line.startswith("|")]
    return [[c.strip() for c in line.replace("\\|", "").strip("|").split("|")] for line in rows]


def _as_printed(text: str, value: float) -> bool:
    """Whether ``text`` is ``value`` rounded to the significant digits ``text`` shows."""
    import re

    mantissa = re.split(r"[eE]", text)[0]
    digits = len(re.sub(r"[^0-9]", "", mantissa).lstrip("0"))
    return float(text) == float(f"{value:.{digits}g}")


def test_readme_rabbit_table_is_the_committed_study_output():
    # Every number of the README's RABBIT table is results/rabbit_hzd/rabbit_hzd.csv (written
    # by problems/rabbit_hzd.py) rounded as printed.
    import csv

    with open(RESULTS / "rabbit_hzd.csv", encoding="utf-8") as f:
        committed = {float(r["omega_n"]): r for r in csv.DictReader(f)}
    rows = _readme_table("| ω_n (rad/s) | period (s) | μ (the slope's multiplier)")
    assert len(rows) == len(committed) == 4
    keys = ["period_s", "mu_slope", "mu_minus_slope", "max_abs_other_mu", "max_abs_torque_Nm",
            "min_normal_force_N", "min_friction_margin_N"]  # fmt: skip
    for row in rows:
        r = committed[float(row[0])]
        for text, key in zip(row[1:], keys, strict=True):
            assert _as_printed(text, float(r[key])), (row[0], key, text, r[key])


def test_readme_speed_library_table_is_the_committed_study_output():
    # Every number of the README's speed-library table is results/hzd_multistart/library.csv
    # (problems/hzd_multistart.py) rounded as printed; an empty cell is a speed not run or not
    # reached (success False in the CSV).
    import csv

    path = RESULTS.parent / "hzd_multistart" / "library.csv"
    with open(path, encoding="utf-8") as f:
        rows = [r for r in csv.DictReader(f) if r["success"] == "True"]
    readme = (RESULTS.parent.parent / "README.md").read_text(encoding="utf-8")
    table = readme[readme.index("| speed (m/s) | 0.525") :].split("\n\n", 1)[0].splitlines()
    speeds = [float(c) for c in table[0].strip("|").split("|")[1:]]
    cells = {line.strip("|").split("|")[0].strip(): line.strip("|").split("|")[1:]
             for line in table[2:]}  # fmt: skip
    model = {"three-link": "three_link_walker", "RABBIT": "five_link_biped"}
    checked = 0
    for label, values in cells.items():
        name, what = label.rsplit(" ", 1)
        key = "slope" if what == "δ²" else "cost"
        by_speed = {float(r["speed_m_s"]): r for r in rows if r["model"] == model[name]}
        for v, text in zip(speeds, values, strict=True):
            if text.strip():
                assert _as_printed(text.strip(), float(by_speed[v][key])), (label, v, text)
                checked += 1
            else:
                assert v not in by_speed
    assert checked == 22
