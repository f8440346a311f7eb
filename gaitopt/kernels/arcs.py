"""The compiled simulation's library of a model class: one C call integrates one phase.

For each phase ``i`` of a model class the library holds CasADi-generated C for

* ``flow_i(x, u, p)``, the vector field (the start-up's initial step);
* ``excursion_i(x, u, p) -> (ġ, g̈)``, the signed rates of the transitions' guards (the
  short-excursion step bound);
* per event set (``c``: with the unilateral constraints, ``g``: guards only, a guess's
  simulation) ``events_i_c``, the event functions, and ``admissible_i_c``, each transition's
  admissibility (1 where it has no rule);
* ``reset_i_k(x, u, p)``, transition ``k``'s reset, and ``start_i(x, u, p) -> (c, ċ)``, the
  unilateral constraints' values and rates (the checks where a phase begins);

and the hand-written driver ``gaitopt_arc`` (:mod:`gaitopt.kernels.arc_driver`): the adaptive
steps, error control, dense output, directional event detection and root location of one arc.
The DOP853 step of each phase and event set is the verification's, compiled once in its own
library (:mod:`gaitopt.kernels.verify`: ``dop853_i_c``, :func:`gaitopt.dop853.step_function`)
and called from the driver through its address: the same code as the Python loop's steps, not
compiled twice (a model defined outside gaitopt, whose libraries are not indexed, gets its own
copy, ``step_i_c``).
The library is compiled once per model class and cached like every kernel
(:mod:`gaitopt.kernels.cache`: named by a hash of its source, listed in the index under the
package's source key); it is loaded with ``ctypes``.  Where there is no C compiler,
:func:`arc_library` returns None and the simulation runs its Python loop.
"""

from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from .arc_driver import DRIVER
from .cache import _compile, _key, _write_index, cache_dir, compiler, indexed_entry, source_key
from .verify import CHECKS_PER_STEP, phase_events

__all__ = ["ArcLibrary", "arc_library"]


def _functions(model_cls, steps: bool) -> list[ca.Function]:
    from ..dop853 import step_function
    from ..hybrid import rate_along

    functions = []
    for i, phase in enumerate(model_cls.structure().phases):
        flow = phase.flow
        x, u, p = (ca.SX.sym(s, flow.size1_in(j)) for j, s in enumerate("xup"))
        functions.append(ca.Function(f"flow_{i}", [x, u, p], [flow(x, u, p)]))
        rates, curvatures = [], []
        for tr in phase.transitions:
            rate = rate_along(flow, tr.guard)
            rates.append(tr.direction * rate(x, u, p))
            curvatures.append(tr.direction * rate_along(flow, rate)(x, u, p))
        functions.append(
            ca.Function(f"excursion_{i}", [x, u, p], [ca.vertcat(*rates), ca.vertcat(*curvatures)])
        )
        for k, tr in enumerate(phase.transitions):
            if tr.reset is not None:
                functions.append(ca.Function(f"reset_{i}_{k}", [x, u, p], [tr.reset(x, u, p)]))
        if phase.constraints:  # their values and rates where a phase starts
            values = [c.function(x, u, p)[0] for c in phase.constraints]
            rates = [rate_along(flow, c.function)(x, u, p) for c in phase.constraints]
            start = [ca.vertcat(*values), ca.vertcat(*rates)]
            functions.append(ca.Function(f"start_{i}", [x, u, p], start))
        for constraints in (True, False):
            tag = "c" if constraints else "g"
            events = phase_events(phase, constraints)
            if steps:  # else the verification's compiled steps are used (_steps_library)
                step = step_function(flow, events, CHECKS_PER_STEP)
                args = step.mx_in()  # as the verification's (same graph, same code)
                functions.append(ca.Function(f"step_{i}_{tag}", args, step.call(args)))
            values = [e(x, u, p)[0] for e in events]
            functions.append(ca.Function(f"events_{i}_{tag}", [x, u, p], [ca.vertcat(*values)]))
            rules = [
                tr.admissible(x, u, p)[0] if tr.admissible is not None else ca.SX(1)
                for tr in phase.transitions
            ]
            rules += [ca.SX(1)] * (len(events) - len(phase.transitions))
            functions.append(ca.Function(f"admissible_{i}_{tag}", [x, u, p], [ca.vertcat(*rules)]))
    return functions


def _steps_library(model_cls) -> Path | None:
    """The verification's compiled DOP853 steps of a model class (:mod:`gaitopt.kernels.verify`:
    ``dop853_<phase>_<c|g>``, compiled or loaded here), or None where they are not in the
    index (a model defined outside gaitopt): the arc library then compiles its own copy."""
    from .verify import verification_steps

    name = f"gaitopt_{model_cls.__name__.lower()}_dop853"
    if source_key(name, model_cls) is None or verification_steps(model_cls) is None:
        return None
    found = indexed_entry(name, model_cls)
    return None if found is None else found[0]


def _library_path(model_cls, verbose: bool) -> tuple[Path, Path | None] | None:
    """The compiled arc library of a model class (compiled on first use) and the library of
    the DOP853 steps it uses (None: its own), or None without a compiler or where compiling
    fails."""
    cc = compiler()
    if cc is None:
        return None
    steps = _steps_library(model_cls)
    name = f"gaitopt_{model_cls.__name__.lower()}_arcs"
    key = source_key(name, model_cls)
    found = indexed_entry(name, model_cls)
    if found is not None:
        library, entry = found
        own = "step_0_c" in entry.get("functions", ())  # the steps compiled in
        if own or steps is not None:
            return library, None if own else steps
    functions = _functions(model_cls, steps=steps is None)
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    for f in functions:
        gen.add(f)
    source = gen.dump() + DRIVER
    library = cache_dir() / f"{name}_{_key(source, cc)}.so"
    if not library.exists():
        import subprocess  # here: a warm start compiles nothing

        try:
            _compile(source, cc, library, name, verbose)
        except (OSError, subprocess.SubprocessError) as exc:
            if verbose:
                print(f"gaitopt: could not compile {name} ({exc}); simulating in Python",
                      file=sys.stderr)  # fmt: skip
            return None
    if key is not None:
        _write_index(key, library, [f.name() for f in functions])
    return library, steps


class ArcLibrary:
    """A model class's loaded arc library: :meth:`pointers` of one phase's functions for
    ``gaitopt_arc``."""

    def __init__(self, path: Path, structure, steps: Path | None = None):
        self.path = path
        self._lib = ctypes.CDLL(str(path))
        # the DOP853 steps: the verification's library's (same code), or compiled in here
        self._steps = ctypes.CDLL(str(steps)) if steps is not None else self._lib
        self.arc = self._lib.gaitopt_arc
        self.arc.restype = ctypes.c_int
        vp, i = ctypes.c_void_p, ctypes.c_int
        self.arc.argtypes = [vp, vp, vp, vp, vp, vp, vp, vp, i, vp, vp, vp, vp, vp, vp, vp]
        self._eval = self._lib.gaitopt_eval
        self._eval.restype = ctypes.c_int
        self._eval.argtypes = [vp, vp, i, vp, vp, vp, vp, vp]
        self._pointers: dict[tuple[int, bool], ctypes.Array] = {}
        self._functions: dict[str, tuple[int, int, tuple[int, ...]]] = {}
        self._sizes: dict[str, int] = {}  # each function's state size
        phases = structure.phases
        for i, phase in enumerate(phases):
            n_tr, n = len(phase.transitions), len(phase.states)
            self._function(f"excursion_{i}", n, (n_tr, n_tr))
            for k, tr in enumerate(phase.transitions):
                if tr.reset is not None:
                    self._function(f"reset_{i}_{k}", n, (len(phases[tr.target].states),))
            if phase.constraints:
                self._function(f"start_{i}", n, (len(phase.constraints),) * 2)
        for i in range(len(phases)):
            for constraints in (True, False):
                tag = "c" if constraints else "g"
                step = f"dop853_{i}_{tag}" if steps is not None else f"step_{i}_{tag}"
                names = [step, f"events_{i}_{tag}", f"admissible_{i}_{tag}", f"flow_{i}",
                         f"excursion_{i}"]  # fmt: skip
                table = (ctypes.c_void_p * 10)()
                for j, name in enumerate(names):
                    lib = self._steps if j == 0 else self._lib
                    for k, symbol in enumerate((name, f"{name}_work")):
                        pointer = ctypes.cast(getattr(lib, symbol), ctypes.c_void_p)
                        table[2 * j + k] = pointer.value
                self._pointers[(i, constraints)] = table

    def _function(self, name: str, n: int, sizes: tuple[int, ...]) -> None:
        f, work = (
            ctypes.cast(getattr(self._lib, s), ctypes.c_void_p).value
            for s in (name, f"{name}_work")
        )
        self._functions[name] = (f, work, sizes)
        self._sizes[name] = n

    def function(self, name: str, u: np.ndarray, p: np.ndarray) -> Callable:
        """The library's function ``name`` at fixed ``u`` and ``p``: ``f(x) -> outputs`` (new
        arrays), evaluated through buffers allocated here.  ``name`` is a reset
        ``reset_<phase>_<transition>``, ``excursion_<phase>`` (the transitions' signed guard
        rates and their rates) or ``start_<phase>`` (the unilateral constraints' values and
        rates)."""
        f, work, sizes = self._functions[name]
        u, p = (np.array(a, dtype=float).ravel() for a in (u, p))
        outs = [np.zeros(k) for k in sizes] + [np.zeros(1)] * (2 - len(sizes))
        x = np.zeros(self._sizes[name])
        args = (f, work, len(sizes), address(x), address(u), address(p), *map(address, outs[:2]))
        run = self._eval

        def evaluate(state: np.ndarray, _keep=(u, p)) -> list[np.ndarray]:
            x[:] = state
            code = run(*args)
            if code:
                raise RuntimeError(f"the compiled {name} failed (code {code})")
            return [o.copy() for o in outs[: len(sizes)]]

        return evaluate

    def addresses(self, name: str) -> tuple[int, int] | None:
        """The ``(function, work)`` addresses of the library's function ``name`` (a reset
        ``reset_<phase>_<transition>``, ``excursion_<phase>``, ``start_<phase>``), or None where
        the library has no such function."""
        found = self._functions.get(name)
        return None if found is None else found[:2]

    def pointers(self, phase: int, constraints: bool) -> ctypes.Array:
        """The ``(function, work)`` pointers of phase ``phase``'s step, events, admissibility,
        flow and excursion (with or without the unilateral constraints among the events)."""
        return self._pointers[(phase, constraints)]


@lru_cache(maxsize=64)
def arc_library(model_cls, verbose: bool = True) -> ArcLibrary | None:
    """The (cached) arc library of a model class, or None where there is no C compiler (or
    ``GAITOPT_COMPILE=0``), compiling fails, or the model's functions cannot be built on SX
    symbols: the simulation then runs its Python loop."""
    try:
        found = _library_path(model_cls, verbose)
        if found is None:
            return None
        return ArcLibrary(found[0], model_cls.structure(), found[1])
    except (RuntimeError, TypeError, NotImplementedError, OSError, AttributeError):
        return None


def address(a: np.ndarray) -> int:
    """The address of a C-contiguous array's data (float64 or int32; the caller keeps the
    array alive during the call)."""
    return a.ctypes.data
