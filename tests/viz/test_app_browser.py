"""End to end in a real browser: ``drake-mh app`` in a subprocess, headless Chromium via selenium.

Needs Debian's ``chromium`` + ``chromium-driver`` and the ``selenium`` package (see
docs/app.md); skipped with a message when they are missing (CI installs them). The
screenshot is kept under pytest's tmp dir, and copied to ``$DRAKE_MH_SCREENSHOT`` when set
(``DRAKE_MH_SCREENSHOT=docs/app_screenshot.png``), shrunk below 300 kB.
"""

import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--window-size=1200,800")


def _missing(message: str):
    """Skip locally; in CI (``CI`` set, as .ci/run runs) the browser test must run: fail."""
    if os.environ.get("CI"):
        pytest.fail(f"{message} — .ci/run must install it", pytrace=False)
    pytest.skip(message)


def _browser(tmp_path):
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        _missing("selenium is not installed: pip install selenium (see docs/app.md)")
    if not (os.path.exists(CHROMIUM) and os.path.exists(DRIVER)):
        _missing("Chromium is missing: apt-get install -y chromium chromium-driver (see docs/app.md)")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in FLAGS:
        options.add_argument(flag)
    options.add_argument(f"--user-data-dir={tmp_path / 'chromium-profile'}")
    return webdriver.Chrome(service=Service(DRIVER), options=options)


def _wait(predicate, timeout, what):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def _status(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


def _control(driver, label: str, kind: str):
    """The dat.GUI row (li.cr.<kind>) of Meshcat's control panel whose label starts with ``label``."""
    from selenium.webdriver.common.by import By

    for row in driver.find_elements(By.CSS_SELECTOR, f"li.cr.{kind}"):
        names = row.find_elements(By.CSS_SELECTOR, ".property-name")
        if names and names[0].get_attribute("textContent").startswith(label):
            return row
    return None


def _shrink_png(src: Path, dst: Path, limit: int = 300_000) -> None:
    from PIL import Image

    image = Image.open(src).convert("RGB")
    dst.parent.mkdir(parents=True, exist_ok=True)
    width = image.width
    while True:
        small = image.resize((width, round(image.height * width / image.width)), Image.LANCZOS)
        small.quantize(colors=128).save(dst, optimize=True)
        if dst.stat().st_size < limit or width < 400:
            return
        width = int(width * 0.8)


@pytest.mark.slow
def test_app_in_headless_chromium(tmp_path):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    driver = _browser(tmp_path)
    status = tmp_path / "status.json"
    app = subprocess.Popen([sys.executable, "-m", "drake_mh", "app", "--port", "0", "--max-seconds", "240",
                            "--method", "pso", "--budget", "4000", "--status-file", str(status)],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        url = None
        for line in app.stdout:
            match = re.search(r"open (http://localhost:\d+)", line)
            if match:
                url = match.group(1)
                break
        assert url, "the app did not print its URL"
        driver.get(url)
        # the 3-D canvas renders (WebGL through Chromium's software renderer)
        _wait(lambda: driver.execute_script(
            "const c = [...document.querySelectorAll('canvas')].find(c => c.width > 300);"
            "return c && c.getContext && (c.getContext('webgl2') || c.getContext('webgl')) ? c.width : 0;"),
            60, "a WebGL canvas")
        open_button = driver.find_elements(By.CSS_SELECTOR, ".dg.main .close-button")
        if open_button and "Open" in open_button[0].text:
            open_button[0].click()
        _wait(lambda: _control(driver, "Generate / Regenerate solutions", "function"), 60, "the Meshcat controls")
        for label in ("Next robot", "Next algorithm", "Edit next point", "Show environment", "Test run", "Run", "Stop"):
            assert _control(driver, label, "function") is not None, label
        for label in ("Obstacle X", "Obstacle Y", "Obstacle Z", "Points in path", "Point X"):
            assert _control(driver, label, "number") is not None, label
        _wait(lambda: _control(driver, "Status: ", "function"), 30, "the status line")
        before = _wait(lambda: _status(status) or None, 30, "the status file")
        assert not before["solutions"]

        _control(driver, "Generate / Regenerate solutions", "function").click()
        generated = _wait(lambda: (s := _status(status)).get("solutions") and s, 180, "generated solutions")
        _wait(lambda: (row := _control(driver, "Status: ", "function")) and "generated" in row.text, 30,
              "the status line in the page")
        _control(driver, "Run", "function").click()
        _wait(lambda: _status(status).get("mode") == "run", 30, "run mode")

        # move the obstacle down onto the arm's workspace with its Z slider (typed, as a user would)
        field = _control(driver, "Obstacle Z", "number").find_element(By.CSS_SELECTOR, "input")
        field.click()
        field.send_keys(Keys.CONTROL, "a")
        field.send_keys("0.4", Keys.ENTER)
        moved = _wait(lambda: (s := _status(status)).get("obstacle") and abs(s["obstacle"][2] - 0.4) < 1e-6 and s,
                      60, "the obstacle to move")
        assert moved["obstacle"][:2] == generated["obstacle"][:2]
        assert moved["message"] != generated["message"] or moved["events"] > generated["events"]
        time.sleep(1.0)
        after = _status(status)
        assert after["frames"] > generated["frames"] and after["index"] is not None
        driver.execute_script("document.activeElement.blur(); window.scrollTo(0, 0);"
                              "document.querySelectorAll('*').forEach(e => { e.scrollTop = 0; e.scrollLeft = 0; });")
        time.sleep(0.5)
        shot = tmp_path / "app_screenshot.png"
        driver.save_screenshot(str(shot))
        assert shot.stat().st_size > 10_000
        target = os.environ.get("DRAKE_MH_SCREENSHOT")
        if target:
            _shrink_png(shot, Path(target))
    finally:
        driver.quit()
        app.kill()
        app.wait(timeout=30)
