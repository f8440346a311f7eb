"""Figures of two-parameter curves."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .result import Curve  # noqa: E402

__all__ = ["axis_label", "plot_curve", "draw_curve"]

_MARKERS = {"boundary": "X", "LPPD": "D", "R1": "s", "R2": "s", "PDNS": "P", "LPNS": "P"}


def axis_label(curve: Curve, which: int) -> str:
    """``"quantity `name` (unit)"`` of a curve parameter, from its path or its model spec."""
    path = curve.paths[which]
    specs = {s.name: s for s in curve.model.parameter_specs()}
    doc, unit = path.doc, path.unit
    if path.name in specs:
        doc = doc or specs[path.name].doc
        unit = unit or specs[path.name].unit
    return f"{doc or path.name} `{path.name}` ({unit or '1'})"


def draw_curve(ax, curve: Curve, *, x: int = 0, transform=None, label: str | None = None,
               colour: str | None = None, annotate: bool = True) -> Any:  # fmt: skip
    """Draw a curve in its parameter plane on ``ax`` (``x`` = which parameter is horizontal;
    ``transform(λ₁, λ₂) -> (X, Y)`` maps the values, e.g. to a ratio)."""
    lam = curve.params
    if not len(lam):
        return None
    tf = transform or (lambda a, b: (a, b))
    X, Y = tf(lam[:, 0], lam[:, 1])
    if x == 1:
        X, Y = Y, X
    (line,) = ax.plot(X, Y, "-", lw=2, color=colour, label=label or f"{curve.kind} curve")
    for sp in curve.special_points:
        a, b = (sp.values[p.name] for p in curve.paths)
        px, py = tf(np.array([a]), np.array([b]))
        px, py = (py, px) if x == 1 else (px, py)
        kind = sp.kind.split(":")[0]
        ax.plot(px, py, _MARKERS.get(kind, "o"), color="k", ms=7, zorder=5)
        if annotate:
            ax.annotate(sp.kind, (px[0], py[0]), textcoords="offset points", xytext=(5, 4),
                        fontsize=8)  # fmt: skip
    return line


def plot_curve(curve: Curve):
    """Figure: the curve in the parameter plane (left) and the period along it (right)."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
    draw_curve(left, curve)
    left.set_xlabel(axis_label(curve, 0))
    left.set_ylabel(axis_label(curve, 1))
    left.set_title(f"{curve.model.title or curve.model.name}: {curve.kind} curve", fontsize=10)
    left.grid(alpha=0.3)
    left.legend(fontsize=8)
    if curve.cycles:
        right.plot(curve.values(1), curve.periods, "-o", ms=3)
    right.set_xlabel(axis_label(curve, 1))
    right.set_ylabel("orbit period T (s)")
    right.set_title("period along the curve", fontsize=10)
    right.grid(alpha=0.3)
    return fig, (left, right)
