"""Regions of attraction (gaitopt.basin): the rimless wheel's estimate against its exact basin
from the closed-form map, the compass gait's slice against a brute-force grid, the sampled
fraction's Wilson interval, the unstable gait's empty basin, bad input and the CLI."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

import gaitopt
from gaitopt.basin import basin, basin_fraction, basin_slice, wilson_interval
from gaitopt.cli import main


@pytest.fixture(scope="module")
def wheel():
    """The rolling gait of Drake's rimless wheel (8 spokes, slope 0.08 rad: bistable)."""
    gait = gaitopt.find_limit_cycle(gaitopt.model("rimless_wheel"))
    assert gait.success
    return gait


@pytest.fixture(scope="module")
def compass():
    gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    assert gait.success and gait.stable
    return gait


def _rolls(model, omega: float, limit: int = 400) -> bool:
    """Exact fate of a post-impact rate under Tedrake's closed-form map
    (``RimlessWheel.closed_form_map``): True if it reaches the rolling ω* (to 1e-9 rad/s),
    False if it reaches standing (0) or the hub stops on top (NaN)."""
    rolling = model.rolling_speed()
    for _ in range(limit):
        if not math.isfinite(omega) or abs(omega) < 1e-9:
            return False
        if abs(omega - rolling) < 1e-9:
            return True
        omega = model.closed_form_map(omega)
    raise AssertionError(f"closed-form map undecided from {omega}")


def _exact_lower_end(model, low: float) -> float:
    """The exact basin's lower end on the section below ω*: the largest rate in [low, ω*] from
    which the closed-form map does not roll, found on a grid of 20001 rates and refined by
    bisection of the closed-form fate to 1e-12 rad/s."""
    grid = np.linspace(low, model.rolling_speed(), 20001)
    fates = np.array([_rolls(model, w) for w in grid])
    bad = np.flatnonzero(~fates)
    assert bad.size, "the exact basin reaches below the window"
    lo, hi = grid[bad[-1]], grid[bad[-1] + 1]  # lo fails, hi rolls
    while hi - lo > 1e-12:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _rolls(model, mid) else (mid, hi)
    return hi


# -- the rimless wheel: estimate inside the exact basin, close to its boundary ----------------
def test_rimless_rays_inside_exact_basin_and_close_to_its_boundary(wheel):
    """Exact basin on the section (1-D, θ̇⁺) from the closed-form map: every rate above ω₁
    vaults forward and rolls (the map cos 2α sqrt(ω² + 4 g/l sin α sin γ) stays above ω₁ and
    contracts to ω*); just below ω₁ the wheel rocks back and stands.  So the star-shaped basin of
    ω* along the section is (ω₁, ∞): the upward ray rolls to ``max_radius`` and the downward ray
    ends at ω₁.  Tolerance: the estimate's end lies inside the exact basin (above ω₁) and below
    it by at most the bisection's bracket, max_radius / scan / 2**bisections (scaled), since both
    ends of the final bracket are confirmed by simulation and the simulated map agrees with the
    closed form to 1e-9 rad/s (README, rimless wheel)."""
    model = wheel.model
    estimate = basin(wheel, max_radius=1.0, scan=8, bisections=10)
    assert estimate.success, estimate.message
    omega_star, scale = model.rolling_speed(), estimate.scale[0]
    assert wheel.section_point[0] == pytest.approx(omega_star, abs=1e-9)
    exact_low = _exact_lower_end(model, 0.0)
    assert exact_low == pytest.approx(model.vaulting_speed(), abs=1e-9)  # the boundary is ω₁
    up, down = estimate.directions[:, 0] > 0, estimate.directions[:, 0] < 0
    # upward: the closed form rolls everywhere on (ω*, 2 ω*], so the ray is capped
    assert all(_rolls(model, w) for w in np.linspace(omega_star, 2 * omega_star, 401))
    assert estimate.radii[up][0] == 1.0 and estimate.capped[up][0]
    # downward: inside the exact basin, within one bracket of its end
    end = omega_star - estimate.radii[down][0] * scale
    failure = omega_star - estimate.first_failure[down][0] * scale
    bracket = 1.0 / 8 / 2**10 * scale
    assert end > exact_low, (end, exact_low)
    assert end - exact_low <= bracket
    assert failure <= exact_low  # the first failure found is outside the exact basin
    assert not estimate.flags  # (ω₁, ∞) holds no backward band below radius 1
    assert estimate.claims(np.array([[exact_low + bracket], [1.99 * omega_star]])).all()
    assert not estimate.claims(np.array([[exact_low - 1e-3]])).any()


def test_rimless_non_monotone_ray_is_flagged(wheel):
    """Below ω₁ the closed form rolls again on backward bands (README: −1.466…−1.380 rad/s):
    a scan radius landing at θ̇⁺ = −1.42 rad/s converges after the failure at ω₁ and is flagged;
    the ray's radius stays below the first failure."""
    model = wheel.model
    omega_star = model.rolling_speed()
    assert _rolls(model, -1.42) and not _rolls(model, 0.5)  # the closed form's verdicts
    top = (omega_star + 1.42) / omega_star  # the last of the 16 scan radii lands at −1.42 rad/s
    estimate = basin(wheel, max_radius=top, scan=16, bisections=4)
    down = int(np.flatnonzero(estimate.directions[:, 0] < 0)[0])
    (flag,) = estimate.flags
    assert flag["ray"] == down
    assert flag["converges_at"][-1] == pytest.approx(top, rel=1e-12)
    assert estimate.radii[down] < (omega_star - model.vaulting_speed()) / omega_star
    assert "non-monotone" in estimate.message and "star-shaped" in estimate.message


def test_rimless_fraction_interval_contains_exact_fraction(wheel):
    """Window θ̇⁺ ∈ ω* (1 ± 0.5): the exact basin there is (ω₁, 1.5 ω*], fraction (1.5 ω* − ω₁)
    / ω* = 0.6096 (closed form), checked against a brute-force grid of 4001 closed-form fates
    (to 1/4000); the sampled fraction's 95 % Wilson interval must contain it (fails about 1 run
    in 20 for an unlucky seed; the seed is fixed)."""
    model = wheel.model
    omega_star, omega_1 = model.rolling_speed(), model.vaulting_speed()
    exact = (1.5 * omega_star - omega_1) / omega_star
    grid = np.linspace(0.5 * omega_star, 1.5 * omega_star, 4001)
    brute = np.mean([_rolls(model, w) for w in grid])
    assert brute == pytest.approx(exact, abs=1 / 4000)
    estimate = basin_fraction(wheel, samples=60, window=0.5, seed=0)
    low, high = estimate.interval
    assert low <= exact <= high, (estimate.fraction, estimate.interval, exact)
    assert estimate.window["theta_dot"] == pytest.approx((0.5 * omega_star, 1.5 * omega_star))
    assert (low, high) == pytest.approx(wilson_interval(estimate.converged, 60))


def test_wilson_interval_reference_values():
    """Wilson (1927) score interval, z = 1.959964: 5 of 10 → (0.2366, 0.7634) (as
    statsmodels' proportion_confint(5, 10, method="wilson")); 0 of 5 → upper z²/(n + z²) =
    0.43448 (closed form); to 1e-4."""
    assert wilson_interval(5, 10) == pytest.approx((0.2366, 0.7634), abs=1e-4)
    z2 = 1.959963984540054**2
    assert wilson_interval(0, 5) == pytest.approx((0.0, z2 / (5 + z2)), abs=1e-12)


# -- the compass gait: ray estimate against a brute-force slice --------------------------------
def test_compass_slice_confirms_every_claimed_point(compass):
    """Rays in the (stance, stance_dot) plane (swing_dot at the fixed point) against a 13×13
    grid of simulated starts on x* ± 0.3 scale: every grid point the star estimate claims
    (within the smaller radius of its two neighbouring rays) converges on the grid, and the
    estimate claims a non-trivial part of it.  No tolerance: a boolean per start."""
    pair = ("stance", "stance_dot")
    estimate = basin(compass, rays=8, coordinates=pair, max_radius=0.3, scan=6, bisections=6)
    assert estimate.success and estimate.radii.min() > 0
    grid = basin_slice(compass, pair, points=13, window=0.3)
    claimed = estimate.claims(grid.points()).reshape(grid.converged.shape)
    assert claimed.sum() >= 5
    assert np.all(grid.converged[claimed]), grid.outcomes[claimed & ~grid.converged]
    assert grid.converged.sum() >= claimed.sum()
    assert set(np.unique(grid.outcomes)) <= {"converged", "fell", "not converged", "timeout"}
    assert grid.converged[6, 6]  # the fixed point itself


# -- the unstable gait and bad input -----------------------------------------------------------
def test_unstable_gait_has_an_empty_basin():
    """The simplest walker's short-step gait: multiplier 4.0039 (Garcia et al. 1998: the short
    period gait is unstable), so the basin is empty and the message says why."""
    gait = gaitopt.find_limit_cycle(
        gaitopt.model("simplest_walker"), {"theta": 0.1939, "theta_dot": -0.2039}
    )
    assert gait.success and not gait.stable
    estimate = basin(gait, rays=6)
    assert not estimate.success
    assert np.all(estimate.radii == 0) and len(estimate.radii) == 6
    assert "unstable" in estimate.message and "> 1" in estimate.message
    assert estimate.simulations == 0


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"rays": 0}, "`rays`"),
        ({"steps": 0}, "`steps`"),
        ({"scale": -1.0}, "`scale`"),
        ({"scale": 0.0}, "`scale`"),
        ({"max_radius": 0.0}, "`max_radius`"),
        ({"tol": -1e-4}, "`tol`"),
        ({"scheduler": "nowhere"}, "`scheduler`"),
    ],
)
def test_bad_input_is_one_line_naming_the_argument(wheel, kwargs, name):
    with pytest.raises(gaitopt.GaitoptInputError) as info:
        basin(wheel, **kwargs)
    assert name in str(info.value) and "\n" not in str(info.value)


def test_not_a_gait_is_refused(wheel):
    failed = dataclasses.replace(wheel, success=False, message="no orbit")
    for bad in (failed, wheel.model):
        for function in (basin, basin_fraction):
            with pytest.raises(gaitopt.GaitoptInputError, match="`gait`"):
                function(bad)
    with pytest.raises(gaitopt.GaitoptInputError, match="`points`"):
        basin_slice(wheel, ("theta_dot", "theta"), points=0)


# -- the command line --------------------------------------------------------------------------
def test_cli_json_fields(capsys, tmp_path):
    status = main(
        ["basin", "rimless_wheel", "--json", "--samples", "10", "--out", str(tmp_path / "b")]
    )
    out = json.loads(capsys.readouterr().out)
    assert status == 0
    assert len(out["radii"]) == len(out["directions"]) == 2
    assert out["fraction"]["samples"] == 10
    low, high = out["fraction"]["interval"]
    assert low <= out["fraction"]["fraction"] <= high
    assert set(out["timings"]) == {"solve_s", "rays_s", "fraction_s", "total_s"}
    assert "star-shaped" in out["assumption"]
    assert (tmp_path / "b" / "basin.json").exists() and (tmp_path / "b" / "basin.png").exists()
    with np.load(tmp_path / "b" / "basin.npz") as table:  # every sampled start, its outcome
        assert table["fraction_starts"].shape == (10, 1)
        converged = np.mean(table["fraction_outcomes"] == "converged")
        assert converged == out["fraction"]["fraction"]
        assert table["ray_radii"].tolist() == out["radii"]


@pytest.mark.parametrize("argv", [["--rays", "0"], ["--steps", "0"], ["--samples", "999999"]])
def test_cli_bad_counts_before_any_work(capsys, argv):
    assert main(["basin", "compass_gait", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gaitopt: error: basin: argument") and "\n" not in err


def test_chunks_and_scheduler_reach_the_sweep(wheel, monkeypatch):
    """One sweep point per ray, with ``chunk=`` (points per Dask task: the sweep's chunking) and
    ``scheduler=`` handed to gaitopt.sweep.sweep as given (the recorded call is then run
    serially)."""
    import gaitopt.sweep as sweep_module

    real, calls = sweep_module.sweep, []

    def recording(task, points, **kwargs):
        calls.append((task.__name__, len(points), kwargs["chunk"], kwargs["scheduler"]))
        return real(task, points, **{**kwargs, "scheduler": "serial"})

    monkeypatch.setattr(sweep_module, "sweep", recording)
    estimate = basin(wheel, chunk=1, scan=2, bisections=2, scheduler="tcp://127.0.0.1:8786")
    assert calls == [("rays_task", 2, 1, "tcp://127.0.0.1:8786")]
    assert estimate.success
    basin(wheel, scan=2, bisections=1)
    assert calls[-1] == ("rays_task", 2, 4, "serial")  # default: serial, chunk 4


def test_classify_starts_reports_each_outcome(wheel):
    """The rolling fixed point converges; θ̇⁺ = 0.5 rad/s < ω₁ rocks and stands (closed form,
    README rimless wheel: the simulator ends in "standing"); a start of the wrong width is one
    line naming `starts`."""
    from gaitopt.basin import classify_starts

    omega_star = wheel.model.rolling_speed()
    assert classify_starts(wheel, [[omega_star], [0.5]]) == ["converged", "standing"]
    with pytest.raises(gaitopt.GaitoptInputError, match="`starts`"):
        classify_starts(wheel, [[1.0, 2.0]])


def test_claims_skip_the_sectors_next_to_a_flagged_ray(wheel):
    """Four rays in a plane, radius 1 each, ray 0 (angle 0) flagged: a point at 45° (between rays
    0 and 1) is claimed only with next_to_flags; one at 135° (rays 1 and 2) always; one beyond
    every radius never.  Exact geometry, no tolerance."""
    from gaitopt.basin import Basin

    angles = np.pi / 2 * np.arange(4)
    estimate = Basin(
        True,
        "",
        wheel.model,
        ("a", "b"),
        {"a": 0.0, "b": 0.0},
        np.ones(2),
        np.column_stack([np.cos(angles), np.sin(angles)]),
        np.ones(4),
        np.full(4, 1.1),
        np.zeros(4, bool),
        flags=[{"ray": 0, "first_failure": 1.1, "converges_at": [2.0]}],
    )
    points = np.array([[0.5, 0.5], [-0.5, 0.5], [2.0, 2.0]])
    assert estimate.claims(points).tolist() == [False, True, False]
    assert estimate.claims(points, next_to_flags=True).tolist() == [True, True, False]


def test_module_doctests():
    """The examples in gaitopt/basin/results.py's docstrings (the Wilson interval's values)."""
    import doctest
    import importlib

    module = importlib.import_module("gaitopt.basin.results")
    failures, tried = doctest.testmod(module)
    assert tried >= 1 and failures == 0
