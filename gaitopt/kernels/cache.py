"""Compiled kernels with a disk cache: CasADi codegen, ``gcc -O1 -shared -fPIC``, ``ca.external``.

The cache directory is ``$GAITOPT_CACHE``, else ``$XDG_CACHE_HOME/gaitopt``, else
``~/.cache/gaitopt``.  A library is named by a hash of everything that determines its code: the
generated C source, the CasADi version, the compiler (resolved path, size and modification time)
and the flags; so a changed model, CasADi or compiler gets a new library and a stale one is
never loaded.  Two processes compiling the same kernel at once are safe: each compiles to its own
temporary file in the cache directory and renames it into place atomically (:func:`os.replace`).

The compiler is ``$GAITOPT_CC`` (default ``gcc``).  Without one (or where compiling fails, or with
``GAITOPT_COMPILE=0``) the same functions run in CasADi's interpreter: slower, identical results.
The first use of a model class says on stderr that it is compiling (a few seconds, once).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import casadi as ca

__all__ = ["cache_dir", "compiler", "load", "FLAGS"]

#: Compiler flags: -O1 compiles the step kernels in seconds and runs them within ~10 % of -O3.
FLAGS = ("-O1", "-shared", "-fPIC")


def cache_dir() -> Path:
    """Where compiled kernels are kept (created on first use)."""
    if os.environ.get("GAITOPT_CACHE"):
        return Path(os.environ["GAITOPT_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "gaitopt"


def compiler() -> str | None:
    """The C compiler's resolved path, or None when there is none (or compiling is off)."""
    if os.environ.get("GAITOPT_COMPILE", "1") == "0":
        return None
    return shutil.which(os.environ.get("GAITOPT_CC", "gcc"))


def _key(source: str, cc: str) -> str:
    stat = os.stat(cc)
    ident = "\n".join(
        [source, ca.__version__, cc, str(stat.st_size), str(stat.st_mtime_ns), " ".join(FLAGS)]
    )
    return hashlib.sha256(ident.encode()).hexdigest()[:24]


def load(name: str, functions: list[ca.Function], *, verbose: bool = True) -> list[ca.Function]:
    """The ``functions`` compiled into one shared library (from the cache when present), loaded
    with ``ca.external``; the interpreted functions themselves where there is no compiler or
    compiling fails."""
    cc = compiler()
    if cc is None:
        return functions
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    for f in functions:
        gen.add(f)
    source = gen.dump()
    directory = cache_dir()
    library = directory / f"{name}_{_key(source, cc)}.so"
    if not library.exists():
        try:
            _compile(source, cc, library, name, verbose)
        except (OSError, subprocess.CalledProcessError) as exc:
            if verbose:
                print(
                    f"gaitopt: could not compile {name} ({exc}); interpreting it", file=sys.stderr
                )
            return functions
    try:
        return [ca.external(f.name(), str(library)) for f in functions]
    except RuntimeError as exc:  # a corrupt library: interpret (and let a later run rebuild)
        if verbose:
            print(f"gaitopt: could not load {library} ({exc}); interpreting", file=sys.stderr)
        return functions


def _compile(source: str, cc: str, library: Path, name: str, verbose: bool) -> None:
    library.parent.mkdir(parents=True, exist_ok=True)
    if verbose:
        print(f"gaitopt: compiling the {name} kernels (once; cached in {library.parent})",
              file=sys.stderr, flush=True)  # fmt: skip
    fd, tmp_c = tempfile.mkstemp(suffix=".c", prefix=f".{name}_", dir=library.parent)
    tmp_so = tmp_c[:-2] + ".so"
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(source)
        subprocess.run(
            [cc, *FLAGS, tmp_c, "-o", tmp_so, "-lm"], check=True, capture_output=True, timeout=600
        )
        os.replace(tmp_so, library)  # atomic: a concurrent compile of the same key is harmless
    finally:
        for path in (tmp_c, tmp_so):
            if os.path.exists(path):
                os.unlink(path)
