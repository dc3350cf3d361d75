"""Reading back what a Meshcat ``StaticHtml()`` page contains (for the viz tests).

The page embeds the viewer's JavaScript inline and replays the scene from ``fetch("data:...")``
calls whose payloads are msgpack-encoded Meshcat commands (``set_object``, ``set_transform``,
``set_animation`` ...).
"""

from __future__ import annotations

import base64
import re

import numpy as np

_COMMAND = re.compile(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]*)"\)')


def commands(html: str) -> list[dict]:
    """The Meshcat commands the page replays, decoded (needs ``msgpack``)."""
    import msgpack

    return [msgpack.unpackb(base64.b64decode(b), raw=False, strict_map_key=False)
            for b in _COMMAND.findall(html)]


def transforms(html: str) -> dict[str, np.ndarray]:
    """``{path: X (4, 4)}`` of the page's ``set_transform`` commands (the static scene)."""
    out = {}
    for c in commands(html):
        if c["type"] == "set_transform":
            out[c["path"]] = np.asarray(c["matrix"], dtype=float).reshape(4, 4).T  # column-major
    return out


def objects(html: str) -> set[str]:
    """Paths of the page's ``set_object`` commands."""
    return {c["path"] for c in commands(html) if c["type"] == "set_object"}


def animation(html: str) -> dict | None:
    """The page's last ``set_animation`` command, or ``None`` if there is none or it is empty."""
    found = [c for c in commands(html) if c["type"] == "set_animation"]
    return found[-1] if found and found[-1]["animations"] else None


def track(anim: dict, path: str, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Frame numbers ``(F,)`` and values ``(F, n)`` of one track (``.position``, ``.quaternion``)."""
    for a in anim["animations"]:
        if a["path"] == path:
            for tr in a["clip"]["tracks"]:
                if tr["name"] == name:
                    frames = np.array([k["time"] for k in tr["keys"]], dtype=float)
                    values = np.array([k["value"] for k in tr["keys"]], dtype=float)
                    return frames, values
    raise KeyError(f"no track {name} for {path}")
