"""SDFormat worlds, URDFs of static bodies and model directives, read through Drake: the numbers
written in the files, meshes and half spaces, bodies that move, the errors; and distances in a
scene loaded from them against Drake's own on a fresh plant with the same file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import SceneFileError
from drake_mh.geometry import Box, Mesh, Sphere
from drake_mh.scene import Scene
from drake_mh.scene.files import read_scene
from drake_mh.scene.files.drake_files import HALFSPACE_DEPTH, HALFSPACE_SIDE
from test_scene_yaml import CELL, rot_z, assert_obstacle

DATA = Path(__file__).resolve().parents[2] / "data"
SCENES = DATA / "scenes"

#: the same four obstacles as cell.yaml, named as Drake names them in each file
NAMES = {
    "cell.sdf": {"table::board": "table", "ball::sphere": "ball", "post::cylinder": "post", "rail::capsule": "rail"},
    "cell.urdf": {"test_cell::board": "table", "test_cell::sphere": "ball", "test_cell::cylinder": "post",
                  "test_cell::capsule": "rail"},
}


@pytest.mark.parametrize("file", list(NAMES))
def test_poses_compose_as_written(file):
    """Model, link / joint and collision poses composed by Drake give the numbers of cell.yaml."""
    cell = read_scene(SCENES / file)
    assert cell.format == {"cell.sdf": "sdformat", "cell.urdf": "urdf"}[file]
    assert cell.names == list(NAMES[file])
    for name, ours in NAMES[file].items():
        assert_obstacle(cell[name], *CELL[ours])


def test_directives_weld_models_found_by_package():
    """cell.dmd.yaml names its models as package://drake_mh_test_scenes/... (the folder's
    package.xml) and welds the table at 30 degrees."""
    cell = read_scene(SCENES / "cell.dmd.yaml")
    assert cell.format == "directives" and cell.names == ["table::board", "ball::sphere"]
    assert_obstacle(cell["table::board"], Box(0.6, 1.0, 0.05), [0.7, 0.0, 0.3], rot_z(np.pi / 6))
    assert_obstacle(cell["ball::sphere"], Sphere(0.08), [0.3, 0.4, 0.6], np.eye(3))


def test_meshes_keep_their_own_file_and_scale_and_planes_become_boxes():
    cell = read_scene(SCENES / "cell_mesh.sdf")
    assert cell.names == ["ground::plane", "bin::shell", "bracket::part"]
    ground = cell["ground::plane"]
    assert ground.shape == Box(HALFSPACE_SIDE, HALFSPACE_SIDE, HALFSPACE_DEPTH)
    top = ground.X_WO[:3, 3] + ground.X_WO[:3, :3] @ [0, 0, HALFSPACE_DEPTH / 2]
    np.testing.assert_allclose(top, [0, 0, -0.1], atol=1e-12)  # the top face is the plane z = -0.1
    np.testing.assert_allclose(ground.X_WO[:3, 2], [0, 0, 1], atol=1e-12)
    bin_ = cell["bin::shell"]
    assert bin_.shape == Mesh(DATA / "bin.obj", scale=(1, 1, 0.5))  # the file itself, not Drake's hull
    np.testing.assert_allclose(bin_.X_WO[:3, 3], [0.6, -0.2, 0.1])
    np.testing.assert_allclose(bin_.X_WO[:3, :3], rot_z(1.0), atol=1e-12)
    bracket = cell["bracket::part"].shape  # an .stl Drake's proximity engine does not read
    assert bracket == Mesh(DATA / "bracket_mm.stl", scale=0.001) and bracket.path.suffix == ".stl"


def test_package_meshes_resolve_through_the_packages_given(tmp_path):
    cell = read_scene(SCENES / "cell_mesh.urdf", packages={"cell_meshes": str(DATA)})
    assert cell.names == ["mesh_fixture::bracket", "mesh_fixture::plinth"]
    assert_obstacle(cell["mesh_fixture::bracket"], Mesh(DATA / "bracket.obj", scale=2), [0.5, -0.3, 0.1],
                    rot_z(np.pi / 2))
    assert_obstacle(cell["mesh_fixture::plinth"], Box(0.2, 0.2, 0.1), [0.5, -0.3, 0.0], np.eye(3))
    elsewhere = tmp_path / "cell_mesh.urdf"  # away from tests/data, where the resolver would find bracket.obj
    elsewhere.write_text((SCENES / "cell_mesh.urdf").read_text())
    with pytest.raises(SceneFileError, match=r"cell_mesh\.urdf, mesh 'package://cell_meshes/bracket.obj': .*"
                                             r"unknown package 'cell_meshes'"):
        read_scene(elsewhere)


def test_bodies_that_move_are_refused_or_taken_at_their_default_pose():
    with pytest.raises(SceneFileError, match=r"free_body\.sdf: bodies \['body'\] can move.*movable='default_pose'"):
        read_scene(SCENES / "free_body.sdf")
    cell = read_scene(SCENES / "free_body.sdf", movable="default_pose")
    assert_obstacle(cell["ball::sphere"], Sphere(0.05), [0.5, 0.0, 0.6], np.eye(3))
    with pytest.raises(SceneFileError, match=r"hinged\.urdf: bodies \['door'\] can move"):
        read_scene(SCENES / "hinged.urdf")
    door = read_scene(SCENES / "hinged.urdf", movable="default_pose")["cabinet::panel"]
    assert_obstacle(door, Box(0.02, 0.4, 0.8), [0.59, 0.0, 0.4], np.eye(3))  # the hinge at 0
    with pytest.raises(drake_mh.errors.InvalidArgument, match="movable"):
        read_scene(SCENES / "hinged.urdf", movable="freeze")


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


SDF = '<?xml version="1.0"?><sdf version="1.9"><world name="w"><model name="m"><static>true</static>' \
      '<link name="l"><collision name="c"><geometry>{}</geometry></collision></link></model></world></sdf>'


def test_malformed_and_unsupported_files_name_the_file_and_the_entry(tmp_path):
    bad_xml = _write(tmp_path, "broken.sdf", "<sdf version='1.9'><world>")
    with pytest.raises(SceneFileError, match=r"broken\.sdf: malformed XML"):
        read_scene(bad_xml)
    rejected = _write(tmp_path, "rejected.urdf", '<robot name="r"><link name="a"/><joint name="j" type="fixed">'
                                                 '<parent link="world"/><child link="nowhere"/></joint></robot>')
    with pytest.raises(SceneFileError, match=r"rejected\.urdf: Drake cannot parse it"):
        read_scene(rejected)
    ellipsoid = _write(tmp_path, "egg.sdf", SDF.format("<ellipsoid><radii>0.1 0.2 0.3</radii></ellipsoid>"))
    with pytest.raises(SceneFileError, match=r"egg\.sdf, collision geometry 'm::c': an ellipsoid is not"):
        read_scene(ellipsoid)
    missing = _write(tmp_path, "lost.sdf", SDF.format("<mesh><uri>lost.obj</uri></mesh>"))
    with pytest.raises(SceneFileError, match=r"lost\.sdf, mesh 'lost.obj': .*cannot find 'lost.obj'"):
        read_scene(missing)
    directives = _write(tmp_path, "cell.dmd.yaml", "directives:\n- add_model:\n    name: x\n"
                                                   "    file: package://no_such_package/x.sdf\n")
    with pytest.raises(SceneFileError, match=r"cell\.dmd\.yaml, package://no_such_package: package 'no_such_package'"
                                             r".*--package no_such_package=DIR"):
        read_scene(directives)
    garbage = _write(tmp_path, "garbage.dmd.yaml", "directives:\n- add_nothing: {}\n")
    with pytest.raises(SceneFileError, match=r"garbage\.dmd\.yaml: not valid model directives"):
        read_scene(garbage)


SPHERE_ARM = """<robot name="sphere_arm">
  <link name="base"/>
  <link name="l1"><collision><origin xyz="0 0 0.15"/><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="l2">
    <collision><origin xyz="0 0 0.1"/><geometry><sphere radius="0.04"/></geometry></collision>
    <collision><origin xyz="0 0 0.3"/><geometry><sphere radius="0.04"/></geometry></collision>
  </link>
  <link name="l3"><collision><origin xyz="0 0 0.2"/><geometry><sphere radius="0.03"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.05"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.4"/>
    <axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
</robot>"""
"""A 3-DOF arm of spheres (its base carries no geometry): Drake's sphere-vs-primitive distances
are closed forms, so Drake on a fresh plant is an exact, independent reference."""


def drake_reference(file: str, Q: np.ndarray) -> list[dict]:
    """``[{scene geometry name: smallest signed distance to the arm}]`` for each row of ``Q``,
    from a fresh plant holding the arm and the scene file, both parsed by Drake itself."""
    from pydrake.multibody.parsing import LoadModelDirectives, Parser, ProcessModelDirectives
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    parser = Parser(plant)
    (arm,) = parser.AddModels(file_contents=SPHERE_ARM, file_type="urdf")
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base", arm))
    if file.endswith(".dmd.yaml"):
        parser.package_map().Add("drake_mh_test_scenes", str(SCENES))
        ProcessModelDirectives(LoadModelDirectives(str(SCENES / file)), plant, parser)
    else:
        parser.AddModels(str(SCENES / file))
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    inspector = scene_graph.model_inspector()
    arm_frames = {plant.GetBodyFrameIdOrThrow(b) for b in plant.GetBodyIndices(arm)}
    out = []
    for q in Q:
        plant.SetPositions(plant_context, arm, q)
        query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
        distances: dict = {}
        for pair in query.ComputeSignedDistancePairwiseClosestPoints():
            on_arm = [inspector.GetFrameId(g) in arm_frames for g in (pair.id_A, pair.id_B)]
            if on_arm[0] != on_arm[1]:
                name = inspector.GetName(pair.id_B if on_arm[0] else pair.id_A)
                distances[name] = min(distances.get(name, np.inf), pair.distance)
        out.append(distances)
    return out


@pytest.fixture(scope="module")
def sphere_arm():
    return drake_mh.Robot(SPHERE_ARM)


@pytest.mark.parametrize("file", ["cell.sdf", "cell.urdf", "cell.dmd.yaml"])
def test_distances_equal_drakes_on_a_fresh_plant_with_the_same_file(sphere_arm, file):
    """Scene.from_file's exact distance to each obstacle at 40 random configurations (some in
    penetration) equals Drake's with the file loaded into a fresh plant by Drake directly."""
    Q = sphere_arm.random_configurations(40, 7)
    scene = Scene.from_file(SCENES / file, sphere_arm)
    reference = drake_reference(file, Q)
    assert min(min(r.values()) for r in reference) < 0 < max(min(r.values()) for r in reference)
    for q, expected in zip(Q, reference):
        ours: dict = {}
        for pair in scene.distances(q):
            ours[pair.other] = min(ours.get(pair.other, np.inf), pair.distance)
        assert set(ours) == set(expected)
        for name, distance in expected.items():
            assert ours[name] == pytest.approx(distance, abs=1e-12), name
        assert scene.min_distance(q) == pytest.approx(min(expected.values()), abs=1e-12)
