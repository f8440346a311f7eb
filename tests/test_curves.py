"""Two-parameter curves: against one-parameter continuation, exact Jacobians, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import slope_at

import gaitopt
from gaitopt import GaitoptInputError, ParameterError, ParameterPath
from gaitopt.cli import main
from gaitopt.continuation import PseudoArclength, continuation
from gaitopt.curves import bifurcation_curve, curve_from
from gaitopt.curves.system import Parametrisation, augmented_system, bordering
from gaitopt.shooting import shooting_problem

MASS_HIP_AT = 12.0  # kg: an intermediate point located exactly on the curve
MASS_HIP_TO = 14.0  # kg: the curve's end


@pytest.fixture(scope="module")
def pd_curve():
    model = gaitopt.model("compass_gait", slope=0.07)
    return bifurcation_curve(
        model, "PD", "slope", "mass_hip", to=MASS_HIP_TO, param_to=0.08, at=(MASS_HIP_AT,)
    )


def _first_pd(mass_hip: float, slope_from: float) -> float:
    model = gaitopt.model("compass_gait", mass_hip=mass_hip, slope=slope_from)
    branch = continuation(model, "slope", to=0.08, cascade=False)
    return next(sp.param for sp in branch.special_points if sp.kind == "PD")


def test_pd_curve_agrees_with_one_parameter_period_doublings(pd_curve):
    # Independent method: gaitopt.continuation in the slope at fixed mass_hip, its PD located by
    # regula falsi on det(A + I) to 1e-10.  The curve's point at that mass_hip (corrected at
    # exactly that value) must give the same slope to 1e-8 (both located to 1e-10, discretisation
    # error ≤ 1e-10 each).
    assert pd_curve.success, pd_curve.message
    lam = pd_curve.params
    for mass_hip, slope_from in ((MASS_HIP_AT, 0.07), (MASS_HIP_TO, 0.065)):
        row = np.flatnonzero(np.abs(lam[:, 1] - mass_hip) < 1e-12)
        assert row.size == 1
        assert lam[row[0], 0] == pytest.approx(_first_pd(mass_hip, slope_from), abs=1e-8)
    # Every point is a certified gait with a multiplier at −1 (to 1e-8) and verified.
    for cycle in pd_curve.cycles:
        assert cycle.success and cycle.verified
        assert np.min(np.abs(cycle.multipliers + 1)) < 1e-8


def test_curve_ends_exactly_on_to(pd_curve):
    # The last point is corrected at λ₂ = to (not overshot): exact to rounding.
    assert pd_curve.message.startswith("reached mass_hip")
    assert pd_curve.values(1)[-1] == pytest.approx(MASS_HIP_TO, abs=1e-12)
    assert np.all(np.diff(pd_curve.values(1)) > 0)  # monotone in mass_hip here


@pytest.mark.parametrize("kind", ["PD", "NS"])
def test_augmented_jacobian_matches_finite_differences(kind):
    # Independent method: central differences of H with steps 1e-6 (truncation error O(h²),
    # ~1e-10 relative; rounding ~1e-10/1e-6): agreement to 1e-6 relative to max |∂H/∂y|.
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait", slope=0.07))
    system = augmented_system(type(cycle.model), cycle.discretisation, 1, kind)
    paths = (
        ParameterPath.of(cycle.model, "slope"),
        ParameterPath("a", {"a": (0.0, 1.0), "b": (1.0, -1.0)}, unit="m"),
    )
    par = Parametrisation.build(cycle.model, paths, cycle.inputs)
    b, c = bordering(kind, cycle.jacobian)
    y = np.concatenate([system.problem.unknowns_from_cycle(cycle), par.lam0 / par.scale])
    _, J, A = system.evaluate(y, b, c, par)
    np.testing.assert_allclose(np.linalg.eigvals(A), cycle.multipliers, atol=1e-10)
    fd = np.zeros_like(J)
    for k in range(y.size):
        e = np.zeros_like(y)
        e[k] = 1e-6
        fd[:, k] = (
            system.evaluate(y + e, b, c, par)[0] - system.evaluate(y - e, b, c, par)[0]
        ) / 2e-6
    assert np.max(np.abs(J - fd)) < 1e-6 * np.max(np.abs(J))


def test_parameter_path_sets_both_parameters():
    # a + b = 1 held along the path (closed form); a model off the path is refused.
    path = ParameterPath("a", {"a": (0.0, 1.0), "b": (1.0, -1.0)}, unit="m")
    assert path.values(0.3) == pytest.approx({"a": 0.3, "b": 0.7})
    assert path.value_of(gaitopt.model("compass_gait")) == pytest.approx(0.5)
    with pytest.raises(GaitoptInputError, match="not on the path"):
        path.value_of(gaitopt.model("compass_gait", b=0.6))


def test_bad_input_raises():
    model = gaitopt.model("compass_gait")
    with pytest.raises(GaitoptInputError, match="`kind`"):
        bifurcation_curve(model, "XX", "slope", "mass_hip", to=12.0)
    with pytest.raises(GaitoptInputError, match="must differ"):
        bifurcation_curve(model, "PD", "slope", "slope", to=0.1)
    with pytest.raises(GaitoptInputError, match="equals the start value"):
        bifurcation_curve(model, "PD", "slope", "mass_hip", to=10.0)
    with pytest.raises(ParameterError, match="mass_hip"):
        bifurcation_curve(model, "PD", "slope", "mass_hip", to=-1.0)
    with pytest.raises(ParameterError, match="did you mean"):
        bifurcation_curve(model, "PD", "slope", "mass_hp", to=1.0)
    slip = gaitopt.find_limit_cycle(gaitopt.model("slip"))
    with pytest.raises(GaitoptInputError, match="Neimark"):
        augmented_system(type(slip.model), slip.discretisation, 1, "NS")


def test_no_special_point_of_that_kind_fails_cleanly():
    # The compass gait's branch from slope 0.0525 to 0.06 has no PD (it is at 0.0766): no curve.
    curve = bifurcation_curve(
        gaitopt.model("compass_gait"),
        "PD",
        "slope",
        "mass_hip",
        to=12.0,
        param_to=0.06,
        branch_options=PseudoArclength(max_step=0.25),
    )
    assert not curve.success and "no PD point" in curve.message
    assert curve.as_dict()["points"] == []


def test_cli_json_keys(capsys):
    status = main(
        ["continue", "compass_gait", "--set", "slope=0.07", "--param", "slope", "--to", "0.08",
         "--follow", "PD", "--param2", "mass_hip", "--to2", "10.5", "--json"]
    )  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert status == 0
    assert {"model", "params", "kind", "param", "param2", "points", "special_points"} <= set(out)
    assert out["kind"] == "PD" and out["param"] == "slope" and out["param2"] == "mass_hip"
    point = out["points"][-1]
    assert {"slope", "mass_hip", "period", "fixed_point", "multipliers"} <= set(point)
    assert point["mass_hip"] == pytest.approx(10.5, abs=1e-12)


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--follow", "PD"], "--follow PD: needs --param2"),
        (["--follow", "PD", "--param2", "mass_hip"], "needs --to2"),
        (["--param2", "mass_hip", "--to2", "3"], "applies only with --follow"),
        (["--follow", "PD", "--param2", "mas_hip", "--to2", "3"], "did you mean 'mass_hip'"),
        (["--follow", "PD", "--param2", "slope", "--to2", "0.1"], "must differ"),
        (["--follow", "PD", "--param2", "mass_hip", "--to2", "-3"], "out of range"),
        (["--follow", "PD", "--param2", "mass_hip", "--to2", "abc"], "not a number"),
        (["--follow", "PD", "--param2", "mass_hip", "--to2", "10"], "equals the start value"),
        (["--follow", "PD", "--param2", "mass_hip", "--to2", "12", "--both"], "--both"),
        (["--follow", "XX", "--param2", "mass_hip", "--to2", "12"], "invalid choice"),
    ],
)
def test_cli_bad_input_exits_2_with_one_line(capsys, extra, needle):
    status = main(["continue", "compass_gait", "--param", "slope", "--to", "0.09", *extra])
    err = capsys.readouterr().err
    assert status == 2
    assert needle in err and err.count("\n") == 1 and "Traceback" not in err


# -- the kneed walker: its first PD and the clearance boundary in slope × foot radius ------------
KNEED_RADIUS = 0.03  # m: the second radius at which the curves meet one-parameter continuation


@pytest.fixture(scope="module")
def kneed():
    """The branch in the slope at R = 0 and at R = KNEED_RADIUS (gaitopt.continuation), and the
    PD and clearance-boundary curves from R = 0 to KNEED_RADIUS."""
    paths = None
    out = {}
    for radius in (0.0, KNEED_RADIUS):
        model = gaitopt.model("kneed_walker", slope=0.0504, foot_radius=radius)
        branch = continuation(model, "slope", to=0.13, cascade=False)
        out[radius] = {sp.kind: sp for sp in branch.special_points}
        out[radius]["branch"] = branch
        if paths is None:
            paths = (ParameterPath.of(model, "slope"), ParameterPath.of(model, "foot_radius"))
    zero = out[0.0]
    out["PD"] = curve_from(zero["PD"], "PD", paths, KNEED_RADIUS)
    out["boundary"] = curve_from(
        zero["boundary"], "boundary", paths, KNEED_RADIUS, first=zero["branch"].cycles[0]
    )
    return out


def test_kneed_walker_pd_curve_meets_one_parameter_period_doublings(kneed):
    # Independent method: gaitopt.continuation in the slope at fixed foot radius, its PD located by
    # regula falsi on det(A + I) to 1e-10 (at R = 0: 0.1062117 rad).  Curve and branch solve the
    # same condition, each located to 1e-10 with discretisation error ≤ 1e-10: 1e-8 rad.
    curve = kneed["PD"]
    assert curve.success and curve.message.startswith("reached foot_radius"), curve.message
    for radius in (0.0, KNEED_RADIUS):
        assert slope_at(curve, radius) == pytest.approx(kneed[radius]["PD"].param, abs=1e-8)
    assert kneed[0.0]["PD"].param == pytest.approx(0.1062117, abs=1e-7)
    for cycle in curve.cycles:
        assert cycle.success and cycle.verified
        assert np.min(np.abs(cycle.multipliers + 1)) < 1e-8


def test_kneed_walker_clearance_boundary_meets_one_parameter_boundary(kneed):
    # The boundary is the swing foot grazing the slope mid-swing: an interior minimum of the
    # declared clearance constraint touching zero, followed with its time t* as an unknown.
    curve = kneed["boundary"]
    assert curve.success and curve.message.startswith("reached foot_radius"), curve.message
    assert "graze_min of 'swing foot above the slope'" in curve.condition
    # Independent method: gaitopt.continuation in the slope, whose branch ends (0.1196457 rad at
    # R = 0) where certification first fails, bisected to 1e-10.  Its checks accept a gait whose
    # foot dips by less than they resolve (dense samples T/64 ≈ 4.7 ms apart around a minimum of
    # curvature c̈ ≈ 0.08 m/s² hide dips up to ½ c̈ (2.3 ms)² ≈ 2e-7 m, i.e. 3e-6 rad at
    # |∂c_min/∂γ| ≈ 0.075 m/rad; the verification simulation catches smaller ones), so its end
    # can only lie beyond the true boundary, by at most 3e-6 rad.
    for radius in (0.0, KNEED_RADIUS):
        gap = kneed[radius]["boundary"].param - slope_at(curve, radius)
        assert -1e-9 < gap < 3e-6
    # Every point's gait is certified (just inside: 1e-9 of the slope's scale) and verified.
    for cycle, (slope, _) in zip(curve.cycles, curve.params, strict=True):
        assert cycle.success and cycle.verified
        assert 0 < slope - cycle.model.slope < 1e-9


@pytest.mark.parametrize("radius", [0.0, KNEED_RADIUS])
def test_kneed_walker_clearance_boundary_brackets_the_graze(kneed, radius):
    # Independent method: the gait solved at the curve's slope ∓ 2e-8 rad, its three-link phase
    # integrated by SciPy's DOP853 (rtol 1e-13) and the clearance sampled every 2.5 µs over the
    # first 0.1 s: its lowest value must change sign across the curve (|∂c_min/∂γ| ≈ 0.075 m/rad
    # makes that ±1.5e-9 m, far above the integration error and the 1e-10 fixed-point residual).
    from scipy.integrate import solve_ivp

    slope = slope_at(kneed["boundary"], radius)
    lowest = []
    guess = kneed["boundary"].cycles[0 if radius == 0.0 else -1]
    for offset in (-2e-8, 2e-8):
        model = gaitopt.model("kneed_walker", slope=slope + offset, foot_radius=radius)
        cycle = gaitopt.find_limit_cycle(model, guess, verify=False)
        assert cycle.residual < 1e-10
        phase = model.phases[0]
        clearance = next(c for c in phase.constraints if c.outcome == "trip")
        sol = solve_ivp(
            lambda t, x, ph=phase, m=model, u=cycle.inputs: np.asarray(ph.flow(x, u, m.p)).ravel(),
            (0.0, 0.1), cycle.orbit[0].x[:, 0], method="DOP853", rtol=1e-13, atol=1e-14,
            dense_output=True,
        )  # fmt: skip
        t = np.linspace(1e-3, min(0.1, cycle.durations[0]), 40001)
        c = np.asarray(clearance.function.map(t.size)(sol.sol(t), cycle.inputs, model.p)).ravel()
        lowest.append(float(np.min(c)))
    assert lowest[0] > 0 > lowest[1]


def test_lift_off_rate_condition_matches_the_constraint_rate():
    # Closed form of the definition: ċ = ∇c · f at the three-link phase's start, evaluated by
    # the lift_off condition from the shooting unknowns and directly on the certified orbit
    # (gaitopt.hybrid.rate_along): the same number to rounding (1e-12 m/s); 0.2757 m/s at the
    # defaults (results/kneed_walker_slope).
    from gaitopt.curves.system import constraint_condition
    from gaitopt.hybrid import rate_along

    cycle = gaitopt.find_limit_cycle(gaitopt.model("kneed_walker"))
    problem = shooting_problem(type(cycle.model), cycle.discretisation, 1)
    g = constraint_condition(type(cycle.model), cycle.discretisation, 1, ("lift_off", 0, 0))
    value = float(g(problem.unknowns_from_cycle(cycle), cycle.inputs, cycle.model.p))
    phase = cycle.model.phases[0]
    direct = float(
        rate_along(phase.flow, phase.constraints[0].function)(
            cycle.orbit[0].x[:, 0], cycle.inputs, cycle.model.p
        )  # fmt: skip
    )
    assert value == pytest.approx(direct, abs=1e-12)
    assert value == pytest.approx(0.2757, abs=1e-4)
