"""Shared fixtures: limit cycles are solved once per test session."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

import gaitopt  # noqa: E402

try:  # Hypothesis profiles (tests/test_cli_fuzz.py): "ci" by default, "long" before a release
    from hypothesis import HealthCheck, settings

    _FIXTURES = [HealthCheck.function_scoped_fixture, HealthCheck.too_slow]
    settings.register_profile(
        "ci", max_examples=2000, deadline=30_000, derandomize=True, suppress_health_check=_FIXTURES
    )
    settings.register_profile(
        "long", max_examples=20_000, deadline=60_000, suppress_health_check=_FIXTURES
    )
    settings.load_profile(os.environ.get("GAITOPT_HYPOTHESIS_PROFILE", "ci"))
except ImportError:  # hypothesis is in the dev extra; without it the fuzz tests are skipped
    pass


@pytest.fixture(scope="session")
def cycles() -> dict[str, gaitopt.LimitCycle]:
    """Each registered model's passive gait at its defaults (docs/design.md's reference cases).

    Actuated-only models (``passive_gait`` False, e.g. the five-link biped) have no passive gait
    to find and are left out; their gaits come from optimisation and are tested with it."""
    return {
        name: gaitopt.find_limit_cycle(gaitopt.model(name))
        for name, cls in gaitopt.REGISTRY.items()
        if cls.passive_gait
    }
