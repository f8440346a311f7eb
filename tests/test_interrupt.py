"""Ctrl-C, and output folders that are complete or say they are not (issue 25, item 3).

An interrupt ends every command with exit status 130 and the one line ``gaitopt: interrupted``
on stderr, never a traceback; a ``--out`` folder (and ``make gaits``' ``results/<model>/``) is
written into a hidden ``*.partial`` folder and put in place at the end
(:func:`gaitopt.files.folder_written_whole`), so an interrupted run leaves no folder that looks
complete.  The end-to-end cases are real runs of the console script and of ``python -m
gaitopt.gaits``, sent SIGINT while they compute or while they write their files.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import console_script

import gaitopt
from gaitopt import cli, gaits
from gaitopt.cli.output import write_outputs
from gaitopt.files import INCOMPLETE, _signals_deferred, folder_written_whole, write_json
from gaitopt.interrupts import caused_by_interrupt, interrupts_outside_casadi


def _partials(folder: Path) -> list[Path]:
    """Staging folders (``*.partial``) under ``folder``, at any depth."""
    return sorted(folder.rglob("*.partial"))


def _wait_for(condition, proc: subprocess.Popen, timeout: float = 90.0) -> None:
    """Poll ``condition()`` until it holds (the process must still be running)."""
    deadline = time.monotonic() + timeout
    while not condition():
        assert proc.poll() is None, f"exited {proc.returncode} before it was interrupted"
        assert time.monotonic() < deadline, "the run never reached the point to interrupt"
        time.sleep(0.02)


def _interrupt(proc: subprocess.Popen) -> tuple[int, str, str]:
    """Send SIGINT (what Ctrl-C sends) and collect the exit status, stdout and stderr."""
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=90)
    return proc.returncode, out, err


def _env() -> dict[str, str]:
    return dict(os.environ, MPLBACKEND="Agg")


def _ctrl_c_delivered() -> None:
    """In the child, before it starts: SIGINT at its default.  A shell starts background jobs
    with SIGINT ignored (POSIX), and a child inherits that, so a suite run in the background
    would otherwise test nothing; Python then installs its KeyboardInterrupt handler."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.fixture(autouse=True)
def _python_sigint_handler():
    """Python's own Ctrl-C handler during each test, whatever this process inherited (see
    :func:`_ctrl_c_delivered`); the previous handler afterwards."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


# -- real runs, interrupted ----------------------------------------------------------------------
def test_ctrl_c_while_optimize_writes_its_out_folder_leaves_no_folder(tmp_path):
    """The issue's case: interrupted while it wrote the GIF, `optimize --out` left optimal.json,
    inputs.csv and the figures, a folder that looked complete.  Interrupted the moment its
    staging folder appears (the optimum found, its files being written), it must leave no
    `--out` folder at all, and say one line."""
    out = tmp_path / "gait"
    proc = subprocess.Popen(
        [console_script("gaitopt"), "optimize", "compass_gait", "--out", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=_env(),
        preexec_fn=_ctrl_c_delivered,
    )  # fmt: skip
    try:
        _wait_for(lambda: any(_partials(tmp_path)), proc)
        status, stdout, stderr = _interrupt(proc)
    finally:
        proc.kill()
    assert status == 130, stderr
    assert stderr == "gaitopt: interrupted\n"
    assert stdout == ""
    assert not out.exists() and _partials(tmp_path) == []


def test_ctrl_c_while_continue_computes_keeps_an_existing_out_folder_as_it_was(tmp_path):
    """Interrupted in the middle of the continuation: exit 130, one line, and the existing
    `--out` folder (an earlier run's branch.json, the user's notes) untouched, no marker."""
    out = tmp_path / "branch"
    out.mkdir()
    (out / "branch.json").write_text('{"from": "an earlier run"}')
    (out / "notes.txt").write_text("mine")
    # The continuation itself now takes well under a second, so no fixed delay lands inside it:
    # the child runs it for real and then stays inside the call (before the CLI writes anything)
    # until the signal comes, saying on stderr when it is there.
    code = (
        "import sys, time\n"
        "from gaitopt.cli import main\n"
        "from gaitopt.cli import continue_\n"
        "follow = continue_.continuation\n"
        "def held(*args, **kwargs):\n"
        "    branch = follow(*args, **kwargs)\n"
        "    print('computed', file=sys.stderr, flush=True)\n"
        "    while True:\n"
        "        time.sleep(0.01)\n"
        "continue_.continuation = held\n"
        "print('started', file=sys.stderr, flush=True)\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    argv = ["continue", "compass_gait", "--param", "slope", "--to", "0.09", "--out", str(out)]
    proc = subprocess.Popen(
        [sys.executable, "-c", code, *argv],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=_env(),
        preexec_fn=_ctrl_c_delivered,
    )  # fmt: skip
    try:
        assert proc.stderr.readline() == "started\n"  # imports done: main() is running
        lines = []
        while not lines or lines[-1] != "computed\n":  # the branch computed, nothing written
            lines.append(proc.stderr.readline())
            assert lines[-1], f"the child ended before it was interrupted: {lines}"
        assert proc.poll() is None, "the continuation ended before it was interrupted"
        status, stdout, stderr = _interrupt(proc)
    finally:
        proc.kill()
    assert status == 130, stderr
    assert stderr == "gaitopt: interrupted\n" and "Traceback" not in stderr
    assert stdout == ""
    assert sorted(p.name for p in out.iterdir()) == ["branch.json", "notes.txt"]
    assert (out / "branch.json").read_text() == '{"from": "an earlier run"}'
    assert _partials(tmp_path) == []


def test_ctrl_c_in_make_gaits_leaves_the_model_folder_of_the_last_complete_run(tmp_path):
    """`python -m gaitopt.gaits --out g` left a model folder with cycle.json only.  Interrupted
    while it writes the Van der Pol oscillator's files, the folder keeps the earlier run's files
    (and a study's file) unchanged, and no staging folder stays behind."""
    folder = tmp_path / "vanderpol"
    folder.mkdir()
    earlier = {"cycle.json": "{}\n", "phase_portrait.png": "earlier", "numbers.json": "study"}
    for name, text in earlier.items():
        (folder / name).write_text(text)
    proc = subprocess.Popen(
        [sys.executable, "-m", "gaitopt.gaits", "--out", str(tmp_path), "--models", "vanderpol"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=_env(),
        preexec_fn=_ctrl_c_delivered,
    )  # fmt: skip
    try:
        _wait_for(lambda: any(_partials(tmp_path)), proc)
        status, _, stderr = _interrupt(proc)
    finally:
        proc.kill()
    assert status == 130, stderr
    assert stderr == "gaitopt.gaits: interrupted\n"
    assert {p.name: p.read_text() for p in folder.iterdir()} == earlier
    assert _partials(tmp_path) == []


# -- the folder writer ---------------------------------------------------------------------------
def test_a_new_folder_appears_whole_at_the_end(tmp_path):
    target = tmp_path / "deep" / "run"
    with folder_written_whole(target) as stage:
        write_json({"a": 1}, stage / "a.json")
        (stage / "sub").mkdir()
        (stage / "sub" / "b.txt").write_text("b")
        assert not target.exists()  # nothing at the final name until the block ends
    assert json.loads((target / "a.json").read_text()) == {"a": 1}
    assert (target / "sub" / "b.txt").read_text() == "b"
    assert sorted(p.name for p in target.parent.iterdir()) == ["run"]  # no hidden leftovers


@pytest.mark.parametrize("replaces", [None, ("a.json",)])
def test_an_interrupted_write_leaves_the_folder_as_it_was(tmp_path, replaces):
    new, old = tmp_path / "new", tmp_path / "old"
    old.mkdir()
    (old / "a.json").write_text("old")
    for target in (new, old):
        with pytest.raises(KeyboardInterrupt):
            with folder_written_whole(target, replaces=replaces) as stage:
                (stage / "a.json").write_text("half")
                raise KeyboardInterrupt
    assert not new.exists()
    assert [p.name for p in old.iterdir()] == ["a.json"] and (old / "a.json").read_text() == "old"
    assert _partials(tmp_path) == [] and sorted(p.name for p in tmp_path.iterdir()) == ["old"]


def test_into_an_existing_folder_the_new_files_replace_theirs_and_the_rest_stays(tmp_path):
    (tmp_path / "optimal.json").write_text("old")
    (tmp_path / "notes.txt").write_text("mine")
    (tmp_path / "figures").mkdir()
    (tmp_path / "figures" / "old.png").write_text("old")
    with folder_written_whole(tmp_path) as stage:
        (stage / "optimal.json").write_text("new")
        (stage / "figures").mkdir()
        (stage / "figures" / "new.png").write_text("new")
        assert (tmp_path / "optimal.json").read_text() == "old"
    files = {str(p.relative_to(tmp_path)): p.read_text() for p in tmp_path.rglob("*")
             if p.is_file()}  # fmt: skip
    assert files == {"optimal.json": "new", "notes.txt": "mine", "figures/new.png": "new"}


def test_a_move_that_fails_half_way_leaves_the_folder_saying_it_is_incomplete(
    tmp_path, monkeypatch
):
    (tmp_path / "a.json").write_text("old a")
    (tmp_path / "b.json").write_text("old b")
    real_replace, moved = os.replace, []

    def replace(src, dst):
        if moved:
            raise OSError(28, "No space left on device")
        moved.append(dst)
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(OSError, match="No space"):
        with folder_written_whole(tmp_path) as stage:
            (stage / "a.json").write_text("new a")
            (stage / "b.json").write_text("new b")
    assert (tmp_path / "a.json").read_text() == "new a"  # a mix of two runs ...
    assert (tmp_path / "b.json").read_text() == "old b"
    assert "stopped" in (tmp_path / INCOMPLETE).read_text()  # ... which the folder says
    assert _partials(tmp_path) == []


def test_a_replaced_folder_keeps_what_other_tools_wrote_and_drops_stale_owned_files(tmp_path):
    folder = tmp_path / "strandbeest"
    folder.mkdir()
    for name in ("cycle.json", "walking.gif", "numbers.json", "foot_path.png"):
        (folder / name).write_text(f"old {name}")
    (folder / "study").mkdir()
    (folder / "study" / "data.csv").write_text("x")
    with folder_written_whole(folder, replaces=gaits.OWNED) as stage:
        (stage / "cycle.json").write_text("new")
    files = {str(p.relative_to(folder)): p.read_text() for p in folder.rglob("*") if p.is_file()}
    assert files == {
        "cycle.json": "new",  # rewritten
        "numbers.json": "old numbers.json",  # another tool's: carried over
        "foot_path.png": "old foot_path.png",
        "study/data.csv": "x",
    }  # walking.gif, owned and not written again, is gone
    assert sorted(p.name for p in tmp_path.iterdir()) == ["strandbeest"]


def test_ctrl_c_while_a_folder_is_put_in_place_takes_effect_after_it():
    with pytest.raises(KeyboardInterrupt):
        with _signals_deferred():
            signal.raise_signal(signal.SIGINT)
            finished = True  # not interrupted here
    assert finished
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


# -- the CLI and make gaits in process ------------------------------------------------------------
def test_a_writer_that_fails_loses_no_result_and_says_so_in_one_line(tmp_path):
    def write(folder: Path) -> None:
        write_json({"period": 1.0}, folder / "optimal.json")
        raise ValueError("the figure cannot be drawn")

    message = write_outputs(str(tmp_path / "run"), write)
    assert message == (
        f"gaitopt: error: --out {tmp_path / 'run'}: writing the files failed (ValueError: the "
        f"figure cannot be drawn); nothing was written there"
    )
    assert sorted(tmp_path.iterdir()) == []


def test_an_out_under_a_file_falls_back_and_says_where(tmp_path, monkeypatch):
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    (tmp_path / "a_file").write_text("keep me")
    message = write_outputs(
        str(tmp_path / "a_file" / "run"), lambda f: (f / "x.json").write_text("{}")
    )
    assert message.startswith(f"gaitopt: error: --out {tmp_path / 'a_file' / 'run'}: cannot ")
    fallback = Path(message.rsplit("written to ", 1)[1].removesuffix(" instead"))
    assert fallback.parent == tmp_path and (fallback / "x.json").read_text() == "{}"
    assert (tmp_path / "a_file").read_text() == "keep me" and _partials(tmp_path) == []


def test_make_gaits_interrupted_in_process_exits_130_with_one_line(tmp_path, monkeypatch, capsys):
    def interrupted(model, cycle, folder, previous=None):
        (folder / "cycle.json").write_text("{}")
        raise KeyboardInterrupt

    monkeypatch.setattr(gaits, "find_limit_cycle", lambda model: None)
    monkeypatch.setattr(gaits, "_write_model", interrupted)
    assert gaits.main(["--out", str(tmp_path), "--models", "vanderpol"]) == 130
    assert capsys.readouterr().err == "gaitopt.gaits: interrupted\n"
    assert list(tmp_path.iterdir()) == []


# -- Ctrl-C inside CasADi ----------------------------------------------------------------------
def _casadi_mangled() -> SystemError:
    """What CasADi's ``DM.full`` raises when Ctrl-C lands in its Python ``toarray``."""
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError(
                "<function DM.__array__> returned a result with an exception set"
            ) from exc
    except SystemError as exc:
        return exc


def test_an_interrupt_turned_into_another_error_is_recognised():
    assert caused_by_interrupt(KeyboardInterrupt())
    assert caused_by_interrupt(_casadi_mangled())
    assert not caused_by_interrupt(SystemError("a bug"))
    try:
        try:
            raise ValueError("first")
        except ValueError:
            raise RuntimeError("then")  # noqa: B904 (the implicit context is the point)
    except RuntimeError as exc:
        assert not caused_by_interrupt(exc)


def test_the_cli_exits_130_for_an_interrupt_that_casadi_turned_into_a_system_error(
    capsys, monkeypatch
):
    def solve(*args, **kwargs):
        raise _casadi_mangled()

    monkeypatch.setattr(cli.solve, "find_limit_cycle", solve)
    assert cli.main(["solve", "compass_gait", "--json"]) == 130
    out, err = capsys.readouterr()
    assert out == "" and err == "gaitopt: interrupted\n"


def test_an_interrupt_landing_in_casadi_code_is_raised_just_after_it():
    """The handler does not raise inside CasADi's package (its C++ core would lose the
    exception); it sends SIGINT again and raises it in the caller's code."""
    import casadi

    in_casadi = os.path.join(os.path.dirname(casadi.__file__), "casadi.py")
    code = compile(
        "signal.raise_signal(signal.SIGINT)\nfinished.append(True)\n", in_casadi, "exec"
    )  # runs as if it were CasADi's own Python code
    finished: list[bool] = []
    with pytest.raises(KeyboardInterrupt):
        with interrupts_outside_casadi():
            exec(code, {"signal": signal, "finished": finished})
            assert finished == [True]  # not interrupted inside
            deadline = time.monotonic() + 5.0
            while time.monotonic() < deadline:  # ... but here, a moment later
                time.sleep(0.001)
    assert finished == [True] and time.monotonic() < deadline
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_outside_casadi_an_interrupt_is_raised_at_once():
    with pytest.raises(KeyboardInterrupt):
        with interrupts_outside_casadi():
            signal.raise_signal(signal.SIGINT)
            raise AssertionError("not interrupted")
    assert gaitopt.model("compass_gait")  # the library works on afterwards


# -- make gaits: an output folder that cannot be written -----------------------------------------
def test_make_gaits_refuses_an_unusable_out_before_any_work(tmp_path, capsys, monkeypatch):
    def never(model):
        raise AssertionError("solved before --out was checked")

    monkeypatch.setattr(gaits, "find_limit_cycle", never)
    (tmp_path / "a_file").write_text("keep me")
    out = str(tmp_path / "a_file" / "results")
    assert gaits.main(["--out", out, "--models", "vanderpol"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"gaitopt.gaits: error: --out {out}: ") and len(err.splitlines()) == 1
    assert "is a file" in err and (tmp_path / "a_file").read_text() == "keep me"


def test_make_gaits_keeps_a_solved_gait_whose_folder_cannot_be_written(tmp_path):
    (tmp_path / "a_file").write_text("keep me")  # out/vanderpol would be under a file
    cycle, written, errors = gaits.run_model("vanderpol", tmp_path / "a_file")
    assert cycle.success and written == []
    assert len(errors) == 1 and errors[0].startswith(f"{tmp_path / 'a_file' / 'vanderpol'}: ")
    assert "cannot write there" in errors[0] and (tmp_path / "a_file").read_text() == "keep me"
