"""Two-parameter bifurcation curves: a period doubling (``PD``), fold (``LP``), Neimark–Sacker
point (``NS``) or existence ``boundary`` of a gait followed through two parameters, with the
codimension-two points on the way.

* :mod:`gaitopt.curves.system` — the extended system (orbit + defining condition) as one CasADi
  function with its exact Jacobian; built from :mod:`gaitopt.curves.paths` (parameter paths),
  :mod:`gaitopt.curves.matrices` (the singular matrices, bordering vectors) and
  :mod:`gaitopt.curves.constraints` (the conditions of declared unilateral constraints);
* :mod:`gaitopt.curves.follow` — pseudo-arclength continuation of the curve, every point
  certified; :func:`bifurcation_curve`;
* :mod:`gaitopt.curves.codim2` — test functions of the codimension-two points;
* :mod:`gaitopt.curves.result` — :class:`Curve`.

>>> import gaitopt
>>> curve = gaitopt.bifurcation_curve(gaitopt.model("compass_gait"), "PD", "slope", "mass_hip",
...                                   to=12.0, param_to=0.09)  # doctest: +SKIP
"""

from __future__ import annotations

from .follow import bifurcation_curve, curve_from
from .result import Curve, CurvePoint
from .system import CURVE_KINDS, ParameterPath, augmented_system

__all__ = [
    "bifurcation_curve",
    "curve_from",
    "Curve",
    "CurvePoint",
    "ParameterPath",
    "CURVE_KINDS",
    "augmented_system",
]
