"""Newton on the shooting system in one compiled call (:mod:`gaitopt.kernels.newton_driver`).

:class:`CompiledNewton` binds a problem's :class:`~gaitopt.kernels.assemble.Assembly` (its chain
of phases, mesh, section) to the one generic C library: the model's compiled kernels are called
through their addresses in the model's kernel libraries (found by the cache's index, as the arc
library finds the verification's steps), so the whole Newton iteration — the residual, the
Jacobian's assembly, the LU solve and the stopping tests — runs without a return to Python, and
the return map's Jacobians at the solution come from the same Jacobian by block elimination.

It exists only where everything is compiled: a C compiler (``GAITOPT_CC``; none, or
``GAITOPT_COMPILE=0``: :meth:`CompiledNewton.build` returns None), the model's kernels compiled
and listed in the index (a model class defined inside gaitopt) and dense kernel inputs.  The
callers then run the Python Newton of :mod:`gaitopt.orbit.newton` on the same equations: the same
stopping tests, the same root to rounding (``tests/test_newton_compiled.py``).
"""

from __future__ import annotations

import ctypes
import sys
import threading
import weakref
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from .cache import FLAGS_O2, _compile, _key, cache_dir, compiler, indexed_entry
from .evaluation import Evaluation
from .newton_driver import SOURCE

__all__ = ["CONVERGED", "CompiledNewton", "driver"]

#: Return codes of ``gaitopt_newton_solve`` that mean converged: ``max |F| ≤ abstol`` (1) and
#: ``max |step| ≤ abstol_step`` (2); 0 is ``max_iter`` reached, −1 a non-finite ``F`` or
#: ``∂F/∂w`` (both: not converged, as the Python Newton), −2 an exactly singular ``∂F/∂w`` (the
#: Python Newton's least-squares step: the caller runs it), others a kernel's failure.
CONVERGED = (1, 2)


@lru_cache(maxsize=1)
def driver(verbose: bool = True) -> ctypes.CDLL | None:
    """The (cached) compiled Newton library, or None where there is no C compiler (or
    ``GAITOPT_COMPILE=0``) or compiling fails."""
    cc = compiler()
    if cc is None:
        return None
    library = cache_dir() / f"gaitopt_newton_driver_{_key(SOURCE, cc, FLAGS_O2)}.so"
    try:
        if not library.exists():
            import subprocess  # here: a warm start compiles nothing

            try:
                _compile(SOURCE, cc, library, "gaitopt_newton_driver", verbose, FLAGS_O2)
            except subprocess.SubprocessError as exc:
                raise OSError(str(exc)) from None
        lib = ctypes.CDLL(str(library))
    except OSError as exc:
        if verbose:
            print(f"gaitopt: could not compile the Newton driver ({exc}); Newton in Python",
                  file=sys.stderr)  # fmt: skip
        return None
    vp, i, d = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    lib.gaitopt_newton_open.restype = vp
    lib.gaitopt_newton_open.argtypes = [vp, vp, vp, vp]
    lib.gaitopt_newton_close.restype = None
    lib.gaitopt_newton_close.argtypes = [vp]
    lib.gaitopt_newton_eval.restype = i
    lib.gaitopt_newton_eval.argtypes = [vp, vp, vp, vp, i, i]
    lib.gaitopt_newton_solve.restype = i
    lib.gaitopt_newton_solve.argtypes = [vp, vp, vp, vp, i, i, d, d, vp]
    lib.gaitopt_newton_map.restype = i
    lib.gaitopt_newton_map.argtypes = [vp, vp, vp, vp]
    lib.gaitopt_newton_samples.restype = i
    lib.gaitopt_newton_samples.argtypes = [vp, vp, vp, vp, i, vp]
    lib.gaitopt_newton_correct.restype = i
    lib.gaitopt_newton_correct.argtypes = [vp, vp, vp, vp, i, vp]
    return lib


def _indexed(name: str, model_cls) -> Path | None:
    """The compiled library the cache's index lists for ``name`` of ``model_cls`` (None: not
    listed, or missing)."""
    found = indexed_entry(name, model_cls)
    return None if found is None else found[0]


def _spec(f) -> np.ndarray:
    """``[n_out, (nnz, numel, dense) per output, each sparse output's dense column-major index
    per nonzero]`` of a CasADi function (``gn_open``'s spec); raises NotImplementedError for a
    sparse input (the driver passes dense arrays)."""
    if not all(f.sparsity_in(i).is_dense() for i in range(f.n_in())):
        raise NotImplementedError(f"{f.name()}: a sparse input")
    head, tail = [f.n_out()], []
    for j in range(f.n_out()):
        sp = f.sparsity_out(j)
        dense = sp.is_dense()
        head += [sp.nnz(), sp.numel(), int(dense)]
        if not dense:
            tail += list(sp.find())
    return np.array(head + tail, dtype=np.int32)


def _address(lib: ctypes.CDLL, name: str) -> tuple[int, int]:
    f, work = (ctypes.cast(getattr(lib, s), ctypes.c_void_p).value for s in (name, f"{name}_work"))
    return f, work


class _Handle:
    """One thread's problem in the driver: the output arrays it writes and its C handle."""

    def __init__(self, owner: CompiledNewton):
        size, nu, np_ = owner.size, owner.n_u, owner.n_p
        self.F = np.zeros(size)
        self.J = np.zeros((size, size))
        self.Ju = np.zeros((size, nu))
        self.Jp = np.zeros((size, np_))
        self.x_return = np.zeros(owner.n_return)
        self.ends = np.zeros(sum(owner.n))
        self.rates = np.zeros(owner.K)
        self.adm = np.zeros(owner.K)
        outs = (ctypes.c_void_p * 8)(*(a.ctypes.data for a in self.arrays))
        lib = owner.lib
        self.ptr = lib.gaitopt_newton_open(owner.dims.ctypes.data, owner.fns, owner.specs, outs)
        if not self.ptr:
            raise MemoryError("the compiled Newton could not allocate its buffers")
        weakref.finalize(self, lib.gaitopt_newton_close, self.ptr)
        self.info = np.zeros(2)

    @property
    def arrays(self) -> tuple[np.ndarray, ...]:
        return (self.F, self.J, self.Ju, self.Jp, self.x_return, self.ends, self.rates, self.adm)


class CompiledNewton:
    """The shooting system of an :class:`~gaitopt.kernels.assemble.Assembly` in the compiled
    Newton library (see the module docstring); :meth:`build` returns None where it cannot be.
    """

    def __init__(self, asm: Any, lib: ctypes.CDLL, *, reduced: bool = True):
        from . import model_kernels, step_kernels

        cls = asm._model_cls
        kern = model_kernels(cls)
        if kern is None or not kern.compiled:
            raise NotImplementedError("the model's kernels are not compiled")
        base = f"gaitopt_{cls.__name__.lower()}"
        path = _indexed(base, cls)
        steps = step_kernels(cls)  # compiled (and indexed) on first use
        step_path = _indexed(f"{base}_step", cls) if steps is not None else None
        if path is None:
            raise NotImplementedError("the model's kernel library is not in the index")
        kernels = ctypes.CDLL(str(path))
        stepper = ctypes.CDLL(str(step_path)) if step_path is not None else None
        self.lib = lib
        self.K, self.S, self.m = len(asm.chain), asm.S, asm.m
        self.size, self.n_u, self.n_p = asm.size, asm.n_u, asm.n_p
        self.n = list(asm.n)
        self.N = asm._N
        dims = [self.K, self.S, self.m, self.size, self.n_u, self.n_p]
        for k in range(self.K):
            dims += [self.n[k], *asm.offsets[k]]
        dims += list(asm.section_index)
        self.dims = np.array(dims, dtype=np.int32)
        fns = [*_address(kernels, "lift")]
        specs = [_spec(kern.lift)]
        for i in asm.chain:
            fns += [*_address(kernels, f"fold_{i}"), *_address(kernels, f"end_{i}")]
            specs += [_spec(kern.fold[i]), _spec(kern.end[i])]
            if stepper is not None:
                fns += [*_address(stepper, f"step_{i}")]
                specs.append(_spec(steps[i]))
            else:
                fns += [0, 0]
                specs.append(np.zeros(1, dtype=np.int32))
            if reduced and kern.foldx[i] is not None:  # Newton's iterations: ∂x/∂[x₀; hs] only
                fns += [*_address(kernels, f"foldx_{i}")]
                specs.append(_spec(kern.foldx[i]))
            else:
                fns += [0, 0]
                specs.append(np.zeros(1, dtype=np.int32))
        self.n_return = int(kern.end[asm.chain[-1]].sparsity_out(4).numel())
        self._specs = specs  # kept alive: the driver reads them at each call
        self.specs = (ctypes.c_void_p * len(specs))(*(s.ctypes.data for s in specs))
        self.fns = (ctypes.c_void_p * len(fns))(*fns)
        self._keep = (kernels, stepper)  # the kernel libraries stay loaded
        self._local = threading.local()

    @classmethod
    def build(cls, asm: Any, *, reduced: bool = True) -> CompiledNewton | None:
        """The compiled Newton of ``asm``, or None (no compiler, kernels not compiled or not
        indexed, a sparse kernel input).  With ``reduced`` (default) Newton iterates with the
        phases' ``foldx`` kernels where they exist (the state and duration columns alone) and
        evaluates the full ``fold`` once at the point it returns; without, every iteration
        evaluates the full ``fold`` (the previous path, for comparison)."""
        lib = driver()
        if lib is None:
            return None
        try:
            return cls(asm, lib, reduced=reduced)
        except (NotImplementedError, OSError, AttributeError, RuntimeError):
            return None

    def _handle(self) -> _Handle:
        h = getattr(self._local, "handle", None)
        if h is None:
            h = self._local.handle = _Handle(self)
        return h

    def _evaluation(self, h: _Handle, w: np.ndarray, jacobian: bool, return_map=None):
        split, at = [], 0
        ends = h.ends.copy()
        for n in self.n:
            split.append(ends[at : at + n])
            at += n
        durations = w[[int(self.dims[8 + 3 * k]) for k in range(self.K)]]
        J = (h.J.copy(), h.Ju.copy(), h.Jp.copy()) if jacobian else (None, None, None)
        return Evaluation(h.F.copy(), *J, h.x_return.copy(), split, h.rates.copy(),
                          h.adm.copy(), durations, return_map)  # fmt: skip

    @staticmethod
    def _vector(a, size: int) -> np.ndarray:
        v = np.ascontiguousarray(a, dtype=float).ravel()
        if v.size != size:
            raise ValueError(f"expected {size} values, got {v.size}")
        return v

    def evaluate(self, w, u, p, *, jacobian: bool = True, rk_steps: int | None = None):
        """The shooting equations at ``w`` (an :class:`~gaitopt.kernels.assemble.Evaluation`),
        with ``rk_steps`` RK steps per segment (default the assembly's)."""
        h = self._handle()
        w, u, p = (self._vector(a, s) for a, s in ((w, self.size), (u, self.n_u), (p, self.n_p)))
        code = self.lib.gaitopt_newton_eval(
            h.ptr, w.ctypes.data, u.ctypes.data, p.ctypes.data, rk_steps or self.N, int(jacobian)
        )
        if code:
            raise RuntimeError(f"a compiled kernel failed (code {code})")
        return self._evaluation(h, w, jacobian)

    def solve(self, w0, u, p, *, max_iter: int, abstol: float, abstol_step: float):
        """Plain Newton from ``w0`` in one call.

        Returns
        -------
        (code, w, iterations, evaluation)
            The driver's return code (:data:`CONVERGED`, 0, −1, −2, …), the last point, the
            Jacobians evaluated and the evaluation at ``w`` with, where converged and ``G_z`` is
            regular, its ``return_map`` ``(A, B_u, B_p)`` from the same Jacobian.
        """
        h = self._handle()
        w = np.array(w0, dtype=float).ravel()
        u, p = (self._vector(a, s) for a, s in ((u, self.n_u), (p, self.n_p)))
        if w.size != self.size:
            raise ValueError(f"expected {self.size} unknowns, got {w.size}")
        code = self.lib.gaitopt_newton_solve(
            h.ptr, w.ctypes.data, u.ctypes.data, p.ctypes.data, self.N, max_iter, abstol,
            abstol_step, h.info.ctypes.data,
        )  # fmt: skip
        if code not in (0, -1, *CONVERGED):  # singular or a kernel failure: no evaluation
            return code, w, int(h.info[0]), None
        return_map = self._map(h) if code in CONVERGED else None
        return code, w, int(h.info[0]), self._evaluation(h, w, True, return_map)

    def _map(self, h: _Handle) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        A = np.zeros((self.m, self.m))
        Bu = np.zeros((self.m, self.n_u))
        Bp = np.zeros((self.m, self.n_p))
        if self.lib.gaitopt_newton_map(h.ptr, A.ctypes.data, Bu.ctypes.data, Bp.ctypes.data):
            return None  # G_z singular: the caller's elimination raises LinAlgError
        return A, Bu, Bp

    def return_map(self, F_w, F_u, F_p) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Eq. (1) of :mod:`gaitopt.orbit.sensitivity` on the given Jacobians (``∂F/∂w``,
        ``∂F/∂u``, ``∂F/∂p``): ``(A, B_u, B_p)``; raises ``numpy.linalg.LinAlgError`` where
        ``G_z`` is exactly singular."""
        h = self._handle()
        h.J[:], h.Ju[:], h.Jp[:] = F_w, F_u, F_p
        found = self._map(h)
        if found is None:
            raise np.linalg.LinAlgError("G_z is singular")
        return found

    def correction(self, F_w, w, u, p, rk_steps: int) -> np.ndarray:
        """``−(∂F/∂w)⁻¹ F_fine(w)``, ``F_fine`` with ``rk_steps`` RK steps per segment (the error
        estimate's step); raises ``numpy.linalg.LinAlgError`` where ``∂F/∂w`` is exactly
        singular."""
        h = self._handle()
        h.J[:] = F_w
        w, u, p = (self._vector(a, s) for a, s in ((w, self.size), (u, self.n_u), (p, self.n_p)))
        out = np.zeros(self.size)
        code = self.lib.gaitopt_newton_correct(
            h.ptr, w.ctypes.data, u.ctypes.data, p.ctypes.data, rk_steps, out.ctypes.data
        )
        if code == 1:
            raise np.linalg.LinAlgError("Singular matrix")
        if code:
            raise RuntimeError(f"a compiled kernel failed (code {code})")
        return out

    def samples(self, w, u, p, steps: int) -> list[np.ndarray]:
        """Per chain element, the states at each segment's start and after each of ``steps`` RK
        steps without derivatives (``n × S·(steps + 1)``): the dense samples of
        :meth:`ShootingProblem.sample_numeric`, by the same step kernels."""
        h = self._handle()
        w, u, p = (self._vector(a, s) for a, s in ((w, self.size), (u, self.n_u), (p, self.n_p)))
        cols = self.S * (steps + 1)
        out = np.zeros(sum(self.n) * cols)
        code = self.lib.gaitopt_newton_samples(
            h.ptr, w.ctypes.data, u.ctypes.data, p.ctypes.data, steps, out.ctypes.data
        )
        if code:
            raise RuntimeError(f"a compiled kernel failed (code {code})")
        blocks, at = [], 0
        for n in self.n:
            blocks.append(out[at : at + n * cols].reshape(cols, n).T)
            at += n * cols
        return blocks
