"""Tests of drake_mh._support.cache (content-hash keys, atomic writes, the folder's location)."""

from __future__ import annotations

from drake_mh._support.cache import atomic_write_bytes, cache_dir, content_hash


def test_cache_dir_follows_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("DRAKE_MH_CACHE", str(tmp_path / "c"))
    folder = cache_dir("meshes")
    assert folder == tmp_path / "c" / "meshes" and folder.is_dir()


def test_content_hash_separates_parts():
    assert content_hash("ab", "c") != content_hash("a", "bc")
    assert content_hash(b"x") == content_hash("x")


def test_atomic_write_leaves_no_temporary(tmp_path):
    target = tmp_path / "entry.bin"
    atomic_write_bytes(target, b"one")
    atomic_write_bytes(target, b"two")
    assert target.read_bytes() == b"two"
    assert [p.name for p in tmp_path.iterdir()] == ["entry.bin"]
