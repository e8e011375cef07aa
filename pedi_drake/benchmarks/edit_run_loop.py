"""How long the next run takes after an edit: the kernel cache's edit-run loop, measured.

    python -m pedi_drake.benchmarks.edit_run_loop [--mission hit_target_front]
        [--out benchmarks/results/edit_run_loop.json]

Copies the checkout (the package and its data folders, not .git or out/) into a temporary folder
and runs the README's main job there (`python run_sim.py --mission M --out DIR`) in a process of
its own, five times, with a kernel cache of its own that starts empty:

1. cold: nothing cached (a fresh clone: every kernel the run needs compiles);
2. warm: nothing changed (every kernel loads from the cache);
3. a phase edited (a comment added to mission/phases.py, a module no kernel imports);
4. a plot edited (viz/plots.py, likewise);
5. a kernel module edited (a comment added to control/compiled_stack.py: the whole-body tick and
   what imports it recompile).

Each row gives the run's wall time [s], whether any kernel compiled (the package logs one line
when it starts compiling) and whether the mission succeeded (exit 0). The user's checkout and
cache are never touched. Prints the table and writes JSON.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from pedi_drake.benchmarks.machine import stamped

REPO = Path(__file__).resolve().parents[2]
# What a run needs from the checkout besides the package.
COPIED = ("pedi_drake", "models", "scenarios", "missions", "studies", "run_sim.py")
COMPILE_NOTICE = "compiling the package's numba kernels"
# (row, file edited before the run, relative to the copy's package; None: no edit)
STEPS = (
    ("cold: empty cache", None),
    ("warm: nothing edited", None),
    ("a phase edited (mission/phases.py)", "mission/phases.py"),
    ("a plot edited (viz/plots.py)", "viz/plots.py"),
    ("a kernel module edited (control/compiled_stack.py)", "control/compiled_stack.py"),
)


def _copy_checkout(target: Path) -> None:
    for name in COPIED:
        source = REPO / name
        if source.is_dir():
            shutil.copytree(source, target / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy2(source, target / name)


def _run(copy: Path, cache: Path, mission: str, out: Path) -> dict:
    """The README's main job in the copy: wall time [s], whether kernels compiled, exit code."""
    env = dict(os.environ, PYTHONPATH=str(copy), NUMBA_CACHE_DIR=str(cache), PYTHONDONTWRITEBYTECODE="1")
    command = [sys.executable, str(copy / "run_sim.py"), "--mission", mission, "--out", str(out)]
    start = time.perf_counter()
    done = subprocess.run(command, cwd=copy, env=env, capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - start
    return {
        "seconds": seconds,
        "compiled": COMPILE_NOTICE in done.stderr + done.stdout,
        "exit_code": done.returncode,
    }


def measure(mission: str) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory(prefix="edit_run_loop_") as folder:
        copy, cache = Path(folder) / "checkout", Path(folder) / "cache"
        copy.mkdir()
        cache.mkdir()
        _copy_checkout(copy)
        for k, (name, edited) in enumerate(STEPS):
            if edited is not None:
                path = copy / "pedi_drake" / edited
                path.write_text(path.read_text() + "\n# edited by the edit-run loop benchmark\n")
            row = {"step": name, "edited": edited, **_run(copy, cache, mission, Path(folder) / f"out{k}")}
            print(f"  {name}: {row['seconds']:.1f} s, compiled {row['compiled']}, exit {row['exit_code']}", flush=True)
            rows.append(row)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mission", default="hit_target_front")
    parser.add_argument("--out", default="benchmarks/results/edit_run_loop.json")
    args = parser.parse_args()
    rows = measure(args.mission)
    print(f"{'run after':<52}{'wall s':>8}{'compiled':>10}{'exit':>6}")
    for row in rows:
        print(f"{row['step']:<52}{row['seconds']:8.1f}{str(row['compiled']):>10}{row['exit_code']:6d}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    report = {"mission": args.mission, "rows": rows, "command": "python -m pedi_drake.benchmarks.edit_run_loop"}
    out.write_text(json.dumps(stamped(report), indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
