"""replay.html in a real browser: headless Chromium (the system package) renders it, and the robot
is large in the frame, not a speck in an empty field.

The check reads a screenshot: the Go1's trunk and feet are near-black, the sky, the ground and the
grid are light, so the share of dark pixels in the middle of the frame says how large the robot is.
Meshcat's default camera, several metres off, shows it at under 1 % of the centre.
"""

import subprocess

import numpy as np
import pytest
from browser import chromium
from PIL import Image

from pedi_drake.run import run
from pedi_drake.scenario import load_scenario

WINDOW = (800, 600)  # [px]
DARK = 90  # a pixel whose brightest channel is below this is the robot's (trunk, feet, motors)
MIN_ROBOT_SHARE = 0.03  # of the centre's pixels: several times what the default camera gives


def _screenshot(html, png, profile) -> np.ndarray:
    command = [
        chromium(),
        "--headless",
        "--no-sandbox",  # CI runs as root, where Chromium's sandbox refuses to start
        # Software WebGL (SwiftShader): a CI machine has no GPU.
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        f"--user-data-dir={profile}",
        f"--window-size={WINDOW[0]},{WINDOW[1]}",
        "--hide-scrollbars",
        # Virtual time runs the page's scripts (loading the scene, playing the replay) to the end.
        "--virtual-time-budget=15000",
        f"--screenshot={png}",
        html.resolve().as_uri(),
    ]
    subprocess.run(command, check=True, capture_output=True, timeout=240)
    return np.asarray(Image.open(png).convert("RGB")).astype(int)


def _robot_share_of_centre(image: np.ndarray) -> float:
    h, w, _ = image.shape
    centre = image[h // 4 : 3 * h // 4, w // 4 : 3 * w // 4]
    return float(np.mean(centre.max(axis=2) < DARK))


@pytest.mark.parametrize(
    "scenario_name, mission, duration",
    [("stand", None, 2.0), ("default", "hit_target_front", 0.3)],
)
def test_the_replay_opens_in_chromium_with_the_robot_large_in_the_frame(tmp_path, scenario_name, mission, duration):
    scenario = load_scenario(scenario_name=scenario_name)
    if mission is not None:
        scenario.mission = mission
    scenario.simulation_duration = duration
    out = tmp_path / "run"
    run(scenario=scenario, name=scenario_name, out_dir=out, quiet=True)
    image = _screenshot(out / "replay.html", tmp_path / "shot.png", tmp_path / "profile")
    assert image.shape[:2] == (WINDOW[1], WINDOW[0])
    share = _robot_share_of_centre(image)
    assert share > MIN_ROBOT_SHARE, f"the robot covers {100 * share:.1f} % of the frame's centre"
