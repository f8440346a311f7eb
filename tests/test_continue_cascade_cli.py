"""`gaitopt continue` reaches the period-2 SLIP gait past its period doubling, says how each
branch switch went, and exposes the step control (issue: a PD reported and silently no branch).
"""

from __future__ import annotations

import inspect
import json

import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.cli.continue_ import _continue_arguments
from gaitopt.continuation import DEFAULT_MAX_PERIOD

#: The PD of the SLIP at the defaults in the touchdown angle, from the committed study
#: results/slip_stability_window/touchdown_angle.json (0.5157684246982078 rad, computed with
#: max_step 0.03); located by regula falsi to 1e-10 in the parameter, so 1e-9 here.
SLIP_PD = 0.5157684246982078


@pytest.fixture(scope="module")
def slip_cascade():
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(
            ["continue", "slip", "--param", "touchdown_angle", "--to", "0.5",
             "--max-period", "2", "--json"]
        )  # fmt: skip
    return code, json.loads(out.getvalue())


def test_slip_period_two_branch_from_the_cli(slip_cascade):
    code, data = slip_cascade
    assert code == 0 and data["success"]
    pds = [sp for sp in data["special_points"] if sp["kind"] == "PD"]
    assert len(pds) == 1 and pds[0]["param"] == pytest.approx(SLIP_PD, abs=1e-9)
    assert pds[0]["switch"].startswith("period-2 branch followed")
    [child] = data["branches"]
    assert child["steps"] == 2 and len(child["points"]) >= 2
    first = child["points"][0]
    # Born at the PD, on the steep side (the period-1 gait is stable on the flat side): within
    # 1e-3 relative of the PD in the angle (the switch's largest offset), its period twice the
    # parent's at the PD to within the branch's first step, and its multiplier near +1, into
    # which the parent's −1 squares (switching.BORN_MULTIPLIER = 0.25).
    assert SLIP_PD * (1 - 1e-3) <= first["param"] < SLIP_PD
    assert first["period"] == pytest.approx(2 * pds[0]["period"], rel=1e-3)
    assert abs(first["multipliers"][0][0] - 1) < 0.25
    # The flattened cascade lists every branch's special points with their period.
    assert [(c["steps"], c["kind"]) for c in data["cascade"]][:1] == [(1, "PD")]
    assert any(c["steps"] == 2 for c in data["cascade"])


def test_a_failed_switch_says_why():
    """A PD whose period-2k orbit is not searched for (max_period reached) has no switch note;
    one that is searched and not found says what was tried (here: the period-2 SLIP branch ends
    5e-5 rad past its own PD, so the period-4 orbit has no room to be born)."""
    branch = gaitopt.continuation(gaitopt.model("slip"), "touchdown_angle", to=0.5, max_period=4)
    [child] = branch.children
    notes = [sp.switch for sp in child.special_points if sp.kind == "PD"]
    assert notes and all(note for note in notes)
    assert all(
        note.startswith("period-4 branch followed") or "no period-4 branch found" in note
        for note in notes
    )
    assert all("Try `gaitopt solve slip --steps 4`" in n for n in notes if "no period-4" in n)


def test_cli_and_api_share_the_cascade_depth():
    import argparse

    parser = argparse.ArgumentParser()
    _continue_arguments(parser)
    assert parser.get_default("max_period") == DEFAULT_MAX_PERIOD
    api = inspect.signature(gaitopt.continuation).parameters["max_period"].default
    assert api == DEFAULT_MAX_PERIOD


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--max-step", "abc"], "--max-step abc"),
        (["--step", "-1"], "--step -1"),
        (["--min-step", "0.5", "--max-step", "0.1"], "min_step ≤ step ≤ max_step"),
        (["--bounds", "0.6:0.7"], "--bounds 0.6:0.7"),
        (["--bounds", "0.5"], "expected LOW:HIGH"),
    ],
)
def test_step_control_bad_input(capsys, extra, needle):
    code = main(["continue", "slip", "--param", "touchdown_angle", "--to", "0.5", *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and needle in err[0], err
