"""The IK benchmark command: runs on a few targets and writes a consistent JSON."""

import json

import numpy as np

from pedi_drake.ik import benchmark, leg_ik_solutions


def test_benchmark_writes_consistent_json(tmp_path, capsys):
    out = tmp_path / "ik.json"
    benchmark.main(["--targets", "20", "--seed", "3", "--workspace-samples", "40", "--out", str(out)])
    printed = capsys.readouterr().out
    assert "fabrik" in printed and "snopt" in printed and "closed_form" in printed
    results = json.loads(out.read_text())

    cube = results["paper_cube"]
    targets = np.array(cube["targets_B"])
    assert targets.shape == (20, 3)
    centre = np.array(cube["cube_centre_B"])
    assert np.all(np.abs(targets - centre) <= 0.15)
    reachable = sum(bool(leg_ik_solutions("FR", p)) for p in targets)
    assert cube["reachable"] == reachable
    assert sum(cube["target_classes"].values()) == 20

    rows = {(r["solver"], r["start"], r["threshold_m"]): r for r in cube["rows"]}
    assert len(rows) == 3 * 2 * 2
    for start in ("extended", "standing"):
        assert rows[("closed_form", start, 1e-3)]["reached"] == reachable
        fabrik = rows[("fabrik", start, 1e-3)]
        assert fabrik["reached"] >= reachable
        assert fabrik["max_error_reached_m"] <= 1e-3
        assert fabrik["median_time_us"] > 0.0
    # Every FABRIK miss is classified, and no reachable target is missed.
    assert all(m["class"].startswith("unreachable") for m in cube["misses"])
    for m in cube["misses"]:
        assert not leg_ik_solutions("FR", np.array(m["target_B"]))

    workspace = results["workspace"]
    assert set(workspace["legs"]) == {"FR", "FL", "RR", "RL"}
    assert workspace["legs"]["RL"]["standing"]["targets"] == 40
    assert 0.0 <= workspace["reach_rate"] <= 1.0
    assert set(results["floors"]["met"]) == {
        "reach_99_5",
        "mean_error_below_0_2mm",
        "mean_iterations_at_most_1_76",
        "median_time_below_100us",
    }
