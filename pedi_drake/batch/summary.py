"""A study's summary: for each varied factor, the success rate (with a 95 % Wilson interval) and
the distributions of foot error and trunk drift by factor value; tables and plots.
"""

import json
import math
import statistics
from pathlib import Path

import matplotlib.pyplot as plt

Z_95 = 1.959964  # two-sided 95 % normal quantile


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


def summarise(rows: list[dict], factor_names: list[str]) -> dict:
    """{factor: [{value, n, succeeded, rate, ci95, foot_error_m, drift_m, statuses}]} over `rows`."""
    summary = {}
    for name in factor_names:
        column = f"factor.{name}"
        values = list(dict.fromkeys(json.dumps(row.get(column), sort_keys=True) for row in rows))
        if len(values) < 2:
            continue  # not varied in these rows
        groups = []
        for key in values:
            group = [row for row in rows if json.dumps(row.get(column), sort_keys=True) == key]
            ok = sum(bool(row.get("success")) for row in group)
            statuses: dict[str, int] = {}
            for row in group:
                statuses[row["status"]] = statuses.get(row["status"], 0) + 1
            groups.append(
                {
                    "value": json.loads(key),
                    "n": len(group),
                    "succeeded": ok,
                    "rate": ok / len(group),
                    "ci95": wilson_interval(ok, len(group)),
                    "foot_error_m": _stats(
                        [r["foot_error_max_m"] for r in group if r.get("foot_error_max_m") is not None]
                    ),
                    "drift_m": _stats([r["max_base_drift_m"] for r in group if r.get("max_base_drift_m") is not None]),
                    "statuses": statuses,
                }
            )
        summary[name] = groups
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
            lines.append(
                f"  {json.dumps(g['value'])[:28]:<28} {g['succeeded']:>3}/{g['n']:<3} {g['rate']:6.2f} "
                f"[{lo:4.2f}, {hi:4.2f}] {mm(g['foot_error_m']['median'])} {mm(g['foot_error_m']['max'])} "
                f"{mm(g['drift_m']['max'])}"
            )
    return "\n".join(lines)


def plot_summary(summary: dict, rows: list[dict], folder: Path) -> list[Path]:
    """success_vs_<factor>.png for each varied factor, and foot_errors.png (a histogram)."""
    folder = Path(folder)
    paths = []
    for name, groups in summary.items():
        fig, ax = plt.subplots(figsize=(7, 3.5))
        labels = [json.dumps(g["value"])[:20] for g in groups]
        rates = [g["rate"] for g in groups]
        low = [g["rate"] - g["ci95"][0] for g in groups]
        high = [g["ci95"][1] - g["rate"] for g in groups]
        ax.errorbar(range(len(groups)), rates, yerr=[low, high], fmt="o", capsize=4)
        ax.set_xticks(range(len(groups)), labels, rotation=30, ha="right", fontsize=8)
        ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel("success rate (95 % CI)")
        ax.set_title(f"success against {name}")
        fig.tight_layout()
        path = folder / f"success_vs_{name}.png"
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
