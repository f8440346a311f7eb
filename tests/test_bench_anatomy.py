"""``bench.anatomy``: the stages of a warm verified solve, timed by wrapping each stage (its
fast mode, two repeats of the compass gait)."""

from __future__ import annotations

import gaitopt
from bench import anatomy


def test_anatomy_counts_the_stages_and_restores_them():
    # Source: the solve's own record — the compass gait at its defaults needs no mesh
    # refinement, so its Newton iterations (LimitCycle.iterations, one Jacobian each) are the
    # one solve's: inside one call of the compiled Newton where there is a C compiler, else one
    # Jacobian evaluation from Python per iteration; one call of every other stage per solve.
    # Times are not asserted (no timing assertions), only that they are recorded and
    # non-negative.
    import gaitopt.kernels.assemble as assemble
    import gaitopt.orbit.solve as orbit_solve
    from gaitopt.kernels.newton import driver

    before = (assemble.Assembly.__call__, orbit_solve.certificate)
    entry = anatomy.anatomy("compass_gait", 2)
    assert (assemble.Assembly.__call__, orbit_solve.certificate) == before  # put back
    cycle = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
    assert entry["success"] and entry["verified"] and entry["repeats"] == 2
    assert entry["newton_iterations"] == cycle.iterations
    calls = entry["calls_per_solve"]
    compiled = driver() is not None
    assert calls["  compiled Newton (one call)"] == (1 if compiled else 0)
    assert calls["  Jacobian evaluations (F, ∂F/∂w)"] == (0 if compiled else cycle.iterations)
    for label in ("arguments", "guess simulation", "Newton", "certificate", "referee", "result"):
        assert calls[label] == 1, label
    assert all(v >= 0 for k, v in entry["stages_ms"].items() if k != "other")
    assert set(entry["stages_ms"]) == {label for label, _, _ in anatomy.STAGES} | {"other"}


def test_kernel_steps_name_each_phase_and_its_derivative_columns():
    # Source: the model's own sizes — one entry per phase, with its states and derivative
    # columns (states + inputs + parameters + duration: the kernels' D); times recorded, not
    # asserted beyond being positive.
    m = gaitopt.model("kneed_walker")
    steps = anatomy.kernel_steps("kneed_walker", calls=40)
    assert [s["states"] for s in steps] == [p.n for p in m.phases]
    for s in steps:
        assert s["derivative_columns"] == s["states"] + len(m.inputs) + len(m.p) + 1
        assert s["fold_us"] > 0 and s["step_us"] > 0
    if gaitopt.kernels.model_kernels(type(m)).compiled:  # the reduced folds (staged phases)
        assert all(s["foldx_us"] > 0 for s in steps)


def test_anatomy_with_full_folds_restores_the_hook():
    # Source: the solve's own record — the compiled Newton on the full folds takes the same
    # number of Newton iterations as on the reduced ones (the same state and duration columns,
    # tests/test_kernels_foldx.py); the assembly's hook is put back afterwards.
    from gaitopt.kernels.assemble import Assembly

    before = Assembly.__dict__["compiled_newton"]
    full = anatomy.anatomy("kneed_walker", 2, compiled="full")
    assert Assembly.__dict__["compiled_newton"] is before
    reduced = anatomy.anatomy("kneed_walker", 2)
    assert full["success"] and full["verified"]
    assert full["newton_iterations"] == reduced["newton_iterations"]


def test_anatomy_without_the_compiled_newton_is_the_python_newton():
    # Source: the solve's own record — without the compiled Newton every Newton iteration is
    # one Jacobian evaluation from Python (LimitCycle.iterations of the same solve); the
    # assembly's hook is put back afterwards.
    from gaitopt.kernels.assemble import Assembly

    before = Assembly.__dict__["compiled_newton"]
    entry = anatomy.anatomy("compass_gait", 2, compiled=False)
    assert Assembly.__dict__["compiled_newton"] is before
    calls = entry["calls_per_solve"]
    assert entry["success"] and entry["verified"]
    assert calls["  compiled Newton (one call)"] == 0
    assert calls["  Jacobian evaluations (F, ∂F/∂w)"] == entry["newton_iterations"]


def test_the_drake_goal_is_judged_on_the_alternating_rounds():
    """bench.goals' first row: with the alternating measurement present (bench.anatomy's
    rounds, both sides under the same load) the goal is judged on its CPU ratio, and the ratio of
    the two sections' separate medians is printed beside it; without it, on the separate medians
    as before.  The records are made up (the rows only divide what the record holds)."""
    from bench import goals

    record = {
        "models": {"compass_gait": {
            "once_built": {"verify_true": {"median_s": 2.0e-3}},
            "drake": {"runs": {"settle to 1e-08, accuracy 1e-4 (default)": {"median_s": 30e-3}}},
        }},
        "goals_issue_23_measured": {"compass_vs_drake_rounds": {
            "ratio_cpu": 24.0, "gaitopt_cpu_ms": 2.2, "drake_cpu_ms": 52.8}},
    }  # fmt: skip
    row = goals.rows(record)[0]
    assert row["met"] is True and row["measured"].startswith("24×")
    assert "separate medians 15×" in row["measured"]
    del record["goals_issue_23_measured"]
    row = goals.rows(record)[0]
    assert row["met"] is False and row["measured"].startswith("15×")
