"""Runs a batch study: python -m pedi_drake.batch STUDY.yaml [--engine ray|serial] [--address ADDR]
[--out DIR] [--resume] [--num-cpus N] [--max-retries K]

Writes to --out (default out/studies/<study name>/): results.jsonl and results.csv (a row per
task, appended as tasks finish), summary.json, summary.txt and the plots. Exit codes: 0 every
task ran (whatever its outcome), 1 a task could not run (crashed or timed out), 2 bad input,
130 interrupted (Ctrl-C or SIGTERM; what finished is kept: run again with --resume).
"""

import argparse
import json
import signal
import sys
from pathlib import Path

from pedi_drake.batch.engines import ENGINES, make_engine
from pedi_drake.batch.runner import run_study
from pedi_drake.batch.study import load_study
from pedi_drake.batch.summary import format_summary, plot_summary, summarise
from pedi_drake.exceptions import ConfigError


def _interrupt(signum, frame):
    raise KeyboardInterrupt()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study", help="the study file (YAML)")
    parser.add_argument("--engine", choices=ENGINES, default="ray")
    parser.add_argument("--address", default=None, help="a Ray cluster's address (default: a local Ray)")
    parser.add_argument("--num-cpus", type=int, default=None, help="workers of a local Ray (default: every core)")
    parser.add_argument("--max-retries", type=int, default=2, help="retries of a task whose worker died")
    parser.add_argument("--out", default=None, help="results folder (default: out/studies/<name>)")
    parser.add_argument("--resume", action="store_true", help="run only the tasks with no row yet")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    try:
        study = load_study(args.study)
        if args.num_cpus is not None and args.num_cpus < 1:
            raise ConfigError(f"--num-cpus: must be >= 1, got {args.num_cpus}")
        if args.max_retries < 0:
            raise ConfigError(f"--max-retries: must be >= 0, got {args.max_retries}")
        folder = Path(args.out) if args.out else Path("out") / "studies" / study.name
        if folder.exists() and not folder.is_dir():
            raise ConfigError(f"--out: {folder} is a file, not a folder")
        if args.engine == "ray":
            try:
                import ray  # noqa: F401 (only checked: the engine imports it)
            except ImportError:
                raise ConfigError(
                    '--engine ray: Ray is not installed (pip install -e ".[batch]"), or use --engine serial'
                ) from None
    except ConfigError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    engine = make_engine(args.engine, address=args.address, num_cpus=args.num_cpus, max_retries=args.max_retries)
    # SIGTERM stops a study like Ctrl-C: the rows already written stay. SIGINT is installed too:
    # a study started in the background of a shell inherits SIGINT ignored, and Ctrl-C (or a
    # test's SIGINT) must still stop it.
    signal.signal(signal.SIGTERM, _interrupt)
    signal.signal(signal.SIGINT, _interrupt)
    print(f"study {study.name}: {len(study.tasks)} tasks on {args.engine}, results in {folder}/", flush=True)
    try:
        results = run_study(study, folder, engine, resume=args.resume, quiet=args.quiet)
    except FileExistsError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"\ninterrupted: finished rows are in {folder}/; run again with --resume", file=sys.stderr)
        return 130
    rows = [row for row in results.rows if row["task_id"] in {t.task_id for t in study.tasks}]
    summary = summarise(rows, study.factor_names)
    (folder / "summary.json").write_text(json.dumps(summary, indent=2, default=str) + "\n")
    text = format_summary(summary)
    (folder / "summary.txt").write_text(text + "\n")
    plot_summary(summary, rows, folder)
    print(text)
    not_run = sum(row["status"] in ("crashed", "timeout") for row in rows)
    print(f"\n{len(rows)} rows ({sum(r['status'] == 'ok' for r in rows)} ok, {not_run} crashed or timed out)")
    return 1 if not_run else 0


if __name__ == "__main__":
    sys.exit(main())
