"""On-disk cache of derived data (converted collision meshes, sphere models).

Everything cached is derived from its inputs and keyed by a content hash of them, so a stale
entry can never be returned: changing a mesh file or a tolerance changes the key. Entries are
written atomically (temporary file, then ``os.replace``), so concurrent processes and a kill in
the middle of a write leave either the old state or a complete entry.

The folder is ``$DRAKE_MH_CACHE`` when set, else ``$XDG_CACHE_HOME/drake_mh``, else
``~/.cache/drake_mh``. Deleting it is always safe (the next load recomputes).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

__all__ = ["cache_dir", "content_hash", "atomic_write_bytes", "temporary_cache"]


def cache_dir(kind: str) -> Path:
    """The cache folder for ``kind`` (e.g. ``"meshes"``, ``"spheres"``), created if missing.

    Args:
        kind: a sub-folder name (letters, digits, ``_`` and ``-``).

    Returns:
        The folder path. When the cache root cannot be created (read-only home), a folder
        under the system's temporary directory is used instead.
    """
    env = os.environ.get("DRAKE_MH_CACHE")
    if env:
        root = Path(env).expanduser()
    else:
        base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        root = Path(base).expanduser() / "drake_mh"
    folder = root / kind
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        folder = Path(tempfile.gettempdir()) / "drake_mh_cache" / kind
        folder.mkdir(parents=True, exist_ok=True)
    return folder


def content_hash(*parts: bytes | str) -> str:
    """A SHA-256 hex digest of ``parts`` (each length-prefixed, so ``("ab", "c") != ("a", "bc")``)."""
    h = hashlib.sha256()
    for part in parts:
        data = part.encode() if isinstance(part, str) else bytes(part)
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.hexdigest()


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder, then rename)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


@contextlib.contextmanager
def temporary_cache() -> Iterator[Path]:
    """Point ``$DRAKE_MH_CACHE`` at a new, empty folder for the block (benchmarks of first loads),
    then restore it and delete the folder."""
    old = os.environ.get("DRAKE_MH_CACHE")
    with tempfile.TemporaryDirectory(prefix="drake_mh_cache_") as folder:
        os.environ["DRAKE_MH_CACHE"] = folder
        try:
            yield Path(folder)
        finally:
            if old is None:
                os.environ.pop("DRAKE_MH_CACHE", None)
            else:
                os.environ["DRAKE_MH_CACHE"] = old
