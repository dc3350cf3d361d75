"""End to end in a real browser: ``drake-mh app`` in a subprocess, headless Chromium via selenium.

Needs Debian's ``chromium`` + ``chromium-driver`` and the ``selenium`` package (see
docs/app.md); skipped with a message when they are missing (CI installs them). The window is
1400×900: the app's status box and every control must be visible without scrolling. The
screenshot is kept under pytest's tmp dir, and copied to ``$DRAKE_MH_SCREENSHOT`` when set
(``DRAKE_MH_SCREENSHOT=docs/app_screenshot.png``), shrunk below 300 kB.
"""

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--window-size=1400,900")



_OUTSIDE_THE_PANEL = """
const panel = document.getElementById("panel");
const box = panel.getBoundingClientRect();
const left = box.left + panel.clientLeft, right = left + panel.clientWidth;   // clientWidth: no scrollbar
const out = [];
for (const element of panel.querySelectorAll("button, .slider > *, #status")) {
  const r = element.getBoundingClientRect();
  if (r.width === 0 && r.height === 0) continue;                              // not displayed
  if (r.left < left - 0.5 || r.right > right + 0.5)
    out.push([element.closest("[data-name]")?.dataset.name || element.textContent, element.tagName,
              Math.round(r.left - left), Math.round(right - r.right)]);
}
if (panel.scrollWidth > panel.clientWidth) out.push(["panel", "scrollWidth", panel.scrollWidth, panel.clientWidth]);
return out;
"""


def _default_sigint():
    """In the app's process, before exec: Ctrl-C as in a terminal. A test run started as a
    background job (``cmd &`` in a script) ignores SIGINT, and a child would inherit that."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


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


COMPILE_WAIT = 1800.0
"""[s] the wait for the app's solutions and plan: from an empty kernel cache the app compiles its IK,
planning and verification kernels for minutes first (each wait ends as soon as its condition holds)."""


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


def _button(driver, label: str):
    """The app page's button labelled ``label`` (``None`` if absent)."""
    from selenium.webdriver.common.by import By

    found = [b for b in driver.find_elements(By.CSS_SELECTOR, "#panel button") if b.text == label]
    return found[0] if found else None


def _slider_field(driver, name: str):
    """The number field of the app page's slider ``name`` (``None`` if absent)."""
    from selenium.webdriver.common.by import By

    found = driver.find_elements(By.CSS_SELECTOR, f'#panel .slider[data-name="{name}"] input[type=number]')
    return found[0] if found else None


def _status_text(driver) -> str:
    from selenium.webdriver.common.by import By

    return driver.find_element(By.ID, "status").text


def _shrink_png(src: Path, dst: Path, limit: int = 300_000) -> None:
    """Copy a screenshot below ``limit`` bytes: as is if it fits, else 256 colours, then smaller.

    (A 128-colour median cut once painted the orange robot the obstacle's red: colours matter here.)
    """
    from PIL import Image

    image = Image.open(src).convert("RGB")
    dst.parent.mkdir(parents=True, exist_ok=True)
    image.save(dst, optimize=True)
    width = image.width
    while dst.stat().st_size >= limit and width >= 400:
        small = image.resize((width, round(image.height * width / image.width)), Image.LANCZOS)
        small.quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(dst, optimize=True)
        width = int(width * 0.8)


@pytest.mark.slow
def test_app_in_headless_chromium(tmp_path):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    from drake_mh.viz.app_controls import SECTIONS

    driver = _browser(tmp_path)
    status = tmp_path / "status.json"
    app = subprocess.Popen([sys.executable, "-m", "drake_mh", "app", "--port", "0", "--max-seconds", "3600",
                            "--method", "pso", "--budget", "4000", "--status-file", str(status)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           preexec_fn=_default_sigint)
    try:
        line = app.stdout.readline()
        match = re.search(r"open (http://localhost:\d+) in a browser", line)
        assert match, f"the app did not print its URL: {line!r}"
        driver.get(match.group(1))
        _wait(lambda: _button(driver, "Generate / Regenerate solutions"), 60, "the app's controls")
        _wait(lambda: "ready" in _status_text(driver), 30, "the status box")
        # Table 1's parts are above the fold of a 1400x900 window, the status box first; the planning
        # section follows (the panel scrolls, the status box stays on top)
        height = driver.execute_script("return window.innerHeight")
        box = driver.find_element(By.ID, "status").rect
        for name in [n for _, group in SECTIONS[:-1] for n in group]:
            element = _button(driver, name) or _slider_field(driver, name)
            assert element is not None and element.is_displayed(), name
            assert box["y"] < element.rect["y"] and element.rect["y"] + element.rect["height"] <= height, name
        # and every control lies fully inside the panel's visible width, beside its scrollbar: each
        # slider's value field was cut off by 9 px (the grid's 1fr column could not shrink below the
        # range input's natural width), and typing in it scrolled the whole panel sideways
        outside = driver.execute_script(_OUTSIDE_THE_PANEL)
        assert outside == [], outside
        plan = _button(driver, "Plan to goal pose")
        assert plan is not None and _slider_field(driver, "Goal joint 6") is not None
        driver.execute_script("arguments[0].scrollIntoView();", plan)
        assert driver.find_element(By.ID, "status").rect["y"] < plan.rect["y"] <= height
        driver.execute_script("document.getElementById('panel').scrollTop = 0;")
        # the 3-D view renders beside the panel (Meshcat's page in the iframe, WebGL)
        frame = driver.find_element(By.ID, "view")
        assert frame.rect["x"] >= box["x"] + box["width"] and frame.rect["width"] >= 900
        driver.switch_to.frame(frame)
        _wait(lambda: driver.execute_script(
            "const c = [...document.querySelectorAll('canvas')].find(c => c.width > 300);"
            "return c && c.getContext && (c.getContext('webgl2') || c.getContext('webgl')) ? c.width : 0;"),
            60, "a WebGL canvas")
        driver.switch_to.default_content()
        before = _wait(lambda: _status(status) or None, 30, "the status file")
        assert not before["solutions"] and before["page_url"] == match.group(1)

        _button(driver, "Generate / Regenerate solutions").click()
        generated = _wait(lambda: (s := _status(status)).get("solutions") and s, COMPILE_WAIT, "generated solutions")
        _wait(lambda: "generated" in _status_text(driver), 30, "the status box to say so")
        _button(driver, "Run").click()
        _wait(lambda: _status(status).get("mode") == "run", 30, "run mode")

        # move the obstacle down onto the arm's workspace: type into its Z field, as a user would
        field = _slider_field(driver, "Obstacle Z [m]")
        field.click()
        field.send_keys(Keys.CONTROL, "a")
        field.send_keys("0.4", Keys.ENTER)
        moved = _wait(lambda: (s := _status(status)).get("obstacle") and abs(s["obstacle"][2] - 0.4) < 1e-6 and s,
                      60, "the obstacle to move")
        assert driver.execute_script("return document.getElementById('panel').scrollLeft;") == 0
        assert moved["obstacle"][:2] == generated["obstacle"][:2]
        assert moved["message"] != generated["message"] or moved["events"] > generated["events"]
        time.sleep(1.0)
        after = _status(status)
        assert after["frames"] > generated["frames"] and after["index"] is not None
        driver.execute_script("document.activeElement.blur();")
        time.sleep(0.5)
        shot = tmp_path / "app_screenshot.png"
        driver.save_screenshot(str(shot))
        assert shot.stat().st_size > 10_000
        target = os.environ.get("DRAKE_MH_SCREENSHOT")
        if target:
            _shrink_png(shot, Path(target))

        # plan from where the arm is to the goal point: a verdict in the status, in the file and on the page
        driver.execute_script("arguments[0].click();", _button(driver, "Plan to goal pose"))
        planned = _wait(lambda: (s := _status(status)).get("plan") and not s["planning"] and s, COMPILE_WAIT,
                        "a planning verdict")
        assert planned["plan"]["goal"] == "pose" and planned["plan_method"] == "rrt_connect_smooth"
        _wait(lambda: any(w in _status_text(driver) for w in ("goal pose", "stays where it is")), 30, "the verdict")

        # Ctrl-C: the app's own stop line, and the page says the app stopped
        app.send_signal(signal.SIGINT)
        out, err = app.communicate(timeout=60)
        assert app.returncode == 0 and "app stopped by Ctrl-C" in out, (out, err)
        assert "run the same command again" not in out + err
        _wait(lambda: "app stopped" in _status_text(driver), 30, "the page to say the app stopped")
    finally:
        driver.quit()
        app.kill()
        app.wait(timeout=30)
