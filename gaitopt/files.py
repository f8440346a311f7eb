"""Files written whole or not at all, and values made strict JSON.

Every file gaitopt writes (``cycle.json``, figures, GIFs, ``bench.json``) goes through
:func:`replaced_atomically`: the content is written to a hidden temporary file in the same
directory and moved into place with :func:`os.replace`, so a reader sees the old file or the new
one, never a part.  :func:`jsonable` turns results (NumPy arrays and scalars, non-finite floats,
complex numbers) into plain JSON types; :func:`write_json` combines the two.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
import uuid
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .errors import GaitoptInputError

__all__ = [
    "replaced_atomically",
    "jsonable",
    "write_json",
    "write_csv",
    "check_output_folder",
    "write_or_fall_back",
]


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
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}{suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


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
    """Write results into ``folder``; where that fails, into a new fallback directory.

    A result that took long to compute is never lost to an unwritable output path: the fallback
    is a fresh directory (:func:`tempfile.mkdtemp`) in the temporary directory, else in the
    current directory, whichever works first.

    Parameters
    ----------
    folder : str or os.PathLike
        The directory asked for (created with its parents if missing).
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
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        write(folder)
        return folder, None
    except OSError as exc:
        error = exc
    for base in (tempfile.gettempdir(), os.getcwd()):
        try:
            fallback = Path(tempfile.mkdtemp(prefix=prefix, dir=base))
            write(fallback)
            return fallback, error
        except OSError:
            continue
    raise error
