"""Compiled numerical kernels: numba's nopython mode for the controller side's hot small-array maths.

At 500 Hz the estimator, the safety filter and the leg kinematics spend most of their time in the
Python and numpy call overhead of operations on 3- to 18-element arrays, not in arithmetic. A
`kernel` is plain Python written as loops over floats; with numba it is compiled to machine code
on first use (and cached on disk, so later processes load it in milliseconds). The same function
is the reference implementation: `kernel(f).py_func` is `f` itself, which the tests compare with
the compiled one on random inputs.

    PEDI_DRAKE_JIT=0    runs every kernel as plain Python (debugging; the same results, slower)

The disk cache lives in a folder named by a hash of the package's sources
(`<cache>/pedi_drake/numba/<hash>`, the user cache folder, or NUMBA_CACHE_DIR when set). numba
judges a cached kernel stale only by its own file's time stamp, not by the kernels it calls in
other files, so a kernel calling a changed kernel of another module would otherwise keep the old
code: with the folder keyed by every source, any change of the package starts a new cache.

Without numba installed the kernels run as plain Python too. Systems that call kernels compile
them in their constructor (`warm_up`), never inside a control tick.

A kernel may call kernels (numba compiles them into it) and reads module constants as they were
when it was compiled; the cache folder's hash covers both.
"""

import hashlib
import logging
import os
from pathlib import Path

import numpy as np

try:
    import numba
    from numba.core import event
except ImportError:  # pragma: no cover - numba is a dependency; this keeps a broken install usable
    numba = None

ENABLED = numba is not None and os.environ.get("PEDI_DRAKE_JIT", "1") != "0"


def _source_hash() -> str:
    """A short hash of every Python source of the package (paths and contents)."""
    package = Path(__file__).resolve().parent
    digest = hashlib.sha1()
    for path in sorted(package.rglob("*.py")):
        digest.update(str(path.relative_to(package)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def cache_folder() -> Path:
    """The disk cache folder of this version of the package's kernels."""
    base = os.environ.get("NUMBA_CACHE_DIR") or os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "pedi_drake" / "numba" / _source_hash()


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
                    "compiling the package's numba kernels into %s: once per version of the package, "
                    "a few minutes on a 2-core machine",
                    numba.config.CACHE_DIR,
                )

        def on_end(self, event_) -> None:
            pass

    # Read by numba when a kernel is decorated (below, as each module is imported).
    numba.config.CACHE_DIR = str(cache_folder())
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
    return numba.njit(cache=True, nogil=True, error_model="numpy")(function)
