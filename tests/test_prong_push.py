"""Paper 003's push experiment with the prongs placed along and across the push
(pedi_drake.benchmarks.prong_push)."""

import numpy as np

from pedi_drake.benchmarks.prong_push import DESIGNS, DIRECTIONS, one_run, variant_mission
from pedi_drake.mission.spec import load_mission


def test_each_variant_is_the_push_recovery_mission_with_its_prongs_and_direction(tmp_path):
    for direction, unit in DIRECTIONS.items():
        for design, points in DESIGNS.items():
            mission = load_mission(str(variant_mission(design, direction, tmp_path)))
            (push,) = mission.pushes
            assert push.direction == unit and push.force == 30.0
            prongs = mission.robot.prongs
            if points is None:
                assert prongs is None
            else:
                assert np.allclose(prongs.attachment_points, points)


def test_a_pair_along_the_push_takes_its_moment_off_the_knees(tmp_path):
    without = one_run("none", "x", tmp_path)
    along = one_run("centre_line", "x", tmp_path)
    assert without["success"] and along["success"], (without["reason"], along["reason"])
    # Without prongs the push along x shifts load from the hind legs to the front ones by about 2 N m
    # per knee; a centre-line pair carries that pitch moment itself.
    assert without["largest_knee_torque_added_Nm"] > 1.0
    assert along["largest_knee_torque_added_Nm"] < 0.5 * without["largest_knee_torque_added_Nm"]
    assert along["prong_share_of_push"] > 0.5
