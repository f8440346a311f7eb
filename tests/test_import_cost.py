"""What a fresh process imports (issue 23): ``import gaitopt`` and ``gaitopt solve`` import only
what they use.  Each check runs a new interpreter (``sys.modules`` of the test process holds
everything the other tests imported) and asserts on the module names it reports — the property
itself, not a timing."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import gaitopt
from gaitopt.cli import SUBCOMMANDS
from gaitopt.models import BUILTIN, REGISTRY

ROOT = Path(gaitopt.__file__).parent


def _modules_after(code: str) -> set[str]:
    """The names in ``sys.modules`` after ``code`` runs in a fresh interpreter."""
    script = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    env = {**os.environ, "PYTHONPATH": str(ROOT.parent), "MPLBACKEND": "Agg"}
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True
    ).stdout
    return set(json.loads(out.strip().splitlines()[-1]))


def _under(modules: set[str], *prefixes: str) -> list[str]:
    return sorted(m for m in modules if any(m == p or m.startswith(p + ".") for p in prefixes))


#: Never needed to find and verify a gait: plotting, Dask, and the other subsystems of gaitopt.
_NOT_ON_THE_SOLVE_PATH = (
    "matplotlib",
    "dask",
    "distributed",
    "pandas",
    "gaitopt.basin",
    "gaitopt.continuation",
    "gaitopt.curves",
    "gaitopt.optimize",
    "gaitopt.plotting",
    "gaitopt.control",
    "gaitopt.sweep",
    "gaitopt.hzd",
    "gaitopt.transverse",
)


def test_import_gaitopt_imports_no_numerics():
    """``import gaitopt`` binds the public names lazily (PEP 562): NumPy, CasADi and SciPy wait
    for the first call."""
    modules = _modules_after("import gaitopt")
    assert _under(modules, "numpy", "casadi", "scipy", "matplotlib") == []


def test_solve_path_imports_only_what_it_uses():
    """Finding and verifying the compass gait imports one model's module, none of the subsystems
    above and not ``scipy.integrate``: with a C compiler the guess and the verification simulate
    in compiled arcs, whose dense output is :mod:`gaitopt.simulation.dense` (without one they run
    SciPy's stepper, which is ``scipy.integrate``'s)."""
    from gaitopt.kernels.cache import compiler

    if compiler() is None:
        pytest.skip("no C compiler: the simulation runs SciPy's stepper")
    solve = "import gaitopt\nassert gaitopt.find_limit_cycle(gaitopt.model('compass_gait')).success"
    _modules_after(solve)  # the kernel cache warm
    modules = _modules_after(solve)
    assert _under(modules, *_NOT_ON_THE_SOLVE_PATH, "scipy.integrate") == []
    model_files = {f"gaitopt.models.{module}" for module, _ in BUILTIN.values()}
    assert sorted(model_files & modules) == ["gaitopt.models.compass_gait"]


def test_optimise_path_imports_no_scipy():
    """The compass gait's optimum (level, 0.3 m in 0.8 s: ``bench.first_call``'s call), solved
    and verified, imports none of SciPy: the referee and the finite-difference multipliers
    simulate the input profile with :class:`gaitopt.dop853.CompiledDOP853` in SciPy's DOP853
    frame restated (:mod:`gaitopt.dop853_base`), its crossings by :func:`gaitopt.brent.brentq`,
    and the BLAS limit loads SciPy's OpenBLAS without ``scipy.linalg``."""
    from gaitopt.kernels.cache import compiler

    if compiler() is None:
        pytest.skip("no C compiler: the guess's simulation runs SciPy's stepper")
    optimise = (
        "import gaitopt\n"
        "g = gaitopt.optimize_gait(gaitopt.model('compass_gait', slope=0.0), period=0.8, "
        "step_length=0.3)\n"
        "assert g.success and g.verified and g.multipliers_fd is not None, g.message"
    )
    _modules_after(optimise)  # the kernel cache warm
    modules = _modules_after(optimise)
    assert _under(modules, "scipy.integrate", "scipy.optimize", "scipy.linalg") == []
    assert _under(modules, "scipy") == []


def test_cli_imports_the_chosen_subcommand_only():
    """``gaitopt solve`` declares and runs the solve subcommand's module alone."""
    modules = _modules_after(
        "from gaitopt.cli import main\n"
        "import contextlib, io\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['solve', 'compass_gait', '--json']) == 0"
    )
    subcommands = {m for m in _under(modules, "gaitopt.cli") if m.count(".") == 2}
    assert subcommands == {"gaitopt.cli.common", "gaitopt.cli.output", "gaitopt.cli.solve"}
    assert _under(modules, *_NOT_ON_THE_SOLVE_PATH) == []


def test_cli_help_matches_the_modules():
    """The lazily declared subcommands carry the help their modules state (``HELP``)."""
    import importlib

    for name, command in SUBCOMMANDS.items():
        module = importlib.import_module(f"gaitopt.cli.{command.run.__qualname__.split('.')[0]}")
        if hasattr(module, "HELP"):
            assert command.help == module.HELP, name


def test_registry_table_names_each_class():
    """:data:`gaitopt.models.BUILTIN` agrees with each class's ``name``; the registry lists the
    names before importing the classes, and ``gaitopt.models.<Class>`` gives the same class."""
    import gaitopt.models as models

    for name, (_, cls_name) in BUILTIN.items():
        cls = REGISTRY[name]
        assert cls.name == name and cls.__name__ == cls_name
        assert getattr(models, cls_name) is cls
    assert list(REGISTRY)[: len(BUILTIN)] == list(BUILTIN)


@pytest.mark.slow  # ~20 s idle, over a minute on the loaded 2-core machine (one fork per module)
def test_every_module_imports_in_a_fresh_process():
    """Any module can be imported first (no half-initialised package on the way: the lazy
    package no longer imports everything in one fixed order).  A forked child per module after
    the third-party libraries are loaded, so only gaitopt's own order is exercised."""
    script = (
        "import importlib, os, sys, pathlib\n"
        "import numpy, casadi, scipy.integrate, scipy.optimize\n"
        f"root = pathlib.Path({str(ROOT)!r})\n"
        "failed = []\n"
        "for path in sorted(root.rglob('*.py')):\n"
        "    parts = list(path.relative_to(root.parent).with_suffix('').parts)\n"
        "    if parts[-1] == '__main__': continue\n"
        "    if parts[-1] == '__init__': parts.pop()\n"
        "    name = '.'.join(parts)\n"
        "    pid = os.fork()\n"
        "    if pid == 0:\n"
        "        try: importlib.import_module(name)\n"
        "        except BaseException as exc: print(name, repr(exc)); os._exit(1)\n"
        "        os._exit(0)\n"
        "    if os.waitpid(pid, 0)[1]: failed.append(name)\n"
        "print('FAILED', failed)\n"
    )
    if not hasattr(os, "fork"):
        pytest.skip("needs os.fork")
    env = {**os.environ, "PYTHONPATH": str(ROOT.parent), "MPLBACKEND": "Agg"}
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True
    ).stdout
    assert out.strip().splitlines()[-1] == "FAILED []", out


def test_blas_limit_without_importing_scipy_linalg():
    """:mod:`gaitopt.threads` limits the loaded BLAS without loading SciPy's (its OpenBLAS would
    start a worker thread that spins for 0.1 s); an OpenBLAS loaded inside the limit (SciPy's,
    by ``import scipy.linalg``) starts with the limit's thread count, and the environment is
    restored after."""
    script = (
        "import os, sys\n"
        "from threadpoolctl import threadpool_info\n"
        "from gaitopt.threads import _limits\n"
        "def scipys(): return [i for i in threadpool_info() if 'scipy.libs' in i['filepath']]\n"
        "with _limits(1):\n"
        "    before = 'scipy.linalg' in sys.modules or bool(scipys())\n"
        "    import scipy.linalg\n"
        "    inside = sorted({i['num_threads'] for i in threadpool_info() if i['user_api'] == "
        "'blas'})\n"
        "    loaded = bool(scipys())\n"
        "print(before, inside, loaded, os.environ.get('OPENBLAS_NUM_THREADS'))\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT.parent)}
    env.pop("OPENBLAS_NUM_THREADS", None)
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True
    ).stdout
    assert out.strip() == "False [1] True None"
