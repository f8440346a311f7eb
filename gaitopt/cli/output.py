"""How the subcommands print and write: the solver's own output kept off stdout, JSON and text
rows, a result's header, and ``--out`` written without ever losing a computed result."""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

from .common import PROG


@contextlib.contextmanager
def _solver_output_to_stderr() -> Iterator[None]:
    """Send whatever the solver prints to stderr while the block runs.

    ``solve --json`` promises one JSON object on stdout, but CasADi's solver plugins print
    (IPOPT's banner), through :data:`sys.stdout` or the C-level file descriptor 1 depending on
    where the output goes.  Both are pointed at stderr here.
    """
    sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:  # no file descriptor 1 to protect
        saved = None
    if saved is not None:
        os.dup2(2, 1)
    try:
        with contextlib.redirect_stdout(sys.stderr):
            yield
            sys.stdout.flush()
    finally:
        if saved is not None:
            _flush_c_stdio()
            os.dup2(saved, 1)
            os.close(saved)


def _flush_c_stdio() -> None:
    """``fflush(NULL)``: push out what C code buffered before file descriptor 1 is restored."""
    with contextlib.suppress(OSError, AttributeError, TypeError):
        ctypes.CDLL(None).fflush(None)


def _print_json(value: Any) -> None:
    from ..files import jsonable  # here: importing the CLI loads no NumPy

    print(json.dumps(jsonable(value), indent=2, ensure_ascii=False, allow_nan=False))


def _format_params(params: Mapping[str, float]) -> str:
    return ", ".join(f"{name}={value:g}" for name, value in params.items())


# -- text rows: one style for every subcommand's result --------------------------------------
#: The narrowest label column (a label and at least two spaces before its value).
_MIN_LABEL_WIDTH = 12


def _label_width(labels: Iterable[str]) -> int:
    """The width of a label column: the longest label and two spaces (at least 12)."""
    return max([_MIN_LABEL_WIDTH - 2, *(len(label) for label in labels)]) + 2


def _print_rows(rows: Iterable[tuple[str, Any]], width: int | None = None) -> None:
    """Print ``label  value`` rows, the values aligned after the widest label (or ``width``)."""
    rows = list(rows)
    if width is None:
        width = _label_width(label for label, _ in rows)
    for label, value in rows:
        print(f"{label:<{width}}{value}")


def with_unit(value: str, unit: str | None) -> str:
    """``value`` followed by its ``unit`` as a model declares it: ``"0.8 s"``, ``"0.3 l"``;
    a dimensionless ``"1"`` adds nothing, an undeclared unit (None) says so.

    >>> with_unit("0.8", "s"), with_unit("0.2", "1"), with_unit("2", None)
    ('0.8 s', '0.2', '2 (unit not declared)')
    """
    if unit is None:
        return f"{value} (unit not declared)"
    return value if unit in ("1", "") else f"{value} {unit}"


def _number(value: Any) -> str:
    """A number to 10 significant digits (``"None"`` for a missing one)."""
    return "None" if value is None else f"{value:.10g}"


def multiplier_text(z: complex) -> str:
    """A Floquet multiplier as ``re ± im j    |λ| = …``, each to 10 significant digits.

    The parts are padded to the widest a 10-digit number takes, so that a column of
    multipliers lines up.

    >>> multiplier_text(complex(-1.3407772917484198, 0.0))
    '-1.340777292     + 0j                |λ| = 1.340777292'
    >>> multiplier_text(complex(0.5, -0.25))
    ' 0.5             − 0.25j             |λ| = 0.5590169944'
    """
    sign = "−" if z.imag < 0 else "+"
    real, imag = f"{z.real: .10g}", f"{abs(z.imag):.10g}j"
    return f"{real:<16} {sign} {imag:<16}  |λ| = {abs(z):.10g}"


def fixed_point_lines(model: Any, fixed_point: Mapping[str, float]) -> list[str]:
    """The fixed point's lines: ``    name   value unit``, one state a line, each with the unit
    the model declares (:func:`gaitopt.plotting.labels.state_unit`)."""
    from ..plotting.labels import state_unit

    width = _label_width(fixed_point)
    return [
        f"    {name:<{width}}{with_unit(f'{value: .10g}', state_unit(model, name))}"
        for name, value in fixed_point.items()
    ]


def print_fixed_point(model: Any, fixed_point: Mapping[str, float]) -> None:
    """Print ``fixed point (section: …)`` and the fixed point, one state a line with its unit."""
    print(f"fixed point (section: {model.section.doc})")
    for line in fixed_point_lines(model, fixed_point):
        print(line)


def print_multipliers(multipliers: Iterable[complex]) -> None:
    """Print ``multipliers`` and each multiplier on its line (:func:`multiplier_text`)."""
    print("multipliers")
    for z in multipliers:
        print(f"    {multiplier_text(complex(z))}")


def print_block(items: Iterable[tuple[str, Any] | str]) -> None:
    """Print rows and lines in order: a ``(label, value)`` row with its value after the label
    column (one width for every row of the block), a string as it is (a heading, or an indented
    line of :func:`fixed_point_lines`)."""
    items = list(items)
    width = _label_width(item[0] for item in items if not isinstance(item, str))
    for item in items:
        if isinstance(item, str):
            print(item)
        else:
            _print_rows([item], width)


def header_rows(model: Any, success: Any, message: str, *rows: tuple[str, Any]) -> list:
    """The first rows of a result as text: its model and parameters, any ``rows``, then
    ``success`` and ``message``."""
    return [
        ("model", f"{model.name} ({model.title})"),
        ("params", _format_params(model.params)),
        *rows,
        ("success", success),
        ("message", message),
    ]


def print_header(result: Any, *rows: tuple[str, Any]) -> None:
    """The first lines of a result as text: its model and parameters, any ``rows``, then
    ``success`` and ``message`` (a gait, a branch, a curve)."""
    _print_rows(header_rows(result.model, result.success, result.message, *rows))


def write_outputs(out: str | None, write: Callable[[Path], None]) -> str | None:
    """Write a subcommand's files into ``--out`` after its computation, whole and never lost.

    The files are written into a hidden staging folder and put in place at the end
    (:func:`gaitopt.files.folder_written_whole`): a new ``--out`` folder appears complete or not
    at all, and an existing one gets the new files at once (while they are moved in, a
    ``gaitopt-INCOMPLETE.txt`` there says so).  Ctrl-C while the files are written leaves
    ``--out`` as it was.  ``--out`` was checked before the computation (:func:`main`); if
    writing still fails (the directory was removed or filled meanwhile) the files go to a fresh
    fallback directory (:func:`gaitopt.files.write_or_fall_back`).

    Parameters
    ----------
    out : str or None
        The ``--out`` argument (None: nothing to write).
    write : callable
        ``write(folder)`` writes the files into ``folder``.

    Returns
    -------
    str or None
        None if the files are in ``--out`` (or there is no ``--out``); otherwise the one-line
        error to print on stderr, saying where the files are (or that none were written): the
        caller prints it after its results, which it prints as usual, and exits with status 2.
    """
    from ..files import write_or_fall_back
    from ..interrupts import caused_by_interrupt

    if not out:
        return None
    try:
        folder, error = write_or_fall_back(out, write, prefix=f"{PROG}-out-")
    except OSError as exc:
        reason = " ".join(str(exc).split())
        return (
            f"{PROG}: error: --out {out}: cannot write there, nor to a fallback folder ({reason})"
        )
    except Exception as exc:  # a file that cannot be made (a figure): the result is still printed
        if caused_by_interrupt(exc):
            raise
        reason = " ".join(f"{type(exc).__name__}: {exc}".split())
        return (
            f"{PROG}: error: --out {out}: writing the files failed ({reason}); nothing was "
            f"written there"
        )
    if error is None:
        return None
    reason = " ".join(str(error).split())
    return (
        f"{PROG}: error: --out {out}: cannot write there ({reason}); the results were written "
        f"to {folder} instead"
    )


def write_result(result: Any, folder: Path, stem: str, plot: Callable[[Any], Any]) -> None:
    """``stem``.json, and with points ``stem``.csv and ``stem``.png, in ``folder`` (each written
    atomically): the files of a branch or a curve (``as_dict``, ``cycles``, ``csv_rows``)."""
    from ..files import write_csv, write_json
    from ..plotting import save_figure

    folder.mkdir(parents=True, exist_ok=True)
    write_json(result.as_dict(), folder / f"{stem}.json")
    if result.cycles:
        write_csv(*result.csv_rows(), folder / f"{stem}.csv")
        fig, _ = plot(result)
        save_figure(fig, folder / f"{stem}.png")
