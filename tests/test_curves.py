"""Two-parameter curves: against one-parameter continuation, exact Jacobians, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

import gaitopt
from gaitopt import GaitoptInputError, ParameterError, ParameterPath
from gaitopt.cli import main
from gaitopt.continuation import PseudoArclength, continuation
from gaitopt.curves import bifurcation_curve
from gaitopt.curves.follow import _w_of
from gaitopt.curves.system import Parametrisation, augmented_system, bordering

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
    y = np.concatenate([_w_of(cycle, system.tr), par.lam0 / par.scale])
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
