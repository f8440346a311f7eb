"""Writing a figure whole or not at all."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from ..files import replaced_atomically

__all__ = ["save_figure"]


def save_figure(fig: Figure, path: str | os.PathLike, *, dpi: int = 110) -> Path:
    """Write ``fig`` to ``path`` whole or not at all, then close it.

    The figure is saved to a temporary file in the same directory and moved into place with
    :func:`os.replace` (:func:`gaitopt.files.replaced_atomically`); the format comes from the
    suffix of ``path``.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".") or "png"
    try:
        with replaced_atomically(path) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi)
    finally:
        plt.close(fig)
    return path
