"""The robustness study's figures: every shipped mission against random draws of the reality gap.

    python -m pedi_drake.batch studies/reality_gap.yaml                  # run the study (Ray)
    python -m pedi_drake.benchmarks.reality_gap [out/studies/reality_gap]
        [--out benchmarks/results/reality_gap.json]

Reads the study's rows (`studies/reality_gap.yaml`: the same seeded draws of payload, ground
friction, motor strength, command latency, foot stiffness and joint friction for every mission,
judged by physics), prints the success of each mission and of all runs, the failed runs with
their draw and reason, and the floors it is held to (at least MIN_DRAWS draws per mission, at
least MIN_OVERALL of all runs succeeding, no mission below MIN_PER_MISSION); writes the
study's summary (`pedi_drake.batch.summary`: success against each drawn field, binned, per
mission; summary.json, summary.txt and success_vs_*.png) into the study folder, and the figures
to the JSON file.
"""

import argparse
import json
import sys
from pathlib import Path

from pedi_drake.batch.results_file import ROWS_FILE, read_rows
from pedi_drake.batch.summary import factor_names_of, format_summary, plot_summary, summarise, wilson_interval
from pedi_drake.benchmarks.machine import stamped

MIN_DRAWS = 30  # draws per mission
MIN_OVERALL = 0.95  # share of all runs that succeed
MIN_PER_MISSION = 0.85  # share of each mission's runs that succeed
GAP_FACTOR = "gap"  # the study's draw factor


def mission_rates(rows: list[dict]) -> list[dict]:
    """Per mission: runs, successes, rate and its 95 % Wilson interval."""
    table = []
    for mission in dict.fromkeys(row["factor.mission"] for row in rows):
        mine = [row for row in rows if row["factor.mission"] == mission]
        ok = sum(bool(row["success"]) for row in mine)
        table.append(
            {"mission": mission, "runs": len(mine), "succeeded": ok, "rate": ok / len(mine)}
            | {"ci95": wilson_interval(ok, len(mine))}
        )
    return table


def failures(rows: list[dict]) -> list[dict]:
    """The failed runs: mission, the draw and the reason."""
    return [
        {"mission": row["factor.mission"], "draw": row[f"factor.{GAP_FACTOR}"], "reason": row["reason"]}
        for row in rows
        if not row["success"]
    ]


def floors(table: list[dict]) -> dict:
    """The study's floors (module docstring), each with whether it held."""
    runs = sum(row["runs"] for row in table)
    ok = sum(row["succeeded"] for row in table)
    overall = ok / runs if runs else 0.0
    return {
        "draws_per_mission": {"min": min((r["runs"] for r in table), default=0), "floor": MIN_DRAWS},
        "overall": {"rate": overall, "floor": MIN_OVERALL, "held": overall >= MIN_OVERALL},
        "worst_mission": min(table, key=lambda r: r["rate"], default=None),
        "per_mission_floor": MIN_PER_MISSION,
        "every_mission_held": all(r["rate"] >= MIN_PER_MISSION for r in table),
        "enough_draws": all(r["runs"] >= MIN_DRAWS for r in table),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder", nargs="?", default="out/studies/reality_gap", help="the study's results folder")
    parser.add_argument("--out", default="benchmarks/results/reality_gap.json")
    args = parser.parse_args(argv)
    folder = Path(args.folder)
    if not (folder / ROWS_FILE).is_file():
        print(
            f"error: {folder}: no {ROWS_FILE} (run python -m pedi_drake.batch studies/reality_gap.yaml)",
            file=sys.stderr,
        )
        return 2
    rows = read_rows(folder)
    summary = summarise(rows, factor_names_of(rows))
    (folder / "summary.json").write_text(json.dumps(summary, indent=2, default=str) + "\n")
    (folder / "summary.txt").write_text(format_summary(summary) + "\n")
    plots = plot_summary(summary, rows, folder)
    table = mission_rates(rows)
    held = floors(table)
    print(f"{'mission':<28}{'runs':>6}{'succeeded':>11}{'rate':>8}")
    for row in table:
        print(f"{row['mission']:<28}{row['runs']:>6}{row['succeeded']:>11}{100 * row['rate']:>7.1f}%")
    print(
        f"all: {sum(r['succeeded'] for r in table)} of {sum(r['runs'] for r in table)} "
        f"({100 * held['overall']['rate']:.1f} %, floor {100 * MIN_OVERALL:.0f} %); every mission at least "
        f"{100 * MIN_PER_MISSION:.0f} %: {'yes' if held['every_mission_held'] else 'NO'}; "
        f"at least {MIN_DRAWS} draws each: {'yes' if held['enough_draws'] else 'NO'}"
    )
    for failure in failures(rows):
        print(f"  failed: {failure['mission']}: {failure['reason']}\n    draw {failure['draw']}")
    print(f"success against each drawn field: {folder / 'summary.txt'}, plots {[p.name for p in plots]}")
    report = {"missions": table, "floors": held, "failures": failures(rows), "by_field": summary}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped(report), indent=2, default=str) + "\n")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
