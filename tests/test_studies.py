"""The bifurcation studies in problems/ run in their fast mode and find the published physics.

Each script's ``main(["--out", tmp, "--fast"])`` runs once per module (the stability map with
``--scheduler serial``: the Dask path is tested in test_sweep.py); the assertions read the JSON
the scripts write, as a user of results/ would.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from helpers import load_study, run_study

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"
FEIGENBAUM = 4.669201609  # Feigenbaum's δ (Feigenbaum 1978, J. Stat. Phys. 19:25)


def _load(folder: Path, name: str) -> dict:
    return json.loads((folder / name).read_text(encoding="utf-8"))


# -- rimless wheel -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def rimless(tmp_path_factory):
    return run_study("rimless_wheel_slope", tmp_path_factory.mktemp("studies"))


def test_rimless_wheel_boundary_matches_the_closed_form(rimless):
    # Source: Tedrake, Underactuated Robotics, rimless wheel: rolling exists while
    # ω* = cot 2α sqrt(4 g/l sin α sin γ) exceeds ω₁ = sqrt(2 g/l (1 − cos(γ − α))); the root of
    # ω* = ω₁ for 8 spokes is γ_b = 0.0682294525.  Tolerance 1e-8 (issue 4: special points
    # located to 1e-8), located on the side where the gait exists.
    summary = _load(rimless, "summary.json")
    boundary = summary["boundary"]
    assert boundary["closed_form"] == pytest.approx(0.0682294525, abs=1e-10)
    assert boundary["located"] == pytest.approx(boundary["closed_form"], abs=1e-8)
    assert boundary["located"] >= boundary["closed_form"]


def test_rimless_wheel_rolling_branch_follows_the_closed_form_to_the_range_end(rimless):
    # Source: Tedrake (closed forms above; multiplier cos² 2α).  Tolerances: 1e-9 in ω* (the
    # discretisation-error estimate is ≤ 1e-10) and 1e-7 in the multiplier (the shooting Jacobian
    # degrades next to the boundary, where the period diverges); the branch ends within 1e-8 of
    # π/spokes, the end of the slope's range.
    summary = _load(rimless, "summary.json")
    rolling = summary["rolling"]
    assert rolling["max_abs_difference_from_closed_form"] < 1e-9
    assert rolling["max_abs_multiplier_difference"] < 1e-7
    assert rolling["all_stable"]
    assert summary["range_end"]["difference"] == pytest.approx(0.0, abs=1e-8)
    assert rolling["branch_to"] < math.pi / 8


def test_rimless_wheel_standing_is_the_rocking_maps_fixed_point(rimless):
    # Source: Tedrake: below ω₁ the wheel rocks back, P(ω) = cos² 2α · ω, so ω = 0 (standing) is
    # a fixed point with multiplier cos² 2α = 0.5 for 8 spokes, for every slope below π/spokes.
    # Tolerance 1e-8 on P(ω)/ω from simulation (rtol 1e-11), recomputed here from the written
    # samples (simulated map over start rate) as well as read from the summary.
    summary = _load(rimless, "summary.json")
    standing = summary["standing"]
    samples = np.genfromtxt(rimless / "rocking_map.csv", delimiter=",", skip_header=1, ndmin=2)
    assert len(samples) == standing["rocking_map_samples"] > 0
    omega, simulated = samples[:, 1], samples[:, 2]
    np.testing.assert_allclose(simulated / omega, 0.5, atol=1e-8)  # cos² 2α, α = π/8
    assert standing["rocking_map_defined"] == standing["rocking_map_samples"] > 0
    assert standing["max_abs_ratio_error"] < 1e-8
    assert summary["bistable"] == pytest.approx([0.0682294525, math.pi / 8], abs=1e-9)
    assert (rimless / "existence.png").stat().st_size > 0


# -- simplest walker -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def garcia(tmp_path_factory):
    return run_study("simplest_walker_slope", tmp_path_factory.mktemp("studies"))


def test_simplest_walker_gaits_at_garcias_slope(garcia):
    # Source: Garcia, Chatterjee, Ruina & Coleman 1998, γ = 0.009: stable long-step gait
    # θ* = 0.20031090049483, θ̇* = −0.19983247291764; unstable short-step gait θ* =
    # 0.19393736960624, θ̇* = −0.20386692731962.  Tolerance 1e-9 (as test_reference.py).
    gaits = _load(garcia, "summary.json")["gaits_at_0.009"]
    assert gaits["long"]["theta"] == pytest.approx(0.20031090049483, abs=1e-9)
    assert gaits["long"]["theta_dot"] == pytest.approx(-0.19983247291764, abs=1e-9)
    assert gaits["short"]["theta"] == pytest.approx(0.19393736960624, abs=1e-9)
    assert gaits["short"]["theta_dot"] == pytest.approx(-0.20386692731962, abs=1e-9)
    assert gaits["long"]["stable"] and not gaits["short"]["stable"]


def test_simplest_walker_first_period_doubling_matches_garcia(garcia):
    # Source: Garcia et al. 1998: the long gait is stable for 0 < γ < 0.015 and period-doubles
    # at γ ≈ 0.0151.  Tolerance 5e-5: half a unit in the last published digit.  The branch is
    # stable from its small-γ end up to the PD.
    summary = _load(garcia, "summary.json")
    first = summary["first_period_doubling"]["continuation"]
    assert first == pytest.approx(0.0151, abs=5e-5)
    stable = summary["families"]["long"]["stable_slopes"]
    assert stable[0] == pytest.approx(summary["slope_range"][0], rel=1e-9)
    assert stable[1] < first < stable[1] + 2e-3
    # the overview (coarse steps) and the resolved cascade locate the same PDs to 1e-8
    # (issue 4: special points to 1e-8)
    overview = {d["period"]: d["slope"] for d in summary["period_doublings_overview"]}
    for d in summary["period_doublings"]:
        if d["period"] in overview:
            assert d["slope"] == pytest.approx(overview[d["period"]], abs=1e-8)


def test_simplest_walker_cascade_is_a_feigenbaum_cascade(garcia):
    # Source: Garcia et al. 1998 (abstract): "chaotic through a sequence of period doublings";
    # Feigenbaum 1978: successive PD intervals shrink by δ = 4.669.  The fast run resolves PDs of
    # periods 1, 2, 4, 8; the last ratio within 5 % of δ.  Each period-2k branch is born at its
    # PD: its first orbit has a multiplier within 0.25 of +1 (the square of −1) and lies within
    # 2 % of the PD in γ.
    summary = _load(garcia, "summary.json")
    periods = [d["period"] for d in summary["period_doublings"]]
    assert periods[:4] == [1, 2, 4, 8]
    assert summary["feigenbaum_ratios"][-1] == pytest.approx(FEIGENBAUM, rel=0.05)
    cascade = _load(garcia, "branches.json")["cascade"]

    def check(branch: dict) -> int:
        pds = [sp["param"] for sp in branch["special_points"] if sp["kind"] == "PD"]
        for child in branch["branches"]:
            first = child["points"][0]
            assert min(abs(complex(*z) - 1) for z in first["multipliers"]) < 0.25
            assert any(abs(first["param"] - pd) <= 0.02 * pd for pd in pds)
        return 1 + sum(check(child) for child in branch["branches"])

    assert check(cascade) >= 4  # period 1, 2, 4, 8


def test_simplest_walker_step_angle_scales_as_the_cube_root_of_the_slope(garcia):
    # Source: Garcia et al. 1998: θ* ∝ γ^(1/3) as γ → 0.  Fitted on γ ≤ 1e-3; tolerance 0.02 in
    # the exponent, for both families.
    scaling = _load(garcia, "summary.json")["scaling"]
    for family in ("long", "short"):
        assert scaling[family]["exponent"] == pytest.approx(1 / 3, abs=0.02)
        assert scaling[family]["range"][1] <= 1e-3 * (1 + 1e-9)
        assert scaling[family]["points"] >= 5
    for figure in ("bifurcation.png", "cascade.png", "scaling.png"):
        assert (garcia / figure).stat().st_size > 0


# -- compass gait stability map and basin ------------------------------------------------------
@pytest.fixture(scope="module")
def goswami(tmp_path_factory):
    return run_study(
        "compass_gait_stability_map", tmp_path_factory.mktemp("studies"), "--scheduler", "serial"
    )


def test_stability_map_is_stable_at_the_defaults(goswami):
    # Source: docs/design.md (Drake's CompassGait run to convergence): at the defaults the gait is
    # [−0.2187746, 0.3237746, 1.0928668, 0.3761346], and it is stable (Goswami et al. 1996:
    # the passive gait at μ = 2 on a shallow slope is stable).  Tolerance 5e-7 (the reference's
    # 7 digits).  The grid point nearest the defaults is stable too.
    summary = _load(goswami, "summary.json")
    basin = summary["basin"]
    expected = {
        "stance": -0.2187746,
        "swing": 0.3237746,
        "stance_dot": 1.0928668,
        "swing_dot": 0.3761346,
    }
    for name, value in expected.items():
        assert basin["fixed_point"][name] == pytest.approx(value, abs=5e-7)
    assert max(abs(complex(*z)) for z in basin["multipliers"]) < 1
    nearest = summary["map"]["nearest_to_defaults"]
    assert nearest["stable"] and nearest["max_abs_multiplier"] < 1


def test_stability_map_limit_agrees_with_the_period_doubling(goswami):
    # The map's stability limit in the column nearest μ = 2 (interpolated between grid slopes)
    # against the period doubling located by continuation at μ = 2 (0.0766356, as
    # test_continuation.py's bisection).  Tolerance: half the fast grid's slope spacing, which
    # also covers the limit's drift between μ = 2 and that column.
    summary = _load(goswami, "summary.json")
    slopes = summary["map"]["stability_limit_by_ratio"]
    spacing = (0.15 - 0.005) / 7
    pd = summary["map"]["period_doubling_at_mass_ratio_2"]
    assert pd["continuation"] == pytest.approx(0.0766356, abs=1e-6)
    assert pd["map_limit"] == pytest.approx(pd["continuation"], abs=spacing / 2)
    assert summary["map"]["gait_found"] + summary["map"]["other_gait"] > 0
    assert len(slopes) == 8


def test_basin_of_attraction_contains_the_gait_and_is_small(goswami):
    # A start 1e-2 off the fixed point converges to it within 1e-6 in 60 steps (multipliers
    # ≈ 0.58: the error shrinks ~1e-14-fold); the basin is a thin band (Schwab & Wisse 2001
    # found the same for the simplest walker): a fraction strictly between 0 and 1/2 of the
    # slice.  Each sweep's journal is removed once the sweep is complete.
    summary = _load(goswami, "summary.json")
    basin = summary["basin"]
    assert basin["perturbed_fixed_point_converges"]
    assert 0 < basin["area_fraction"] < 0.5
    total = (
        basin["area_fraction"]
        + basin["fell_fraction"]
        + basin["walking_not_converged_fraction"]
        + basin["other_fraction"]
    )
    assert total == pytest.approx(1.0, abs=1e-12)
    assert not list(goswami.glob("*.jsonl"))
    assert (goswami / "stability_map.png").stat().st_size > 0


# -- compass gait on a slope: the optimum at the passive step is the passive gait ---------------
@pytest.fixture(scope="module")
def compass_slope(tmp_path_factory):
    return run_study("optimal_compass_slope", tmp_path_factory.mktemp("studies"))


def test_least_effort_at_the_passive_step_is_the_passive_gait(compass_slope):
    # Two independent transcriptions: multiple shooting's passive gait (discretisation error
    # ≤ 1e-10) and the least-effort collocation at its period and step length (refined to 1e-8).
    # Zero effort to the refinement target (1e-8 N²·m²·s); same fixed point and multipliers
    # to 1e-6 (the optimiser's tolerance on the orbit, well above both transcriptions' errors).
    summary = _load(compass_slope, "summary.json")
    assert summary["optimum_at_passive"]["success"]
    assert summary["effort_at_passive"] <= 1e-8
    assert summary["fixed_point_difference"] <= 1e-6
    assert summary["multiplier_difference"] <= 1e-6


def test_least_effort_rises_quadratically_away_from_the_passive_period(compass_slope):
    # A smooth minimum at a gait that needs no torque: effort ∝ (T − T*)² to leading order, so
    # effort / (T − T*)² is about the same at ±5 % and ±10 % of T* (a linear rise would halve
    # it from 10 % to 5 %: ratio 2); the library is certified and agrees with cold starts.
    summary = _load(compass_slope, "summary.json")
    assert summary["library"]["success"]
    ratios = summary["effort_over_squared_period_offset"]
    assert len(ratios) >= 4 and min(ratios) > 0
    assert max(ratios) / min(ratios) < 1.5


# -- the other optimal-gait studies, in their fast modes ------------------------------------------
def test_compass_library_study_reproduces_the_readme_efforts(tmp_path):
    # README table (problems/optimal_compass_library.py, full run): least effort at 0.8 s for
    # 0.2, 0.25, 0.3 m; each refined below 1e-8, so 1e-8 relative; cold starts agree (1e-8).
    folder = run_study("optimal_compass_library", tmp_path)
    rows = np.genfromtxt(folder / "library.csv", delimiter=",", skip_header=1, usecols=(0, 1, 2))
    expected = {0.2: 0.2856223108, 0.25: 1.469482918, 0.3: 6.668848534}
    assert len(rows) == 3
    for step, warm, cold in rows:
        assert warm == pytest.approx(expected[round(step, 2)], rel=1e-8)
        assert cold == pytest.approx(warm, rel=1e-8)


ROOT = PROBLEMS.parent


def _readme_table(header: str) -> list[list[str]]:
    """The body rows of the README table whose header row begins with ``header``, as stripped
    cells (``\\|`` inside a cell is kept as ``|``)."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    table = readme[readme.index(header) :].split("\n\n", 1)[0]
    rows = [line for line in table.splitlines()[2:] if line.startswith("|")]
    return [
        [
            cell.strip().replace("\x00", "|")
            for cell in line.replace("\\|", "\x00").strip("|").split("|")
        ]
        for line in rows
    ]


def _as_printed(text: str, value: float) -> bool:
    """Whether ``text`` (a number as the README prints it: ``0.01942516337``, ``6.2e-10``,
    ``0.58750``) is ``value`` rounded to the significant digits ``text`` shows."""
    import re

    mantissa = re.split(r"[eE]", text)[0]
    digits = len(re.sub(r"[^0-9]", "", mantissa).lstrip("0"))
    return float(text) == float(f"{value:.{digits}g}")


def _committed(name: str, key: str) -> dict[float, dict[str, str]]:
    """results/<name> (a CSV written by a full run) as rows by ``key`` rounded to 2 decimals."""
    import csv

    with open(ROOT / "results" / name, encoding="utf-8") as f:
        return {round(float(r[key]), 2): r for r in csv.DictReader(f)}


def test_readme_compass_library_table_is_the_committed_study_output():
    """Every row of the README's compass-library table is the committed study table
    (results/optimal_compass_library/library.csv, written by the full run) rounded to the digits
    the README prints: a rerun that moves a number, or a README edited by hand, fails here."""
    rows = _readme_table("| step length L (m) | least effort")
    committed = _committed("optimal_compass_library/library.csv", "step_length_m")
    assert len(rows) == len(committed) == 7
    for step, effort, mu, _error, _cold in rows:
        row = committed[float(step)]
        assert row["success"] == "True"
        assert _as_printed(effort, float(row["effort_N2m2s"])), step
        assert float(mu) == round(float(row["max_abs_multiplier"]), 3), step


def test_compass_effort_study_warm_and_cold_agree(tmp_path):
    # The script exits 0 only if every warm-started optimum equals its cold start (1e-8).
    run_study("optimal_compass_effort", tmp_path)


def test_kuo_study_push_off_is_the_closed_form(tmp_path):
    # Kuo 2002: the optimal push-off gait's P = v tan α (closed form), to 1e-9 relative.
    summary = _load(run_study("optimal_kuo_pushoff", tmp_path), "pushoff.json")
    assert summary["push_off_relative_error"] <= 1e-9


# -- one-dimensional hopper (Tedrake's exercise) ---------------------------------------------------
def test_one_d_hopper_study_finds_the_deadbeat_map_and_the_apex_ratio(tmp_path):
    # Source: Tedrake, Underactuated Robotics, One-Dimensional Hopper exercise (notebook
    # exercises/simple_legs/one_d_hopper.ipynb), closed forms in gaitopt.models.one_d_hopper:
    # the gait h* = h_d = 1 m with multiplier 0; the deadbeat region (0, h_d/ρ] = (0, 1.21] m;
    # the passive ratio ρ = (10/11)² = 0.826446281; the stroke's highest apex
    # h_max = k s²/(2 m_b g) − s = 2.18393476 m.  Tolerances: the simulated map (rtol 1e-11)
    # 1e-8 m, the ratio 1e-9, the shooting's fixed point 1e-9 m and |λ| 1e-9, the continuation's
    # boundary 1e-7 m; the passive hopper (h_d = 0) has no gait and the report says why.
    run_study("one_d_hopper", tmp_path)
    summary = _load(tmp_path / "one_d_hopper_study", "summary.json")
    assert summary["fixed_point"] == pytest.approx(1.0, abs=1e-9)
    assert summary["multiplier_abs"] < 1e-9
    assert summary["deadbeat_region_m"] == pytest.approx([0.0, 1.21], abs=1e-12)
    assert (
        summary["deadbeat_max_error_m"] < 1e-8 and summary["map_max_error_vs_closed_form_m"] < 1e-8
    )
    assert summary["apex_ratio_closed_form"] == pytest.approx((10 / 11) ** 2, rel=1e-15)
    assert summary["apex_ratio_simulated"] == pytest.approx([(10 / 11) ** 2] * 3, abs=1e-9)
    assert summary["highest_apex_closed_form_m"] == pytest.approx(2.18393476045, abs=1e-10)
    assert summary["stroke_boundary_continuation_m"] == pytest.approx(2.18393476045, abs=1e-7)
    passive = summary["passive_hopper_gait"]
    assert passive["success"] is False and "no hopping gait" in passive["message"]
    rows = np.genfromtxt(
        tmp_path / "one_d_hopper_study" / "apex_map.csv", delimiter=",", skip_header=1,
        usecols=(0, 1, 2),
    )  # fmt: skip
    np.testing.assert_allclose(rows[:, 1], rows[:, 2], atol=1e-8)
    assert (tmp_path / "one_d_hopper_study" / "apex_map.png").stat().st_size > 0


# -- three-link walker (issue 20) ------------------------------------------------------------------
def test_three_link_walker_gain_study_sends_the_transverse_multipliers_to_zero(tmp_path):
    # Source: Grizzle, Abba & Plestan 2001's walker under I/O linearisation (issue 20, ζ = 1.1);
    # the numbers at ω_n = 5 are those of tests/test_three_link_walker.py (computed there and
    # checked by its NumPy referee; the 2.2583406929 s is not reproduced): step time
    # 1e-8 s, μ₁ 1e-6.  The slow transverse multiplier tracks exp(λ_slow T) of the output
    # dynamics (ratio 1.8–2.4 measured; asserted in [1, 3]) and falls by 13 decades from ω_n = 5
    # to ω_n = 100 (to the Jacobian's rounding, < 1e-12); the step time and μ₁ settle (the
    # high-gain limit), and every gait is verified by simulation (return error < 1e-8).
    folder = run_study("three_link_walker_gains", tmp_path)
    summary = _load(folder, "gains.json")
    first, last = summary["default_gait"], summary["high_gain_gait"]
    assert first["step_time_s"] == pytest.approx(2.1677530383, abs=1e-8)
    assert first["dominant_multiplier"] == pytest.approx(0.6713863, abs=1e-6)
    assert first["transverse_multipliers_abs"][0] == pytest.approx(1.7455e-3, abs=1e-7)
    assert last["omega_n"] == 100.0 and last["largest_transverse_multiplier_abs"] < 1e-12
    ratios = summary["transverse_over_exp_slow_root_T"]
    assert ratios and all(1.0 < r < 3.0 for r in ratios)
    assert last["step_time_s"] == pytest.approx(1.5329155, abs=1e-6)
    assert last["dominant_multiplier"] == pytest.approx(0.5609174, abs=1e-6)
    assert summary["max_verification_error"] < 1e-8
    assert (folder / "gains.csv").stat().st_size > 0 and (folder / "gains.png").stat().st_size > 0


# -- kneed walker: least cost of transport across speeds (problems/optimal_kneed_cot.py) --------
def test_kneed_cot_reports_the_lowest_certified_attempt_and_flags_different_minima():
    # The study's choice and flag on attempts as it records them: the lowest certified cost is
    # kept whatever the order; certified costs apart by more than SAME (1e-6 relative) are
    # different local minima and are flagged with every certified cost; 1e-9 apart is one minimum.
    study = load_study("optimal_kneed_cot")

    def attempt(start, cost, rejected=None):
        return {"start": start, "success": cost is not None, "cost": cost,
                "converged_cost": rejected if cost is None else cost}  # fmt: skip

    jump = [attempt("cold", None), attempt("from above", 0.0433), attempt("from below", 0.0194)]
    assert study.lowest(jump) == 2
    assert study.disagreement(jump) == "from below 0.0194 < from above 0.0433"
    same = [attempt("cold", 0.0266840609), attempt("from below", 0.0266840609 * (1 + 1e-9))]
    assert study.lowest(same) == 0
    assert study.disagreement(same) == ""
    assert study.lowest([attempt("cold", None), attempt("from above", None)]) is None
    assert study.disagreement([attempt("cold", 0.03), attempt("from above", None)]) == ""
    # cot.png marks the worse minima of the flagged speeds (from the CSV's `minima`).
    flagged = [(0.8, True, "from below 0.0194 < from above 0.0433"), (0.84, False, "")]
    assert study._worse(flagged) == [(0.8, 0.0433)]
    # A chain continues from the lowest certified attempt, else from the lowest converged one
    # its checks rejected (a start, not a result), else from nowhere.
    rejected = [attempt("cold", None, 0.0075), attempt("from above", None, 0.0074)]
    assert study.lowest(rejected) is None and study.seed_of(rejected) == 1
    assert study.seed_of([attempt("cold", None, 0.001), attempt("from above", 0.03)]) == 1
    assert study.seed_of([attempt("cold", None), attempt("from below", None)]) is None


@pytest.mark.slow  # ≥ 25 s: run by `make test-slow` (CI runs both)
def test_kneed_cot_fast_mode_keeps_the_lowest_certified_optimum(tmp_path):
    # Fast mode: 0.80 and 0.84 m/s, a cold start at each and the chains between them.  At every
    # speed the reported gait is the lowest certified attempt (exactly), the flag is set iff the
    # certified attempts differ by more than SAME and then names every certified cost, and each
    # attempt that failed gives its reason.  Numbers: 0.84 m/s is the README's 0.02668406090
    # (the certificate's 1e-8 relative); at 0.80 m/s the chain from 0.84 reaches the worse local
    # minimum 0.04333637603 (README: the chain from below reaches 0.0194 in the full run).
    folder = run_study("optimal_kneed_cot", tmp_path)
    data = _load(folder, "cot.json")
    assert [round(p["speed"], 2) for p in data["points"]] == [0.8, 0.84]
    for point in data["points"]:
        attempts = point["attempts"]
        assert attempts[0]["start"] == "cold" and attempts[0]["seed"] is None
        assert all(a["message"] for a in attempts if not a["success"])
        good = [a for a in attempts if a["success"]]
        if not good:
            assert point["gait"] is None and point["start"] is None
            continue
        least = min(good, key=lambda a: a["cost"])
        assert point["gait"]["cost"] == least["cost"] and point["start"] == least["start"]
        spread = max(a["cost"] for a in good) / least["cost"] - 1
        flag = point["different_minima"]
        assert bool(flag) == (spread > data["same_minimum_rel"])
        for a in good if flag else []:
            assert f"{a['start']} {a['cost']:.10g}" in flag
    slow, fast = data["points"]
    assert fast["gait"]["cost"] == pytest.approx(0.02668406090, rel=1e-8)
    above = [a for a in slow["attempts"] if a["start"] == "from above"]
    assert above[0]["seed"].startswith("0.84") and above[0]["success"]
    assert above[0]["cost"] == pytest.approx(0.04333637603, rel=1e-8)
    csv_rows = (folder / "cot.csv").read_text(encoding="utf-8").splitlines()
    assert len(csv_rows) == 3


def test_readme_kneed_cot_table_is_the_committed_study_output():
    """Every row of the README's kneed-walker cost-of-transport table is the committed study
    table (results/optimal_kneed_cot/cot.csv, written by the full run) at the digits the README
    prints: the least cost, the start it came from, period, discretisation error and largest
    |μ| of each certified speed, the flag and every certified cost where the starts reached
    different local minima, and a reason where no start is certified."""
    rows = _readme_table("| speed v (m/s) | least cost of transport")
    committed = _committed("optimal_kneed_cot/cot.csv", "speed_m_per_s")
    assert len(rows) == len(committed) == 8
    for speed, cost, start, period, error, mu, minima in rows:
        row = committed[float(speed)]
        if cost.startswith("—"):
            assert row["success"] == "False" and row["failed_starts"], speed
            assert len(cost) > 4 and not any((start, period, error, mu, minima)), speed
            continue
        assert row["success"] == row["verified"] == "True", speed
        assert _as_printed(cost, float(row["cost_of_transport"])), speed
        assert start == row["start"], speed
        assert _as_printed(period, float(row["period_s"])), speed
        assert _as_printed(error, float(row["discretisation_error"])), speed
        assert _as_printed(mu, float(row["max_abs_multiplier"])), speed
        assert (minima != "—") == (row["different_minima"] == "True"), speed
        if minima != "—":
            printed = [part.rsplit(" ", 1) for part in minima.split(" < ")]
            recorded = [part.rsplit(" ", 1) for part in row["minima"].split(" < ")]
            assert [k for k, _ in printed] == [k for k, _ in recorded], speed
            for (_, text), (_, value) in zip(printed, recorded, strict=True):
                assert _as_printed(text, float(value)), speed


def test_compass_gait_basin_study_confirms_the_ray_estimate_on_the_grid(tmp_path):
    """problems/compass_gait_basin.py --fast: every point of the 11×11 brute-force slice that the
    ray estimate claims converges on the grid (a boolean per simulated start, no tolerance); the
    3-D volume fraction's 95 % Wilson interval contains the brute-force 5×5×5 grid fraction of the
    same box (seeded; statistically it would fail about 1 run in 20 plus the grid's own error);
    the gait is stable (largest |multiplier| 0.5798, as `gaitopt solve compass_gait`, to 1e-3)."""
    folder = run_study("compass_gait_basin", tmp_path)
    summary = _load(folder, "summary.json")
    assert summary["max_abs_multiplier"] == pytest.approx(0.5798, abs=1e-3)
    cut = summary["slice"]
    assert cut["claimed_by_rays"] >= 5
    assert cut["claimed_and_confirmed"] == cut["claimed_by_rays"]
    assert cut["fraction_converged"] * cut["points"] >= cut["claimed_by_rays"]
    plane = summary["plane_rays"]
    assert plane["rays"] == 8 and 0 < plane["radius_min"] <= plane["radius_max"] <= 0.3
    fraction = summary["fraction_3d"]
    low, high = fraction["interval"]
    assert low <= fraction["fraction"] <= high
    assert fraction["interval_contains_brute_force"]
    assert low <= fraction["brute_force_fraction"] <= high
    rows = (folder / "slice.csv").read_text(encoding="utf-8").splitlines()
    assert len(rows) == 1 + 121
    assert (folder / "basin_slice.png").stat().st_size > 0
    # the columnar file beside the figure: every classified start with its outcome
    with np.load(folder / "basin.npz") as table:
        assert table["slice_points"].shape == (121, 2)
        assert [r.split(",")[2] for r in rows[1:]] == table["slice_outcomes"].tolist()
        assert table["fraction_starts"].shape == (fraction["samples"], 3)
        converged = table["fraction_outcomes"] == "converged"
        assert converged.mean() == pytest.approx(fraction["fraction"], abs=0)
        assert table["grid_starts"].shape == (125, 3) and table["grid_outcomes"].shape == (125,)
        assert table["plane_radii"].tolist() == plane["radii"]


def test_kneed_cot_chains_from_both_ends_reach_the_minimum_the_cold_starts_miss(monkeypatch):
    # The library's walk with a stand-in solver shaped like the full run: cold starts fail at
    # 0.72-0.80 m/s and are rejected at 0.68 (converged, lower branch); from 0.84's optimum
    # (branch A) a warm start finds branch A at 0.80 and nothing below; from the lower branch a
    # warm start finds it at 0.72-0.80.  The chain from above alone would report A at 0.80;
    # the chain from below, seeded by the rejected 0.68 orbit, finds the lower branch there, the
    # point is flagged with both costs, the second pass from above carries the lower branch
    # down, and the walk stops once no seed changes.
    study = load_study("optimal_kneed_cot")

    class Gait:
        def __init__(self, branch, v, ok):
            self.branch, self.success = branch, ok
            self.cost = (0.01 if branch == "low" else 0.05) * v if branch else None
            self.orbit = [1] if branch else []
            self.message = "" if ok else ("rejected" if branch else "infeasible")
            self.discretisation_error = 1e-9

    def solve(problem, guess=None):
        v = round(problem.speed, 2)
        if guess is None:
            return Gait({0.68: "low", 0.84: "A"}.get(v), v, v == 0.84)
        if guess.branch == "low" and v < 0.84:
            return Gait("low", v, v > 0.68)
        return Gait("A" if v >= 0.80 else None, v, v >= 0.80)

    monkeypatch.setattr(study, "solve_problem", solve)
    points = study.library([0.68, 0.72, 0.76, 0.8, 0.84])
    at80 = points[0.8]
    assert [a["start"] for a in at80] == ["cold", "from above", "from below"]
    assert at80[1]["cost"] == pytest.approx(0.04) and at80[2]["cost"] == pytest.approx(0.008)
    assert at80[2]["seed"] == "0.76 from below"
    assert at80[study.lowest(at80)]["start"] == "from below"
    assert study.disagreement(at80) == "from below 0.008 < from above 0.04"
    assert points[0.72][1]["seed"] == "0.80 from above" and not points[0.72][1]["success"]
    assert points[0.72][2]["seed"] == "0.68 cold (rejected)" and points[0.72][2]["success"]
    assert points[0.76][-1]["start"] == "from above, pass 2" and points[0.76][-1]["success"]
    assert points[0.68][-1]["start"] == "from above, pass 2"
    assert all(study.lowest(points[v]) is None for v in [0.68])
    assert sum(len(a) for a in points.values()) == 5 + 4 + 4 + 3


def test_planar_quadruped_study_pronk_and_bound_are_unstable_passive_gaits(tmp_path):
    """problems/planar_quadruped.py --fast.  The pronk at the defaults is the SLIP of stiffness
    2k (tests/test_planar_quadruped.py: apex speed 0.90945063 m/s, multiplier 3.5305550, to
    1e-6 here since both are re-solved to 1e-10); the bound's default multipliers 4.1217 (1e-4,
    as tests/test_planar_quadruped.py).  Along the energy branch at θ_b = θ_f = 0.21 rad the bound
    ends at two boundaries bracketing 90 J where a flight phase's duration reaches zero (≤ 1e-6 s:
    the apex meets a touchdown or a lift-off, the gait leaves its phase sequence).  The study's
    window verdict agrees with every computed bound's |λ|max in the written tables."""
    run_study("planar_quadruped", tmp_path)
    folder = tmp_path / "planar_quadruped_study"
    summary = _load(folder, "summary.json")
    pronk, bound = summary["defaults"]["pronk"], summary["defaults"]["bound"]
    assert pronk["speed"] == pytest.approx(0.90945063, abs=1e-6)
    assert pronk["max_abs_multiplier"] == pytest.approx(3.5305550, abs=1e-6)
    assert bound["max_abs_multiplier"] == pytest.approx(4.1217, abs=1e-4)
    energy = summary["branches"]["pronk_energy"]
    assert energy["range"] == pytest.approx([70.0, 200.0], abs=1e-9)
    branch = summary["branches"]["bound_energy_theta_0.21"]
    edges = [sp for sp in branch["special_points"] if sp["kind"] == "boundary"]
    assert len(edges) == 2 and edges[0]["param"] < 90.0 < edges[1]["param"]
    assert all(sp["shortest_phase_duration"] <= 1e-6 for sp in edges)
    assert all(sp["shortest_phase"] in ("descent", "ascent") for sp in edges)
    # Window verdict = the tables: a bound is stable iff its largest |multiplier| < 1.
    rows = np.genfromtxt(folder / "theta_scan.csv", delimiter=",", names=True)
    moduli = list(rows["max_abs_multiplier"])
    for name in summary["branches"]:
        if name.startswith("bound"):
            table = np.genfromtxt(folder / f"{name}.csv", delimiter=",", names=True)
            moduli += list(table["max_abs_multiplier"])
    assert len(moduli) == summary["bound_points_examined"] >= 10
    window = summary["bound_self_stable_window"]
    assert (window is None) == (min(moduli) >= 1.0)
    assert summary["bound_least_unstable"]["max_abs_multiplier"] == pytest.approx(min(moduli))
    assert summary["theta_scan"]["found"][0] < 0.21 < summary["theta_scan"]["found"][1]
    assert (folder / "branches.png").stat().st_size > 0


def test_planar_quadruped_raibert_study_the_controller_stabilises_the_bound(tmp_path):
    """problems/planar_quadruped_raibert.py --fast.  At the passive default bound's apex energy
    (90 J) and speed (0.681691 m/s) the controlled bound is found by Newton on (ẋ_d, δ) to 1e-9
    (checked here to 1e-8): every multiplier inside the unit circle, where the passive bound's
    largest is 4.1217 (1e-4, as tests/test_planar_quadruped.py).  Along ẋ_d in [0.5, 1.5] m/s
    every gait is stable and the speed rises with ẋ_d, below it (Raibert's ẋ T_s/2 overshoots the
    neutral point); the table's `stable` column is |λ|max < 1."""
    run_study("planar_quadruped_raibert", tmp_path)
    folder = tmp_path / "planar_quadruped_raibert_study"
    summary = _load(folder, "summary.json")
    match = summary["matched_to_passive"]
    controlled, passive = match["controlled"], match["passive"]
    assert controlled["apex_energy_J"] == pytest.approx(match["energy_J"], abs=1e-8)
    assert controlled["speed_m_s"] == pytest.approx(match["speed_m_s"], abs=1e-8)
    assert passive["abs_multipliers"][0] == pytest.approx(4.1217, abs=1e-4)
    assert not passive["stable"]
    assert controlled["verified"] and controlled["stable"]
    assert max(controlled["abs_multipliers"]) < 1.0
    rows = np.genfromtxt(folder / "speed.csv", delimiter=",", names=True)
    assert len(rows) == summary["branch"]["points"] >= 5
    assert rows["desired_speed_m_s"][0] == pytest.approx(0.5, abs=1e-9)
    assert rows["desired_speed_m_s"][-1] == pytest.approx(1.5, abs=1e-9)
    assert np.all(np.diff(rows["speed_m_s"]) > 0)
    assert np.all(rows["speed_m_s"] < rows["desired_speed_m_s"])
    np.testing.assert_array_equal(rows["stable"], rows["max_abs_multiplier"] < 1.0)
    assert np.all(rows["stable"] == 1)
    # The pronk's speed loop period-doubles in k_ẋ: one PD in [0.02, 0.05] s, located where the
    # speed multiplier is −1 (the continuation's tolerance; checked to 1e-6), at the full
    # run's k_ẋ = 0.041635 s (regression, 1e-5 s).
    pd = [sp for sp in summary["pronk"]["special_points"] if sp["kind"] == "PD"]
    assert len(pd) == 1 and pd[0]["k_speed"] == pytest.approx(0.041635, abs=1e-5)
    assert pd[0]["multipliers"][0] == pytest.approx(-1.0, abs=1e-6)
    assert (folder / "speed.png").stat().st_size > 0


# -- biped runner ----------------------------------------------------------------------------------
def test_biped_runner_study_symmetric_run_is_the_slip_and_the_limps_are_classified(tmp_path):
    """problems/biped_runner.py --fast.  Exact: the symmetric run is the SLIP run twice (apex,
    period = 2 T_SLIP, multiplier = λ_SLIP²; tolerance 1e-10 as tests/test_biped_runner.py).
    The branch with leg B softer passes through the limp of tests/test_biped_runner.py (θ_b =
    0.56 rad: apex heights 0.8757558 and 0.8763260 m, multiplier 0.43740420; 1e-6) and every
    gait on it is a limp (classify); the equal-leg branch holds the symmetric run at θ_b = π/6
    and its fold (LP) where the stable run meets the unstable one."""
    folder = run_study("biped_runner", tmp_path)
    symmetric = _load(folder, "symmetric.json")
    for row in symmetric:
        assert row["apex_m"] == pytest.approx(row["slip_apex_m"], abs=1e-10)
        assert row["period_s"] == pytest.approx(row["twice_slip_period_s"], abs=1e-10)
        assert row["multiplier"] == pytest.approx(row["slip_multiplier_squared"], abs=1e-10)
        assert row["verified"]
    soft = np.genfromtxt(folder / "branch_soft_b.csv", delimiter=",", names=True, dtype=None,
                         encoding="utf-8")  # fmt: skip
    assert set(soft["gait"]) == {"limp"}
    start = soft[np.abs(soft["touchdown_angle_b_rad"] - 0.56) < 1e-12]  # the branch's start
    assert len(start) == 1
    assert start["apex_a_m"][0] == pytest.approx(0.8757558, abs=1e-6)
    assert start["apex_b_m"][0] == pytest.approx(0.8763260, abs=1e-6)
    assert start["multiplier"][0] == pytest.approx(0.43740420, abs=1e-6)
    assert start["stable"][0]
    summary = _load(folder, "summary.json")
    assert "LP" in {sp["kind"] for sp in summary["special_points"]["equal"]}
    equal = np.genfromtxt(folder / "branch_equal.csv", delimiter=",", names=True, dtype=None,
                          encoding="utf-8")  # fmt: skip
    assert "symmetric run" in set(equal["gait"])


@pytest.mark.slow
def test_compass_transverse_lqr_study_fast_mode(tmp_path):
    """The transverse-LQR study in its fast mode: both controllers stabilise the level compass
    optimum (the script exits 0 only if transverse_lqr and stabilise succeed: closed-loop
    monodromy and measured multipliers within 1e-4, the perturbed runs returning)."""
    folder = run_study("compass_transverse_lqr", tmp_path)
    data = _load(folder, "comparison.json")
    # the open-loop optimum is unstable (−1.34, the README's optimal-gait table)
    assert max(abs(complex(*z)) for z in data["gait"]["multipliers"]) > 1.3
    rows = {row["controller"].split(",")[0]: row for row in data["comparison"]}
    assert rows["transverse LQR"]["largest_modulus"] < 1
    assert rows["step-to-step LQR"]["largest_modulus"] < 1
    # every probe of the bisection is a simulated start, classified: the largest survived size
    # is one of them (or 0) and below the smallest failed one
    for row in rows.values():
        for s in row["survived"]:
            sizes = [p[0] for p in s["probes"] if p[1]]
            assert s["survived"] == (max(sizes) if sizes else 0.0)
            assert s["failed"] is None or s["survived"] < s["failed"]
    # the fast run's one transverse start (stance_dot + 0.005) returned in 10 orbits
    assert data["transverse"]["trials"][0]["converged"]
    assert (folder / "table.md").exists() and (folder / "transverse.png").exists()


def test_readme_transverse_table_is_the_committed_study_output():
    """The README's transverse-LQR table is results/compass_transverse_lqr/table.md (the full
    run), line for line."""
    readme = (PROBLEMS.parent / "README.md").read_text(encoding="utf-8")
    table = (PROBLEMS.parent / "results" / "compass_transverse_lqr" / "table.md").read_text(
        encoding="utf-8"
    )
    assert table.strip() in readme
