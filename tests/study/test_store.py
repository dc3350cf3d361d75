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
