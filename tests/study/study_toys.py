"""Toy studies written to temporary files, as users write them in studies/ (test helpers)."""

from __future__ import annotations

import textwrap
from pathlib import Path

TOY = '''
import time
import numpy as np
from drake_mh.study import Fields, Study

def run(case):
    if case["method"] == "bad" and case["rep"] == 1:
        raise ValueError("boom on purpose")
    time.sleep(SLEEP)
    scale = {"a": 1.0, "b": 0.5, "bad": 2.0}[case["method"]]
    x = case.instance_rng.uniform(0.5, 1.0)
    best = scale * x / (1.0 + np.arange(20)) * (1.0 + 0.1 * case.rng.uniform(size=20))
    out = {
        "success": bool(best[-1] < 0.04),
        "error": float(np.min(best)),
        "time": float(case.rng.uniform(0.01, 0.02)),
        "nfe": 20 * 10,
        "x": x,
        "draw": float(case.rng.uniform()),
        "history_nfe": np.arange(1, 21) * 10,
        "history_best": best,
    }
    if case["rep"] == 0:
        t = np.linspace(0.0, 1.0, 30)
        out["traj_t"] = t
        out["traj_q"] = np.c_[np.sin(t), np.cos(t)]
        case.attach("anim.html", "<html><body><p>animation of " + case.key + "</p></body></html>")
    return out

study = Study(
    name="toy",
    run=run,
    grid={"inst": ["p", "q"], "method": ["a", "b", "bad"], "rep": range(REPS)},
    quick_grid={"inst": ["p"], "method": ["a", "b"], "rep": range(2)},
    seed=3,
    description="A toy study for the tests.",
    summarize=lambda records: "toy summary: %d records" % len(records),
)
'''


def write_toy(folder: Path, sleep: float = 0.0, reps: int = 4, name: str = "toy.py") -> Path:
    """Writes the toy study file and returns its path."""
    path = folder / name
    path.write_text(textwrap.dedent(TOY).replace("SLEEP", repr(sleep)).replace("REPS", str(reps)))
    return path



def comparable(records):
    """Records without timing and machine fields, keyed by case key."""
    varying = ("wall_time", "traceback", "case_cpu_time", "case_load_average", "case_cpu_model")
    return {r["key"]: {k: v for k, v in r.items() if k not in varying} for r in records}


def external_resources(page: str) -> list[str]:
    """URLs of resources an HTML page would fetch from elsewhere (tags' src/href/... and CSS
    url()/@import), looking inside ``<iframe srcdoc>`` pages too. Script text is not
    scanned: strings in JavaScript are not resources."""
    import re
    from html.parser import HTMLParser

    remote = re.compile(r"^\s*(?:https?:)?//", re.I)
    css = re.compile(r"url\(\s*[\"']?\s*((?:https?:)?//[^)\"']*)|@import\s+[\"']?((?:https?:)?//\S+)", re.I)
    found: list[str] = []

    class Audit(HTMLParser):
        def __init__(self):
            super().__init__(convert_charrefs=True)
            self.in_style = False

        def handle_starttag(self, tag, attrs):
            self.in_style = tag == "style"
            for name, value in attrs:
                if value is None:
                    continue
                if name == "srcdoc":
                    found.extend(external_resources(value))
                elif name in ("src", "href", "data", "poster", "action", "background") and remote.match(value):
                    found.append(value)
                elif name == "style":
                    found.extend(a or b for a, b in css.findall(value))

        def handle_endtag(self, tag):
            if tag == "style":
                self.in_style = False

        def handle_data(self, data):
            if self.in_style:
                found.extend(a or b for a, b in css.findall(data))

    Audit().feed(page)
    return found
