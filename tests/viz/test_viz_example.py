"""examples/show_panda.py runs headless and writes its animation page."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import viz_html

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "show_panda.py"


@pytest.mark.slow
def test_show_panda_example_writes_the_page(tmp_path):
    out = tmp_path / "panda_animation.html"
    result = subprocess.run([sys.executable, str(EXAMPLE), "--quick", "--out", str(out)],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "http://localhost:" in result.stdout
    html = out.read_text(encoding="utf-8")
    anim = viz_html.animation(html)
    assert anim is not None and len(anim["animations"]) == 8  # the Panda's 8 links with geometry
    paths = viz_html.objects(html)
    assert any(p.startswith("/drake_mh/ghosts/goal/") for p in paths)
    assert "/drake_mh/obstacles/ball" in paths
    assert any(p.startswith("/drake_mh/distances/") for p in paths)
