"""The headless browser of the browser tests: the system's Chromium (.ci/run installs it from apt)."""

import shutil

import pytest

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")


def chromium() -> str:
    """The path of the system's Chromium; fails the test, saying how to install it, without one."""
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    pytest.fail("no Chromium found: install the system package (apt-get install -y chromium); .ci/run does")
