"""drake_mh's own scene YAML: what it holds, exact round trips, and the errors of bad files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drake_mh.errors import SceneFileError, SceneFileNotFound
from drake_mh.geometry import Box, Capsule, Cylinder, Mesh, PointCloud, Sphere
from drake_mh.scene.files import detect_format, read_scene, write_scene

DATA = Path(__file__).resolve().parents[2] / "data"
SCENES = DATA / "scenes"


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rot_x(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


#: the test cell as written in tests/data/scenes/cell.yaml (and the other formats' cell files):
#: name -> (shape, p_WO, R_WO)
CELL = {
    "table": (Box(0.6, 1.0, 0.05), [0.7, 0.0, 0.3], rot_z(0.3)),
    "ball": (Sphere(0.08), [0.3, 0.4, 0.6], np.eye(3)),
    "post": (Cylinder(0.05, 0.8), [-0.4, 0.3, 0.4], rot_x(0.2)),
    "rail": (Capsule(0.04, 0.5), [0.0, -0.5, 0.7], rot_x(np.pi / 2)),
}


def assert_refused(path: Path, text: str, message: str, **options) -> SceneFileError:
    """Write ``text`` to ``path``: reading it raises a SceneFileError that names the file and
    matches ``message`` (the entry and what is expected)."""
    path.write_text(text)
    with pytest.raises(SceneFileError, match=message) as err:
        read_scene(path, **options)
    assert err.value.path == str(path) and str(path) in str(err.value)
    return err.value


def assert_obstacle(obstacle, shape, p_WO, R_WO):
    assert obstacle.shape == shape, obstacle.name
    np.testing.assert_allclose(obstacle.X_WO[:3, 3], p_WO, atol=1e-12)
    np.testing.assert_allclose(obstacle.X_WO[:3, :3], R_WO, atol=1e-12)
    np.testing.assert_array_equal(obstacle.X_WO[3], [0, 0, 0, 1])


def test_cell_file_holds_the_numbers_written_in_it():
    cell = read_scene(SCENES / "cell.yaml")
    assert cell.format == "drake_mh" and cell.name == "test cell" and cell.names == list(CELL)
    for name, expected in CELL.items():
        assert_obstacle(cell[name], *expected)
    np.testing.assert_array_equal(cell["ball"].velocity_W, [0.0, -0.1, 0.0])
    np.testing.assert_array_equal(cell["table"].velocity_W, [0.0, 0.0, 0.0])
    assert cell.frames == {} and detect_format(SCENES / "cell.yaml") == "drake_mh"


def test_mesh_and_point_cloud_entries():
    cell = read_scene(SCENES / "cell_mesh_cloud.yaml")
    assert cell.names == ["bin", "scan", "probe"]
    bin_ = cell["bin"].shape
    assert isinstance(bin_, Mesh) and bin_ == Mesh(DATA / "bin.obj", scale=(1.0, 1.0, 0.5))
    assert bin_.path == (DATA / "bin.obj").resolve()  # relative to the YAML file's folder
    np.testing.assert_allclose(cell["bin"].X_WO[:3, :3], rot_z(1.0), atol=1e-12)
    scan = cell["scan"].shape
    assert isinstance(scan, PointCloud) and scan.radius == 0.01
    np.testing.assert_array_equal(scan.points, PointCloud.from_file(DATA / "cloud.xyz", 0.01).points)
    probe = cell["probe"].shape
    np.testing.assert_array_equal(probe.points, [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0.05]])
    np.testing.assert_allclose(cell["probe"].position, [-0.3, -0.3, 0.5])


def _random_obstacles(rng, with_files: bool):
    """Obstacles at random poses (quaternions drawn uniformly) with random sizes and velocities."""
    from scipy.spatial.transform import Rotation

    from drake_mh.scene import Obstacle

    shapes = [Sphere(rng.uniform(0.01, 1)), Box(*rng.uniform(0.01, 1, 3)), Cylinder(*rng.uniform(0.01, 1, 2)),
              Capsule(*rng.uniform(0.01, 1, 2))]
    if with_files:
        shapes += [Mesh(DATA / "bracket.obj", scale=rng.uniform(0.5, 2)), Mesh(DATA / "bin.obj", scale=(1, 2, 3)),
                   PointCloud(rng.normal(size=(50, 3)), rng.uniform(0, 0.1))]
    out = []
    for k, shape in enumerate(shapes):
        X = np.eye(4)
        X[:3, :3] = Rotation.random(random_state=int(rng.integers(1 << 31))).as_matrix()
        X[:3, 3] = rng.normal(size=3)
        velocity = rng.normal(size=3) if k % 2 else np.zeros(3)
        out.append(Obstacle(f"obstacle {k}::{type(shape).__name__}", shape, X, velocity))
    return out


@pytest.mark.parametrize("seed", range(5))
def test_round_trip_is_exact_to_float_precision(tmp_path, seed):
    """write -> read gives the same obstacles: sizes, positions, velocities and cloud points bit for
    bit, rotations to 1e-15 (written as roll-pitch-yaw), meshes by file and scale."""
    obstacles = _random_obstacles(np.random.default_rng(seed), with_files=True)
    files = write_scene(tmp_path / "scene.yaml", obstacles, name="cell")
    assert files[0] == tmp_path / "scene.yaml" and len(files) == 2  # the YAML file and one cloud
    again = read_scene(tmp_path / "scene.yaml")
    assert again.names == [o.name for o in obstacles] and again.name == "cell"
    for before, after in zip(obstacles, again.obstacles):
        assert after.shape == before.shape if not isinstance(before.shape, PointCloud) else \
            np.array_equal(after.shape.points, before.shape.points) and after.shape.radius == before.shape.radius
        np.testing.assert_array_equal(after.X_WO[:3, 3], before.X_WO[:3, 3])
        np.testing.assert_array_equal(after.velocity_W, before.velocity_W)
        np.testing.assert_allclose(after.X_WO[:3, :3], before.X_WO[:3, :3], rtol=0, atol=2e-15)
    twice = write_scene(tmp_path / "again.yaml", again.obstacles, name="cell")
    assert read_scene(twice[0]).names == again.names


def test_saved_files_are_relative_inside_the_folder(tmp_path):
    from drake_mh.scene import Obstacle

    (tmp_path / "meshes").mkdir()
    local = tmp_path / "meshes" / "bracket.obj"
    local.write_bytes((DATA / "bracket.obj").read_bytes())
    obstacles = [Obstacle("near", Mesh(local), np.eye(4)), Obstacle("far", Mesh(DATA / "bin.obj"), np.eye(4))]
    text = Path(write_scene(tmp_path / "cell.yml", obstacles)[0]).read_text()
    assert "file: meshes/bracket.obj" in text and f"file: {(DATA / 'bin.obj').resolve()}" in text


BAD = {
    "shape": ("obstacles:\n  - {name: a, shape: cone, radius: 1, position: [0, 0, 0]}\n",
              r"obstacle 1 \('a'\): shape must be one of sphere, box"),
    "missing key": ("obstacles:\n  - {name: a, shape: box, position: [0, 0, 0]}\n", r"obstacle 1 \('a'\): a box needs size"),
    "typo": ("obstacles:\n  - {name: a, shape: sphere, radius: 1, positon: [0, 0, 0], position: [0, 0, 0]}\n",
             r"obstacle 1 \('a'\): unknown key\(s\) \['positon'\]"),
    "negative": ("obstacles:\n  - {name: a, shape: sphere, radius: -1, position: [0, 0, 0]}\n",
                 r"obstacle 1 \('a'\): Sphere radius must be a positive"),
    "position": ("obstacles:\n  - {name: a, shape: sphere, radius: 1, position: [0, 0]}\n",
                 r"obstacle 1 \('a'\): position \[m\] must be 3 finite numbers"),
    "nan": ("obstacles:\n  - {name: a, shape: sphere, radius: 1, position: [0, .nan, 0]}\n",
            r"obstacle 1 \('a'\): position \[m\] must be 3 finite numbers"),
    "two rotations": ("obstacles:\n  - {name: a, shape: sphere, radius: 1, position: [0, 0, 0], rpy: [0, 0, 0], "
                      "quaternion: {w: 1, x: 0, y: 0, z: 0}}\n", r"obstacle 1 \('a'\): give the orientation once"),
    "quaternion list": ("obstacles:\n  - {name: a, shape: sphere, radius: 1, position: [0, 0, 0], "
                        "quaternion: [1, 0, 0, 0]}\n", r"obstacle 1 \('a'\): quaternion must be a mapping"),
    "quaternion norm": ("obstacles:\n  - {name: a, shape: sphere, radius: 1, position: [0, 0, 0], "
                        "quaternion: {w: 1, x: 1, y: 0, z: 0}}\n", r"obstacle 1 \('a'\): the quaternion .* norm 1.41"),
    "duplicate": ("obstacles:\n  - {name: a, shape: sphere, radius: 1, position: [0, 0, 0]}\n"
                  "  - {name: a, shape: sphere, radius: 1, position: [1, 0, 0]}\n",
                  r"obstacle 2 \('a'\): a second obstacle named 'a'"),
    "mesh file": ("obstacles:\n  - {name: m, shape: mesh, file: nowhere.obj, position: [0, 0, 0]}\n",
                  r"obstacle 1 \('m'\): .*cannot find 'nowhere.obj'"),
    "mesh scale": (f"obstacles:\n  - {{name: m, shape: mesh, file: {DATA / 'bin.obj'}, scale: 0, position: [0, 0, 0]}}\n",
                   r"obstacle 1 \('m'\): .*scale must be a positive number"),
    "cloud twice": ("obstacles:\n  - {name: c, shape: point_cloud, radius: 0.1, points: [[0, 0, 0]], file: a.xyz, "
                    "position: [0, 0, 0]}\n", r"obstacle 1 \('c'\): a point_cloud needs either file or points"),
    "cloud points": ("obstacles:\n  - {name: c, shape: point_cloud, radius: 0.1, points: [[0, 0]], position: [0, 0, 0]}\n",
                     r"obstacle 1 \('c'\): points must have shape \(N, 3\)"),
    "entry": ("obstacles:\n  - just a name\n", r"obstacle 1: each obstacle is a mapping"),
    "version": ("drake_mh_scene: 2\nobstacles: []\n", r"drake_mh_scene: 2 is not a version"),
    "top level": ("obstacles: []\nrobot: panda\n", r"unknown top-level key\(s\) \['robot'\]"),
    "list": ("obstacles: {a: 1}\n", r"obstacles must be a list"),
    "yaml": ("obstacles:\n  - {name: a, shape: [\n", r"line \d+: not valid YAML"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_malformed_files_name_the_file_and_the_entry(tmp_path, case):
    assert_refused(tmp_path / "bad.yaml", *BAD[case], format="drake_mh")


def test_format_detection_and_missing_files(tmp_path):
    with pytest.raises(SceneFileNotFound, match="no such file"):
        read_scene(tmp_path / "missing.yaml")
    (tmp_path / "odd.yaml").write_text("robots: [panda]\n")
    with pytest.raises(SceneFileError, match=r"cannot tell the format from its top-level keys \['robots'\]"):
        read_scene(tmp_path / "odd.yaml")
    (tmp_path / "empty.yaml").write_text("")
    with pytest.raises(SceneFileError, match="empty"):
        read_scene(tmp_path / "empty.yaml")
    with pytest.raises(SceneFileError, match="a curobo file is a YAML mapping, got NoneType"):
        read_scene(tmp_path / "empty.yaml", format="curobo")
    (tmp_path / "cell.txt").write_text("x")
    with pytest.raises(SceneFileError, match="unknown scene file suffix '.txt'"):
        read_scene(tmp_path / "cell.txt")
    with pytest.raises(SceneFileError, match="unknown format 'obj'"):
        read_scene(SCENES / "cell.yaml", format="obj")


def test_save_refuses_other_suffixes_and_missing_folders(tmp_path):
    with pytest.raises(SceneFileError, match="ending in .yaml or .yml"):
        write_scene(tmp_path / "cell.scene", [])
    with pytest.raises(SceneFileError, match="does not exist"):
        write_scene(tmp_path / "no" / "cell.yaml", [])
