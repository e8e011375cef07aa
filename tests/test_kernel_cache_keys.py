"""The kernel cache is keyed per kernel module by the sources its kernels can see: editing a
module no kernel imports (a phase, a plot, a benchmark, an app) leaves every cache folder as it
is, and editing a kernel module starts new folders only for the modules that import it."""

from pathlib import Path

import pytest

from pedi_drake.runtime import jit

PACKAGE = Path(jit.__file__).resolve().parents[1]
KERNEL_MODULES = sorted(path for path in PACKAGE.rglob("*.py") if "@kernel" in path.read_text())


def _closures() -> dict[Path, list[Path]]:
    return {path: jit.import_closure(path) for path in KERNEL_MODULES}


@pytest.mark.parametrize(
    "module", ["mission/phases.py", "viz/plots.py", "run.py", "apps/sil.py", "benchmarks/missions.py"]
)
def test_no_kernel_a_run_compiles_sees_a_module_of_the_upper_layers(module):
    # A benchmark's own kernels (benchmarks/) are compiled by that benchmark alone.
    path = PACKAGE / module
    assert path.is_file()
    runtime = {kernel: closure for kernel, closure in _closures().items() if "benchmarks" not in kernel.parts}
    assert not [kernel for kernel, closure in runtime.items() if path in closure]


def test_a_kernel_module_sees_the_kernel_modules_it_imports():
    closure = jit.import_closure(PACKAGE / "estimation" / "kalman_estimator.py")
    assert PACKAGE / "estimation" / "leg_odometry.py" in closure
    assert PACKAGE / "vector3.py" in closure


def test_each_kernel_module_has_its_own_cache_folder():
    folders = {jit.cache_folder(path) for path in KERNEL_MODULES}
    assert len(folders) == len(KERNEL_MODULES)
    assert all(folder.parent == jit.cache_root() for folder in folders)


def test_a_changed_source_moves_only_the_folders_of_the_modules_that_see_it(tmp_path, monkeypatch):
    # A copy of the package in which one kernel module changes: the folders of the modules that
    # import it change, the others stay.
    copy = tmp_path / "pedi_drake"
    for path in PACKAGE.rglob("*.py"):
        target = copy / path.relative_to(PACKAGE)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(path.read_bytes())
    monkeypatch.setattr(jit, "_PACKAGE", copy)
    jit._imported_files.cache_clear()
    before = {path.relative_to(PACKAGE): jit.cache_folder(copy / path.relative_to(PACKAGE)) for path in KERNEL_MODULES}
    changed = copy / "vector3.py"
    changed.write_text(changed.read_text() + "\n# an edit\n")
    jit._imported_files.cache_clear()
    after = {name: jit.cache_folder(copy / name) for name in before}
    moved = {name for name in before if before[name] != after[name]}
    sees = {
        path.relative_to(PACKAGE)
        for path in KERNEL_MODULES
        if changed in jit.import_closure(copy / path.relative_to(PACKAGE))
    }
    jit._imported_files.cache_clear()
    assert moved == sees
    assert Path("vector3.py") in moved and Path("polygon.py") not in moved
