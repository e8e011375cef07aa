"""Regenerates each paper's tables and figures for the Go1, beside the published numbers.

    python -m pedi_drake.reproduce {000,002,003,all} [--quick] [--out out/reproduce] [--jobs N]

Writes out/reproduce/<paper>/report.md (every reproduced number beside the one it reproduces,
and where they differ, why) and the figures it shows. `--quick` runs smaller versions (fewer IK
targets, SUF configurations and heights, one mission) for a test of the pipeline; its numbers
are not the published comparison. With `all`, the papers run side by side in `--jobs` processes
(default: one per core, at most one per paper); each report says how long its own paper took.
"""

import argparse
import concurrent.futures
import multiprocessing
import os
import sys
import time

from pedi_drake.reproduce.papers import PAPERS, reproduce_paper

# Rough wall time of each paper's full run on a 2-core machine [min], to start the longest first.
EXPECTED_MINUTES = {"000": 4.0, "002": 8.0, "003": 6.0}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("paper", choices=[*PAPERS, "all"])
    parser.add_argument("--quick", action="store_true", help="small versions, to check the pipeline")
    parser.add_argument("--out", default="out/reproduce")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="processes for `all`")
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error(f"--jobs: at least 1, got {args.jobs}")
    papers = list(PAPERS) if args.paper == "all" else [args.paper]
    start = time.perf_counter()
    jobs = min(args.jobs, len(papers))
    if jobs == 1:
        for paper in papers:
            print(f"paper {paper}: {reproduce_paper(paper, args.out, args.quick)}", flush=True)
    else:
        # Longest first, so the last one to start is a short one. Fresh interpreters ("spawn"):
        # nothing of this process's Drake state is shared.
        order = sorted(papers, key=lambda p: -EXPECTED_MINUTES[p])
        context = multiprocessing.get_context("spawn")
        with concurrent.futures.ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
            futures = {pool.submit(reproduce_paper, paper, args.out, args.quick): paper for paper in order}
            for future in concurrent.futures.as_completed(futures):
                print(f"paper {futures[future]}: {future.result()}", flush=True)
    print(f"reproduced {', '.join(papers)} in {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
