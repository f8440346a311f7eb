"""Compiled kernels with a disk cache: CasADi codegen, ``gcc -O1 -shared -fPIC`` (or the flags a
caller chooses for a library, :func:`load`'s ``flags``), ``ca.external``.

The cache directory is ``$GAITOPT_CACHE``, else ``$XDG_CACHE_HOME/gaitopt``, else
``~/.cache/gaitopt``.  A library is named by a hash of everything that determines its code: the
generated C source, the CasADi version, the compiler (resolved path, size and modification time)
and the library's flags; so a changed model, CasADi, compiler or flag gets a new library and a
stale one is never loaded.  Two processes compiling the same kernel at once are safe: each
compiles to its own temporary file in the cache directory and renames it into place atomically
(:func:`os.replace`).

Finding a library by that hash means generating the C source, which takes longer than loading the
library (0.1–0.6 s per model class).  So each library is also listed in an index under a *source
key*: a hash of gaitopt's own source files, the model class's module, the CasADi version, the
compiler and the flags, which determine the generated code as well.  A warm start looks the
library up there and builds nothing.  Only model classes defined inside the ``gaitopt`` package
use the index (a model defined elsewhere may depend on code the key does not see); an index entry
whose library is missing or does not load is ignored and rewritten.  The sources' digest is
remembered under a stamp of the files' sizes and times (:func:`tree_digest`), and what costs more
to build than to unpickle — a model class's symbolic structure — is kept pickled under the same
key (:func:`remembered`), so a warm start reads no source and builds no graph.

The compiler is ``$GAITOPT_CC`` (default ``gcc``).  Without one (or where compiling fails, or with
``GAITOPT_COMPILE=0``) the same functions run in CasADi's interpreter: slower, identical results.
The first use of a model class says on stderr that it is compiling (a few seconds, once).
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import Any

import casadi as ca

try:  # CPython's own SHA-256: no OpenSSL library to load at start (the same digests)
    from _sha256 import sha256
except ImportError:  # another Python: hashlib's
    from hashlib import sha256

__all__ = ["cache_dir", "compiler", "load", "remembered", "source_key", "FLAGS", "FLAGS_O2"]

#: Compiler flags: -O1 compiles the step kernels in seconds and runs them within ~10 % of -O3.
FLAGS = ("-O1", "-shared", "-fPIC")
#: For a library of small functions whose work is in loops over vectors (the staged folds,
#: :data:`gaitopt.kernels.symbolic.STAGED_ABOVE`): -O1 runs them 40 % slower than -O2.
FLAGS_O2 = ("-O2", "-shared", "-fPIC")
#: Seconds a compile may take before the functions are interpreted instead.
_COMPILE_TIMEOUT = 600


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


def _key(source: str, cc: str, flags: tuple[str, ...] = FLAGS) -> str:
    stat = os.stat(cc)
    ident = "\n".join(
        [source, ca.__version__, cc, str(stat.st_size), str(stat.st_mtime_ns), " ".join(flags)]
    )
    return sha256(ident.encode()).hexdigest()[:24]


def _package_files(root: Path) -> list[tuple[tuple[str, ...], os.stat_result]]:
    """Every ``.py`` file under ``root`` (its path parts relative to ``root``, in the order of
    ``sorted(root.rglob("*.py"))``) with its ``stat``."""
    found: list[tuple[tuple[str, ...], os.stat_result]] = []
    pending = [((), str(root))]
    while pending:
        parts, directory = pending.pop()
        with os.scandir(directory) as entries:
            for entry in entries:
                if entry.is_dir(follow_symlinks=False):
                    pending.append(((*parts, entry.name), entry.path))
                elif entry.name.endswith(".py") and entry.is_file():
                    found.append(((*parts, entry.name), entry.stat()))
    return sorted(found, key=lambda item: item[0])


#: Seconds a source file must be older than a remembered digest: a file changed again within a
#: timestamp's granularity (1–2 s on some file systems) could keep its size and times.
_SETTLED_S = 3.0


@lru_cache(maxsize=1)
def _package_digest() -> str:
    """SHA-256 of every ``.py`` file of the installed gaitopt package (paths and contents), by
    :func:`tree_digest` (once per process)."""
    return tree_digest(Path(__file__).resolve().parents[1])


def tree_digest(root: Path) -> str:
    """SHA-256 of every ``.py`` file under ``root``: each file's path relative to ``root``, then
    its bytes, in sorted order.

    Reading and hashing gaitopt's 2 MB of sources takes 10–20 ms, so the digest is remembered in
    the cache directory (``sources/``) under a *stamp*: a hash of ``root`` and of each file's
    path, size, modification and status-change times (ns), inode and device.  Any write to a
    file changes its status-change time (which no program can set back), so a changed source
    never finds the stamp of its old content; a digest is remembered only when every file is
    older than ``_SETTLED_S`` seconds, so that coarse timestamps cannot hide a second quick
    change.
    """
    root = Path(root)
    files = _package_files(root)
    stamp = sha256(str(root).encode())
    for parts, st in files:
        fields = (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino, st.st_dev)
        stamp.update(f"{'/'.join(parts)}\0{fields}\n".encode())
    memo = cache_dir() / "sources" / stamp.hexdigest()[:32]
    try:
        known = memo.read_text().strip()
        if len(known) == 64 and int(known, 16) >= 0:
            return known
    except (OSError, ValueError):
        pass
    digest = sha256()
    for parts, _ in files:
        digest.update("/".join(parts).encode())
        digest.update(root.joinpath(*parts).read_bytes())
    value = digest.hexdigest()
    newest = max((max(st.st_mtime_ns, st.st_ctime_ns) for _, st in files), default=0)
    if newest < time.time_ns() - _SETTLED_S * 1e9:
        _write_atomic(memo, value)
    return value


def _write_atomic(path: Path, data: str | bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename (a reader sees the whole
    file or none); nothing where the directory is not writable."""
    import tempfile  # here: a warm start writes nothing

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}_", dir=path.parent)
        with os.fdopen(fd, "wb" if isinstance(data, bytes) else "w") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except OSError:
        pass


def source_key(name: str, model_cls: type) -> str | None:
    """The index key of a model class's kernels, or None where the index is not used (a model
    defined outside the gaitopt package, or no compiler)."""
    cc = compiler()
    if cc is None or not model_cls.__module__.startswith("gaitopt."):
        return None
    stat = os.stat(cc)
    ident = "\n".join(
        [name, model_cls.__module__, model_cls.__qualname__, _package_digest(), ca.__version__,
         cc, str(stat.st_size), str(stat.st_mtime_ns), " ".join(FLAGS)]
    )  # fmt: skip
    return sha256(ident.encode()).hexdigest()[:24]


def indexed_entry(name: str, model_cls: type) -> tuple[Path, dict] | None:
    """The compiled library the cache's index lists for ``name`` of ``model_cls`` and its index
    entry, or None (no key, not listed, an unreadable entry or a missing library)."""
    key = source_key(name, model_cls)
    if key is None:
        return None
    try:
        entry = json.loads((cache_dir() / "index" / f"{key}.json").read_text())
        library = cache_dir() / entry["library"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return (library, entry) if library.exists() else None


def remembered(name: str, model_cls: type, build: Callable[[], Any]) -> Any:
    """``build()`` for a model class, kept pickled in the cache directory (``objects/``) under
    the class's :func:`source_key` and the Python version, and unpickled from there later.

    For what costs more to build than to unpickle: a model class's symbolic structure (its
    CasADi functions, serialised exactly: the same graphs, so the same generated code and the
    same numbers).  Built every time where the key is None (a model defined outside gaitopt, or
    no compiler) or the value cannot be pickled; a file that does not unpickle is rebuilt and
    replaced.
    """
    key = source_key(f"{name}_py{sys.version_info[0]}{sys.version_info[1]}", model_cls)
    if key is None:
        return build()
    import pickle

    path = cache_dir() / "objects" / f"{name}_{model_cls.__name__.lower()}_{key}.pickle"
    try:
        with open(path, "rb") as fh:
            return pickle.load(fh)
    except Exception:  # none yet, or a damaged or foreign file (any unpickling error)
        pass
    value = build()
    try:
        data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # e.g. a lambda inside: kept in this process only
        return value
    _write_atomic(path, data)
    return value


def _from_index(key: str) -> list[ca.Function] | None:
    entry_path = cache_dir() / "index" / f"{key}.json"
    try:
        entry = json.loads(entry_path.read_text())
        library = cache_dir() / entry["library"]
        if not library.exists():
            return None
        return [ca.external(f, str(library)) for f in entry["functions"]]
    except (OSError, ValueError, KeyError, TypeError, RuntimeError):
        return None


def _write_index(key: str, library: Path, names: list[str]) -> None:
    import tempfile  # here: a warm start writes nothing

    directory = cache_dir() / "index"
    try:
        directory.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(suffix=".json", prefix=".index_", dir=directory)
        with os.fdopen(fd, "w") as fh:
            json.dump({"library": library.name, "functions": names}, fh)
        os.replace(tmp, directory / f"{key}.json")  # atomic, as for the libraries
    except OSError:
        pass  # no index: the next start generates the source to find the library


def load(
    name: str,
    functions: list[ca.Function] | Callable[[], list[ca.Function]],
    *,
    verbose: bool = True,
    key: str | None = None,
    flags: Callable[[list[ca.Function], str], tuple[str, ...]] | None = None,
) -> tuple[list[ca.Function], bool]:
    """The ``functions`` compiled into one shared library (from the cache when present), loaded
    with ``ca.external``; the interpreted functions themselves where there is no compiler or
    compiling fails.

    ``functions`` may be a callable that builds them, called only when needed: with ``key``
    (from :func:`source_key`) a library listed in the index is loaded without building them.
    ``flags(functions, source)`` chooses the compiler flags (default :data:`FLAGS`).  Returns the
    functions and whether they are compiled.
    """
    if key is not None:
        found = _from_index(key)
        if found is not None:
            return found, True
    if callable(functions):
        functions = functions()
    cc = compiler()
    if cc is None:
        return functions, False
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    for f in functions:
        gen.add(f)
    source = gen.dump()
    chosen = FLAGS if flags is None else flags(functions, source)
    directory = cache_dir()
    library = directory / f"{name}_{_key(source, cc, chosen)}.so"
    if not library.exists():
        import subprocess  # here: a warm start compiles nothing

        try:
            _compile(source, cc, library, name, verbose, chosen)
        except (OSError, subprocess.SubprocessError) as exc:
            if verbose:
                print(
                    f"gaitopt: could not compile {name} ({exc}); interpreting it", file=sys.stderr
                )
            return functions, False
    try:
        loaded = [ca.external(f.name(), str(library)) for f in functions]
    except RuntimeError as exc:  # a corrupt library: interpret (and let a later run rebuild)
        if verbose:
            print(f"gaitopt: could not load {library} ({exc}); interpreting", file=sys.stderr)
        return functions, False
    if key is not None:
        _write_index(key, library, [f.name() for f in functions])
    return loaded, True


def _compile(
    source: str, cc: str, library: Path, name: str, verbose: bool, flags: tuple[str, ...] = FLAGS
) -> None:
    import signal
    import subprocess
    import tempfile

    library.parent.mkdir(parents=True, exist_ok=True)
    if verbose:
        print(f"gaitopt: compiling the {name} kernels (once; cached in {library.parent})",
              file=sys.stderr, flush=True)  # fmt: skip
    fd, tmp_c = tempfile.mkstemp(suffix=".c", prefix=f".{name}_", dir=library.parent)
    tmp_so = tmp_c[:-2] + ".so"
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(source)
        # Its own process group: on a timeout the compiler proper (cc1) is ended with the driver,
        # not left running as an orphan.
        proc = subprocess.Popen(
            [cc, *flags, tmp_c, "-o", tmp_so, "-lm"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            start_new_session=True,
        )
        try:
            out, err = proc.communicate(timeout=_COMPILE_TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            raise
        if proc.returncode:
            raise subprocess.CalledProcessError(proc.returncode, cc, out, err)
        os.replace(tmp_so, library)  # atomic: a concurrent compile of the same key is harmless
    finally:
        for path in (tmp_c, tmp_so):
            if os.path.exists(path):
                os.unlink(path)
