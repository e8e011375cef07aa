"""A study's summary: for each varied factor, the success rate (with a 95 % Wilson interval) and
the distributions of foot error and trunk drift by factor value; tables and plots.

A `draw` factor (random draws of several fields at once, see pedi_drake.batch.study) is
summarised field by field: its draws are binned on each field's label number into DRAW_BINS
bins of equal counts (quantiles, so a log-uniform draw gets as fine bins as a uniform one), and
each bin also carries the success rate for each value of the study's other factors (`by`: per
mission in a mission study).

Run on a finished (or interrupted) study folder to summarise it again:

    python -m pedi_drake.batch.summary out/studies/reality_gap [--out DIR]

which prints the tables and writes summary.json, summary.txt and the plots into the folder.
"""

import argparse
import json
import math
import statistics
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from pedi_drake.batch.results_file import ROWS_FILE, read_rows
from pedi_drake.batch.study import draw_label

Z_95 = 1.959964  # two-sided 95 % normal quantile
# Bins of each drawn field: four bins of about 100 runs each in a 14-mission, 30-draw study.
DRAW_BINS = 4


def wilson_interval(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """The Wilson score interval of a success rate (sensible at 0/n and n/n, unlike the normal one)."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def _stats(values: list[float]) -> dict:
    if not values:
        return {"median": None, "max": None}
    return {"median": statistics.median(values), "max": max(values)}


def _group(value, group: list[dict]) -> dict:
    """The summary entry of the rows `group` under `value`."""
    ok = sum(bool(row.get("success")) for row in group)
    statuses: dict[str, int] = {}
    for row in group:
        statuses[row["status"]] = statuses.get(row["status"], 0) + 1
    return {
        "value": value,
        "n": len(group),
        "succeeded": ok,
        "rate": ok / len(group),
        "ci95": wilson_interval(ok, len(group)),
        "foot_error_m": _stats([r["foot_error_max_m"] for r in group if r.get("foot_error_max_m") is not None]),
        "drift_m": _stats([r["max_base_drift_m"] for r in group if r.get("max_base_drift_m") is not None]),
        "statuses": statuses,
    }


def _key(row: dict, column: str) -> str:
    return json.dumps(row.get(column), sort_keys=True)


def _binned(rows: list[dict], name: str, field: str, others: list[str]) -> list[dict] | None:
    """Groups of `rows` by quantile bins of the draw factor `name`'s `field` (by value for a
    choice), each with `bin` ([low, high]; None for a choice) and `by` {other factor: {value:
    {n, succeeded, rate}}}; None when not varied."""
    column = f"factor.{name}"
    drawn = [row[column][field] for row in rows]
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in drawn):
        numbers = np.array(drawn, dtype=float)
        edges = np.unique(np.quantile(numbers, np.linspace(0.0, 1.0, DRAW_BINS + 1)))
        # Bin k holds edges[k] <= x < edges[k + 1]; the last bin also holds its upper edge.
        which = np.clip(np.searchsorted(edges, numbers, side="right") - 1, 0, len(edges) - 2)
        bins = [
            (f"{edges[k]:.3g} to {edges[k + 1]:.3g}", [float(edges[k]), float(edges[k + 1])])
            for k in range(len(edges) - 1)
        ]
    else:  # a choice: one bin per value drawn
        choices = list(dict.fromkeys(json.dumps(v) for v in drawn))
        which = [choices.index(json.dumps(v)) for v in drawn]
        bins = [(json.loads(c) if isinstance(json.loads(c), str) else c, None) for c in choices]
    if len(bins) < 2:
        return None
    groups = []
    for k, (label, span) in enumerate(bins):
        group = [row for row, b in zip(rows, which, strict=True) if b == k]
        if not group:
            continue
        entry = _group(label, group)
        entry["bin"] = span
        entry["by"] = {}
        for other in others:
            by = {}
            for key in dict.fromkeys(_key(row, f"factor.{other}") for row in group):
                members = [row for row in group if _key(row, f"factor.{other}") == key]
                ok = sum(bool(row.get("success")) for row in members)
                by[json.loads(key) if isinstance(json.loads(key), str) else key] = {
                    "n": len(members),
                    "succeeded": ok,
                    "rate": ok / len(members),
                }
            entry["by"][other] = by
        groups.append(entry)
    return groups


def summarise(rows: list[dict], factor_names: list[str]) -> dict:
    """{factor: [{value, n, succeeded, rate, ci95, foot_error_m, drift_m, statuses}]} over `rows`.

    A draw factor gives one entry per drawn field, named "<factor>: <field>", its groups the
    field's bins (see `_binned`: with `bin` and `by`)."""
    summary = {}
    draws = [n for n in factor_names if rows and all(draw_label(row.get(f"factor.{n}")) for row in rows)]
    categorical = [n for n in factor_names if n not in draws]
    for name in factor_names:
        column = f"factor.{name}"
        if name in draws:
            others = [o for o in categorical if len({_key(row, f"factor.{o}") for row in rows}) > 1]
            for field in rows[0][column]:
                groups = _binned(rows, name, field, others)
                if groups is not None:
                    summary[f"{name}: {field}"] = groups
            continue
        values = list(dict.fromkeys(_key(row, column) for row in rows))
        if len(values) < 2:
            continue  # not varied in these rows
        summary[name] = [_group(json.loads(key), [row for row in rows if _key(row, column) == key]) for key in values]
    return summary


def format_summary(summary: dict) -> str:
    """The summary as text tables, one per varied factor."""
    lines = []
    for name, groups in summary.items():
        lines.append(f"\n{name}")
        lines.append(
            f"  {'value':<28} {'ok':>7} {'rate':>6} {'95% CI':>13} {'err med':>8} {'err max':>8} {'drift max':>9}"
        )
        for g in groups:

            def mm(x):
                return f"{1000 * x:8.1f}" if x is not None else "       -"

            lo, hi = g["ci95"]
            shown = g["value"] if "bin" in g else json.dumps(g["value"])
            lines.append(
                f"  {shown[:28]:<28} {g['succeeded']:>3}/{g['n']:<3} {g['rate']:6.2f} "
                f"[{lo:4.2f}, {hi:4.2f}] {mm(g['foot_error_m']['median'])} {mm(g['foot_error_m']['max'])} "
                f"{mm(g['drift_m']['max'])}"
            )
        for other in groups[0].get("by", {}):
            # The success rate of each value of another factor (each mission) in each bin.
            lines.append(f"  rate by {other}, bins as above:")
            for value in dict.fromkeys(v for g in groups for v in g["by"][other]):
                cells = [g["by"][other].get(value) for g in groups]
                text = " ".join(f"{c['rate']:4.2f}/{c['n']:<3}" if c else "   -    " for c in cells)
                lines.append(f"    {str(value)[:26]:<26} {text}")
    return "\n".join(lines)


def plot_summary(summary: dict, rows: list[dict], folder: Path) -> list[Path]:
    """success_vs_<factor>.png for each varied factor, and foot_errors.png (a histogram)."""
    folder = Path(folder)
    paths = []
    for name, groups in summary.items():
        fig, ax = plt.subplots(figsize=(7, 3.5))
        labels = [(g["value"] if "bin" in g else json.dumps(g["value"]))[:20] for g in groups]
        rates = [g["rate"] for g in groups]
        # Clipped at 0: at a rate of 0 or 1 the interval's end differs from it by rounding only.
        low = [max(0.0, g["rate"] - g["ci95"][0]) for g in groups]
        high = [max(0.0, g["ci95"][1] - g["rate"]) for g in groups]
        ax.errorbar(range(len(groups)), rates, yerr=[low, high], fmt="o", capsize=4, color="k", label="all", zorder=3)
        split = False
        for other in groups[0].get("by", {}):
            # One thin line per value of another factor (per mission): where a mission breaks.
            for value in dict.fromkeys(v for g in groups for v in g["by"][other]):
                line = [g["by"][other].get(value, {}).get("rate", np.nan) for g in groups]
                ax.plot(range(len(groups)), line, "-", lw=0.8, alpha=0.6, label=str(value)[:24])
                split = True
        if split:
            ax.legend(fontsize=6, ncol=2, loc="center left", bbox_to_anchor=(1.0, 0.5))
        ax.set_xticks(range(len(groups)), labels, rotation=30, ha="right", fontsize=8)
        ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel("success rate (95 % CI)")
        ax.set_title(f"success against {name}")
        fig.tight_layout()
        path = folder / f"success_vs_{name.replace(': ', '_')}.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        paths.append(path)
    errors = [1000 * r["foot_error_max_m"] for r in rows if r.get("foot_error_max_m") is not None]
    if errors:
        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.hist(errors, bins=min(30, max(5, len(errors) // 3)))
        ax.set_xlabel("largest foot error of a run [mm]")
        ax.set_ylabel("runs")
        fig.tight_layout()
        path = folder / "foot_errors.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        paths.append(path)
    return paths


def factor_names_of(rows: list[dict]) -> list[str]:
    """The factors of a study's rows (their `factor.<name>` columns), in the rows' order."""
    return list(dict.fromkeys(key.removeprefix("factor.") for row in rows for key in row if key.startswith("factor.")))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder", help="a study's results folder (holding results.jsonl)")
    parser.add_argument("--out", default=None, help="where to write the summary and plots (default: the folder)")
    args = parser.parse_args(argv)
    folder = Path(args.folder)
    if not (folder / ROWS_FILE).is_file():
        print(f"error: {folder}: no {ROWS_FILE} (run the study first)", file=sys.stderr)
        return 2
    rows = read_rows(folder)
    out = Path(args.out) if args.out else folder
    out.mkdir(parents=True, exist_ok=True)
    summary = summarise(rows, factor_names_of(rows))
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=str) + "\n")
    text = format_summary(summary)
    (out / "summary.txt").write_text(text + "\n")
    plot_summary(summary, rows, out)
    print(text)
    print(f"\n{len(rows)} rows; summary.json, summary.txt and plots in {out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
