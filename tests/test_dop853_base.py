"""SciPy's DOP853 frame, ``brentq`` and ``OdeSolution`` restated without importing SciPy
(:mod:`gaitopt.dop853_base`, :mod:`gaitopt.brent`, :mod:`gaitopt.simulation.dense`), so that the
optimiser's referee simulates an input profile without ``scipy.integrate``.

Source: SciPy's own ``DOP853``, ``select_initial_step``, ``brentq``, ``OdeSolution`` and
``ConstantDenseOutput``, which they restate operation for operation: every comparison is to the
bit (tolerance 0)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.integrate import DOP853, OdeSolution
from scipy.integrate._ivp.base import ConstantDenseOutput
from scipy.integrate._ivp.common import select_initial_step as scipy_initial_step
from scipy.optimize import brentq as scipy_brentq

from gaitopt.brent import brentq
from gaitopt.dop853_base import Dop853Frame, coefficients, select_initial_step
from gaitopt.simulation.dense import ConstantPiece, Pieces


class _FrameWithScipysStep(Dop853Frame):
    """The frame around SciPy's own DOP853 step (``RungeKutta._step_impl``, its dense output):
    only the frame differs from :class:`scipy.integrate.DOP853`."""

    _step_impl = DOP853._step_impl
    _dense_output_impl = DOP853._dense_output_impl
    _estimate_error_norm = DOP853._estimate_error_norm

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        for name in ("A", "B", "C", "E3", "E5", "D", "A_EXTRA", "C_EXTRA", "n_stages", "order"):
            setattr(self, name, getattr(DOP853, name))
        self.K_extended = np.empty((coefficients().N_STAGES_EXTENDED, self.n))
        self.K = self.K_extended[: DOP853.n_stages + 1]


def _vanderpol(t, y, mu=3.0):
    return np.array([y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]])


@pytest.mark.parametrize("rtol, atol", [(1e-10, 1e-12), (1e-6, 1e-9), (1e-17, 1e-13)])
def test_frame_takes_scipys_steps_to_the_bit(rtol, atol):
    # Van der Pol (μ = 3) over 7 s, forward: every step's time, state, rate, step size and the
    # count of right-hand sides equal SciPy's DOP853, and the dense output at interior points
    # (rtol 1e-17: both raise it to 100 eps with a warning).
    y0 = np.array([2.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        ours = _FrameWithScipysStep(_vanderpol, 0.0, y0, 7.0, rtol=rtol, atol=atol)
        theirs = DOP853(_vanderpol, 0.0, y0, 7.0, rtol=rtol, atol=atol)
    assert ours.rtol == theirs.rtol and ours.h_abs == theirs.h_abs
    steps = 0
    while theirs.status == "running":
        assert ours.step() == theirs.step()
        steps += 1
        assert ours.status == theirs.status
        assert (ours.t, ours.t_old, ours.h_abs) == (theirs.t, theirs.t_old, theirs.h_abs)
        assert np.array_equal(ours.y, theirs.y) and np.array_equal(ours.f, theirs.f)
        assert ours.step_size == theirs.step_size and ours.nfev == theirs.nfev
        times = np.linspace(theirs.t_old, theirs.t, 5)
        assert np.array_equal(ours.dense_output()(times), theirs.dense_output()(times))
    assert steps > 20
    with pytest.raises(RuntimeError):
        ours.step()


def test_frame_checks_arguments_as_scipy():
    # The argument errors SciPy's solver raises, with its messages.
    for y0, text in ((np.zeros((2, 2)), "1-dimensional"), ([1.0, np.nan], "finite")):
        with pytest.raises(ValueError, match=text):
            _FrameWithScipysStep(_vanderpol, 0.0, y0, 1.0)
    with pytest.raises(ValueError, match="positive"):
        _FrameWithScipysStep(_vanderpol, 0.0, [1.0, 0.0], 1.0, atol=-1.0)
    # A solver at its bound: the zero-length step's dense output is constant, as SciPy's.
    ours = _FrameWithScipysStep(_vanderpol, 1.0, [1.0, 0.0], 1.0)
    ours.step()
    assert ours.status == "finished"
    piece = ours.dense_output()
    assert isinstance(piece, ConstantPiece) and np.array_equal(piece(1.0), [1.0, 0.0])


def test_select_initial_step_equals_scipy():
    # Random states and rates over 12 decades, and the branches of small d0/d1 and of a zero
    # rate change; a max_step and a short interval that bound the step.
    rng = np.random.default_rng(4)
    for k in range(60):
        n = 1 + k % 5
        y0 = rng.normal(size=n) * 10.0 ** rng.integers(-8, 4)
        f0 = rng.normal(size=n) * 10.0 ** rng.integers(-8, 4)
        if k % 7 == 0:
            f0[:] = 0.0
        slope = rng.normal(size=(n, n))
        fun = (lambda t, y, s=slope: s @ y) if k % 3 else (lambda t, y, f=f0: f)
        for t_bound, max_step in ((5.0, np.inf), (1e-7, np.inf), (5.0, 1e-3)):
            args = (fun, 0.5, y0, t_bound, max_step, f0, 1.0, 7, 1e-10, 1e-12)
            assert select_initial_step(*args) == scipy_initial_step(*args)


@pytest.mark.parametrize(
    "f, a, b",
    [
        (lambda x: x**3 - 2 * x - 5, 2.0, 3.0),
        (lambda x: np.cos(x) - x, 0.0, 1.0),
        (lambda x: (x - 0.3) ** 5, -1.0, 2.0),  # flat at the root: many bisections
        (lambda x: -1.0 if x < 0.123456789 else 1.0, 0.0, 1.0),  # a jump
        (lambda x: x - 1e-9, 0.0, 1.0),
        (lambda x: float(np.tanh(50 * (x - 0.7))), 0.0, 1.0),
    ],
)
def test_brentq_equals_scipy(f, a, b):
    # The tolerances the simulation's crossings use (xtol 1e-15, rtol 4 eps) and SciPy's
    # defaults: the same root to the bit.
    assert brentq(f, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200) == (
        scipy_brentq(f, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    )
    assert brentq(f, a, b) == scipy_brentq(f, a, b)
    assert brentq(f, b, a) == scipy_brentq(f, b, a)  # the bracket reversed


def test_brentq_errors_as_scipy():
    for kwargs in ({"xtol": 0.0}, {"rtol": 1e-17}):
        with pytest.raises(ValueError, match="too small"):
            brentq(np.sin, 3.0, 4.0, **kwargs)
    with pytest.raises(ValueError, match="different signs"):
        brentq(np.sin, 1.0, 2.0)
    with pytest.raises(ValueError, match="NaN"):
        brentq(lambda x: np.nan if x > 3.5 else -1.0, 3.0, 4.0)
    with pytest.raises(RuntimeError, match="converge"):
        brentq(lambda x: (x - 0.3) ** 5, -1.0, 2.0, maxiter=3)
    assert brentq(np.sin, 0.0, 1.0) == 0.0 == scipy_brentq(np.sin, 0.0, 1.0)  # f(a) = 0


def test_pieces_equal_odesolution():
    # A held arc (two equal stamps, one constant piece) and an arc of constant pieces on
    # increasing stamps: the values at scalar and vector times (on the stamps, inside, outside)
    # equal SciPy's OdeSolution of ConstantDenseOutput pieces.
    x = np.array([1.0, -2.0, 3.0])
    held = Pieces([0.4, 0.4], [ConstantPiece(0.4, 0.4, x)])
    theirs = OdeSolution([0.4, 0.4], [ConstantDenseOutput(0.4, 0.4, x)])
    for t in (0.4, 0.0, np.array([0.3, 0.4, 0.5])):
        assert np.array_equal(held(t), theirs(t))
    assert (held.t_min, held.t_max, held.n_segments) == (theirs.t_min, theirs.t_max, 1)
    ts = [0.0, 0.1, 0.25, 0.5]
    values = [x, 2 * x, -x]
    spans = list(zip(ts[:-1], ts[1:], values, strict=True))
    ours = Pieces(ts, [ConstantPiece(a, b, v) for a, b, v in spans])
    theirs = OdeSolution(ts, [ConstantDenseOutput(a, b, v) for a, b, v in spans])
    times = np.array([0.3, -1.0, 0.1, 0.25, 0.05, 0.6, 0.0, 0.5])
    assert np.array_equal(ours(times), theirs(times))
    for t in times:
        assert np.array_equal(ours(t), theirs(t))
    with pytest.raises(ValueError, match="increasing"):
        Pieces([0.0, 0.2, 0.2], values[:2])
    with pytest.raises(ValueError, match="match"):
        Pieces(ts, values[:2])
