"""SciPy's DOP853 without importing :mod:`scipy.integrate` (0.3–0.5 s at start-up): its
coefficients and the frame of its solver.

* :func:`coefficients` — ``scipy/integrate/_ivp/dop853_coefficients.py`` (Dormand & Prince's
  8(5,3) pair; Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.10), plain NumPy arrays read from
  SciPy's own file, so that no coefficient is retyped;
* :class:`Dop853Frame` — what :class:`scipy.integrate.DOP853` does around its steps
  (``OdeSolver.__init__``, ``RungeKutta.__init__``, ``OdeSolver.step``,
  ``OdeSolver.dense_output``; ``scipy/integrate/_ivp/base.py``, ``rk.py``, ``common.py``):
  the argument checks, the tolerances' floor, the start-up's first step
  (:func:`select_initial_step`, *Solving ODEs I*, §II.4) and the step bookkeeping, the same
  operations in the same order, so that a subclass (:class:`gaitopt.dop853.CompiledDOP853`,
  which supplies ``_step_impl`` and ``_dense_output_impl``) takes SciPy's steps to the bit.

The optimiser's referee simulates the optimal input profile with it
(``tests/test_dop853_base.py`` compares it with SciPy's class).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType
from warnings import warn

import numpy as np

__all__ = ["Dop853Frame", "coefficients", "rms_norm", "select_initial_step"]

EPS = np.finfo(float).eps

#: DOP853's error estimator order (``scipy.integrate.DOP853.error_estimator_order``).
ERROR_ESTIMATOR_ORDER = 7

_COEFFICIENTS: ModuleType | None = None

TOO_SMALL_STEP = "Required step size is less than spacing between numbers."


def coefficients() -> ModuleType:
    """SciPy's ``dop853_coefficients`` module (``N_STAGES``, ``N_STAGES_EXTENDED``, ``A``,
    ``B``, ``C``, ``E3``, ``E5``, ``D``), loaded from its file once; where SciPy's layout
    differs, imported from :mod:`scipy.integrate`."""
    global _COEFFICIENTS
    if _COEFFICIENTS is None:
        try:
            root = Path(importlib.util.find_spec("scipy").origin).parent
            path = root / "integrate" / "_ivp" / "dop853_coefficients.py"
            spec = importlib.util.spec_from_file_location("_gaitopt_dop853_coefficients", path)
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
        except (AttributeError, OSError, TypeError):  # another SciPy layout
            from scipy.integrate._ivp import dop853_coefficients as module
        _COEFFICIENTS = module
    return _COEFFICIENTS


def rms_norm(x: np.ndarray) -> float:
    """The root-mean-square norm (``scipy.integrate._ivp.common.norm``)."""
    return np.linalg.norm(x) / x.size**0.5


def select_initial_step(fun, t0, y0, t_bound, max_step, f0, direction, order, rtol, atol):
    """The first step's size (``scipy.integrate._ivp.common.select_initial_step``; Hairer,
    Nørsett & Wanner, *Solving ODEs I*, §II.4), in the time unit of ``t0``."""
    if y0.size == 0:
        return np.inf
    interval_length = abs(t_bound - t0)
    if interval_length == 0.0:
        return 0.0
    scale = atol + np.abs(y0) * rtol
    d0 = rms_norm(y0 / scale)
    d1 = rms_norm(f0 / scale)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, interval_length)  # t0 + h0 * direction not beyond t_bound
    y1 = y0 + h0 * direction * f0
    f1 = fun(t0 + h0 * direction, y1)
    d2 = rms_norm((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1 / (order + 1))
    return min(100 * h0, h1, interval_length, max_step)


class Dop853Frame:
    """SciPy's ``DOP853`` without its step: a subclass supplies ``_step_impl()`` (returning
    ``(success, message)``) and ``_dense_output_impl()``.

    Parameters
    ----------
    fun : callable
        ``fun(t, y)``, the right-hand side (state units per second).
    t0 : float
        Start time (s).
    y0 : array_like
        Start state (real, 1-D, finite).
    t_bound : float
        The integration does not go past it (s).
    max_step : float
        Largest step (s).
    rtol, atol : float
        Tolerances (``rtol`` raised to 100 eps, with a warning, as SciPy does).

    Attributes as SciPy's: ``t``, ``y``, ``t_old``, ``y_old``, ``f``, ``h_abs``, ``status``
    (``"running"``, ``"finished"``, ``"failed"``), ``direction``, ``n``, ``nfev``, …
    """

    TOO_SMALL_STEP = TOO_SMALL_STEP

    def __init__(self, fun, t0, y0, t_bound, max_step=np.inf, rtol=1e-3, atol=1e-6):
        # OdeSolver.__init__ (check_arguments, not vectorised, real states)
        self.t_old = None
        self.t = t0
        y0 = np.asarray(y0)
        if np.issubdtype(y0.dtype, np.complexfloating):
            raise ValueError("`y0` is complex; gaitopt's DOP853 integrates real states")
        y0 = y0.astype(float, copy=False)
        if y0.ndim != 1:
            raise ValueError("`y0` must be 1-dimensional.")
        if not np.isfinite(y0).all():
            raise ValueError("All components of the initial state `y0` must be finite.")

        def fun_wrapped(t, y):
            return np.asarray(fun(t, y), dtype=float)

        self._fun, self.y = fun_wrapped, y0
        self.t_bound = t_bound
        self.vectorized = False
        self.fun_single = fun_wrapped

        def counted(t, y):
            self.nfev += 1
            return self.fun_single(t, y)

        self.fun = counted
        self.direction = np.sign(t_bound - t0) if t_bound != t0 else 1
        self.n = self.y.size
        self.status = "running"
        self.nfev = self.njev = self.nlu = 0
        # RungeKutta.__init__ (first_step None)
        self.y_old = None
        if max_step <= 0:
            raise ValueError("`max_step` must be positive.")
        self.max_step = max_step
        self.rtol, self.atol = _validate_tol(rtol, atol, self.n)
        self.f = self.fun(self.t, self.y)
        self.h_abs = select_initial_step(
            self.fun, self.t, self.y, t_bound, max_step, self.f, self.direction,
            ERROR_ESTIMATOR_ORDER, self.rtol, self.atol,
        )  # fmt: skip
        self.error_exponent = -1 / (ERROR_ESTIMATOR_ORDER + 1)
        self.h_previous = None

    @property
    def step_size(self):
        """The last step's size (s), None before the first."""
        return None if self.t_old is None else np.abs(self.t - self.t_old)

    def step(self):
        """One integration step (``OdeSolver.step``): the message of a failure, else None."""
        if self.status != "running":
            raise RuntimeError("Attempt to step on a failed or finished solver.")
        if self.n == 0 or self.t == self.t_bound:  # nothing to integrate
            self.t_old = self.t
            self.t = self.t_bound
            message = None
            self.status = "finished"
        else:
            t = self.t
            success, message = self._step_impl()
            if not success:
                self.status = "failed"
            else:
                self.t_old = t
                if self.direction * (self.t - self.t_bound) >= 0:
                    self.status = "finished"
        return message

    def dense_output(self):
        """The interpolant over the last step (``OdeSolver.dense_output``)."""
        if self.t_old is None:
            raise RuntimeError("Dense output is available after a successful step was made.")
        if self.n == 0 or self.t == self.t_old:
            from .simulation.dense import ConstantPiece

            return ConstantPiece(self.t_old, self.t, self.y)
        return self._dense_output_impl()

    def _step_impl(self):  # pragma: no cover - supplied by subclasses
        raise NotImplementedError

    def _dense_output_impl(self):  # pragma: no cover - supplied by subclasses
        raise NotImplementedError


def _validate_tol(rtol, atol, n):
    """``scipy.integrate._ivp.common.validate_tol``."""
    if np.any(rtol < 100 * EPS):
        warn(
            "At least one element of `rtol` is too small. "
            f"Setting `rtol = np.maximum(rtol, {100 * EPS})`.",
            stacklevel=3,
        )
        rtol = np.maximum(rtol, 100 * EPS)
    atol = np.asarray(atol)
    if atol.ndim > 0 and atol.shape != (n,):
        raise ValueError("`atol` has wrong shape.")
    if np.any(atol < 0):
        raise ValueError("`atol` must be positive.")
    return rtol, atol
