"""cuRobo's world YAML: the numbers written in the files (poses scalar first, capsules from base
to tip) and the errors of bad files."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from drake_mh.geometry import Capsule, Mesh
from drake_mh.scene.files import read_scene
from test_scene_yaml import CELL, rot_z, assert_obstacle, assert_refused

DATA = Path(__file__).resolve().parents[2] / "data"
SCENES = DATA / "scenes"


def test_world_file_holds_the_numbers_written_in_it():
    world = read_scene(SCENES / "curobo_world.yml")
    assert world.format == "curobo" and world.names == ["table", "ball", "post", "rail", "hook"]
    for name in ("table", "ball", "post", "rail"):
        assert_obstacle(world[name], *CELL[name])
    # base (0, 0, 0) -> tip (0.3, 0, 0): centre (0.15, 0, 0), axis along x
    hook = world["hook"]
    assert hook.shape == Capsule(0.02, 0.3)
    np.testing.assert_allclose(hook.position, [0.15, 0.6, 0.4], atol=1e-12)
    np.testing.assert_allclose(hook.X_WO[:3, 2], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(hook.X_WO[:3, :3] @ hook.X_WO[:3, :3].T, np.eye(3), atol=1e-12)


def test_capsule_between_any_two_points(tmp_path):
    """The capsule's segment is base -> tip in the pose's frame, whatever their direction."""
    path = tmp_path / "world.yml"
    path.write_text("capsule:\n  bar:\n    radius: 0.05\n    base: [0.1, 0.2, 0.3]\n    tip: [0.4, -0.2, 0.3]\n"
                    "    pose: [1, 0, 0, 0.9887710779360422, 0, 0, 0.14943813247359922]\n")
    bar = read_scene(path)["bar"]
    assert bar.shape == Capsule(0.05, 0.5)
    X_WP = np.eye(4)
    X_WP[:3, :3], X_WP[:3, 3] = rot_z(0.3), [1, 0, 0]
    ends = [bar.X_WO[:3, 3] + s * 0.25 * bar.X_WO[:3, 2] for s in (-1, 1)]
    expected = [X_WP[:3, :3] @ p + X_WP[:3, 3] for p in ([0.1, 0.2, 0.3], [0.4, -0.2, 0.3])]
    np.testing.assert_allclose(ends, expected, atol=1e-12)


def test_meshes_from_files_and_written_out(tmp_path):
    bin_ = read_scene(SCENES / "curobo_mesh.yml")["bin"]
    assert bin_.shape == Mesh(DATA / "bin.obj", scale=(1, 1, 0.5))
    np.testing.assert_allclose(bin_.position, [0.6, -0.2, 0.1])
    path = tmp_path / "world.yml"
    path.write_text("mesh:\n  wedge:\n    vertices: [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]\n"
                    "    faces: [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]\n    scale: [2, 2, 2]\n"
                    "    pose: [0, 0, 0, 1, 0, 0, 0]\n")
    wedge = read_scene(path)["wedge"].shape
    np.testing.assert_allclose(wedge.bounds, [[0, 0, 0], [0.2, 0.2, 0.2]])  # cuRobo scales the vertices


def test_scale_on_primitives_is_ignored_as_curobo_does(tmp_path, caplog):
    path = tmp_path / "world.yml"
    path.write_text("sphere:\n  ball: {radius: 0.1, pose: [0, 0, 0, 1, 0, 0, 0], scale: [2, 2, 2]}\n")
    with caplog.at_level(logging.WARNING, logger="drake_mh.scene.files.curobo"):
        ball = read_scene(path)["ball"]
    assert ball.shape.radius == 0.1 and "scale is ignored" in caplog.text
    path.write_text("sphere:\n  ball: {radius: 0.1, position: [1, 2, 3]}\n")  # cuRobo's older sphere field
    np.testing.assert_allclose(read_scene(path)["ball"].position, [1, 2, 3])


BAD = {
    "blox": ("blox:\n  map: {map_path: m.nvblx}\n", r"blox: nvblox maps are not read"),
    "type": ("cuboid: {}\ncone:\n  c: {}\n", r"cannot tell the format"),
    "field": ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0, 0], size: 2}\n",
              r"cuboid 't': unknown field\(s\) \['size'\]"),
    "pose": ("cuboid:\n  t: {dims: [1, 1, 1]}\n", r"cuboid 't': a cuboid needs pose"),
    "pose length": ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, 0, 1, 0, 0]}\n",
                    r"cuboid 't': pose \[x, y, z, qw, qx, qy, qz\] must be 7 finite numbers"),
    "quaternion": ("cuboid:\n  t: {dims: [1, 1, 1], pose: [0, 0, 0, 0, 0, 0, 0]}\n",
                   r"cuboid 't': the quaternion \(qw, qx, qy, qz\) .* has norm 0"),
    "dims": ("cuboid:\n  t: {dims: [1, 0, 1], pose: [0, 0, 0, 1, 0, 0, 0]}\n", r"cuboid 't': Box side must be"),
    "capsule": ("capsule:\n  c: {radius: 0.1, base: [0, 0, 0], pose: [0, 0, 0, 1, 0, 0, 0]}\n",
                r"capsule 'c': a capsule needs tip"),
    "mesh": ("mesh:\n  m: {pose: [0, 0, 0, 1, 0, 0, 0]}\n", r"mesh 'm': a mesh needs file_path, or vertices and faces"),
    "mesh file": ("mesh:\n  m: {file_path: nowhere.stl, pose: [0, 0, 0, 1, 0, 0, 0]}\n",
                  r"mesh 'm': .*cannot find 'nowhere.stl'"),
    "group": ("sphere: [1, 2]\n", r"sphere: sphere must map obstacle names to their fields"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_malformed_worlds_name_the_file_and_the_obstacle(tmp_path, case):
    text, message = BAD[case]
    assert_refused(tmp_path / "world.yml", text, message)
    assert_refused(tmp_path / "world.yml", text, message if case != "type" else r"cone: unknown obstacle type 'cone'",
                   format="curobo")
