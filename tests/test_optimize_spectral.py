"""Optimal gaits stable by design (issue 21, item 4): ``max_multiplier=R`` bounds the spectral
radius of the return map's Jacobian inside the NLP.

Sources of the expected values: the Schur–Cohn–Jury conditions against NumPy's eigenvalues
(an independent method) on random matrices; the NLP's Jacobian (variational equations
collocated with the orbit) against :func:`gaitopt.optimize.floquet.return_map_jacobian` (the
implicit function theorem applied after the solve, separate code); the bounded optimum's
multipliers by AD and by central differences of the independent simulator; the inactive bound
against the committed library study (results/optimal_compass_library/library.csv, 0.2 m:
0.2856223108); the price-of-stability README table against its committed study output.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from helpers import load_study

import gaitopt
from gaitopt.cli import main
from gaitopt.errors import GaitoptInputError
from gaitopt.optimize import GaitProblem, RadauMesh, optimize_gait
from gaitopt.optimize.attempt import _collocation
from gaitopt.optimize.floquet import return_map_jacobian
from gaitopt.optimize.guess import _start_guess
from gaitopt.optimize.schur import charpoly_numpy, disc_conditions, scaled
from gaitopt.optimize.spectral import fill_sensitivities

ROOT = Path(__file__).resolve().parent.parent
LEVEL = {"period": 0.8, "step_length": 0.3}
UNBOUNDED_COST = 6.668848535  # README: the level compass optimum, 0.3 m in 0.8 s


# -- the conditions ----------------------------------------------------------------------------
@pytest.mark.parametrize("m", [1, 2, 3, 4])
def test_conditions_are_the_closed_disc(m):
    # Independent method: NumPy's eigenvalues.  On 400 random matrices per size, the conditions
    # of A/R are all >= 0 at R = 1.001 ρ(A) and not all at R = 0.999 ρ(A), and the smallest
    # vanishes at R = ρ(A) (to 1e-8 of the conditions' scale: a root on the circle).
    rng = np.random.default_rng(m)
    for _ in range(400):
        A = rng.normal(size=(m, m)) * rng.uniform(0.1, 3.0)
        rho = float(np.max(np.abs(np.linalg.eigvals(A))))
        c = charpoly_numpy(A)
        np.testing.assert_allclose(c, np.poly(A)[1:], rtol=1e-10, atol=1e-10)
        assert min(disc_conditions(scaled(c, 1.001 * rho))) >= 0
        assert min(disc_conditions(scaled(c, 0.999 * rho))) < 0
        at = disc_conditions(scaled(c, rho))
        assert min(abs(v) for v in at) <= 1e-8 * max(1.0, max(abs(v) for v in at))


# -- bad input ---------------------------------------------------------------------------------
@pytest.mark.parametrize("value", [0, -1.0, math.nan, math.inf, True, "1"])
def test_bad_bound_is_one_line_naming_it(value):
    with pytest.raises(GaitoptInputError, match="max_multiplier") as info:
        optimize_gait(gaitopt.model("compass_gait", slope=0.0), **LEVEL, max_multiplier=value)
    assert "\n" not in str(info.value) and "e.g. max_multiplier=1" in str(info.value)


def test_bound_refused_where_it_cannot_apply():
    five = gaitopt.model("five_link_biped")
    with pytest.raises(GaitoptInputError, match="9 coordinates; the bound is formulated"):
        GaitProblem(five, period=0.6, step_length=0.4, max_multiplier=1.0)
    level = gaitopt.model("compass_gait", slope=0.0)
    with pytest.raises(GaitoptInputError, match="cost 'work'"):
        GaitProblem(level, "work", bounds={"hip_torque": 20}, **LEVEL, max_multiplier=1.0)
    with pytest.raises(GaitoptInputError, match="applies with max_multiplier"):
        GaitProblem(level, **LEVEL, max_roughness=100.0)
    with pytest.raises(GaitoptInputError, match="max_roughness"):
        GaitProblem(level, **LEVEL, max_multiplier=1.0, max_roughness=-1.0)


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["--max-multiplier", "0"], "argument --max-multiplier: expected a positive finite"),
        (["--max-multiplier", "nan"], "argument --max-multiplier: expected a positive finite"),
        (["--max-multiplier", "-2"], "argument --max-multiplier: expected a positive finite"),
        (["--max-roughness", "50"], "--max-roughness 50 applies with --max-multiplier"),
        (["--cost", "work", "--bound", "hip_torque=20", "--max-multiplier", "1"],
         "--max-multiplier 1 with cost 'work'"),
    ],
)  # fmt: skip
def test_cli_bad_bound_exits_2_with_one_line(args, fragment, capsys):
    code = main(["optimize", "compass_gait", "--set", "slope=0", "--fix", "period=0.8",
                 "--fix", "step_length=0.3", *args])  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert code == 2 and fragment in err and "\n" not in err and "Traceback" not in err


def test_cli_bound_refused_on_a_large_section(capsys):
    code = main(["optimize", "five_link_biped", "--fix", "period=0.6", "--fix", "step_length=0.4",
                 "--max-multiplier", "1"])  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--max-multiplier 1: five_link_biped's section has 9" in err
    assert "\n" not in err


# -- the Jacobian inside the NLP ---------------------------------------------------------------
@pytest.mark.parametrize(
    "name, params, statement",
    [
        ("compass_gait", {"slope": 0.0}, LEVEL),
        # Two phases per step: the start-time shift δt₀ and the input rates at the knee strike
        # enter the variational rows (tests/test_optimize_kneed.py's 0.47 m in 0.5643 s).
        ("kneed_walker", {}, {"period": 0.5643, "step_length": 0.47}),
    ],
)
def test_nlp_jacobian_is_the_floquet_jacobian(name, params, statement):
    # The sensitivity unknowns solved from the variational rows (fill_sensitivities) give the
    # NLP's A; the floquet module's implicit function theorem, applied to the same collocation
    # equations at the same point, must give the same matrix (to 1e-10: two linear solves of
    # the same equations, conditioned to about 5e3).  The orbit: the unbounded optimum on the
    # 6-interval mesh, carried into the bounded transcription.
    from gaitopt.optimize.attempt import _run

    model = gaitopt.model(name, **params)
    free = GaitProblem(model, **statement)
    bounded = GaitProblem(model, **statement, max_multiplier=1.0, max_roughness=1e3)
    mesh = RadauMesh(6, 6)
    col_free, col = _collocation(free, mesh), _collocation(bounded, mesh)
    w_free, stats = _run(col_free, _start_guess(col_free, free, 0, 0, None), model.p)
    assert stats["success"]
    w0 = np.clip(col.from_solution(col_free, w_free, model.p), col.lbx, col.ubx)  # as _run
    w = fill_sensitivities(col, w0, model.p)
    A_nlp = np.asarray(col.spectral.A(w, model.p), dtype=float)
    A_ift = return_map_jacobian(col, w, model.p)
    np.testing.assert_allclose(A_nlp, A_ift, rtol=0, atol=1e-10 * np.max(np.abs(A_ift)))
    if name == "compass_gait":
        # The unbounded optimum's |μ| 1.3408 (README, AD and FD): the rows of ρ <= 1 fail.
        assert np.max(np.abs(np.linalg.eigvals(A_nlp))) == pytest.approx(1.3408, abs=1e-3)
        g = np.asarray(col.constraints(w, model.p), dtype=float).ravel()
        group = next(gr for gr in col.groups if gr.name.startswith("spectral radius"))
        assert np.min(g[group.start : group.start + group.size]) < 0


# -- the bound, inactive and active (a minute each: slow) --------------------------------------
@pytest.mark.slow
def test_inactive_bound_leaves_the_optimum_unchanged():
    # The library point at 0.2 m (results/optimal_compass_library/library.csv: effort
    # 0.2856223108, |μ| 0.716): R = 0.9 is inactive, so the optimum must not move.  Against the
    # unbounded optimum solved here: 1e-10 relative (the two solves differ by ~3e-13).  Against
    # the library's stored value: 1e-9 relative, inside the 1e-8 both are certified to (the
    # closed-form Radau matrix moved the last stored digit by 1.2e-10 relative).
    model = gaitopt.model("compass_gait", slope=0.0)
    g = optimize_gait(model, period=0.8, step_length=0.2, max_multiplier=0.9)
    free = optimize_gait(model, period=0.8, step_length=0.2)
    assert g.success and g.verified, g.message
    assert free.success, free.message
    assert g.cost == pytest.approx(free.cost, rel=1e-10)
    assert g.cost == pytest.approx(0.2856223108, rel=1e-9)
    assert g.spectral_radius == pytest.approx(0.716, abs=5e-4)
    assert not any(a.startswith("spectral radius") for a in g.active_constraints)


@pytest.mark.slow
def test_active_bound_gives_a_certified_stable_optimum(capsys):
    # 0.3 m in 0.8 s, R = 1 (the unbounded optimum: |μ| 1.341): certified, verified, costing
    # more than 6.668848535; ρ <= R by AD (to 1e-8, IPOPT's tolerance on the rows) and by
    # extrapolated central differences of the simulated map (to 1e-5, their noise).
    code = main(["optimize", "compass_gait", "--set", "slope=0", "--fix", "period=0.8",
                 "--fix", "step_length=0.3", "--max-multiplier", "1", "--json"])  # fmt: skip
    report = json.loads(capsys.readouterr().out)
    assert code == 0 and report["success"], report["message"]
    assert report["verified"] and report["discretisation_error"] <= 1e-8
    assert report["cost"] > UNBOUNDED_COST * (1 + 1e-3)
    assert report["max_multiplier"] == 1.0
    assert report["spectral_radius"] <= 1.0 + 1e-8
    assert report["spectral_radius_fd_extrapolated"] <= 1.0 + 1e-5
    # The plain central differences: first order in their step, about 2e-6 off here.
    assert abs(report["spectral_radius_fd"] - report["spectral_radius"]) <= 1e-4
    assert "spectral radius <= 1" in report["active_constraints"]
    assert report["roughness"] <= report["max_roughness"] * (1 + 1e-8)
    # The text output names the bound and the radius reached.
    from gaitopt.cli.optimize_report import report_items

    rows = dict(i for i in report_items(report, gaitopt.model("compass_gait", slope=0.0))
                if isinstance(i, tuple))  # fmt: skip
    assert "bound 1;" not in rows["spectral radius"] and "bound 1)" in rows["spectral radius"]


# -- the price-of-stability study --------------------------------------------------------------
@pytest.mark.slow
def test_study_fast_mode_meets_its_bounds(tmp_path):
    # The fast mode: R = 1 at the default budget (twice the unbounded optimum's roughness) and
    # R = 0.9 at four times it; each certified, costing more than the unbounded optimum, with
    # ρ <= R by AD (1e-8) and by extrapolated finite differences (1e-5); the same values as the
    # committed full run (1e-8: the same warm-start chain's first points).
    assert (
        load_study("optimal_compass_stability_price").main(["--out", str(tmp_path), "--fast"]) == 0
    )
    table = json.loads((tmp_path / "optimal_compass_stability_price" / "price.json").read_text())
    rows = table["table"][1:]
    assert [(r["roughness_factor"], r["max_multiplier_R"]) for r in rows] == [(2, 1), (4, 0.9)]
    committed = _committed()
    for r in rows:
        assert r["success"]
        assert r["spectral_radius_ad"] <= r["max_multiplier_R"] * (1 + 1e-8)
        assert r["spectral_radius_fd_extrapolated"] <= r["max_multiplier_R"] * (1 + 1e-5)
        assert r["effort_N2m2s"] > UNBOUNDED_COST * (1 + 1e-3)
        key = (r["roughness_factor"], r["max_multiplier_R"])
        assert r["effort_N2m2s"] == pytest.approx(float(committed[key]["effort_N2m2s"]), rel=1e-8)


def _committed() -> dict[tuple[float, float], dict[str, str]]:
    """The committed full run's certified rows by (S / S₀, R)."""
    with open(ROOT / "results/optimal_compass_stability_price/price.csv", encoding="utf-8") as f:
        rows = [r for r in csv.DictReader(f) if r["success"] == "True" and r["max_multiplier_R"]]
    return {(float(r["roughness_factor"]), float(r["max_multiplier_R"])): r for r in rows}


def test_readme_price_table_is_the_committed_study_output():
    # Every row of the README's table is a certified row of the committed full run (price.csv)
    # rounded to the digits the README prints, and every certified row is in the table.
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    header = "| S / S₀ | bound R |"
    table = readme[readme.index(header) :].split("\n\n", 1)[0].splitlines()[2:]
    committed = _committed()
    assert len(table) == len(committed) and table
    for line in table:
        cells = [c.strip() for c in line.strip("|").split("|")]
        row = committed[(float(cells[0]), float(cells[1]))]
        assert float(cells[2]) == float(f"{float(row['effort_N2m2s']):.10g}")
        assert float(cells[3]) == float(f"{float(row['price_N2m2s']):.4g}")
        assert float(cells[4]) == round(float(row["spectral_radius_ad"]), 6)
        assert float(cells[5]) == round(float(row["spectral_radius_fd_extrapolated"]), 6)


def test_bound_survives_the_trip_to_a_dask_worker():
    # A worker rebuilds the statement from plain data (gaitopt.optimize.starts): the bound and
    # its budget must survive (exact equality of the statement).
    from gaitopt.optimize.starts import problem_data, problem_from

    problem = GaitProblem(
        gaitopt.model("compass_gait", slope=0.0), **LEVEL, max_multiplier=0.9, max_roughness=100.0
    )
    rebuilt = problem_from(problem_data(problem))
    assert rebuilt.describe() == problem.describe()
    assert (rebuilt.max_multiplier, rebuilt.max_roughness) == (0.9, 100.0)
