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
