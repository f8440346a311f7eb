"""Small helpers shared by the bench's sections: medians, JSON-ready multipliers, the machine and
versions, and the number formats of the printed tables."""

from __future__ import annotations

import math
import os
import platform
import statistics
from importlib import metadata
from typing import Any

import numpy as np

__all__: list[str] = []


def _median(values: list[float]) -> float:
    return float(statistics.median(values)) if values else math.nan


def _complex_list(z: np.ndarray) -> list[list[float]]:
    return [[float(v.real), float(v.imag)] for v in np.asarray(z, complex)]


def _version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def _machine() -> dict[str, Any]:
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor() or None,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "versions": {d: _version(d) for d in ("gaitopt", "casadi", "scipy", "numpy", "drake")},
    }


def _ms(s: float | None) -> str:
    return (
        "—"
        if s is None or not math.isfinite(s)
        else f"{1e3 * s:.3g}"
        if s < 1
        else f"{1e3 * s:.0f}"
    )


def _sci(e: float | None) -> str:
    return "—" if e is None or not math.isfinite(e) else f"{e:.1e}"
