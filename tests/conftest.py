"""Shared fixtures: limit cycles are solved once per test session."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

import gaitopt  # noqa: E402


@pytest.fixture(scope="session")
def cycles() -> dict[str, gaitopt.LimitCycle]:
    """Each registered model's passive gait at its defaults (DESIGN.md's reference cases).

    Actuated-only models (``passive_gait`` False, e.g. the five-link biped) have no passive gait
    to find and are left out; their gaits come from optimisation and are tested with it."""
    return {
        name: gaitopt.find_limit_cycle(gaitopt.model(name))
        for name, cls in gaitopt.REGISTRY.items()
        if cls.passive_gait
    }
