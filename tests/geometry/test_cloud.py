"""Point-cloud obstacles: arrays and files, non-finite points, cropping and down-sampling."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drake_mh.errors import ObstacleFileError, ObstacleFileNotFound, SceneError
from drake_mh.geometry import PointCloud

DATA = Path(__file__).resolve().parents[1] / "data"


def test_every_format_reads_the_same_points():
    reference = np.load(DATA / "cloud.npy")
    for name in ("cloud.npy", "cloud.xyz", "cloud.ply", "cloud_binary.pcd"):
        cloud = PointCloud.from_file(DATA / name, radius=0.005)
        assert cloud.points.shape == reference.shape and cloud.dropped == 0
        assert np.allclose(cloud.points, reference, atol=1e-6), name  # float32 / 6 decimals in some files
    ascii_cloud = PointCloud.from_file(DATA / "cloud_ascii.pcd", radius=0.005)
    assert ascii_cloud.dropped == 1 and "dropped=1" in repr(ascii_cloud)
    assert np.allclose(ascii_cloud.points, np.delete(reference, 7, axis=0), atol=1e-6)


def test_scale_and_radius():
    cloud = PointCloud.from_file(DATA / "cloud.npy", radius=0.0, scale=1000.0)
    assert np.allclose(cloud.points, 1000.0 * np.load(DATA / "cloud.npy"))
    for radius in (-0.1, np.nan, "0.1", None):
        with pytest.raises(SceneError, match="radius"):
            PointCloud(np.zeros((3, 3)), radius)
    with pytest.raises(ObstacleFileError, match="scale"):
        PointCloud.from_file(DATA / "cloud.npy", radius=0.01, scale=0)


def test_bad_points_and_files(tmp_path):
    with pytest.raises(SceneError, match="shape"):
        PointCloud(np.zeros((4, 2)), 0.01)
    with pytest.raises(SceneError, match="no finite point"):
        PointCloud(np.full((3, 3), np.nan), 0.01)
    with pytest.raises(SceneError):
        PointCloud("points", 0.01)
    with pytest.raises(ObstacleFileNotFound):
        PointCloud.from_file(tmp_path / "none.pcd", 0.01)
    (tmp_path / "c.las").write_text("x")
    with pytest.raises(ObstacleFileError, match="unknown point-cloud format"):
        PointCloud.from_file(tmp_path / "c.las", 0.01)
    (tmp_path / "c.pcd").write_text("VERSION 0.7\nFIELDS x y\nDATA ascii\n0 0\n")
    with pytest.raises(ObstacleFileError, match="x, y and z"):
        PointCloud.from_file(tmp_path / "c.pcd", 0.01)
    (tmp_path / "d.pcd").write_text("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nPOINTS 1\n"
                                    "DATA binary_compressed\n")
    with pytest.raises(ObstacleFileError, match="binary_compressed"):
        PointCloud.from_file(tmp_path / "d.pcd", 0.01)
    (tmp_path / "e.pcd").write_bytes(b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nPOINTS 10\nDATA binary\n"
                                     + np.zeros(6, "<f4").tobytes())
    with pytest.raises(ObstacleFileError, match="truncated"):
        PointCloud.from_file(tmp_path / "e.pcd", 0.01)
    np.save(tmp_path / "f.npy", np.zeros((5, 2)))
    with pytest.raises(ObstacleFileError, match=r"\(N, 3\)"):
        PointCloud.from_file(tmp_path / "f.npy", 0.01)
    (tmp_path / "g.xyz").write_text("1 2\n")
    with pytest.raises(ObstacleFileError, match="three numbers"):
        PointCloud.from_file(tmp_path / "g.xyz", 0.01)


def test_crop_and_voxel_cover():
    rng = np.random.default_rng(0)
    points = rng.uniform(-1, 1, (5000, 3))
    cloud = PointCloud(points, 0.01)
    cropped = cloud.cropped([0.2, 0, 0], 0.5)
    assert np.all(np.linalg.norm(cropped.points - [0.2, 0, 0], axis=1) <= 0.5)
    assert len(cropped) == np.count_nonzero(np.linalg.norm(points - [0.2, 0, 0], axis=1) <= 0.5)
    with pytest.raises(SceneError, match="no point"):
        cloud.cropped([10, 10, 10], 0.1)
    down = cloud.voxel_downsampled(0.2)
    assert len(down) < len(cloud)
    # every old ball inside a new one: each old point within (new radius - old radius) of a new point
    from scipy.spatial import cKDTree

    d, _ = cKDTree(down.points).query(points)
    assert np.all(d + cloud.radius <= down.radius + 1e-12)
    assert down.radius <= cloud.radius + 0.2 * np.sqrt(3)
