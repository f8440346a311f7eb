"""bench/branches.py's slope study at a tiny size (no timing asserted)."""

from __future__ import annotations

import math

from bench import branches


def test_slope_study_quick_record():
    # The quick slope study (cascade to period 4) with an 8-slope orbit diagram of 40 steps per
    # slope, serially.  Sources: the continuation's first period doubling is the compass gait's
    # (tests/test_continuation.py's cascade value, located to 1e-10; 1e-9 here); the two orbit
    # diagrams simulate the same slopes by two implementations (SciPy's DOP853 stepper driven
    # from Python, and the compiled arcs, which restate its operations): the same settled
    # states to 1e-9 and so the same first doubling seen.
    record = branches._slope_study(True, 1, "serial", resolution=5e-3, steps=(40, 8))
    assert math.isclose(record["first_pd_continuation"], 0.07663563157614978, abs_tol=1e-9)
    assert len(record["period_doublings"]) == 3  # period 1 → 2 → 4 → 8 (max_period 4)
    python, compiled = record["orbit_diagram_python"], record["orbit_diagram_compiled"]
    assert record["orbit_diagram_slopes"] == 8
    assert record["orbit_diagrams_max_difference"] <= 1e-9
    assert python["first_pd"] == compiled["first_pd"]
    # The goal's ratio is the one against the brute-force loop, the compiled one beside it.
    assert record["speedup_baseline"] == "python" and record["speedup"] == python["speedup"]
    assert record["speedup_compiled"] == compiled["speedup"]
    lines = "\n".join(branches._diagram_lines(record))
    assert "backend='python'" in lines and "compiled" in lines
