"""A real headless Chromium on the station's page, for the tests and the benchmark.

Needs Debian's ``chromium`` and ``chromium-driver`` and the ``selenium`` package (a dev
dependency; the station itself never imports this module). WebDriver talks to
``/usr/bin/chromedriver`` directly: nothing is downloaded.
"""

from __future__ import annotations

import contextlib
import shutil
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--window-size=1600,1250",
)
CHROMIUM = ("/usr/bin/chromium", "chromium")
CHROMEDRIVER = ("/usr/bin/chromedriver", "chromedriver")


def _find(candidates: tuple[str, ...], package: str) -> str:
    for name in candidates:
        path = shutil.which(name)
        if path:
            return path
    raise FileNotFoundError(f"{candidates[-1]} not found: install Debian's {package}")


@contextlib.contextmanager
def chromium(
    profile_dir: Path, *, page_load_timeout: float = 30.0, extra_flags: Sequence[str] = ()
) -> Iterator[Any]:
    """A headless Chromium WebDriver with a fresh profile in ``profile_dir``; console messages
    are kept (``driver.get_log("browser")``). ``extra_flags`` are added (e.g.
    ``--host-resolver-rules=MAP station.test 127.0.0.1`` to reach loopback by another name).
    Quit on exit."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = _find(CHROMIUM, "chromium")
    for flag in (*CHROMIUM_FLAGS, *extra_flags):
        options.add_argument(flag)
    profile_dir.mkdir(parents=True, exist_ok=True)
    options.add_argument(f"--user-data-dir={profile_dir}")
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    service = Service(_find(CHROMEDRIVER, "chromium-driver"))
    driver = webdriver.Chrome(service=service, options=options)
    try:
        driver.set_page_load_timeout(page_load_timeout)
        driver.set_script_timeout(10)
        yield driver
    finally:
        driver.quit()


def console_errors(driver: Any) -> list[str]:
    """The page's console errors (level SEVERE) since the last call."""
    return [e["message"] for e in driver.get_log("browser") if e.get("level") == "SEVERE"]
