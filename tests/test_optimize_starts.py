"""A multi-start goes on past a start that cannot begin or fails (issue 24).

Source of the failing start: seed 0's draw for start 13 (``numpy.random.default_rng([0, 13])``)
perturbs the five-link biped's default section point to one where its section lift (an arccos
placing the swing foot on the ground) is undefined, so that start has no state to simulate.  It
used to raise ``StateError`` ("a state needs 10 finite values") and abort the whole search after
the twelve starts before it; any ``--starts >= 14`` with the default seed hit it.  Now each start
has a record (``OptimalGait.starts``, the JSON's ``starts``): ``converged`` (to which minimum),
``not_converged`` or ``no_start``, with its reason.

The OptimTraj statement (0.4 m in 0.6 s, ∫Σu² dt, |u| ≤ 100 N·m, |q| ≤ π/2, |q̇| ≤ 10) and its
two minima are those of ``tests/test_optimize_five_link.py`` (GPOPS-IPOPT 263.69884582,
GPOPS-SNOPT 302.25469438, OptimTraj commit 8c43235's logs; 1e-6 relative, their own mesh error).
"""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

import gaitopt
from gaitopt.cli import main
from gaitopt.optimize import optimize_gait
from gaitopt.optimize.guess import NoStart, _start_guess
from gaitopt.optimize.problem import as_problem
from gaitopt.optimize.solve import DEFAULT_MESH, _collocation, attempt

GPOPS_IPOPT = 263.69884582  # OptimTraj 8c43235, TrajOpt_GPOPSIPOPTinfo.txt, final objective
GPOPS_SNOPT = 302.25469438  # OptimTraj 8c43235, TrajOpt_GPOPSSNOPTinfo.txt, final objective
OPTIMTRAJ = ["--fix", "step_length=0.4", "--fix", "period=0.6"]


def _statement():
    model = gaitopt.model("five_link_biped")
    return dict(
        period=0.6,
        step_length=0.4,
        bounds={name: high for name, (_, high) in model.input_bounds.items()},
        state_bounds=model.state_bounds,
    ), model


def test_start_13_has_no_state_and_is_recorded_not_raised():
    options, model = _statement()
    problem = as_problem(model, cost="effort", **options)
    col = _collocation(problem, DEFAULT_MESH)
    # The cause: the perturbed section point lifts to a state with NaN (the arccos's argument
    # leaves [-1, 1]); the guess builder says so instead of letting the simulator refuse it.
    with pytest.raises(NoStart, match="not a state of five_link_biped"):
        _start_guess(col, problem, 13, 0, None)
    rng = np.random.default_rng([0, 13])
    s0 = model.section_vector(model.default_start())
    s = s0 * (1 + 0.3 * rng.uniform(-1, 1, s0.size)) + 0.05 * rng.normal(size=s0.size)
    assert not np.all(np.isfinite(model.lift(s)))  # the draw the guess builder made
    # The start is an outcome, not an exception; no IPOPT run is made for it.
    t0 = time.perf_counter()
    run = attempt(col, problem, 13, 0, None)
    assert time.perf_counter() - t0 < 1.0
    assert run["ok"] is False and run["status"] == "no_start"
    assert run["reason"].startswith("start 13 could not begin")
    assert "swing_shank" in run["reason"]  # the section's definition, naming the lift
    assert run["w"].shape == col.lbx.shape and np.all(np.isnan(run["w"]))


def test_only_a_start_that_cannot_begin_is_a_failed_result():
    options, model = _statement()
    gait = optimize_gait(model, starts=[13], **options)
    assert not gait.success and gait.cost is None
    assert gait.message.startswith("no start could begin: start 13 could not begin")
    assert [(r.start, r.status, r.minimum) for r in gait.starts] == [(13, "no_start", None)]
    report = gait.to_json(minima=True)
    assert report["minima"] == [] and report["starts"][0]["status"] == "no_start"


@pytest.mark.slow  # ≥ 25 s: run by `make test-slow` (CI runs both)
def test_twenty_starts_from_the_cli(capsys):
    # The command, at the size users run (29 s on a loaded 2-core machine; it used to
    # exit 2 after two minutes with no JSON): exit 0 with one JSON object, start 13 among the
    # 20 records as `no_start`, every other start in the minimum its record names, the best
    # certified minimum OptimTraj's GPOPS-IPOPT optimum and the other one GPOPS-SNOPT's.
    status = main(["optimize", "five_link_biped", *OPTIMTRAJ, "--starts", "20", "--json"])
    report = json.loads(capsys.readouterr().out)
    assert status == 0, report["message"]
    assert [s["start"] for s in report["starts"]] == list(range(20))
    by_start = {s["start"]: s for s in report["starts"]}
    assert by_start[13]["status"] == "no_start" and "could not begin" in by_start[13]["message"]
    reached = sorted(s for m in report["minima"] for s in m["starts"])
    converged = sorted(s["start"] for s in report["starts"] if s["status"] == "converged")
    assert reached == converged and 13 not in reached
    for s in report["starts"]:
        if s["status"] == "converged":
            assert s["start"] in report["minima"][s["minimum"]]["starts"]
    assert "1 could not begin" in report["message"]
    assert report["cost"] == pytest.approx(GPOPS_IPOPT, rel=1e-6)
    assert report["verified"] and report["discretisation_error"] <= 1e-8
    costs = [m["cost"] for m in report["minima"] if m["verified"]]
    assert any(c == pytest.approx(GPOPS_SNOPT, rel=1e-6) for c in costs)
