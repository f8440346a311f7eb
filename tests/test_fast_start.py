"""A fast start (issue 23): what a warm ``gaitopt solve`` process may skip, and that skipping
never serves a stale result.  The source digest that keys the kernel cache is remembered under a
stamp of the files' sizes and times (a changed file never finds it); a built-in model's symbolic
structure is unpickled from the cache (the same CasADi graphs: the same generated code); the
``gaitopt`` command starts NumPy's BLAS with one thread instead of limiting it with threadpoolctl.
Every check compares with an independent computation or inspects a fresh process's modules."""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import subprocess
import sys
import time
from pathlib import Path

import casadi as ca
import pytest

import gaitopt
from gaitopt.hybrid import HybridModel
from gaitopt.kernels import cache
from gaitopt.models import BUILTIN, model_class

ROOT = Path(gaitopt.__file__).parent


def _independent_digest(root: Path) -> str:
    """The digest as the cache defined it before it was remembered: ``sorted(rglob)``, each
    file's relative path then its bytes, read now (no memo involved)."""
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


# -- the remembered source digest ----------------------------------------------------------------
def test_package_digest_equals_reading_every_source():
    assert cache.tree_digest(ROOT) == _independent_digest(ROOT)


def _tree(root: Path) -> Path:
    (root / "sub").mkdir(parents=True)
    (root / "a.py").write_text("x = 1\n")
    (root / "sub" / "b.py").write_text("y = 2\n")
    (root / "notes.txt").write_text("not a source")
    return root


def test_a_changed_source_never_finds_the_remembered_digest(monkeypatch, tmp_path):
    monkeypatch.setenv("GAITOPT_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(cache, "_SETTLED_S", 0.05)  # the files below are older than that
    root = _tree(tmp_path / "pkg")
    time.sleep(0.1)
    assert cache.tree_digest(root) == _independent_digest(root)
    memos = list((tmp_path / "cache" / "sources").iterdir())
    assert len(memos) == 1
    # The memo is what a second look-up returns (a stand-in value proves it is read) ...
    memos[0].write_text("0" * 64)
    assert cache.tree_digest(root) == "0" * 64
    # ... until any source changes: same size, its modification time set back, one byte else.
    b = root / "sub" / "b.py"
    before = b.stat()
    b.write_text("y = 3\n")
    os.utime(b, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert b.stat().st_size == before.st_size and b.stat().st_mtime_ns == before.st_mtime_ns
    assert cache.tree_digest(root) == _independent_digest(root) != "0" * 64
    # A new source and a renamed one change it too; a file that is no source does not count.
    (root / "c.py").write_text("")
    assert cache.tree_digest(root) == _independent_digest(root)
    (root / "c.py").rename(root / "d.py")
    assert cache.tree_digest(root) == _independent_digest(root)
    (root / "notes.txt").write_text("changed")
    assert cache.tree_digest(root) == _independent_digest(root)


def test_a_digest_of_fresh_files_is_not_remembered(monkeypatch, tmp_path):
    # Files changed within _SETTLED_S of the look-up: a timestamp's granularity could hide a
    # second change, so nothing is remembered (the next process reads the sources again).
    monkeypatch.setenv("GAITOPT_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(cache, "_SETTLED_S", 3600.0)
    root = _tree(tmp_path / "pkg")
    assert cache.tree_digest(root) == _independent_digest(root)
    assert not (tmp_path / "cache" / "sources").exists()


# -- the remembered model structure --------------------------------------------------------------
def _generated(functions: list[ca.Function]) -> str:
    gen = ca.CodeGenerator("check.c", {"with_header": False})
    for f in functions:
        gen.add(f)
    return gen.dump()


def _same_generated_code(cls, monkeypatch) -> None:
    """A model class's structure as built and as a later process unpickles it: the C code of
    its shooting kernels (where it has them), its RK steps and its simulation arcs is the same
    text (so the same libraries, the same numbers)."""
    from gaitopt.kernels.arcs import _functions as arc_functions
    from gaitopt.kernels.symbolic import kernel_functions, step_functions

    built = cls._build_structure()
    loaded = pickle.loads(pickle.dumps(built, protocol=pickle.HIGHEST_PROTOCOL))
    codes = []
    for structure in (built, loaded):
        monkeypatch.setitem(HybridModel._cache, cls, structure)
        code = [_generated(step_functions(cls)), _generated(arc_functions(cls, True))]
        try:
            code.append(_generated(kernel_functions(cls)))
        except TypeError:  # a flow with no SX form (the ballistic walker): no shooting kernels
            code.append("none")
        codes.append(code)
    assert codes[0] == codes[1]
    assert loaded.section.coordinates == built.section.coordinates
    assert [p.states for p in loaded.phases] == [p.states for p in built.phases]


def test_unpickled_structure_generates_the_same_kernels(monkeypatch):
    _same_generated_code(model_class("compass_gait"), monkeypatch)


@pytest.mark.slow  # every built-in model: minutes (the Strandbeest's graphs alone take ~15 s)
@pytest.mark.parametrize("name", sorted(BUILTIN))
def test_every_unpickled_structure_generates_the_same_kernels(name, monkeypatch):
    _same_generated_code(model_class(name), monkeypatch)


def test_remembered_is_rebuilt_when_the_sources_change(monkeypatch, tmp_path):
    monkeypatch.setenv("GAITOPT_CACHE", str(tmp_path))
    if cache.compiler() is None:
        pytest.skip("no C compiler: nothing is remembered (the source key is None)")
    cls = model_class("vanderpol")
    builds = []

    def build():
        builds.append(1)
        return {"value": len(builds)}

    assert cache.remembered("probe", cls, build) == {"value": 1}
    assert cache.remembered("probe", cls, build) == {"value": 1} and len(builds) == 1
    # Another source digest (any source of the package changed): another key, built again.
    monkeypatch.setattr(cache, "_package_digest", lambda: "f" * 64)
    assert cache.remembered("probe", cls, build) == {"value": 2}
    # A damaged file is rebuilt and replaced; a value that cannot be pickled is not kept.
    for path in (tmp_path / "objects").glob("probe_*"):
        path.write_bytes(b"not a pickle")
    assert cache.remembered("probe", cls, build) == {"value": 3}
    assert cache.remembered("probe", cls, build) == {"value": 3}
    before = sorted(p.name for p in (tmp_path / "objects").iterdir())
    assert callable(cache.remembered("lambda", cls, lambda: lambda: None))
    assert sorted(p.name for p in (tmp_path / "objects").iterdir()) == before


def test_a_model_defined_outside_gaitopt_is_always_built(monkeypatch, tmp_path):
    # Its module may depend on code the source key does not see.
    monkeypatch.setenv("GAITOPT_CACHE", str(tmp_path))
    Local = type("Local", (model_class("vanderpol"),), {"__module__": "elsewhere"})
    builds = []
    for _ in range(2):
        cache.remembered("probe", Local, lambda: builds.append(1))
    assert len(builds) == 2 and not (tmp_path / "objects").exists()


def test_only_built_in_classes_without_build_side_effects_are_unpickled():
    # A class made at run time inside gaitopt (an HZD closed loop, an optimum's feedforward) is
    # named alike for different contents, and the three-link walker's build() fills its output
    # functions' table: none may take an unpickled structure (a fresh process computing the
    # three-link walker's torques once failed that way).  The plain built-in models may.
    from gaitopt.hzd import virtual_constraint_model

    assert model_class("compass_gait")._may_remember_structure()
    assert not model_class("three_link_walker")._may_remember_structure()
    closed = virtual_constraint_model(gaitopt.model("three_link_walker"), 4)
    assert closed.__module__.startswith("gaitopt.")
    assert not closed._may_remember_structure()
    code = (
        "import numpy as np, gaitopt\n"
        "m = gaitopt.model('three_link_walker')\n"
        "print(m.torques(np.array([-0.39, 0.39, 0.39, 0.8, -0.26, 1.6])).tolist())\n"
    )
    runs = [
        subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        for _ in range(2)
    ]
    assert runs[0].stdout == runs[1].stdout != ""


# -- the command's start -------------------------------------------------------------------------
def test_the_command_starts_blas_with_one_thread_and_imports_no_extras():
    """A fresh ``gaitopt solve compass_gait --json`` (the cache warm): importing the CLI loads
    no NumPy (so BLAS starts with its thread count from the environment), the solve runs with
    one BLAS thread without threadpoolctl, and it imports none of what only a cold cache,
    ``--out`` or ``--version`` needs."""
    if cache.compiler() is None:
        pytest.skip("no C compiler: the simulation runs SciPy's stepper")
    script = (
        "import sys, json, contextlib, io\n"
        "from gaitopt.cli import main\n"
        "early = 'numpy' in sys.modules\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    status = main(['solve', 'compass_gait', '--json'])\n"
        "loaded = sorted(sys.modules)\n"
        "from threadpoolctl import threadpool_info\n"
        "blas = {i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas'}\n"
        "print(json.dumps([early, status, sorted(blas), loaded]))\n"
    )
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    env.update(PYTHONPATH=str(ROOT.parent), GAITOPT_BLAS_THREADS="1")
    for _ in range(2):  # the first run warms the cache (a cold one compiles and writes)
        out = subprocess.run(
            [sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True
        ).stdout
    early, status, threads, loaded = json.loads(out.strip().splitlines()[-1])
    assert early is False and status == 0 and threads == [1]
    never = ("threadpoolctl", "importlib.metadata", "subprocess", "tempfile", "uuid")
    assert [m for m in never if m in loaded] == []


def test_bench_process_fast_mode(tmp_path, monkeypatch):
    """``python -m bench.process`` (one round, no Drake): the command exits 0, the five stages
    are timed, and the second solve inside repeats the first's fixed point."""
    monkeypatch.syspath_prepend(str(ROOT.parent))
    from bench import process

    out = tmp_path / "bench_process.json"
    assert process.main(["--repeats", "1", "--no-peers", "--out", str(out)]) == 0
    record = json.loads(out.read_text())
    assert record["processes"]["gaitopt"]["exit_codes"] == [0]
    assert record["processes"]["baseline"]["exit_codes"] == [0]
    assert record["processes"]["drake"] == {"skipped": "off"}
    stages = [v["cpu_median_s"] for k, v in record["stages"].items() if k != "load_1min"]
    assert len(stages) == 5 and all(s > 0 for s in stages)
    assert record["inside"]["same"] is True and record["modules"] > 10
