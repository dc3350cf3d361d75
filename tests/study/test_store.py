import json

import numpy as np
import pytest

from drake_mh.errors import NoResults, ResultsMismatch
from drake_mh.study.store import RecordStore


def _record(i):
    return {"key": f"k={i}", "case_id": f"k{i}", "value": i, "status": "ok"}


def test_append_and_load_with_arrays_and_attachments(tmp_path):
    store = RecordStore(tmp_path)
    written = store.append(_record(0), {"h": np.arange(3)}, {"a.html": "<p>x</p>", "b.bin": b"\x00"})
    assert written["arrays"] == "arrays/k0.npz"
    assert (tmp_path / "artifacts/k0/a.html").read_text() == "<p>x</p>"
    records = store.load()
    assert list(records) == ["k=0"]
    assert np.array_equal(store.load_arrays(records["k=0"])["h"], np.arange(3))


def test_torn_last_line_is_ignored_then_repaired(tmp_path):
    store = RecordStore(tmp_path)
    store.append(_record(0))
    store.append(_record(1))
    with open(store.records_path, "ab") as handle:  # what a SIGKILL mid-write could leave
        handle.write(b'{"key":"k=2","case_id":"k2","val')
    assert sorted(store.load()) == ["k=0", "k=1"]
    store.append(_record(3))
    lines = store.records_path.read_bytes().splitlines()
    assert [json.loads(line)["key"] for line in lines] == ["k=0", "k=1", "k=3"]


def test_duplicate_keys_keep_the_first(tmp_path):
    store = RecordStore(tmp_path)
    store.append(_record(0))
    store.append({**_record(0), "value": 99})
    assert store.load()["k=0"]["value"] == 0


def test_prepare_refuses_other_settings(tmp_path):
    store = RecordStore(tmp_path)
    meta = {"name": "s", "seed": 0, "quick": False, "cases_digest": "abc", "created": "t0"}
    store.prepare(meta)
    store.prepare({**meta, "created": "t1"})  # same settings: fine, creation time kept
    assert store.read_meta()["created"] == "t0"
    with pytest.raises(ResultsMismatch, match="seed"):
        store.prepare({**meta, "seed": 1})


def test_records_of_empty_folder_raises(tmp_path):
    with pytest.raises(NoResults, match="drake-mh study"):
        RecordStore(tmp_path).records()


def test_nul_block_and_garbage_lines_are_skipped_and_reported(tmp_path):
    store = RecordStore(tmp_path)
    store.append(_record(0))
    with open(store.records_path, "ab") as handle:    # a zero-filled block after a power loss
        handle.write(b"\x00" * 4096 + b"\n" + b"\xff\xfe garbage\n")
    store.append(_record(1))
    with open(store.records_path, "ab") as handle:    # NULs glued to the front of a good line
        handle.write(b"\x00" * 16 + json.dumps(_record(2)).encode() + b"\n")
    assert sorted(store.load()) == ["k=0", "k=1", "k=2"]
    assert [why for _, why in store.damaged] == ["NUL bytes", "unreadable (UnicodeDecodeError)"]


def test_record_with_truncated_arrays_runs_again(tmp_path):
    store = RecordStore(tmp_path)
    store.append(_record(0), {"h": np.arange(50)})
    store.append(_record(1), {"h": np.arange(50)})
    path = tmp_path / "arrays/k1.npz"
    path.write_bytes(path.read_bytes()[:40])           # truncated by a crash of the file system
    assert sorted(store.load()) == ["k=0"]             # k=1 counts as not run
    assert store.damaged and "k=1" in store.damaged[0][0]
    assert store.load_arrays({"arrays": "arrays/k1.npz"}) == {}
    store.append(_record(1), {"h": np.arange(50)})     # the re-run's line wins over the damaged one
    assert sorted(store.load()) == ["k=0", "k=1"] and not store.damaged


def test_second_writer_is_refused_until_the_first_closes(tmp_path):
    from drake_mh.errors import ResultsLocked

    first, second = RecordStore(tmp_path), RecordStore(tmp_path)
    first.prepare({"name": "x"})
    with pytest.raises(ResultsLocked, match="another run"):
        second.prepare({"name": "x"})
    first.close()
    second.prepare({"name": "x"})
    second.close()


def test_case_returning_an_unstorable_value_is_that_cases_error():
    from drake_mh.study.worker import split_result

    with pytest.raises(TypeError, match="datetime64"):
        split_result({"when": np.datetime64("2026-01-01")})
    assert split_result({"n": np.int64(3)})[0] == {"n": 3}


def test_unusable_folders_are_named(tmp_path):
    from drake_mh.errors import ResultsFolderError

    (tmp_path / "afile").write_text("x")
    with pytest.raises(ResultsFolderError, match="is a file"):
        RecordStore(tmp_path / "afile").prepare({"name": "x"})
    store = RecordStore(tmp_path / "out")
    store.prepare({"name": "x"})
    store.close()
    store.meta_path.write_text('{"name": "x", "se')          # truncated study.json
    with pytest.raises(ResultsFolderError, match="damaged"):
        RecordStore(tmp_path / "out").prepare({"name": "x"})
