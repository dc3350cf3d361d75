"""MoveIt's ``.scene`` text files and planning-scene YAML (MotionBenchMaker, robowflex): the
numbers written in the files, frames resolved against a robot, and the errors of bad files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import SceneFileError
from drake_mh.geometry import Box, Cylinder, Mesh, Sphere
from drake_mh.scene.files import read_scene
from test_scene_yaml import CELL, assert_obstacle, assert_refused, rot_z

DATA = Path(__file__).resolve().parents[2] / "data"
SCENES = DATA / "scenes"
PANDA = drake_mh.load_robot("panda")


def test_scene_text_newer_format():
    """Object poses, shape poses relative to them, several shapes, subframes (read, ignored)."""
    cell = read_scene(SCENES / "cell.scene")
    assert cell.format == "moveit_scene" and cell.name == "test cell"
    assert cell.names == ["table", "ball", "post", "rack_0", "rack_1"]
    for name in ("table", "ball", "post"):
        assert_obstacle(cell[name], *CELL[name])
    # the rack's pose turns its shapes by 90 degrees about z: (0.2, 0, 0) -> (0, 0.2, 0)
    assert_obstacle(cell["rack_0"], Box(0.1, 0.2, 0.3), [0.0, -0.3, 0.7], rot_z(np.pi / 2))
    assert_obstacle(cell["rack_1"], Sphere(0.05), [-0.3, -0.5, 0.7], rot_z(np.pi / 2))


def test_scene_text_older_format_and_written_meshes():
    old = read_scene(SCENES / "cell_old.scene")
    assert old.names == ["ball", "table"] and old.name == "old format cell"
    assert_obstacle(old["ball"], *CELL["ball"])
    assert_obstacle(old["table"], *CELL["table"])
    wedge = read_scene(SCENES / "cell_mesh.scene")["wedge"]
    assert isinstance(wedge.shape, Mesh) and len(wedge.shape.faces) == 4
    np.testing.assert_allclose(wedge.shape.bounds, [[0, 0, 0], [0.2, 0.2, 0.2]])
    np.testing.assert_allclose(wedge.position, [0.5, 0.0, 0.2])


SCENE_BAD = {
    "cone": ("cell\n* pylon\n1\ncone\n0.1 0.3\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n",
             r"line 4 \(object 'pylon'\): a cone has no drake_mh obstacle shape"),
    "type": ("cell\n* thing\n1\ntorus\n0.1 0.3\n", r"line 4 \(object 'thing'\): unknown shape type 'torus'"),
    "number": ("cell\n* ball\n1\nsphere\nbig\n", r"line 5: sphere dimensions: 1 number expected, got 'big'"),
    "short": ("cell\n* ball\n1\nsphere\n0.1\n0 0\n", r"end of file: object 'ball' shape 0 position x y z expected"),
    "count": ("cell\n* ball\nmany\n", r"line 3: object 'ball': number of shapes: a whole number"),
    "quaternion": ("cell\n* ball\n1\nsphere\n0.1\n0 0 0\n0 0 0 0\n0 0 0 0\n",
                   r"line 7: the quaternion \(x y z w\) \[0.0, 0.0, 0.0, 0.0\] has norm 0"),
    "marker": ("cell\n* ball\n1\nsphere\n0.1\n0 0 0\n0 0 0 1\n0 0 0 0\nextra\n",
               r"line 9: '\* <object name>' or '\.' expected, got 'extra'"),
    "radius": ("cell\n* ball\n1\nsphere\n-0.1\n0 0 0\n0 0 0 1\n0 0 0 0\n",
               r"line 4 \(object 'ball'\): Sphere radius must be a positive"),
    "name": ("\n* ball\n", r"line 1: a .scene file starts with the scene's name"),
    "duplicate": ("cell\n* ball\n1\nsphere\n0.1\n0 0 0\n0 0 0 1\n0 0 0 0\n* ball\n1\nsphere\n0.1\n0 0 0\n0 0 0 1\n"
                  "0 0 0 0\n", r"line 9 \(object 'ball'\): a second obstacle named 'ball'"),
    "mesh": ("cell\n* m\n1\nmesh\n3 1\n0 0 0\n1 0 0\n0 1 0\n0 1 7\n0 0 0\n0 0 0 1\n0 0 0 0\n",
             r"line 4 \(object 'm'\): a mesh needs finite vertices and triangles of 3 vertex indices in \[0, 3\)"),
}


@pytest.mark.parametrize("case", list(SCENE_BAD))
def test_malformed_scene_text_names_the_file_and_the_line(tmp_path, case):
    assert_refused(tmp_path / "bad.scene", *SCENE_BAD[case])


def test_planning_scene_yaml():
    scene = read_scene(SCENES / "planning_scene.yaml")
    assert scene.format == "planning_scene" and scene.name == "shelf cell"
    assert scene.names == ["shelf_0", "shelf_1", "can"]
    assert scene.frames == {"shelf_0": "panda_link0", "shelf_1": "panda_link0"}  # 'world' is no entry
    assert scene.robot_state == dict(zip([f"panda_joint{k}" for k in range(1, 8)],
                                         [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]))
    # object pose (0.7, 0, 0) turned 0.3 rad about z, composed with the primitives' poses
    assert_obstacle(scene["shelf_0"], Box(0.6, 1.0, 0.05), [0.7, 0.0, 0.3], rot_z(0.3))
    assert_obstacle(scene["shelf_1"], Cylinder(0.05, 0.8), [0.7 + 0.2 * np.cos(0.3), 0.2 * np.sin(0.3), 0.4],
                    rot_z(0.3))
    assert_obstacle(scene["can"], Sphere(0.08), [0.3, 0.4, 0.6], np.eye(3))


def test_planning_scene_frames_are_placed_by_the_robot():
    scene = read_scene(SCENES / "planning_scene.yaml")
    world = {o.name: o for o in scene.resolved(PANDA)}  # panda_link0 is welded at the origin
    assert_obstacle(world["shelf_0"], Box(0.6, 1.0, 0.05), [0.7, 0.0, 0.3], rot_z(0.3))
    moved = type(scene)(scene.path, scene.format, scene.obstacles, {"can": "panda_link0_sc"})
    with pytest.raises(SceneFileError, match=r"obstacle 'can': its pose is given in frame 'panda_link0_sc', which "
                                             r"is neither the world .* nor a frame of robot 'panda'"):
        moved.resolved(PANDA)
    moving = type(scene)(scene.path, scene.format, scene.obstacles, {"can": "panda_link3"})
    with pytest.raises(SceneFileError, match=r"obstacle 'can': .*'panda_link3', which moves with the joints"):
        moving.resolved(PANDA)


def test_planning_scene_meshes_from_files_and_written_out():
    scene = read_scene(SCENES / "planning_scene_mesh.yaml")
    assert scene.names == ["parts_0", "parts_1"]
    assert scene["parts_0"].shape == Mesh(DATA / "bracket.obj")
    np.testing.assert_allclose(scene["parts_0"].position, [0.5, 0.2, 0.3])
    wedge = scene["parts_1"].shape
    assert wedge == read_scene(SCENES / "cell_mesh.scene")["wedge"].shape  # the same triangles, the same mesh
    np.testing.assert_allclose(scene["parts_1"].X_WO[:3, :3], np.eye(3))


OBJECT = "world:\n  collision_objects:\n    - id: thing\n{}"
BOX = "      primitives: [{type: box, dimensions: [0.1, 0.2, 0.3]}]\n"
AT = "      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]\n"
YAML_BAD = {
    "cone": (OBJECT.format("      primitives: [{type: cone, dimensions: [0.3, 0.1]}]\n" + AT),
             r"collision object 1 \('thing'\): a cone has no drake_mh obstacle shape"),
    "dimensions": (OBJECT.format("      primitives: [{type: box, dimensions: [0.1, 0.2]}]\n" + AT),
                   r"collision object 1 \('thing'\): box dimensions \[x, y, z\] must be 3 finite numbers"),
    "poses": (OBJECT.format(BOX), r"collision object 1 \('thing'\): primitives and primitive_poses must be lists "
                                  r"of the same length"),
    "operation": (OBJECT.format(BOX + AT + "      operation: remove\n"),
                  r"collision object 1 \('thing'\): operation 'remove'"),
    "orientation": (OBJECT.format(BOX + "      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 3]}]\n"),
                    r"collision object 1 \('thing'\): the quaternion \(x, y, z, w\) .* has norm 3"),
    "empty": (OBJECT.format("      header: {frame_id: world}\n"), r"collision object 1 \('thing'\): it has no "
                                                                   "primitives or meshes"),
    "planes": (OBJECT.format("      planes: [{coef: [0, 0, 1, 0]}]\n      plane_poses: [{}]\n"),
               r"collision object 1 \('thing'\): planes are not read"),
    "mesh": (OBJECT.format("      meshes: [{resource: missing.stl}]\n      mesh_poses: [{}]\n"),
             r"collision object 1 \('thing'\): .*cannot find 'missing.stl'"),
    "attached": (OBJECT.format(BOX + AT) + "robot_state:\n  attached_collision_objects: [{link_name: hand}]\n",
                 r"robot_state.attached_collision_objects: objects attached to the robot"),
    "octomap": ("world:\n  octomap:\n    octomap: {id: OcTree, data: [1, 2]}\n", r"world.octomap: octomaps are not read"),
    "joints": (OBJECT.format(BOX + AT) + "robot_state:\n  joint_state: {name: [a, b], position: [1]}\n",
               r"robot_state.joint_state: 2 joint names but 1 positions"),
}


@pytest.mark.parametrize("case", list(YAML_BAD))
def test_malformed_planning_scenes_name_the_file_and_the_object(tmp_path, case):
    assert_refused(tmp_path / "bad.yaml", *YAML_BAD[case])


def test_numeric_primitive_types_and_bare_worlds(tmp_path):
    """``shape_msgs/SolidPrimitive`` constants (BOX = 1, SPHERE = 2, CYLINDER = 3) and a bare
    ``PlanningSceneWorld`` (``collision_objects`` at the top)."""
    path = tmp_path / "world.yaml"
    path.write_text("collision_objects:\n  - id: a\n    primitives: [{type: 3, dimensions: [0.8, 0.05]}]\n"
                    "    primitive_poses: [{position: {x: 1, y: 2, z: 3}, orientation: {x: 0, y: 0, z: 0, w: 1}}]\n")
    scene = read_scene(path)
    assert scene.format == "planning_scene"
    assert_obstacle(scene["a"], Cylinder(0.05, 0.8), [1, 2, 3], np.eye(3))
