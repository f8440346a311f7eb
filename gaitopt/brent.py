"""Brent's root bracketing in Python: SciPy's ``brentq`` without importing
:mod:`scipy.optimize` (0.3–0.5 s at start-up, most of SciPy with it).

:func:`brentq` is ``scipy/optimize/Zeros/brentq.c`` (R. P. Brent, *Algorithms for Minimization
without Derivatives*, 1973, ch. 4: inverse quadratic interpolation, secant, bisection) with the
checks of its Python wrapper (``scipy.optimize.brentq``), the same operations in the same order
on IEEE doubles, so that it returns the same root to the bit (``tests/test_dop853_base.py``
compares them); the compiled arc driver (:mod:`gaitopt.kernels.arc_driver`) restates the same
routine in C.
"""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["brentq"]

_RTOL_MIN = 4 * 2.220446049250313e-16  # scipy.optimize._zeros_py._rtol: 4 eps


def _value(f: Callable[[float], float], x: float) -> float:
    fx = float(f(x))
    if math.isnan(fx):  # scipy.optimize._zeros_py._wrap_nan_raise
        raise ValueError(f"The function value at x={x} is NaN; solver cannot converge.")
    return fx


def brentq(
    f: Callable[[float], float],
    a: float,
    b: float,
    xtol: float = 2e-12,
    rtol: float = _RTOL_MIN,
    maxiter: int = 100,
) -> float:
    """A root of ``f`` in ``[a, b]`` where ``f(a)`` and ``f(b)`` differ in sign.

    Parameters
    ----------
    f : callable
        ``f(x) -> float``.
    a, b : float
        The bracket (``f``'s argument units).
    xtol, rtol : float
        The root is accurate to ``xtol + rtol·|x|`` (``rtol`` at least 4 eps).
    maxiter : int
        Iterations before a :class:`RuntimeError` (SciPy's ``disp=True``).

    Returns
    -------
    float
        The root.
    """
    if xtol <= 0:
        raise ValueError(f"xtol too small ({xtol:g} <= 0)")
    if rtol < _RTOL_MIN:
        raise ValueError(f"rtol too small ({rtol:g} < {_RTOL_MIN:g})")
    xpre, xcur = float(a), float(b)
    xblk = fblk = spre = scur = 0.0
    fpre, fcur = _value(f, xpre), _value(f, xcur)
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise ValueError("f(a) and f(b) must have different signs")
    for _ in range(maxiter):
        if fpre != 0 and fcur != 0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):  # keep the best estimate in xcur
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # secant
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # inverse quadratic interpolation
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            bound = abs(spre) if abs(spre) < 3 * abs(sbis) - delta else 3 * abs(sbis) - delta
            if 2 * abs(stry) < bound:  # a good short step
                spre, scur = scur, stry
            else:  # bisect
                spre = scur = sbis
        else:  # bisect
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = _value(f, xcur)
    raise RuntimeError(f"Failed to converge after {maxiter} iterations, value is {xcur}")
