"""Shared fixtures: limit cycles are solved once per test session."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

import gaitopt  # noqa: E402


@pytest.fixture(scope="session")
def cycles() -> dict[str, gaitopt.LimitCycle]:
    """Each registered model's gait at its defaults (DESIGN.md's reference cases)."""
    return {name: gaitopt.find_limit_cycle(gaitopt.model(name)) for name in gaitopt.REGISTRY}
