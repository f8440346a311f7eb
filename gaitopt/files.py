"""Files and folders written whole or not at all, and values made strict JSON.

Every file gaitopt writes (``cycle.json``, figures, GIFs, ``bench.json``) goes through
:func:`replaced_atomically`: the content is written to a hidden temporary file in the same
directory and moved into place with :func:`os.replace`, so a reader sees the old file or the new
one, never a part.  A folder of results (``gaitopt ... --out DIR``, ``results/<model>/`` of
``make gaits``) goes through :func:`folder_written_whole`: its files are written into a hidden
``*.partial`` folder and put in place at the end, so an interrupted run (Ctrl-C) leaves no folder
that looks complete.  :func:`jsonable` turns results (NumPy arrays and scalars, non-finite floats,
complex numbers) into plain JSON types; :func:`write_json` combines the two.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .errors import GaitoptInputError

__all__ = [
    "replaced_atomically",
    "folder_written_whole",
    "INCOMPLETE",
    "jsonable",
    "write_json",
    "write_csv",
    "check_output_folder",
    "write_or_fall_back",
]


def _token() -> str:
    """12 random hex digits naming a temporary sibling (as ``uuid.uuid4().hex[:12]``, without
    importing :mod:`uuid`)."""
    return os.urandom(6).hex()


@contextlib.contextmanager
def replaced_atomically(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """Write a file whole or not at all: yield a temporary path, then move it onto ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        The file to (re)place.  Its directory must exist.
    suffix : str
        Suffix of the temporary name, for writers that pick the format from it (Pillow: ``".gif"``).

    Yields
    ------
    pathlib.Path
        A fresh hidden name beside ``path`` (same directory, so :func:`os.replace` is atomic),
        ``.<name>.<random><suffix>``; nothing exists there yet.  The caller writes the file.

    Notes
    -----
    On normal exit of the block the temporary file replaces ``path``.  If the block raises, the
    exception propagates and ``path`` is left untouched.  Either way the temporary file is
    removed if it still exists.

    Examples
    --------
    >>> with replaced_atomically("figure.png") as tmp:  # doctest: +SKIP
    ...     fig.savefig(tmp, format="png")
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{_token()}{suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


#: The file that says a folder's results are incomplete, while they are moved into a folder
#: that already existed (see :func:`folder_written_whole`); removed once they are all in place.
INCOMPLETE = "gaitopt-INCOMPLETE.txt"


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) and SIGTERM while the block runs; deliver them when it ends.

    The block is a handful of renames that put a folder of results in place: interrupted half
    way, the folder would mix two runs.  A signal received meanwhile is recorded and raised again
    with the previous handler restored, so Ctrl-C still ends the program (a moment later) with
    its :class:`KeyboardInterrupt`.  Signals whose handler is ``SIG_IGN`` stay ignored.  Outside
    the main thread (where Python cannot set handlers) the block simply runs.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []
    previous: dict[int, Any] = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        handler = signal.getsignal(signum)
        if handler in (signal.SIG_IGN, None):  # None: set outside Python; leave it alone
            continue
        previous[signum] = handler
        signal.signal(signum, lambda number, frame: received.append(number))
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        for signum in dict.fromkeys(received):
            signal.raise_signal(signum)


def _hidden_sibling(folder: Path, kind: str) -> Path:
    """``.NAME.<random>.<kind>`` beside ``folder`` (same directory: renames stay atomic)."""
    return folder.with_name(f".{folder.name}.{_token()}.{kind}")


def _carry_over(old: Path, new: Path, replaces: Iterable[str]) -> None:
    """Put into ``new`` every entry of ``old`` whose name is not in ``replaces`` and that ``new``
    does not have: as hard links (a copy where the file system has none), so ``old`` stays
    whole until it is swapped out."""
    import shutil  # here: the CLI's JSON output needs none of it

    replaced = set(replaces)
    for entry in old.iterdir():
        target = new / entry.name
        if entry.name in replaced or target.exists() or entry.name.endswith(".partial"):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.copytree(entry, target, symlinks=True, copy_function=_link_or_copy)
        else:
            _link_or_copy(entry, target, follow_symlinks=False)


def _link_or_copy(src: str | os.PathLike, dst: str | os.PathLike, **kwargs: Any) -> None:
    """A hard link ``dst`` to ``src``, or a copy with its metadata where links fail."""
    import shutil  # here: the CLI's JSON output needs none of it

    try:
        if os.path.islink(src):
            os.symlink(os.readlink(src), dst)
        else:
            os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst, follow_symlinks=False)


def _move_into(stage: Path, folder: Path) -> None:
    """Move every entry of ``stage`` into the existing ``folder`` (replacing entries of the same
    name); ``folder`` says it is incomplete (:data:`INCOMPLETE`) until the last one is in."""
    import shutil  # here: the CLI's JSON output needs none of it

    marker = folder / INCOMPLETE
    marker.write_text(
        "gaitopt stopped while it moved its results into this folder: some files here may be\n"
        "from an earlier run.  Run the command again.\n",
        encoding="utf-8",
    )
    for entry in sorted(stage.iterdir()):
        target = folder / entry.name
        if entry.is_dir() and target.is_dir() and not target.is_symlink():
            aside = _hidden_sibling(target, "old")
            os.rename(target, aside)
            os.rename(entry, target)
            shutil.rmtree(aside, ignore_errors=True)
        else:
            os.replace(entry, target)
    marker.unlink()


@contextlib.contextmanager
def folder_written_whole(
    folder: str | os.PathLike, replaces: Iterable[str] | None = None
) -> Iterator[Path]:
    """Write a folder of results whole or not at all: yield an empty staging folder, then put
    what was written there in place.

    Parameters
    ----------
    folder : str or os.PathLike
        The folder of results.  Its parents are created if missing.
    replaces : iterable of str, optional
        The names of the entries this writer owns in ``folder`` (``make gaits``: ``cycle.json``
        and the figures of :mod:`gaitopt.gaits`).  Given, an existing ``folder`` is replaced as
        a whole by the staged one, into which every *other* entry of the old folder (files that
        other tools wrote there: a study's ``numbers.json``) is carried over first, and owned
        entries the writer did not write again (a figure of an earlier run) are dropped.  Not
        given (a user's ``--out DIR``, which may hold anything), the staged entries are moved
        into the existing ``folder`` one by one, replacing those of the same names and leaving
        the rest.

    Yields
    ------
    pathlib.Path
        The staging folder: a fresh hidden ``.NAME.<random>.partial`` beside ``folder`` (inside
        an existing ``folder`` when ``replaces`` is not given), on the same file system, so the
        final renames are atomic.  The caller writes the files there.

    Raises
    ------
    OSError
        If the staging folder cannot be made or the files cannot be put in place; ``folder``
        is then as it was.

    Notes
    -----
    If the block raises (an error, Ctrl-C's :class:`KeyboardInterrupt`), the exception propagates,
    the staging folder is removed and ``folder`` is left as it was: missing if it was, never
    half-written.  On normal exit:

    * ``folder`` did not exist: the staging folder is renamed to it (one atomic rename);
    * ``replaces`` given: the old folder is renamed aside, the staging folder renamed to
      ``folder``, and the old one removed;
    * otherwise the entries are moved in, while a file :data:`INCOMPLETE` in ``folder`` says
      that its contents may mix two runs; it is removed once every entry is in.

    The renames run with Ctrl-C and SIGTERM held back (:func:`_signals_deferred`), so an
    interrupt there takes effect just after them.  Files another program writes into ``folder``
    while the block runs are not carried over (``replaces`` given).

    Examples
    --------
    >>> with folder_written_whole("results/run") as stage:  # doctest: +SKIP
    ...     write_json(data, stage / "branch.json")
    ...     save_figure(fig, stage / "branch.png")
    """
    import shutil  # here: the CLI's JSON output needs none of it

    folder = Path(os.path.abspath(folder))
    if replaces is None and folder.is_dir():  # a user's folder: stage inside it, move in
        stage = folder / f".gaitopt.{_token()}.partial"
    else:
        folder.parent.mkdir(parents=True, exist_ok=True)
        stage = _hidden_sibling(folder, "partial")
    try:
        # made inside the try: an interrupt that lands just after the folder is made (inside
        # pathlib's mkdir, before it returns) still finds it removed by the finally
        stage.mkdir()
        yield stage
        if replaces is not None and folder.is_dir():
            _carry_over(folder, stage, replaces)
            shutil.copymode(folder, stage)  # the folder keeps its permissions
        with _signals_deferred():
            if not os.path.lexists(folder):
                os.rename(stage, folder)
            elif replaces is None:
                _move_into(stage, folder)
            else:  # the writer's own folder, replaced as a whole
                aside = _hidden_sibling(folder, "old")
                os.rename(folder, aside)
                try:
                    os.rename(stage, folder)
                except OSError:
                    os.rename(aside, folder)
                    raise
                shutil.rmtree(aside, ignore_errors=True)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def jsonable(value: Any) -> Any:
    """``value`` in plain JSON types; non-finite numbers become ``None`` (strict JSON has no NaN).

    Parameters
    ----------
    value : Any
        Mappings (keys become ``str``), lists, tuples and NumPy arrays (nested lists), Python and
        NumPy booleans, integers, floats and complex numbers, converted recursively.

    Returns
    -------
    Any
        ``dict``, ``list``, ``bool``, ``int``, ``float`` or ``None`` for the types above: NaN and
        ±inf become ``None``, a complex number ``[real, imag]``.  Anything else (``str``,
        ``None``, other objects) is returned unchanged, so :func:`json.dumps` still refuses an
        object it cannot serialise.
    """
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [jsonable(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, (complex, np.complexfloating)):
        return [jsonable(value.real), jsonable(value.imag)]
    return value


def write_json(data: Any, path: str | os.PathLike) -> Path:
    """Write ``data`` as strict JSON to ``path``, whole or not at all.

    Parameters
    ----------
    data : Any
        Converted with :func:`jsonable` (non-finite numbers are written as ``null``).
    path : str or os.PathLike
        Output file (UTF-8, indented by 2, ending with a newline).  Its directory must exist.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    TypeError
        If ``data`` holds an object JSON cannot represent; ``path`` is then left untouched.
    """
    path = Path(path)
    text = json.dumps(jsonable(data), indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    with replaced_atomically(path) as tmp, open(tmp, "x", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    return path


def write_csv(
    header: Sequence[str], rows: Iterable[Sequence[Any]], path: str | os.PathLike
) -> Path:
    """Write a table as CSV, whole or not at all (non-finite numbers as empty cells).

    Parameters
    ----------
    header : sequence of str
        Column names.
    rows : iterable of sequences
        The rows, one value per column.
    path : path-like
        Destination.
    """
    import csv

    path = Path(path)
    with replaced_atomically(path) as tmp, open(tmp, "x", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(list(header))
        for row in rows:
            writer.writerow(
                [
                    "" if v is None or (isinstance(v, float) and not math.isfinite(v)) else v
                    for v in jsonable(list(row))
                ]
            )
    return path


def check_output_folder(folder: str | os.PathLike) -> Path:
    """Check, before any work, that ``folder`` is or can become a writable directory.

    Nothing is created: the directory is made when the results are written.

    Parameters
    ----------
    folder : str or os.PathLike
        An existing directory, or a path whose nearest existing ancestor is a writable directory.

    Returns
    -------
    pathlib.Path
        ``folder``.

    Raises
    ------
    GaitoptInputError
        If ``folder`` is empty, an existing file, under a file (``/dev/null/x``), not writable, or
        not a valid path; the message says which.
    """
    text = os.fspath(folder)
    if not str(text).strip():
        raise GaitoptInputError("the output folder is empty; give a directory, e.g. results/run")
    if "\0" in str(text):
        raise GaitoptInputError("a path cannot contain a null byte; give a directory name")
    path = Path(text)
    try:
        if path.exists() and not path.is_dir():
            raise GaitoptInputError(
                f"{text!s} is an existing file, not a directory; give a new or existing directory"
            )
        ancestor = path.absolute()
        while not ancestor.exists():
            ancestor = ancestor.parent
        if not ancestor.is_dir():
            raise GaitoptInputError(
                f"{text!s} cannot be created: {ancestor} is a file, not a directory"
            )
        if not os.access(ancestor, os.W_OK | os.X_OK):
            raise GaitoptInputError(f"{text!s} cannot be written: no permission in {ancestor}")
    except (OSError, ValueError) as exc:  # a name too long, a NUL byte, ...
        raise GaitoptInputError(f"{text!r} is not a usable directory name ({exc})") from None
    return path


def write_or_fall_back(
    folder: str | os.PathLike, write: Callable[[Path], None], prefix: str = "gaitopt-"
) -> tuple[Path, OSError | None]:
    """Write results into ``folder`` whole or not at all; where that fails, into a new fallback
    directory.

    A result that took long to compute is never lost to an unwritable output path: the fallback
    is a fresh directory in the temporary directory, else in the current directory, whichever
    works first.  Both are written through :func:`folder_written_whole`, so an interrupted write
    (Ctrl-C) leaves neither a folder that looks complete nor a half-written one.

    Parameters
    ----------
    folder : str or os.PathLike
        The directory asked for (created with its parents if missing; an existing one keeps its
        other files).
    write : callable
        ``write(directory)`` writes every file into ``directory``.
    prefix : str
        Name prefix of a fallback directory.

    Returns
    -------
    directory : pathlib.Path
        Where the files are.
    error : OSError or None
        Why ``folder`` could not be used (None if it was).

    Raises
    ------
    OSError
        If neither ``folder`` nor a fallback directory can be written.
    """
    import tempfile  # here: the CLI's JSON output needs none of it

    try:
        with folder_written_whole(folder) as stage:
            write(stage)
        return Path(folder), None
    except OSError as exc:
        error = exc
    for base in (tempfile.gettempdir(), os.getcwd()):
        fallback = Path(base) / f"{prefix}{_token()}"
        try:
            with folder_written_whole(fallback) as stage:
                write(stage)
            return fallback, error
        except OSError:
            continue
    raise error
