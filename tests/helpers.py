"""Helpers shared by the test modules (one copy each, instead of one per file): the studies of
``problems/`` loaded and run in their fast mode, the CLI run in-process, console scripts, and two
small geometric and curve look-ups.  Imported as ``from helpers import ...`` (pytest puts this
directory on ``sys.path``: the tests are not a package)."""

from __future__ import annotations

import importlib.util
import shutil
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"


def load_study(name: str) -> ModuleType:
    """The study ``problems/<name>.py`` as a module (``study_<name>``), loaded from its file."""
    spec = importlib.util.spec_from_file_location(f"study_{name}", PROBLEMS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rows_by_speed(path: Path) -> dict[float, dict[str, str]]:
    """The rows of a study's CSV keyed by their ``speed_m_per_s`` (rounded to 0.01 m/s)."""
    import csv

    with open(path, encoding="utf-8") as f:
        return {round(float(r["speed_m_per_s"]), 2): r for r in csv.DictReader(f)}


def run_study(name: str, out: Path, *extra: str) -> Path:
    """Run the study in its fast mode, writing under ``out``; the folder of its results."""
    assert load_study(name).main(["--out", str(out), "--fast", *extra]) == 0
    return out / name


def run_cli(capsys: Any, *argv: str) -> tuple[int, str, str]:
    """``gaitopt ARGV`` in-process: ``(exit status, stdout, stderr)``."""
    from gaitopt.cli import main

    status = main(list(argv))
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def console_script(name: str) -> str:
    """A console script of this interpreter's environment (the project's .venv)."""
    beside = Path(sys.executable).parent / name
    found = str(beside) if beside.exists() else shutil.which(name)
    assert found, f"the `{name}` console script is not installed beside {sys.executable}"
    return found


def cross(a: Any, b: Any) -> float:
    """The planar cross product ``a × b = a₀ b₁ − a₁ b₀``."""
    return float(a[0] * b[1] - a[1] * b[0])


def slope_at(curve: Any, value: float) -> float:
    """The first parameter of the one point of a two-parameter curve whose second parameter is
    ``value`` (to 1e-12)."""
    row = np.flatnonzero(np.abs(curve.params[:, 1] - value) < 1e-12)
    assert row.size == 1
    return float(curve.params[row[0], 0])


def simulated_return_map_fd(model: Any, s: np.ndarray, u: np.ndarray, h: float = 1e-6):
    """Central differences (step ``h``) of the return map in section coordinates, simulated by
    :func:`gaitopt.simulate` (DOP853 at rtol 1e-12, located events: an independent method, no
    shooting, no fixed-step RK8): truncation O(h²) ~ 1e-12 and the simulation's error ~1e-12 / h,
    so an exact Jacobian agrees to about 1e-6 of (1 + max |A|)."""
    import gaitopt

    def simulated(z):
        sim = gaitopt.simulate(model, model.lift(z), steps=1, inputs=u, rtol=1e-12, atol=1e-13)
        assert sim.success, sim.message
        return model.section_coordinates_of(sim.section_states[-1])

    return np.column_stack([(simulated(s + h * e) - simulated(s - h * e)) / (2 * h)
                            for e in np.eye(s.size)])  # fmt: skip
