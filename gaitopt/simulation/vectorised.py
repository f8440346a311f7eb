"""Vectorised pieces of the batch simulation (:mod:`gaitopt.simulation.batch`): a CasADi
function evaluated for many starts in one call (:class:`Mapped`), the DOP853 dense output of many
steps at once (:func:`dense`), and Brent's root finder run on many brackets in lockstep
(:func:`brentq`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import casadi as ca
import numpy as np

__all__ = ["Mapped", "dense", "brentq"]

#: Smallest evaluation bucket: a group of m starts is evaluated in the next power of two at least
#: this (so that at most log2(N) mapped functions are built per CasADi function).
_MIN_BUCKET = 8


class Mapped:
    """A CasADi function ``f(a0, a1, ...)`` evaluated for m starts in one call.

    ``f.map`` over a bucket of starts (the next power of two ≥ m, the last columns padding), with
    the arguments in ``shared`` the same for every start (CasADi's ``reduce_in``) and evaluated
    through preallocated buffers (``Function.buffer``): one C call (a compiled kernel) or one
    pass of CasADi's virtual machine for the whole batch.  Per-start arguments are ``m × numel``
    arrays (row-major: a start's entries together, which is the mapped function's column-major
    layout), outputs are returned the same way.
    """

    def __init__(self, f: ca.Function, shared: Sequence[int] = ()):
        self.f = f
        self.shared = tuple(shared)
        self._buckets: dict[int, tuple] = {}

    def _bucket(self, m: int):
        size = max(_MIN_BUCKET, 1 << max(0, int(m - 1).bit_length()))
        hit = self._buckets.get(size)
        if hit is None:
            f = self.f
            mapped = f.map(f"{f.name()}_{size}", "serial", size, list(self.shared), [])
            ins = [np.zeros(mapped.numel_in(i)) for i in range(mapped.n_in())]
            outs = [np.zeros(mapped.numel_out(i)) for i in range(mapped.n_out())]
            buffer, trigger = mapped.buffer()
            for i, a in enumerate(ins):
                buffer.set_arg(i, memoryview(a))
            for i, a in enumerate(outs):
                buffer.set_res(i, memoryview(a))
            hit = self._buckets[size] = (ins, outs, trigger, buffer)
        return size, hit

    def __call__(self, m: int, *args: np.ndarray) -> list[np.ndarray]:
        """Outputs (each ``m × numel``) for per-start arguments (``m × numel``, or 1-D shared)."""
        size, (ins, outs, trigger, _) = self._bucket(m)
        for i, (a, buf) in enumerate(zip(args, ins, strict=True)):
            if i in self.shared:
                buf[:] = np.ravel(a)
            elif buf.size:  # a start's entries together: the rows of ``a``, as they are
                buf[: m * (buf.size // size)].reshape(m, -1)[...] = a.reshape(m, -1)
        trigger()
        return [out.reshape(size, -1)[:m].copy() for out in outs]


def dense(F: np.ndarray, y_old: np.ndarray, t_old: np.ndarray, h: np.ndarray, t: np.ndarray):
    """DOP853's dense output of m steps at one time each (SciPy's ``Dop853DenseOutput``, the same
    operations in the same order): ``F`` m × 7 × n coefficients, ``y_old`` m × n, ``t_old``,
    ``h`` (``t_new − t_old``) and ``t`` of length m; returns m × n."""
    x = ((t - t_old) / h)[:, None]
    y = np.zeros_like(y_old)
    for i in range(F.shape[1]):
        y += F[:, F.shape[1] - 1 - i]
        if i % 2 == 0:
            y *= x
        else:
            y *= 1 - x
    return y + y_old


def brentq(
    g: Callable[[np.ndarray, np.ndarray], np.ndarray],
    a: np.ndarray,
    b: np.ndarray,
    xtol: float = 1e-15,
    rtol: float = 4 * np.finfo(float).eps,
    maxiter: int = 200,
) -> np.ndarray:
    """Roots of m functions at once by Brent's method (Brent 1973, ch. 4), as SciPy's ``brentq``
    (its C code: the same bracket bookkeeping, interpolation and bisection tests, step by step,
    each bracket on its own until it converges).

    ``g(index, x)`` evaluates the functions of the brackets ``index`` at ``x`` (arrays); each
    bracket must have ``g(a) < 0 <= g(b)`` or the reverse (the caller checks).  Returns the roots.
    """
    m = a.size
    index = np.arange(m)
    xpre, xcur = a.astype(float).copy(), b.astype(float).copy()
    fpre, fcur = g(index, xpre), g(index, xcur)
    xblk, fblk = np.zeros(m), np.zeros(m)
    spre, scur = np.zeros(m), np.zeros(m)
    root = np.where(fpre == 0, xpre, np.where(fcur == 0, xcur, np.nan))
    live = np.isnan(root)
    for _ in range(maxiter):
        if not live.any():
            break
        i = np.flatnonzero(live)
        xp, xc, xb_, fp, fc, fb = xpre[i], xcur[i], xblk[i], fpre[i], fcur[i], fblk[i]
        sp, sc = spre[i], scur[i]
        new = (fp != 0) & (fc != 0) & (np.signbit(fp) != np.signbit(fc))
        xb_ = np.where(new, xp, xb_)
        fb = np.where(new, fp, fb)
        sp = np.where(new, xc - xp, sp)
        sc = np.where(new, xc - xp, sc)
        swap = np.abs(fb) < np.abs(fc)
        xp, xc, xb_ = np.where(swap, xc, xp), np.where(swap, xb_, xc), np.where(swap, xc, xb_)
        fp, fc, fb = np.where(swap, fc, fp), np.where(swap, fb, fc), np.where(swap, fc, fb)
        delta = (xtol + rtol * np.abs(xc)) / 2
        sbis = (xb_ - xc) / 2
        done = (fc == 0) | (np.abs(sbis) < delta)
        root[i[done]] = xc[done]
        with np.errstate(all="ignore"):
            interpolate = xp == xb_
            stry_i = -fc * (xc - xp) / (fc - fp)
            dpre = (fp - fc) / (xp - xc)
            dblk = (fb - fc) / (xb_ - xc)
            stry_e = -fc * (fb * dblk - fp * dpre) / (dblk * dpre * (fb - fp))
            stry = np.where(interpolate, stry_i, stry_e)
        tried = (np.abs(sp) > delta) & (np.abs(fc) < np.abs(fp))
        good = tried & (2 * np.abs(stry) < np.minimum(np.abs(sp), 3 * np.abs(sbis) - delta))
        sp = np.where(good, sc, sbis)
        sc = np.where(good, stry, sbis)
        xp, fp = xc, fc
        xc = np.where(np.abs(sc) > delta, xc + sc, xc + np.where(sbis > 0, delta, -delta))
        going = ~done
        j = i[going]
        xpre[j], xcur[j], xblk[j], fpre[j], fblk[j] = (
            xp[going], xc[going], xb_[going], fp[going], fb[going]
        )  # fmt: skip
        spre[j], scur[j] = sp[going], sc[going]
        live[i[done]] = False
        if j.size:
            fcur[j] = g(j, xcur[j])
    root[live] = xcur[live]  # no convergence in maxiter: the last iterate, as SciPy's C code
    return root
