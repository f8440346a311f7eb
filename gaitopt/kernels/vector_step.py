"""A model's DOP853 step on :data:`LANES` starts at once: C on explicit vector types, emitted from
the CasADi SX function's instruction list (:func:`emit`), compiled per model class
(:func:`vector_steps`) for the lane driver (:mod:`gaitopt.kernels.lane_driver`).

Each SX instruction becomes one operation on a GCC vector of :data:`LANES` doubles
(``typedef double gaitopt_v __attribute__((vector_size(64)))``): ``+ − × ÷``, negation, square
and twice as vector arithmetic, every other operation (``sin``, ``cos``, ``sqrt``, ``fabs``,
``fmax``, ``pow``, comparisons…) per lane with the C library's scalar function, as CasADi's
generated C calls it (:data:`_LANEWISE`).  The instructions are value-numbered (an operation on
the values of an earlier one is that one, as gcc's value numbering does in the scalar step), so
a ``sin`` and a ``cos`` of one value are one ``sincos`` per lane, as gcc makes them in the
scalar step.  The operations and their order are the scalar step's (the instruction list is
what CasADi's code generator prints), compiled with the same ``-ffp-contract=off`` (no fused
multiply-adds): with ``math="exact"`` the vector step gives each lane the scalar step's numbers
to the bit (tested, ``tests/test_vector_step.py``).  With ``math="fast"`` its ``sin`` and
``cos`` are glibc's libmvec (:data:`MVEC`; at most 4 ulp from the correctly rounded value, the
C library's 1 ulp): 1.7× the starts per second on the compass gait, not the same bits.

Nothing relies on auto-vectorisation.  The library is compiled for the host's widest vector unit
(:func:`host_flags`: ``-mavx512f``, one instruction per vector operation; ``-mavx2``, two; else
the compiler's baseline, SSE2 on x86-64, four — the same numbers in each case), so it runs where
it was compiled (the cache is per machine; the flags are in the library's key).

Layout: lane ``l`` of input (or output) ``j``'s nonzero ``k`` is ``arg[j][k * LANES + l]``
(structure of arrays).
"""

from __future__ import annotations

import ctypes
import os
import platform
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from functools import lru_cache
from pathlib import Path

import casadi as ca

from ..errors import GaitoptInputError
from .cache import _compile, _key, cache_dir, compiler
from .verify import CHECKS_PER_STEP, STEP_FLAGS, phase_events

__all__ = ["LANES", "MATH", "MAX_INSTRUCTIONS", "VectorSteps", "emit", "host_flags", "vector_math",
           "vector_steps"]  # fmt: skip

#: Starts per vector step call (one AVX-512 register of doubles; two AVX2, four SSE2 ones).
LANES = 8
#: Steps with more SX instructions than this keep the scalar driver (GCC's time on one function
#: compiled three times grows faster than linearly; the five-link biped's step, ~40 000, still
#: compiles in seconds).
MAX_INSTRUCTIONS = 60_000

#: The vector steps' ``sin`` and ``cos`` by default (:func:`vector_steps`): ``"exact"``, the C
#: library's per lane (each lane the scalar step's bits).
MATH = "exact"
_MATHS = ("exact", "fast")
_CONTEXT: ContextVar[str | None] = ContextVar("gaitopt_vector_math", default=None)


@contextmanager
def vector_math(math: str) -> Iterator[None]:
    """Within the block, the vector steps' ``sin``/``cos`` are ``math`` (``"exact"`` or
    ``"fast"``, :func:`vector_steps`) unless ``$GAITOPT_VECTOR_MATH`` says otherwise."""
    if math not in _MATHS:
        raise GaitoptInputError(f"`math` must be 'exact' or 'fast', got {math!r}")
    token = _CONTEXT.set(math)
    try:
        yield
    finally:
        _CONTEXT.reset(token)


_OPS = {getattr(ca, name): name[3:] for name in dir(ca) if name.startswith("OP_")}
#: Vector arithmetic (CasADi's printing: ``casadi_sq(x)`` is ``x*x``, twice ``2.*x``).
_VECTOR = {"ADD": "({0}+{1})", "SUB": "({0}-{1})", "MUL": "({0}*{1})", "DIV": "({0}/{1})",
           "NEG": "(-{0})", "SQ": "({0}*{0})", "TWICE": "(2.*{0})", "INV": "(1./{0})",
           "ASSIGN": "{0}"}  # fmt: skip
#: Per lane, as CasADi's generated C writes each operation on doubles.
_LANEWISE = {
    "SIN": "sin({0})", "COS": "cos({0})", "TAN": "tan({0})", "ASIN": "asin({0})",
    "ACOS": "acos({0})", "ATAN": "atan({0})", "SINH": "sinh({0})", "COSH": "cosh({0})",
    "TANH": "tanh({0})", "ASINH": "asinh({0})", "ACOSH": "acosh({0})", "ATANH": "atanh({0})",
    "EXP": "exp({0})", "LOG": "log({0})", "SQRT": "sqrt({0})", "FABS": "fabs({0})",
    "FLOOR": "floor({0})", "CEIL": "ceil({0})", "ERF": "erf({0})", "EXPM1": "expm1({0})",
    "LOG1P": "log1p({0})", "SIGN": "({0}<0 ? -1. : ({0}>0 ? 1. : {0}))",
    "POW": "pow({0},{1})", "CONSTPOW": "pow({0},{1})", "ATAN2": "atan2({0},{1})",
    "FMIN": "fmin({0},{1})", "FMAX": "fmax({0},{1})", "FMOD": "fmod({0},{1})",
    "COPYSIGN": "copysign({0},{1})", "HYPOT": "hypot({0},{1})",
    "LT": "({0}<{1})", "LE": "({0}<={1})", "EQ": "({0}=={1})", "NE": "({0}!={1})",
    "NOT": "(!{0})", "AND": "({0}&&{1})", "OR": "({0}||{1})", "IF_ELSE_ZERO": "({0}?{1}:0)",
}  # fmt: skip
_BINARY = {"ADD", "SUB", "MUL", "DIV", "POW", "CONSTPOW", "ATAN2", "FMIN", "FMAX", "FMOD",
           "COPYSIGN", "HYPOT", "LT", "LE", "EQ", "NE", "AND", "OR", "IF_ELSE_ZERO"}  # fmt: skip

HEADER = f"""
/* gaitopt vector steps (gaitopt/kernels/vector_step.py): {LANES} lanes per call */
#define _GNU_SOURCE /* sincos */
#include <math.h>
#include <string.h>
#define GAITOPT_LANES {LANES}
typedef double gaitopt_v __attribute__((vector_size({8 * LANES})));
static inline gaitopt_v gaitopt_vload(const double* p) {{
  gaitopt_v v; memcpy(&v, p, sizeof v); return v;
}}
static inline void gaitopt_vstore(double* p, gaitopt_v v) {{ memcpy(p, &v, sizeof v); }}
"""

#: sin and cos of a whole vector from glibc's libmvec (its x86-64 vector ABI: 8 lanes in one
#: AVX-512 call, 4 in an AVX2 one, 2 in an SSE one), for ``math="fast"``.
MVEC = r"""
#include <immintrin.h>
#if defined(__AVX512F__)
__m512d _ZGVeN8v_sin(__m512d);
__m512d _ZGVeN8v_cos(__m512d);
#define GAITOPT_MVEC_PART 8
#define GAITOPT_MVEC_SIN(x) _ZGVeN8v_sin(x)
#define GAITOPT_MVEC_COS(x) _ZGVeN8v_cos(x)
typedef __m512d gaitopt_part;
#elif defined(__AVX2__)
__m256d _ZGVdN4v_sin(__m256d);
__m256d _ZGVdN4v_cos(__m256d);
#define GAITOPT_MVEC_PART 4
#define GAITOPT_MVEC_SIN(x) _ZGVdN4v_sin(x)
#define GAITOPT_MVEC_COS(x) _ZGVdN4v_cos(x)
typedef __m256d gaitopt_part;
#else
__m128d _ZGVbN2v_sin(__m128d);
__m128d _ZGVbN2v_cos(__m128d);
#define GAITOPT_MVEC_PART 2
#define GAITOPT_MVEC_SIN(x) _ZGVbN2v_sin(x)
#define GAITOPT_MVEC_COS(x) _ZGVbN2v_cos(x)
typedef __m128d gaitopt_part;
#endif
#define GAITOPT_MVEC(NAME, F)                                                   \
  static inline gaitopt_v NAME(gaitopt_v x) {                                   \
    gaitopt_v r; int i;                                                         \
    for (i = 0; i < GAITOPT_LANES; i += GAITOPT_MVEC_PART) {                    \
      gaitopt_part a;                                                           \
      memcpy(&a, (double*)&x + i, sizeof a);                                    \
      a = F(a);                                                                 \
      memcpy((double*)&r + i, &a, sizeof a);                                    \
    }                                                                           \
    return r;                                                                   \
  }
GAITOPT_MVEC(gaitopt_vsin, GAITOPT_MVEC_SIN)
GAITOPT_MVEC(gaitopt_vcos, GAITOPT_MVEC_COS)
"""


def _c(value: float) -> str:
    """A double constant exactly (C99 hexadecimal floating literal)."""
    if value != value:
        return "NAN"
    if value in (float("inf"), float("-inf")):
        return "INFINITY" if value > 0 else "(-INFINITY)"
    return float(value).hex()


def emit(fn: ca.Function, name: str, math: str = "exact") -> str:
    """C of ``int name(const double** arg, double** res)``: ``fn`` (an SX function) on
    :data:`LANES` lanes (module docstring's layout); with ``math="fast"`` its ``sin`` and ``cos``
    are libmvec's (:data:`MVEC`), else the C library's per lane.  Raises NotImplementedError for
    an operation it cannot write (a call of another function)."""
    if not fn.is_a("SXFunction"):
        raise NotImplementedError(f"{fn.name()} is not an SX function")
    n = fn.n_instructions()
    ids = [fn.instruction_id(k) for k in range(n)]
    ins = [fn.instruction_input(k) for k in range(n)]
    outs = [fn.instruction_output(k) for k in range(n)]
    # SSA names: value v<k> is instruction k's result; slot[w] the value in work slot w.  An
    # operation on the same values as an earlier one is that one (value numbering, as GCC's
    # on the scalar step: it finds the sin and cos of one value that it makes one sincos)
    slot: dict[int, int] = {}
    args: list[list[int]] = []
    seen: dict[tuple, int] = {}
    same: dict[int, int] = {}  # instruction -> the earlier one it repeats
    for k in range(n):
        op = _OPS.get(ids[k], str(ids[k]))
        if op == "INPUT":
            args.append([])
            key = ("INPUT", ins[k][0], ins[k][1])
        elif op == "CONST":
            args.append([])
            key = ("CONST", float(fn.instruction_constant(k)).hex())
        elif op == "OUTPUT":
            args.append([slot[ins[k][0]]])
            key = None
        else:
            if op not in _VECTOR and op not in _LANEWISE:
                raise NotImplementedError(f"{fn.name()}: operation {op} has no vector form")
            arity = 2 if op in _BINARY else 1
            args.append([slot[w] for w in ins[k][:arity]])
            operands = sorted(args[k]) if op in ("ADD", "MUL") else args[k]
            key = (op, *operands)
        if key is not None:
            if key in seen:
                same[k] = seen[key]
            else:
                seen[key] = k
        if op != "OUTPUT":
            slot[outs[k][0]] = same.get(k, k)
    # a sin and a cos of the same value: one loop over the lanes (GCC: one sincos per lane)
    partner: dict[int, int] = {}
    first: dict[tuple[str, int], int] = {}
    for k in range(n):
        op = _OPS.get(ids[k])
        if op in ("SIN", "COS") and k not in same:
            other = first.get(("COS" if op == "SIN" else "SIN", args[k][0]))
            if other is not None and other not in partner:
                partner[other], partner[k] = k, other
            else:
                first.setdefault((op, args[k][0]), k)
    lines = [f"int {name}(const double** arg, double** res) {{",
             "  int l;", "  (void)l;"]  # fmt: skip
    for k in range(n):
        op = _OPS.get(ids[k], str(ids[k]))
        a = [f"v{j}" for j in args[k]]
        if k in same:
            continue  # the value of an earlier instruction
        if op == "INPUT":
            j, nz = ins[k][0], ins[k][1]
            lines.append(f"  const gaitopt_v v{k} = gaitopt_vload(arg[{j}] + {nz * LANES});")
        elif op == "CONST":
            c = _c(fn.instruction_constant(k))
            lines.append(f"  const gaitopt_v v{k} = {{{', '.join([c] * LANES)}}};")
        elif op == "OUTPUT":
            j, nz = outs[k][0], outs[k][1]
            lines.append(f"  if (res[{j}]) gaitopt_vstore(res[{j}] + {nz * LANES}, {a[0]});")
        elif op in _VECTOR:
            lines.append(f"  const gaitopt_v v{k} = {_VECTOR[op].format(*a)};")
        elif math == "fast" and op in ("SIN", "COS"):
            lines.append(f"  const gaitopt_v v{k} = gaitopt_v{op.lower()}({a[0]});")
        elif k in partner:
            other = partner[k]
            if other < k:
                continue  # written with its partner
            sin_k, cos_k = (k, other) if op == "SIN" else (other, k)
            lines.append(f"  gaitopt_v v{sin_k}, v{cos_k};")
            lines.append(
                f"  for (l = 0; l < {LANES}; l++) {{ double s_, c_; sincos({a[0]}[l], &s_, &c_);"
                f" v{sin_k}[l] = s_; v{cos_k}[l] = c_; }}"
            )
        else:
            expr = _LANEWISE[op].format(*(f"{x}[l]" for x in a))
            lines.append(f"  gaitopt_v v{k};")
            lines.append(f"  for (l = 0; l < {LANES}; l++) v{k}[l] = {expr};")
    lines += ["  return 0;", "}"]
    return "\n".join(lines) + "\n"


def _step_functions(model_cls) -> list[tuple[str, ca.Function]]:
    """The verification's DOP853 steps of a model class in SX (:mod:`gaitopt.kernels.verify`),
    each phase with and without its unilateral constraints among the events."""
    from ..dop853 import step_function

    out = []
    for i, phase in enumerate(model_cls.structure().phases):
        for constraints in (True, False):
            f = step_function(phase.flow, phase_events(phase, constraints), CHECKS_PER_STEP)
            out.append((f"gaitopt_vstep_{i}_{'c' if constraints else 'g'}", f))
    return out


class VectorSteps:
    """A loaded vector step library: :meth:`address` of phase ``i``'s step (with or without the
    constraints among its events), kept alive with the library."""

    def __init__(self, library: ctypes.CDLL, names: list[str], n_p: dict[str, int]):
        self._library = library
        self.names = names
        self._n_p = n_p

    def n_p(self, phase: int, constraints: bool) -> int:
        """The parameters (entries of ``p``) phase ``phase``'s step reads."""
        return self._n_p[f"gaitopt_vstep_{phase}_{'c' if constraints else 'g'}"]

    def function(self, phase: int, constraints: bool):
        return getattr(self._library, f"gaitopt_vstep_{phase}_{'c' if constraints else 'g'}")

    def address(self, phase: int, constraints: bool) -> int:
        return ctypes.cast(self.function(phase, constraints), ctypes.c_void_p).value


#: Above this many SX instructions in all a model class's steps, its vector steps are compiled
#: at -O1 (the Strandbeest's 136 000: 33 s of gcc at -O2; the five-link biped's 42 000, 7 s).
VECTOR_O2_BELOW = 100_000


def _flags(instructions: int) -> tuple[str, ...]:
    """The verification's step flags (:data:`~gaitopt.kernels.verify.STEP_FLAGS`), -O1 above
    :data:`VECTOR_O2_BELOW` instructions (as the scalar steps above a size), still without fused
    multiply-adds."""
    return STEP_FLAGS if instructions < VECTOR_O2_BELOW else ("-O1", *STEP_FLAGS[1:])


def _build(cc: str, source: str, flags: tuple[str, ...], verbose: bool) -> ctypes.CDLL:
    library = cache_dir() / f"gaitopt_vstep_{_key(source, cc, flags)}.so"
    if not library.exists():
        _compile(source, cc, library, "vector step", verbose, flags)
    return ctypes.CDLL(str(library))


def host_flags() -> tuple[str, ...]:
    """The compiler flags of the widest vector unit the host has (``-mavx512f``, ``-mavx2``),
    read from ``/proc/cpuinfo`` on an x86-64 Linux host, else none (the compiler's baseline, SSE2
    on x86-64: the same numbers, four instructions per vector operation)."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return ()
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return ()
    for line in text.splitlines():
        if line.startswith("flags"):
            flags = set(line.split(":", 1)[1].split())
            if "avx512f" in flags:
                return ("-mavx512f",)
            return ("-mavx2",) if "avx2" in flags else ()
    return ()


def vector_steps(model_cls, math: str | None = None, verbose: bool = True) -> VectorSteps | None:
    """The vector steps of a model class compiled for the host (cached like every kernel), or
    None: no compiler, ``GAITOPT_LANES=0`` in the environment, a step that is not an SX
    function or is larger than :data:`MAX_INSTRUCTIONS`, or a failed compile (the batch then
    runs the scalar driver, one start at a time).  ``math``: ``"exact"`` (the C library's
    ``sin``/``cos`` per lane: the scalar step's bits) or ``"fast"`` (libmvec's, on x86-64 with
    glibc; else exact); default ``$GAITOPT_VECTOR_MATH``, else the innermost
    :func:`vector_math` block's, else :data:`MATH`."""
    if os.environ.get("GAITOPT_LANES", "1") == "0":
        return None
    math = math or os.environ.get("GAITOPT_VECTOR_MATH") or _CONTEXT.get() or MATH
    if math not in _MATHS:
        raise GaitoptInputError(
            f"`math` (GAITOPT_VECTOR_MATH) must be 'exact' or 'fast', got {math!r}"
        )
    return _vector_steps(model_cls, math, verbose)


@lru_cache(maxsize=64)
def _vector_steps(model_cls, math: str, verbose: bool) -> VectorSteps | None:
    cc = compiler()
    if cc is None:
        return None
    try:
        functions = _step_functions(model_cls)
        if any(f.n_instructions() > MAX_INSTRUCTIONS for _, f in functions):
            return None
    except (RuntimeError, TypeError, NotImplementedError):
        return None
    names = [name for name, _ in functions]
    n_p = {name: f.nnz_in(5) for name, f in functions}
    isa = host_flags()
    tries = [(math, isa), ("exact", isa), ("exact", ())] if isa else [(math, ()), ("exact", ())]
    if math == "fast" and platform.machine().lower() not in ("x86_64", "amd64"):
        tries = [t for t in tries if t[0] == "exact"]
    errors = []
    for kind, extra in dict.fromkeys(tries):
        try:
            body = "".join(emit(f, name, kind) for name, f in functions)
        except NotImplementedError:
            return None
        source = HEADER + (MVEC if kind == "fast" else "") + body
        link = ("-Wl,--no-as-needed", "-lmvec") if kind == "fast" else ()
        try:
            flags = _flags(sum(f.n_instructions() for _, f in functions)) + extra + link
            steps = VectorSteps(_build(cc, source, flags, verbose), names, n_p)
        except (OSError, subprocess.SubprocessError) as exc:
            errors.append(exc)
            continue
        steps.math = kind
        return steps
    if verbose:
        print(f"gaitopt: could not compile the vector steps ({errors[-1]}); one start at a time",
              file=sys.stderr)  # fmt: skip
    return None
