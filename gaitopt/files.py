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
import uuid
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["replaced_atomically", "jsonable", "write_json", "write_csv"]


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
