"""A model from another package, found through the ``gaitopt.models`` entry point group.

docs/writing-a-model.md tells a user to put the worked example in a package and declare it as an
entry point.  This test does exactly that, end to end: a separate tiny package in a temporary
folder (its module is the document's Python block, its entry-point table the document's TOML
block, both copied out of the document, so the document is what is tested), installed by pip into
a temporary ``--target`` folder, then ``gaitopt solve kicked_ball --json`` (the console script)
and ``gaitopt.model("kicked_ball")`` in fresh processes that see that folder on ``PYTHONPATH``.

The package is built offline by a minimal PEP 517 backend written beside it (``backend-path``):
the project's ``.venv`` has no wheel-building setuptools (``pip install -e`` fetched one into an
isolated build environment), and a test must not need the network.  The backend writes what any
backend writes for the declared entry points (``entry_points.txt`` in the wheel's ``.dist-info``,
from ``[project.entry-points]``); pip installs the wheel as usual.

In process, on the same module: the ``@register`` decorator, registering the same class again
(a no-op), a different class under a taken name (refused), and entry points that name the module
alone, do not load, or carry another name than their model (each one clear line).
"""

from __future__ import annotations

import importlib
import json
import os
import re
import subprocess
import sys
import textwrap
from importlib.metadata import EntryPoint
from pathlib import Path

import pytest
from helpers import console_script

import gaitopt
import gaitopt.models
from gaitopt.cli import main
from gaitopt.errors import GaitoptInputError, UnknownModelError
from gaitopt.models import ENTRY_POINT_GROUP

DOC = Path(__file__).resolve().parents[1] / "docs" / "writing-a-model.md"

#: The minimal build backend: a wheel with the package's files and the entry points of
#: pyproject.toml's [project.entry-points] tables.
BACKEND = '''
"""A minimal PEP 517 backend (tests/test_entry_points.py): pure-Python packages only."""

import base64
import hashlib
import os
import zipfile

try:
    import tomllib
except ImportError:  # Python 3.10: pip's own TOML parser
    from pip._vendor import tomli as tomllib


def _project():
    with open("pyproject.toml", "rb") as fh:
        return tomllib.load(fh)["project"]


def _record(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    project = _project()
    dist = project["name"].replace("-", "_")
    info = f"{dist}-{project['version']}.dist-info"
    files = {}
    for root, _, names in os.walk(dist):
        for name in names:
            if name.endswith(".py"):
                path = os.path.join(root, name)
                with open(path, "rb") as fh:
                    files[path.replace(os.sep, "/")] = fh.read()
    files[f"{info}/METADATA"] = (
        f"Metadata-Version: 2.1\\nName: {project['name']}\\nVersion: {project['version']}\\n"
    ).encode()
    files[f"{info}/WHEEL"] = (
        b"Wheel-Version: 1.0\\nGenerator: test-backend\\nRoot-Is-Purelib: true\\n"
        b"Tag: py3-none-any\\n"
    )
    groups = project.get("entry-points", {})
    files[f"{info}/entry_points.txt"] = "".join(
        f"[{group}]\\n" + "".join(f"{k} = {v}\\n" for k, v in entries.items()) + "\\n"
        for group, entries in groups.items()
    ).encode()
    record = [_record(name, data) for name, data in files.items()] + [f"{info}/RECORD,,"]
    files[f"{info}/RECORD"] = ("\\n".join(record) + "\\n").encode()
    wheel = f"{dist}-{project['version']}-py3-none-any.whl"
    with zipfile.ZipFile(os.path.join(wheel_directory, wheel), "w") as zf:
        for name, data in files.items():
            zf.writestr(name, data)
    return wheel
'''


def _doc_blocks(language: str) -> list[str]:
    """The fenced code blocks of docs/writing-a-model.md in ``language``."""
    return re.findall(rf"^```{language}\n(.*?)^```", DOC.read_text(encoding="utf-8"), re.M | re.S)


def _example_module() -> str:
    """The document's worked example: its (only) Python block that defines ``KickedBall``."""
    blocks = [b for b in _doc_blocks("python") if "class KickedBall" in b]
    assert len(blocks) == 1, "docs/writing-a-model.md: expected one worked example"
    return blocks[0]


def _entry_point_table() -> str:
    """The document's ``[project.entry-points."gaitopt.models"]`` TOML block."""
    blocks = [b for b in _doc_blocks("toml") if '[project.entry-points."gaitopt.models"]' in b]
    assert len(blocks) == 1, "docs/writing-a-model.md: expected one entry-point table"
    return blocks[0]


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """The environment of a process that has the example package installed (by pip, offline)."""
    root = tmp_path_factory.mktemp("entry_points")
    source, target = root / "my_package_src", root / "site"
    table = _entry_point_table()
    module, _, attribute = re.search(r'kicked_ball = "([\w.]+:\w+)"', table)[1].partition(":")
    package, _, module_name = module.rpartition(".")
    (source / package.replace(".", "/")).mkdir(parents=True)
    (source / package.replace(".", "/") / "__init__.py").write_text("")
    (source / f"{module.replace('.', '/')}.py").write_text(_example_module(), encoding="utf-8")
    (source / "backend.py").write_text(BACKEND, encoding="utf-8")
    (source / "pyproject.toml").write_text(
        textwrap.dedent(
            f"""\
            [build-system]
            requires = []
            build-backend = "backend"
            backend-path = ["."]

            [project]
            name = "{package.replace("_", "-")}"
            version = "0.1.0"

            """
        )
        + table,
        encoding="utf-8",
    )
    assert attribute == "KickedBall" and module_name == "kicked_ball"
    pip = [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-index"]
    proc = subprocess.run(
        [*pip, "--no-build-isolation", "--target", str(target), str(source)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert (target / package / "kicked_ball.py").exists()
    env = dict(os.environ, PYTHONPATH=str(target), MPLBACKEND="Agg")
    env.pop("PYTHONSTARTUP", None)
    return env


def test_the_console_script_solves_a_model_declared_by_an_entry_point(installed, tmp_path):
    # Closed form (docs/writing-a-model.md): v* = Δv/(1 − e) = 4 m/s, multiplier e = 0.5.
    proc = subprocess.run(
        [console_script("gaitopt"), "solve", "kicked_ball", "--json"],
        capture_output=True, text=True, env=installed, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    gait = json.loads(proc.stdout)
    assert gait["model"] == "kicked_ball" and gait["success"] and gait["status"] == "success"
    assert gait["fixed_point"]["v"] == pytest.approx(4.0, abs=1e-9)
    assert gait["multipliers"][0][0] == pytest.approx(0.5, abs=1e-9)


def test_gaitopt_list_lists_a_model_declared_by_an_entry_point(installed, tmp_path):
    proc = subprocess.run(
        [console_script("gaitopt"), "list", "--json"],
        capture_output=True, text=True, env=installed, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    names = [entry["name"] for entry in json.loads(proc.stdout)]
    assert names[-1] == "kicked_ball" and names[:-1] == list(gaitopt.REGISTRY)


def test_the_api_builds_a_model_declared_by_an_entry_point(installed, tmp_path):
    # Loading the entry point imports the module, whose @gaitopt.register registers the class;
    # the loader then registers the same class again: idempotent, not "already registered".
    code = (
        "import gaitopt\n"
        "m = gaitopt.model('kicked_ball', kick=1.0)\n"
        "assert type(m).__module__ == 'my_package.kicked_ball', type(m).__module__\n"
        "assert gaitopt.model('kicked_ball') == type(m)()\n"
        "print(gaitopt.find_limit_cycle(m).fixed_point['v'])\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True, text=True, env=installed, cwd=tmp_path, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert float(proc.stdout) == pytest.approx(2.0, abs=1e-9)  # Δv/(1 − e) with Δv = 1


# -- in process: the decorator, the registry, entry points that are wrong -----------------------
@pytest.fixture
def example(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """The document's module as an importable module ``kicked_ball_doc`` (not imported yet);
    unregistered and forgotten afterwards."""
    (tmp_path / "kicked_ball_doc.py").write_text(_example_module(), encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        yield "kicked_ball_doc"
    finally:
        gaitopt.unregister("kicked_ball")
        sys.modules.pop("kicked_ball_doc", None)


def _declare(monkeypatch: pytest.MonkeyPatch, **entries: str) -> None:
    """Installed packages that declare ``name = "module:attribute"`` in ``gaitopt.models``."""
    declared = [EntryPoint(name, value, ENTRY_POINT_GROUP) for name, value in entries.items()]
    monkeypatch.setattr(gaitopt.models, "_entry_points", lambda: declared)


def test_registering_the_same_class_again_is_idempotent(example):
    cls = importlib.import_module(example).KickedBall  # its @gaitopt.register ran
    assert gaitopt.REGISTRY["kicked_ball"] is cls
    assert gaitopt.register(cls) is cls
    assert gaitopt.REGISTRY["kicked_ball"] is cls


def test_a_different_class_under_a_taken_name_is_refused(example):
    cls = importlib.import_module(example).KickedBall
    other = type("KickedBall", (cls,), {"__module__": "somewhere_else"})
    with pytest.raises(GaitoptInputError, match=r"'kicked_ball' is already registered"):
        gaitopt.register(other)
    assert gaitopt.REGISTRY["kicked_ball"] is cls


@pytest.mark.parametrize("target", ["kicked_ball_doc:KickedBall", "kicked_ball_doc"])
def test_an_entry_point_naming_the_class_or_its_module_registers_the_model(
    example, monkeypatch, target
):
    _declare(monkeypatch, kicked_ball=target)
    assert "kicked_ball" not in gaitopt.REGISTRY and example not in sys.modules
    assert gaitopt.models.model_names()[-1] == "kicked_ball"  # known, not imported yet
    assert example not in sys.modules
    walker = gaitopt.model("kicked_ball", kick=1.0)
    assert type(walker) is sys.modules[example].KickedBall is gaitopt.REGISTRY["kicked_ball"]
    assert walker.kick == 1.0


def test_an_entry_point_that_does_not_load_is_one_line_naming_it(monkeypatch, capsys):
    _declare(monkeypatch, broken_ball="no_such_package.balls:Ball")
    with pytest.raises(UnknownModelError, match=r"broken_ball = no_such_package\.balls:Ball") as e:
        gaitopt.model("broken_ball")
    assert "ModuleNotFoundError" in str(e.value) and "reinstall" in str(e.value)
    assert main(["solve", "broken_ball"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    assert err.startswith("gaitopt: error: MODEL broken_ball: ") and "no_such_package" in err
    # `gaitopt list` warns about it and lists every other model.
    assert main(["list", "--json"]) == 0
    out, err = capsys.readouterr()
    assert [m["name"] for m in json.loads(out)] == list(gaitopt.REGISTRY)
    assert len(err.splitlines()) == 1 and err.startswith("gaitopt: warning: model 'broken_ball'")
    assert "broken_ball" not in gaitopt.REGISTRY


def test_an_entry_point_named_unlike_its_model_is_refused(example, monkeypatch):
    _declare(monkeypatch, kicked=f"{example}:KickedBall")
    with pytest.raises(UnknownModelError, match="gives a model named 'kicked_ball'"):
        gaitopt.model("kicked")


def test_an_unknown_name_is_refused_with_the_declared_models_listed(example, monkeypatch, capsys):
    _declare(monkeypatch, kicked_ball=f"{example}:KickedBall")
    with pytest.raises(UnknownModelError, match=r"did you mean 'kicked_ball'\?.*kicked_ball"):
        gaitopt.model("kicked_bal")
    assert main(["solve", "kicked_bal"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    assert err.startswith("gaitopt: error: MODEL 'kicked_bal' is not a model; did you mean")
    assert example not in sys.modules  # nothing was imported for a name that is not declared
