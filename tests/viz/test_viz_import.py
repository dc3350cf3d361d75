"""``import drake_mh`` never imports Meshcat; ``import drake_mh.viz`` starts nothing."""

from __future__ import annotations

import json
import subprocess
import sys

CHECK = """
import json, sys
import drake_mh
after_top = sorted(m for m in sys.modules if m.startswith(("pydrake", "meshcat", "drake_mh.viz")))
import drake_mh.viz
after_viz = sorted(m for m in sys.modules if m in ("pydrake.geometry", "meshcat"))
print(json.dumps({"top": after_top, "viz": after_viz}))
"""


def test_import_drake_mh_does_not_import_meshcat():
    out = subprocess.run([sys.executable, "-c", CHECK], capture_output=True, text=True, timeout=120, check=True)
    found = json.loads(out.stdout.strip().splitlines()[-1])
    assert found["top"] == [], f"import drake_mh imported {found['top']}"
    # drake_mh.viz imports pydrake's Meshcat only when something is drawn
    assert found["viz"] == [], f"import drake_mh.viz imported {found['viz']}"
    assert "Meshcat listening" not in out.stderr + out.stdout
