"""Wavefront ``.obj`` text of a triangle mesh: how meshes are handed to Drake and cached."""

from __future__ import annotations

import numpy as np

__all__ = ["obj_bytes"]


def obj_bytes(vertices: np.ndarray, faces: np.ndarray, comment: str) -> bytes:
    """A Wavefront ``.obj`` file of the triangles ``vertices[faces]`` (full precision)."""
    lines = [f"# {comment}"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, dtype=float).tolist()]
    lines += [f"f {i} {j} {k}" for i, j, k in (np.asarray(faces, dtype=np.int64) + 1).tolist()]
    return ("\n".join(lines) + "\n").encode()
