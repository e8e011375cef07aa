"""The Meshcat panel in a real browser, started as the README says: `python run_sim.py --meshcat
--teleop` in its own process, headless Chromium (the system package) driven by Playwright.

The person's steps, as a test: open the page and its controls, click "Teleop (t)", step the
foot's forward velocity up with the w key (the panel's slider), drive the lifted FR foot into the
wall in front of it, and read what the page shows: the "foot force [N]" gauge rises, the force
arrow at the foot becomes visible in the scene, and the bar of the limit is drawn. Then the
"Stop foot" and "Autonomous (g)" buttons: the run leaves its teleop phase (the mode changes), puts
the leg back, lies down and ends, and its result.json says the operator ended the phase and
the foot's estimated force stayed under its bound.
"""

import json
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from browser import chromium
from PIL import Image

from pedi_drake.viz.force_display import FORCE_GAUGE, LIMIT_GAUGE

playwright = pytest.importorskip("playwright.sync_api")

REPO = Path(__file__).resolve().parents[1]
# Wall time for the run to reach its teleop phase (stand-up and lift: about 6 s of simulated time
# at real time; the kernels may compile first in a fresh checkout) [s].
TELEOP_PHASE_TIMEOUT = 300.0
PUSH_TIMEOUT = 30.0  # [s] of wall time for the foot to reach the wall and push
ARROW_DRAW_TIMEOUT = 10.0  # [s] of wall time for the page to draw the arrow it shows
TOUCH_FORCE = 5.0  # [N] on the gauge: the foot pushes the wall
ARROW_PATH = ["operator", "force", "arrow"]


class _Run:
    """`python run_sim.py --meshcat --teleop` in its own process, its output lines collected."""

    def __init__(self, folder: Path):
        self.lines: list[str] = []
        self.process = subprocess.Popen(
            [sys.executable, str(REPO / "run_sim.py"), "--meshcat", "--teleop"],
            cwd=folder,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.process.stdout:
            self.lines.append(line.rstrip())

    def wait_for(self, pattern: str, timeout: float) -> re.Match:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in list(self.lines):
                match = re.search(pattern, line)
                if match:
                    return match
            if self.process.poll() is not None and not any(re.search(pattern, line) for line in self.lines):
                break
            time.sleep(0.1)
        pytest.fail(f"the run never printed {pattern!r}; its output:\n" + "\n".join(self.lines[-40:]))


def _gauge(page, label: str) -> float:
    """The value a slider of the panel shows (dat.GUI: the text input beside its label)."""
    row = page.locator("li.cr", has=page.locator("span.property-name", has_text=label))
    return float(row.locator("input").first.input_value())


def _arrow_visible(page) -> bool:
    return bool(
        page.evaluate(
            "path => { const node = viewer.scene_tree.find(path); return node.object.visible && "
            "node.object.children.some(child => child.visible !== false); }",
            ARROW_PATH,
        )
    )


def _magenta_pixels(png: Path) -> int:
    image = np.asarray(Image.open(png).convert("RGB")).astype(int)
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return int(np.sum((r > 120) & (b > 90) & (g < 0.5 * r) & (g < 0.6 * b)))


def test_the_panel_drives_the_foot_into_the_wall_and_shows_the_force(tmp_path):
    run = _Run(tmp_path)
    try:
        url = run.wait_for(r"Meshcat: (http\S+)", 120.0).group(1)
        with playwright.sync_playwright() as p:
            browser = p.chromium.launch(
                executable_path=chromium(),
                # CI runs as root (no sandbox) and has no GPU (software WebGL).
                args=["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
            )
            page = browser.new_page(viewport={"width": 1000, "height": 700})
            page.goto(url)
            page.get_by_text("Open Controls").click()
            page.get_by_text("Teleop (t)").wait_for(timeout=120_000)
            run.wait_for(r"teleop \(running\)", TELEOP_PHASE_TIMEOUT)
            before = tmp_path / "before.png"
            page.screenshot(path=before)
            assert not _arrow_visible(page) and _gauge(page, FORCE_GAUGE) < TOUCH_FORCE
            page.get_by_text("Teleop (t)").click()
            page.locator("body").click(position={"x": 400, "y": 650})  # the scene has the keys' focus
            for _ in range(8):  # 8 steps of 5 mm/s: 4 cm/s forward
                page.keyboard.press("w")
            deadline = time.monotonic() + PUSH_TIMEOUT
            while time.monotonic() < deadline and _gauge(page, FORCE_GAUGE) < TOUCH_FORCE:
                time.sleep(0.2)
            force, limit = _gauge(page, FORCE_GAUGE), _gauge(page, LIMIT_GAUGE)
            assert force >= TOUCH_FORCE, f"the gauge shows {force} N: the foot never pushed the wall"
            assert 0.0 < limit <= 15.0  # the phase's max_force, less the estimate's noise margin
            assert _arrow_visible(page)
            # The page draws the arrow on its next frames; software WebGL on a loaded machine may
            # take a few of them, so the picture is taken until it shows (or the time is up).
            after = tmp_path / "after.png"
            deadline = time.monotonic() + ARROW_DRAW_TIMEOUT
            page.screenshot(path=after)
            while _magenta_pixels(after) <= _magenta_pixels(before) + 20 and time.monotonic() < deadline:
                time.sleep(0.25)
                page.screenshot(path=after)
            assert _magenta_pixels(after) > _magenta_pixels(before) + 20
            page.get_by_text("Stop foot (space)").click()
            page.get_by_text("Autonomous (g)").click()
            run.wait_for(r"leg_to_support", 60.0)
            browser.close()
        run.process.wait(timeout=120.0)
    finally:
        if run.process.poll() is None:
            run.process.terminate()
            run.process.wait(timeout=30.0)
    assert run.process.returncode == 0, "\n".join(run.lines[-40:])
    (result_file,) = (tmp_path / "out").glob("*/result.json")
    result = json.loads(result_file.read_text())
    (teleop,) = result["teleop"]
    assert teleop["ended_by"] == "operator"
    assert teleop["bound_activations"]["force"] > 0 or teleop["bound_activations"]["balance"] > 0
    assert teleop["max_force_n"] < 15.0 + 2.0  # the bound, and the estimate's lag at the impact
