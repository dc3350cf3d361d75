"""The Dask path against a real local cluster (scheduler on 127.0.0.1, 2 worker processes)."""

import pytest
from study_toys import comparable

from drake_mh.errors import InvalidArgument
from drake_mh.study import run_study

distributed = pytest.importorskip("distributed")

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as local:
        yield local


def test_dask_cluster_gives_the_same_records_as_serial(toy, tmp_path, cluster):
    address = cluster.scheduler_address  # tcp://127.0.0.1:PORT
    url = address.replace("tcp://", "dask://")
    dask = run_study(toy, out=tmp_path / "dask", executor=url, report=True)
    serial = run_study(toy, out=tmp_path / "serial", workers=0, report=False)
    assert dask.complete and dask.n_errors == 2
    assert comparable(dask.records) == comparable(serial.records)
    assert (tmp_path / "dask" / "index.html").is_file()


def test_dask_client_executor_object_works(toy, tmp_path, cluster):
    with distributed.Client(cluster.scheduler_address) as client:
        result = run_study(toy, out=tmp_path / "o", executor=client.get_executor(), workers=2, quick=True, report=False)
    assert result.complete and result.n_cases == 4


def test_unreachable_scheduler_is_a_clear_error(toy, tmp_path, monkeypatch):
    monkeypatch.setattr("drake_mh.study.executors.DASK_CONNECT_TIMEOUT", "1s")
    with pytest.raises(InvalidArgument, match="Dask scheduler"):
        run_study(toy, out=tmp_path / "o", executor="dask://127.0.0.1:9", report=False)
