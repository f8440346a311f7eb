"""CasADi functions called from NumPy through preallocated buffers (``Function.buffer``).

Calling a CasADi function with NumPy arguments builds a ``DM`` per argument and per result
(57–109 µs a call for the small functions of gaitopt's models, on a loaded 2-core machine); its
buffer takes the arguments and writes the results in place (under 1 µs plus the arithmetic).  The
numbers are the same, bit for bit: the same function evaluates the same inputs.

:func:`call` keeps one buffer per function and thread (the function kept alive with it, so that
its ``id`` stays its own) and falls back to the ordinary call for what a buffer cannot take
(sparse inputs, arguments whose size does not fit).
"""

from __future__ import annotations

import threading

import casadi as ca
import numpy as np

__all__ = ["call", "call1"]

#: Buffers kept per thread before the oldest are dropped (functions built per call would
#: otherwise be kept alive for ever).
_MAX_BUFFERS = 1024

_local = threading.local()


class _Buffer:
    """One function's buffer: its arguments' and results' arrays (nonzeros, column-major)."""

    __slots__ = ("f", "args", "res", "trigger", "buffer", "shapes", "scatter", "dense_in", "rows")

    def __init__(self, f: ca.Function):
        self.f = f
        self.dense_in = all(f.sparsity_in(i).is_dense() for i in range(f.n_in()))
        self.args = [np.zeros(f.nnz_in(i)) for i in range(f.n_in())]
        self.rows = [f.size1_in(i) for i in range(f.n_in())]
        self.res = [np.zeros(f.nnz_out(i)) for i in range(f.n_out())]
        self.buffer, self.trigger = f.buffer()
        for i, a in enumerate(self.args):
            self.buffer.set_arg(i, memoryview(a))
        for i, r in enumerate(self.res):
            self.buffer.set_res(i, memoryview(r))
        self.shapes = [f.size_out(i) for i in range(f.n_out())]
        self.scatter = [
            None
            if f.sparsity_out(i).is_dense()
            else np.array(f.sparsity_out(i).find(), dtype=np.intp)
            for i in range(f.n_out())
        ]


def _buffer(f: ca.Function) -> _Buffer:
    cache = getattr(_local, "buffers", None)
    if cache is None:
        cache = _local.buffers = {}
    entry = cache.get(id(f))
    if entry is None:
        if len(cache) >= _MAX_BUFFERS:
            cache.clear()
        entry = cache[id(f)] = _Buffer(f)
    return entry


def _fill(target: np.ndarray, value, rows: int) -> bool:
    """Copy ``value`` (column-major) into ``target``; a column of ``rows`` is repeated across
    the input's columns as CasADi repeats it.  False where it does not fit."""
    v = np.asarray(value, dtype=float)
    if v.ndim > 1:
        v = v.ravel(order="F")
    elif v.ndim == 0:
        v = v.reshape(1)
    if v.size == target.size:
        target[:] = v
        return True
    if v.size == rows and rows and target.size % rows == 0:  # one column for every column
        target.reshape(-1, rows)[:] = v
        return True
    return False


def call(f: ca.Function, *args) -> list[np.ndarray]:
    """``f(*args)`` as 2-D float arrays (each output's shape, dense), through ``f``'s buffer;
    the same numbers as ``[np.asarray(r) for r in f.call(args)]``."""
    b = _buffer(f)
    if b.dense_in and len(args) == len(b.args):
        for a, v, rows in zip(b.args, args, b.rows, strict=True):
            if not _fill(a, v, rows):
                break
        else:
            b.trigger()
            out = []
            for r, (rows, cols), nz in zip(b.res, b.shapes, b.scatter, strict=True):
                if nz is None:
                    out.append(r.reshape(cols, rows).T.copy())
                else:
                    dense = np.zeros(rows * cols)
                    dense[nz] = r
                    out.append(dense.reshape(cols, rows).T)
            return out
    result = f(*args)
    result = result if isinstance(result, (tuple, list)) else (result,)
    return [np.asarray(ca.densify(ca.DM(r)), dtype=float) for r in result]


def call1(f: ca.Function, *args) -> np.ndarray:
    """The first output of :func:`call` (a function with one output, as ``f(*args)`` returns
    it)."""
    return call(f, *args)[0]
