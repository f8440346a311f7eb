"""What the measured gaits are compared with: the reference numbers (docs/design.md, the papers),
the errors of each fixed point against gaitopt's and the references, and the compass-gait goals
(the compass-gait goals)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

__all__: list[str] = []

# -- reference numbers (docs/design.md, "Reference numbers the tests meet") ---------------------
_VDP_PERIOD = 6.6632868593231301897  # Hairer, Nørsett & Wanner, μ = 1
_COMPASS = {  # docs/design.md; agrees with Drake's CompassGait simulated to convergence (7 digits)
    "stance": -0.2187746,
    "swing": 0.3237746,
    "stance_dot": 1.0928668,
    "swing_dot": 0.3761346,
}
_GARCIA = {"theta": 0.20031090049483, "theta_dot": -0.19983247291764}  # Garcia et al. 1998


def _reference(name: str, model: Any) -> tuple[str, Callable[[dict, float], float]] | None:
    """What to compare with for ``name``: (description, error of a fixed point and period)."""
    if name == "vanderpol" and model.params.get("mu") == 1.0:
        return "period vs Hairer et al. 6.66328685932313", lambda x, T: abs(T - _VDP_PERIOD)
    if name == "rimless_wheel":
        w = model.rolling_speed()
        return "theta_dot vs closed form ω*", lambda x, T: abs(x["theta_dot"] - w)
    if name == "compass_gait" and model.params == type(model)().params:
        return "state vs docs/design.md (7 digits)", lambda x, T: max(
            abs(x[k] - v) for k, v in _COMPASS.items()
        )
    if name == "simplest_walker" and model.params.get("slope") == 0.009:
        return "theta, theta_dot vs Garcia 1998", lambda x, T: max(
            abs(x[k] - v) for k, v in _GARCIA.items()
        )
    return None


def _max_diff(a: dict[str, float], b: dict[str, float]) -> float:
    keys = [k for k in a if k in b]
    return max(abs(a[k] - b[k]) for k in keys) if keys else math.nan


def _compare(model: Any, entry: dict[str, Any]) -> None:
    """Add errors vs gaitopt's fixed point and vs the reference numbers, in place."""
    ref = _reference(model.name, model)
    entry["reference"] = ref[0] if ref else None
    gx, gT = entry["gaitopt"]["fixed_point"], entry["gaitopt"]["period"]
    entry["gaitopt"]["error_vs_reference"] = ref[1](gx, gT) if ref and gx else None
    targets = []
    if "fixed_point" in entry.get("baseline", {}):
        targets.append((entry["baseline"], entry["baseline"]["period"]))
    for run_ in entry.get("drake", {}).get("runs", {}).values():
        targets.append((run_, math.nan))
    for target, period in targets:
        x = target["fixed_point"]
        target["error_vs_gaitopt"] = _max_diff(x, gx) if x and gx else None
        err = None
        if ref and x:
            err = ref[1](x, period)
            err = None if math.isnan(err) else err
        target["error_vs_reference"] = err


def _goals(record: dict[str, Any]) -> dict[str, Any]:
    """The issue's goals for the compass gait, with the measured numbers."""
    cg = record["models"].get("compass_gait")
    if cg is None:
        return {}
    built = cg["once_built"]["verify_false"]["median_s"]
    goals: dict[str, Any] = {
        "cycle_with_multipliers_once_built_s": built,
        "at_most_2ms": built <= 2e-3,
    }
    runs = cg.get("drake", {}).get("runs", {})
    settle = runs.get("settle, accuracy 1e-4 (default)")
    if settle:
        goals["drake_default_settle_s"] = settle["median_s"]
        goals["drake_default_settle_with_monitor_s"] = settle["median_s_with_monitor"]
        goals["speedup_vs_drake_default_settle"] = settle["median_s"] / built
        goals["at_least_20x_vs_drake"] = settle["median_s"] / built >= 20
        goals["drake_default_settled_error"] = settle["error_vs_gaitopt"]
    conv = runs.get("converge, accuracy 1e-10")
    if conv:
        goals["error_vs_drake_converged_1e-10"] = conv["error_vs_gaitopt"]
    conv_default = runs.get("converge, accuracy 1e-4 (default)")
    if conv_default:
        goals["drake_default_error_floor"] = conv_default["error_vs_gaitopt"]
    if "error_vs_gaitopt" in cg.get("baseline", {}):
        goals["error_vs_baseline"] = cg["baseline"]["error_vs_gaitopt"]
    if conv:
        goals["exact_to_1e-10"] = conv["error_vs_gaitopt"] <= 1e-10
    return goals
