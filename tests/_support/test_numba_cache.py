"""Numba's cache folder keyed by the kernels' sources (drake_mh/_support/numba_cache.py): a change to a
kernel's helper in another file must not leave callers compiled against the old helper."""

import os
import time
from pathlib import Path

import numba
import pytest

from drake_mh._support import numba_cache


@pytest.fixture
def clean_env(monkeypatch, tmp_path):
    """A private cache root; the process's numba folder and environment restored afterwards."""
    monkeypatch.setenv("DRAKE_MH_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv(numba_cache.MARKER, raising=False)
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    return tmp_path / "cache"


def test_fingerprint_follows_the_files_that_mention_numba(tmp_path):
    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    (package / "sub" / "kernel.py").write_text("import numba\n")
    (package / "helper.py").write_text("import numba\nLANES = 128\n")
    (package / "report.py").write_text("TITLE = 'x'\n")
    first = numba_cache.fingerprint(package)
    (package / "report.py").write_text("TITLE = 'y'\n")  # no numba: no recompilation
    assert numba_cache.fingerprint(package) == first
    (package / "helper.py").write_text("import numba\nLANES = 64\n")  # a helper of the kernels
    assert numba_cache.fingerprint(package) != first


def test_the_default_fingerprint_covers_the_whole_package(tmp_path):
    """Every kernel file of drake_mh counts, wherever it sits (the module lives in a sub-package)."""
    import shutil

    import drake_mh

    root = Path(drake_mh.__file__).parent
    assert numba_cache.fingerprint() == numba_cache.fingerprint(root)
    copy = tmp_path / "drake_mh"
    shutil.copytree(root, copy, ignore=shutil.ignore_patterns("__pycache__", "urdf"))
    kernels = copy / "kinematics" / "kernels.py"
    assert numba_cache.fingerprint(copy) == numba_cache.fingerprint()
    kernels.write_text(kernels.read_text() + "\n# changed\n")
    assert numba_cache.fingerprint(copy) != numba_cache.fingerprint()


def test_configure_points_numba_at_the_fingerprint_folder(clean_env):
    folder = numba_cache.configure()
    assert folder == clean_env / "numba" / numba_cache.fingerprint() and folder.is_dir()
    assert os.environ["NUMBA_CACHE_DIR"] == str(folder) == numba.config.CACHE_DIR
    assert numba_cache.configure() == folder  # our own choice, inherited: recomputed, the same


def test_a_users_folder_is_kept(clean_env, monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    assert numba_cache.configure() is None
    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "mine")


def test_old_folders_are_pruned_the_newest_kept(clean_env):
    root = clean_env / "numba"
    root.mkdir(parents=True)
    old = time.time() - 10 * 86400
    for i in range(5):
        (root / f"old{i}").mkdir()
        os.utime(root / f"old{i}", (old + i, old + i))
    (root / "recent").mkdir()
    folder = numba_cache.configure()
    left = {p.name for p in root.iterdir()}
    assert left == {folder.name, "recent", "old4"}  # KEEP = 3: the current, then the two newest
