"""Compiled numerical kernels: numba's nopython mode for the controller side's hot small-array maths.

At 500 Hz the estimator, the safety filter and the leg kinematics spend most of their time in the
Python and numpy call overhead of operations on 3- to 18-element arrays, not in arithmetic. A
`kernel` is plain Python written as loops over floats; with numba it is compiled to machine code
on first use (and cached on disk, so later processes load it in milliseconds). The same function
is the reference implementation: `kernel(f).py_func` is `f` itself, which the tests compare with
the compiled one on random inputs.

    PEDI_DRAKE_JIT=0    runs every kernel as plain Python (debugging; the same results, slower)

The disk cache keeps each kernel module's kernels in a folder of their own, named by a hash of
that module's source and of every package module it imports, directly or through others
(`<cache>/pedi_drake/numba/<module>-<hash>`, under the user cache folder, or NUMBA_CACHE_DIR when
set). numba judges a cached kernel stale only by its own file's time stamp, not by the kernels it
calls in other files or the constants it read from them; a folder keyed by the module's import
closure starts anew whenever anything its kernels can see changes, and only then: editing a
phase, a plot or a benchmark compiles nothing, editing one kernel module recompiles the kernels of
the modules that import it.

Without numba installed the kernels run as plain Python too. Systems that call kernels compile
them in their constructor (`warm_up`), never inside a control tick.

A kernel may call kernels (numba compiles them into it) and reads module constants as they were
when it was compiled; the cache folder's hash covers both.
"""

import ast
import functools
import hashlib
import logging
import os
import sys
from pathlib import Path

import numpy as np

try:
    import numba
    from numba.core import event
except ImportError:  # pragma: no cover - numba is a dependency; this keeps a broken install usable
    numba = None

ENABLED = numba is not None and os.environ.get("PEDI_DRAKE_JIT", "1") != "0"


_PACKAGE = Path(__file__).resolve().parents[1]


def _module_file(name: str) -> Path | None:
    """The source file of the package module `name` (dotted), or None if `name` is not one."""
    parts = name.split(".")
    if parts[0] != _PACKAGE.name:
        return None
    path = _PACKAGE.joinpath(*parts[1:])
    for candidate in (path.with_suffix(".py"), path / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


@functools.cache
def _imported_files(path: Path) -> frozenset[Path]:
    """The package's source files that the module at `path` imports by name (one level)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            # `from pedi_drake.x import y` may name a module y as well as a member.
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return frozenset(file for file in map(_module_file, names) if file is not None)


def import_closure(path: Path) -> list[Path]:
    """The module at `path` and every package module it imports, directly or indirectly, sorted."""
    seen, todo = {path}, [path]
    while todo:
        for file in _imported_files(todo.pop()):
            if file not in seen:
                seen.add(file)
                todo.append(file)
    return sorted(seen)


def _closure_hash(path: Path) -> str:
    """A short hash of the sources (paths and contents) of `import_closure(path)`."""
    digest = hashlib.sha1()
    for file in import_closure(path):
        digest.update(str(file.relative_to(_PACKAGE)).encode())
        digest.update(file.read_bytes())
    return digest.hexdigest()[:16]


def cache_root() -> Path:
    """The folder holding every kernel module's cache folder."""
    base = os.environ.get("NUMBA_CACHE_DIR") or os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "pedi_drake" / "numba"


def cache_folder(module_file: str | Path) -> Path:
    """The disk cache folder of the kernels of the module at `module_file` in its current version."""
    path = Path(module_file).resolve()
    name = ".".join(path.relative_to(_PACKAGE).with_suffix("").parts)
    return cache_root() / f"{name}-{_closure_hash(path)}"


if ENABLED:

    class _CompileNotice(event.Listener):
        """Says once per process that kernels are being compiled: with an empty cache (a new
        version of the package) building the controllers takes minutes, which should not look
        like a hang."""

        def __init__(self) -> None:
            self.told = False

        def on_start(self, event_) -> None:
            if not self.told:
                self.told = True
                logging.getLogger(__name__).warning(
                    "compiling the package's numba kernels into %s: once per version of their modules, "
                    "minutes when all are new",
                    cache_root(),
                )

        def on_end(self, event_) -> None:
            pass

    event.register("numba:compile", _CompileNotice())


def _lock_cache_writes() -> bool:
    """Makes numba's cache safe for processes adding entries to one kernel at the same time
    (`compile_kernels`' workers, two test workers): returns whether the lock is in place.

    numba keeps one index file per kernel that maps each compiled signature to a numbered data
    file, and adds an entry by reading the index, taking the first free number, writing the index
    and then the data. Two processes adding different signatures of one kernel at once read the
    same index, take the same number, and each overwrites the other's data file and index: the
    index can then name a data file holding another signature's machine code. With an exclusive
    lock on a file beside the index held around that sequence, the second writer reads the
    first's index and takes the next number. Readers need no lock: every file is written to a
    temporary name and renamed into place, and a data file missing from under its index reads as
    a cache miss."""
    try:
        import fcntl

        from numba.core.caching import IndexDataCacheFile
    except ImportError:  # pragma: no cover - not POSIX, or a numba without this class
        return False
    save = IndexDataCacheFile.save
    if getattr(save, "pedi_drake_locked", False):
        return True
    if "_index_path" not in IndexDataCacheFile.__init__.__code__.co_names:
        return False  # pragma: no cover - another layout of numba's cache files

    def locked_save(self, key, data):
        with open(f"{self._index_path}.lock", "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            save(self, key, data)

    locked_save.pedi_drake_locked = True
    locked_save.unlocked = save
    IndexDataCacheFile.save = locked_save
    return True


CACHE_WRITES_LOCKED = ENABLED and _lock_cache_writes()


def _serialise_compiles() -> bool:
    """Makes a process that needs a kernel signature another process is compiling wait for it and
    load it from the cache, instead of compiling it too: returns whether this is in place.

    Processes started together on an empty cache (`compile_kernels`' workers) need many of the
    same kernels (the estimator's, the station's, those both controllers call), and each would
    compile every one of them. An exclusive lock on a file named by the kernel's cache index and
    the signature, held around numba's load-or-compile-and-save of that signature, lets the first
    compile it and the others load it. The locks are taken down the call graph (a kernel's callees
    compile inside its compile), which has no cycles, so no two processes wait for each other; a
    process already holding a signature's lock takes it again without waiting."""
    try:
        import fcntl

        from numba.core.dispatcher import Dispatcher
    except ImportError:  # pragma: no cover - not POSIX
        return False
    compile_ = Dispatcher.compile
    if getattr(compile_, "pedi_drake_serialised", False):
        return True
    held: set[str] = set()

    def serialised_compile(self, sig):
        index = getattr(getattr(getattr(self, "_cache", None), "_cache_file", None), "_index_path", None)
        if index is None:  # not cached on disk: nothing to share
            return compile_(self, sig)
        path = f"{index}.{hashlib.sha1(str(sig).encode()).hexdigest()[:16]}.compiling"
        if path in held:
            return compile_(self, sig)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            held.add(path)
            try:
                return compile_(self, sig)
            finally:
                held.discard(path)

    serialised_compile.pedi_drake_serialised = True
    Dispatcher.compile = serialised_compile
    return True


COMPILES_SERIALISED = CACHE_WRITES_LOCKED and _serialise_compiles()


# One dtype object per distinct structured dtype of the records (see `new_record`).
_RECORD_DTYPES: dict[np.dtype, np.dtype] = {}


def new_record(dtype: np.dtype) -> np.ndarray:
    """A one-element array of the structured `dtype`, zeroed: how records cross into compiled
    code (a kernel takes the array and reads `a[0].field`).

    numba resolves a plain record array's type from its dtype at the cost of an array, where a
    tuple of arrays (a NamedTuple) costs tens of microseconds per call. It looks structured dtypes
    up in a table of its own, quickly when the dtype is the very object it saw first, by comparing
    every field otherwise (microseconds a record, at every call): so all records of equal dtypes
    share one dtype object, whichever system built them first (a process often builds several
    controllers: a simulation, then a replay). Interpreted kernels (jit disabled) read fields as
    attributes too, which needs numpy's recarray view."""
    dtype = np.dtype(dtype)
    dtype = _RECORD_DTYPES.setdefault(dtype, dtype)
    record = np.zeros(1, dtype=dtype)
    return record if ENABLED else python_records(record)


def python_records(array):
    """A structured array as numpy's recarray, whose records read fields as attributes the way
    compiled kernels do: for calling a kernel's `.py_func` on the records of compiled code."""
    return array.view(np.recarray)


def kernel(function):
    """`function` compiled by numba (nopython, cached, releases the GIL) when enabled, else itself.

    The returned object is called like `function`; `.py_func` is always the plain function.
    Division by zero gives inf or NaN as in numpy (numba's "numpy" error model), never an
    exception: a kernel inside a control tick must return, and its callers check for finite
    results.
    """
    if not ENABLED:
        function.py_func = function
        return function
    # numba reads its cache folder when the kernel is decorated (as its module is imported).
    module_file = getattr(sys.modules.get(function.__module__), "__file__", None)
    if module_file is None:  # defined in code run from a string (a guide's example): nothing to key a cache by
        return numba.njit(cache=False, nogil=True, error_model="numpy")(function)
    if Path(module_file).resolve().is_relative_to(_PACKAGE):
        numba.config.CACHE_DIR = str(cache_folder(module_file))
    else:  # a kernel outside the package (a test's): numba's own time-stamp check only
        numba.config.CACHE_DIR = str(cache_root() / "outside")
    return numba.njit(cache=True, nogil=True, error_model="numpy")(function)
