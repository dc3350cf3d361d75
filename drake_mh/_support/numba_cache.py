"""Numba's on-disk cache, kept in a folder named by the kernels' sources.

Numba checks a cached function against the modification time of the file that defines it, and
nothing else: a kernel compiled with a helper from another file (inlined or linked into it)
keeps the helper's old code after the helper's file changes. Measured here: after a change to
the packed arrays' layout in ``scene/kernels/packing.py``, ``Scene.collision_free`` of one
configuration (compiled in the unchanged ``scene/kernels/entry.py``) read the new buffers with
the old offsets and accepted a MotionBenchMaker goal that the same code rejects from a clean
cache. Editable installs (``pip install -e``) meet this after every ``git pull``.

So, unless the user chose a folder (``NUMBA_CACHE_DIR``), the cache lives in
``cache_dir("numba")/<fingerprint>``, the fingerprint a content hash of every module of the
package that mentions numba: any change to a kernel's code or to code it calls moves every
kernel to a fresh folder (one full compilation, as on a new machine), and a checkout never reads
another's compiled code. Folders unused for :data:`KEEP_DAYS` days are deleted, the newest
:data:`KEEP` always kept. Processes started from this one (the demo's warm-up, study workers)
inherit the folder through the environment.
"""

from __future__ import annotations

import logging
import os
import shutil
import sys
import time
from pathlib import Path

from drake_mh._support.cache import cache_dir, content_hash

log = logging.getLogger(__name__)

KEEP = 3
"""Fingerprint folders always kept (the newest by last use)."""
KEEP_DAYS = 2.0
"""Older folders than this, beyond :data:`KEEP`, are deleted."""
MARKER = "DRAKE_MH_NUMBA_CACHE_DIR"
"""Environment variable holding the folder this module chose (so that a child process of another
checkout tells our choice from a user's ``NUMBA_CACHE_DIR``)."""


def fingerprint(package: Path | None = None) -> str:
    """A content hash of every ``.py`` file of ``package`` (default: drake_mh) that mentions
    numba, with its path (16 hex digits)."""
    root = Path(package or Path(__file__).parents[1])
    parts: list[bytes | str] = []
    for path in sorted(root.rglob("*.py")):
        data = path.read_bytes()
        if b"numba" in data:
            parts += [path.relative_to(root).as_posix(), data]
    return content_hash(*parts)[:16]


def configure() -> Path | None:
    """Point numba's cache at this checkout's fingerprint folder (module docstring); the folder,
    or None where the user set ``NUMBA_CACHE_DIR`` or no folder could be made (numba's default,
    next to the sources, is then used)."""
    chosen = os.environ.get("NUMBA_CACHE_DIR")
    if chosen and chosen != os.environ.get(MARKER):
        return None  # the user's choice
    try:
        root = cache_dir("numba")
        folder = root / fingerprint()
        folder.mkdir(exist_ok=True)
        os.utime(folder)  # last use, for the pruning
    except OSError as exc:
        log.warning("numba's cache stays next to the sources (%s): after a change to a kernel's helpers, "
                    "delete the __pycache__ folders of drake_mh", exc)
        return None
    os.environ["NUMBA_CACHE_DIR"] = os.environ[MARKER] = str(folder)
    numba_config = sys.modules.get("numba.core.config")
    if numba_config is not None:  # numba was imported first: its locators read the attribute
        numba_config.CACHE_DIR = str(folder)
    _prune(root, folder)
    return folder


def _prune(root: Path, current: Path) -> None:
    """Delete fingerprint folders unused for :data:`KEEP_DAYS` days, keeping the :data:`KEEP` newest."""
    try:
        folders = sorted((p for p in root.iterdir() if p.is_dir() and p != current),
                         key=lambda p: p.stat().st_mtime, reverse=True)
        cutoff = time.time() - KEEP_DAYS * 86400.0
        for old in folders[KEEP - 1:]:
            if old.stat().st_mtime < cutoff:
                shutil.rmtree(old, ignore_errors=True)
    except OSError:
        pass
