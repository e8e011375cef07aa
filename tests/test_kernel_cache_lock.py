"""jit's lock on numba's cache writes: two writers adding signatures of one kernel at once."""

import threading
import time

import pytest

from pedi_drake.runtime import jit

caching = pytest.importorskip("numba.core.caching")


def _race(save, folder, monkeypatch) -> dict:
    """Two threads each add one entry to one kernel's index at the same moment, with numba's read
    of the index slowed so that both read it before either writes; returns what loads back."""
    index = caching.IndexDataCacheFile(str(folder), "kernel-1.py311", source_stamp=(0.0, 1))
    read = caching.IndexDataCacheFile._load_index

    def slow_read(self):
        overloads = read(self)
        time.sleep(0.05)
        return overloads

    monkeypatch.setattr(caching.IndexDataCacheFile, "_load_index", slow_read)
    writers = [threading.Thread(target=save, args=(index, key, f"code of {key}")) for key in ("sig_a", "sig_b")]
    for writer in writers:
        writer.start()
    for writer in writers:
        writer.join()
    return {key: index.load(key) for key in ("sig_a", "sig_b")}


@pytest.mark.skipif(not jit.CACHE_WRITES_LOCKED, reason="numba's cache writes are not locked here")
def test_locked_writers_keep_both_entries_each_with_its_own_code(tmp_path, monkeypatch):
    loaded = _race(caching.IndexDataCacheFile.save, tmp_path, monkeypatch)
    assert loaded == {"sig_a": "code of sig_a", "sig_b": "code of sig_b"}


@pytest.mark.skipif(not jit.CACHE_WRITES_LOCKED, reason="numba's cache writes are not locked here")
def test_without_the_lock_the_same_race_loses_an_entry(tmp_path, monkeypatch):
    # What the lock is for: numba's own save, raced the same way, gives both entries one file.
    loaded = _race(caching.IndexDataCacheFile.save.unlocked, tmp_path, monkeypatch)
    assert loaded != {"sig_a": "code of sig_a", "sig_b": "code of sig_b"}


# A kernel slow enough to compile (a second or so) that two processes started together both ask
# for it before either has saved it.
_SLOW_KERNEL = "\n".join(
    ["from pedi_drake.runtime.jit import kernel", "", "@kernel", "def slow(x):", "    y = x"]
    + [f"    y = y * 1.0001 + {k}.0 / (1.0 + y * y)" for k in range(400)]
    + ["    return y", ""]
)
_COMPILE_AND_COUNT = """
import sys
sys.path.insert(0, sys.argv[1])
from numba.core import event
import slow_kernel
with event.install_recorder("numba:compile") as recorder:
    slow_kernel.slow(1.0)
print(sum(1 for _, ev in recorder.buffer if ev.is_start))
"""


@pytest.mark.skipif(not jit.COMPILES_SERIALISED, reason="compiles are not serialised here")
def test_two_processes_needing_one_signature_compile_it_once(tmp_path):
    import os
    import subprocess
    import sys

    (tmp_path / "slow_kernel.py").write_text(_SLOW_KERNEL)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    processes = [
        subprocess.Popen([sys.executable, "-c", _COMPILE_AND_COUNT, str(tmp_path)], env=env, stdout=subprocess.PIPE)
        for _ in range(2)
    ]
    compiled = [int(process.communicate(timeout=120)[0].split()[-1]) for process in processes]
    assert all(process.returncode == 0 for process in processes)
    # One compiled it; the other waited for the signature's lock and loaded it from the cache.
    assert sorted(compiled) == [0, 1], compiled
