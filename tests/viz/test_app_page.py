"""The app's own page: served on localhost, sections in Table 1's order, Meshcat beside it."""

from __future__ import annotations

import json
import re
import urllib.error
import urllib.request

import pytest

from drake_mh.viz.app_controls import SECTIONS
from drake_mh.viz.app_page import AppPage, page_html

SLIDERS = [n for _, names in SECTIONS for n in names if "[m]" in n or n == "Points in path"]


def _config(html: str) -> dict:
    return json.loads(re.search(r"const CONFIG = (\{.*?\});\n", html).group(1))


def test_page_lists_sections_in_order_and_points_at_meshcat():
    html = page_html(7123, SECTIONS, SLIDERS, primary=("Run",), wide=("Generate / Regenerate solutions",))
    config = _config(html)
    assert config["meshcat_port"] == 7123
    assert [s["title"] for s in config["sections"]] == [t for t, _ in SECTIONS]
    assert config["sections"][3]["controls"][0] == "Obstacle X [m]"
    assert config["sections"][-1]["controls"][0] == "Plan to goal pose"           # planning comes last
    # the status box comes before every control in the page
    assert html.index('id="status"') < html.index('id="sections"') < html.index('<iframe')


def test_names_cannot_close_the_script_element():
    html = page_html(7000, [("x", ["</script><b>"])], [])
    assert "</script><b>" not in html and _config(html)["sections"][0]["controls"] == ["</script><b>"]


def test_server_serves_the_page_and_meshcat_js_only():
    page = AppPage(page_html(7000, SECTIONS, SLIDERS), port=0)
    try:
        assert page.url == f"http://localhost:{page.port}"
        body = urllib.request.urlopen(page.url + "/", timeout=10).read().decode()
        assert "drake-mh app" in body and _config(body)["meshcat_port"] == 7000
        js = urllib.request.urlopen(page.url + "/meshcat.js", timeout=10)
        assert js.headers["Content-Type"].startswith("text/javascript") and b"msgpack" in js.read()
        with pytest.raises(urllib.error.HTTPError, match="404"):
            urllib.request.urlopen(page.url + "/etc/passwd", timeout=10)
    finally:
        page.close()
    page.close()                                                        # idempotent
    with pytest.raises(urllib.error.URLError):
        urllib.request.urlopen(page.url + "/", timeout=5)


def test_page_takes_the_first_free_port_after_meshcats():
    first = AppPage("<p>a</p>", first=7500)
    try:
        second = AppPage("<p>b</p>", first=first.port)
        try:
            assert 7500 <= first.port < second.port < 8000
        finally:
            second.close()
    finally:
        first.close()


def test_page_takes_the_next_free_port_even_past_7999():
    """Meshcat on 7998 with 7999 busy: the page failed to start ("cannot serve the app's page ...
    port from 7999") although ports above were free."""
    import socket

    busy = socket.socket()
    try:
        try:
            busy.bind(("localhost", 7999))
            busy.listen()
        except OSError:  # another process holds it: busy all the same
            pass
        page = AppPage("<p>a</p>", first=7999)
        try:
            assert page.port > 7999
            with urllib.request.urlopen(page.url + "/", timeout=10) as response:
                assert response.read() == b"<p>a</p>"
        finally:
            page.close()
    finally:
        busy.close()
