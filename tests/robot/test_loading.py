"""Your own robot: model files with meshes load as shipped (drake_mh.robot.loading, packages,
meshes, chain); real robots of example-robot-data checked against Pinocchio."""

from __future__ import annotations

import pickle
import shutil

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import (
    FrameNotFound,
    InvalidArgument,
    InvalidURDF,
    MeshNotFound,
    UnknownPackage,
    UnknownRobot,
    UnsupportedModel,
)
from robot_fixtures import ERD_ROBOTS, erd_root, write_arm, write_box_stl


@pytest.fixture(autouse=True)
def _private_cache(tmp_path_factory, monkeypatch):
    """Every test converts meshes into a cache folder of this test session, not the user's."""
    monkeypatch.setenv("DRAKE_MH_CACHE", str(tmp_path_factory.getbasetemp() / "drake_mh_cache"))


def _erd(name: str, **kwargs):
    rel, ee, _ = ERD_ROBOTS[name]
    return drake_mh.load_robot(erd_root() / rel, ee_frame=kwargs.pop("ee_frame", ee), **kwargs)


def _pinocchio_fk_error(robot, path, frame: str, n: int = 25, seed: int = 0) -> float:
    """Largest |X_WE(Drake) - X_WE(Pinocchio)| entry over random configurations."""
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromUrdf(str(path))
    lock = [model.getJointId(n) for n in list(model.names)[1:] if n not in robot.joint_names]
    q_lock = pin.neutral(model)
    for name, value in robot.locked_joints.items():  # lock where drake_mh locked
        jid = model.getJointId(name)
        q_lock[model.idx_qs[jid]] = value
    model = pin.buildReducedModel(model, lock, q_lock)
    data = model.createData()
    fid = model.getFrameId(frame)
    cols = [model.idx_vs[model.getJointId(n)] for n in robot.joint_names]
    err = 0.0
    for q in robot.random_configurations(n, seed):
        v = np.zeros(model.nv)
        v[cols] = q  # from the neutral configuration: revolute and continuous joints alike
        pin.framesForwardKinematics(model, data, pin.integrate(model, pin.neutral(model), v))
        err = max(err, float(np.abs(data.oMf[fid].homogeneous - robot.fk(q)).max()))
    return err


# --- example-robot-data: load as shipped, FK against Pinocchio ---------------------------------


@pytest.mark.parametrize("name", sorted(ERD_ROBOTS))
def test_real_robots_load_as_shipped_and_match_pinocchio(name):
    rel, ee, nq = ERD_ROBOTS[name]
    robot = _erd(name)  # package://example-robot-data found from the model's own folder
    assert robot.nq == nq and robot.ee_frame_name == ee
    summary = robot.collision_summary()
    assert sum(c.get("Convex", 0) for c in summary.values()) >= nq  # meshes became convex hulls
    assert _pinocchio_fk_error(robot, erd_root() / rel, ee) <= 1e-9


def test_panda_with_hand_locks_the_fingers():
    robot = _erd("panda")
    assert robot.nq == 7
    assert robot.joint_names == [f"panda_joint{i}" for i in range(1, 8)]
    assert robot.locked_joints == {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
    assert "locked" in repr(robot)
    opened = _erd("panda", locked={"panda_finger_joint1": 0.04, "panda_finger_joint2": 0.04})
    q = robot.home
    y_closed = robot.fk(q, "panda_leftfinger")[:3, 3] - robot.fk(q, "panda_rightfinger")[:3, 3]
    y_open = opened.fk(q, "panda_leftfinger")[:3, 3] - opened.fk(q, "panda_rightfinger")[:3, 3]
    assert np.linalg.norm(y_open) == pytest.approx(np.linalg.norm(y_closed) + 0.08, abs=1e-12)
    np.testing.assert_allclose(opened.fk(q), robot.fk(q), atol=1e-15)


def test_panda_with_hand_needs_an_end_effector_and_lists_the_tips():
    with pytest.raises(InvalidArgument) as info:
        drake_mh.load_robot(erd_root() / ERD_ROBOTS["panda"][0])
    for tip in ("panda_leftfinger", "panda_rightfinger", "panda_hand_tcp", "ee_frame="):
        assert tip in str(info.value)


def test_packages_argument_and_environment(monkeypatch):
    root = erd_root()
    by_arg = _erd("ur5", packages={"example-robot-data": root})
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(root.parent.parent))
    by_env = _erd("ur5")
    q = by_arg.random_configurations(1, 3)[0]
    np.testing.assert_array_equal(by_arg.fk(q), by_env.fk(q))
    with pytest.raises(InvalidArgument, match="not an existing folder"):
        _erd("ur5", packages={"example-robot-data": root / "nowhere"})


def test_file_robot_pickles_by_path_and_options():
    robot = _erd("panda", locked={"panda_finger_joint1": 0.02})
    data = pickle.dumps(robot)
    assert len(data) < 2000  # the path and options, not the model text
    again = pickle.loads(data)
    assert again.locked_joints == robot.locked_joints and again.ee_frame_name == "panda_hand_tcp"
    q = robot.random_configurations(1, 0)[0]
    np.testing.assert_array_equal(again.fk(q), robot.fk(q))


def test_bundled_robots_unchanged(panda):
    assert panda.locked_joints == {} and panda.mesh_files == {"collision": [], "visual": []}
    assert panda.model_text == panda.urdf  # nothing rewritten
    assert pickle.loads(pickle.dumps(panda)).nq == 7


# --- meshes and the cache ------------------------------------------------------------------------


def test_mesh_conversion_is_cached(tmp_path, monkeypatch):
    """The second load converts nothing (a conversion raises here) and touches no cached file.
    How much faster it is: studies/robot_loading.py (not timed here)."""
    monkeypatch.setenv("DRAKE_MH_CACHE", str(tmp_path / "cache"))
    root = erd_root()
    path = root / ERD_ROBOTS["panda"][0]
    first = drake_mh.load_robot(path, ee_frame="panda_hand_tcp")
    files = sorted((tmp_path / "cache" / "meshes").iterdir())
    assert len(files) == 9  # 9 STL collision hulls (link0-7, hand; fingers are boxes, visuals .dae: kept)
    mtimes = [f.stat().st_mtime_ns for f in files]

    import drake_mh.robot.meshes as meshes

    def no_conversion(path):
        raise AssertionError(f"converted {path} again")

    monkeypatch.setattr(meshes, "_load_trimesh", no_conversion)
    second = drake_mh.load_robot(path, ee_frame="panda_hand_tcp")
    assert sorted((tmp_path / "cache" / "meshes").iterdir()) == files
    assert [f.stat().st_mtime_ns for f in files] == mtimes
    assert first.mesh_files == second.mesh_files
    hull, = [f for u, f in first.mesh_files["collision"] if u.endswith("link3.stl")]
    text = open(hull).read()
    assert text.startswith("# convex hull of link3.stl") and "np.float64" not in text


def test_relative_stl_meshes_scale_and_mimic(tmp_path):
    path = write_arm(tmp_path / "arm")
    robot = drake_mh.load_robot(path, ee_frame="hand")
    assert robot.nq == 2 and robot.joint_names == ["j1", "j2"]
    # finger_joint_left: 0 clipped into [0.01, 0.04]; the mimic finger follows it
    assert robot.locked_joints == {"finger_joint_left": 0.01, "finger_joint_right": 0.01}
    assert robot.collision_summary()["link2"] == {"Convex": 1}
    shape = robot.scene_graph.model_inspector().GetShape(
        robot.plant.GetCollisionGeometriesForBody(robot.plant.GetBodyByName("link2"))[0])
    assert shape.scale3().tolist() == [0.5, 0.5, 0.5]  # <mesh scale> kept
    assert str(shape.source().path()).endswith("_hull.obj")
    np.testing.assert_allclose(robot.fk([0.0, 0.0])[:3, 3], [0.0, 0.0, 0.4], atol=1e-15)


def test_mimic_joint_on_the_chain_is_rejected(tmp_path):
    path = write_arm(tmp_path / "arm")
    with pytest.raises(UnsupportedModel, match="mimics 'finger_joint_left'"):
        drake_mh.load_robot(path, ee_frame="finger_right")
    robot = drake_mh.load_robot(path, ee_frame="finger_right", locked={"finger_joint_right": 0.02})
    assert robot.nq == 2 and robot.locked_joints["finger_joint_right"] == 0.02


def test_several_tips_listed(tmp_path):
    path = write_arm(tmp_path / "arm")
    with pytest.raises(InvalidArgument, match="2 tip links") as info:
        drake_mh.load_robot(path)
    assert "finger_left, finger_right" in str(info.value) and "ee_frame=" in str(info.value)
    with pytest.raises(FrameNotFound, match="no_such_frame"):
        drake_mh.load_robot(path, ee_frame="no_such_frame")
    with pytest.raises(FrameNotFound, match="movable joint"):
        drake_mh.load_robot(path, ee_frame="hand", locked={"hand_joint": 0.0})
    with pytest.raises(InvalidArgument, match="outside the joint's limits"):
        drake_mh.load_robot(path, ee_frame="hand", locked={"finger_joint_left": 1.0})


def test_missing_mesh_names_the_uri_and_every_place(tmp_path):
    path = write_arm(tmp_path / "arm", link_mesh="meshes/nope.stl")
    with pytest.raises(MeshNotFound) as info:
        drake_mh.load_robot(path, ee_frame="hand")
    message = str(info.value)
    assert "meshes/nope.stl" in message and str(tmp_path / "arm" / "meshes" / "nope.stl") in message
    assert "packages=" in message and info.value.uri == "meshes/nope.stl"


def test_unknown_package_lists_the_search(tmp_path, monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)
    uri = "package://my_arm_description/parts/link.stl"
    path = write_arm(tmp_path / "arm", link_mesh=uri)
    with pytest.raises(UnknownPackage) as info:
        drake_mh.load_robot(path, ee_frame="hand")
    message = str(info.value)
    for part in (uri, "packages=", "package.xml", "ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH",
                 "the model's folder", "--package my_arm_description=DIR"):
        assert part in message, part
    assert info.value.package == "my_arm_description"
    pkg = tmp_path / "ws" / "src" / "my_arm_description"
    write_box_stl(pkg / "parts" / "link.stl")
    # 1. given
    assert drake_mh.load_robot(path, ee_frame="hand", packages={"my_arm_description": pkg}).nq == 2
    # 2. ROS_PACKAGE_PATH (an entry holding the package folder)
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(pkg.parent))
    assert drake_mh.load_robot(path, ee_frame="hand").nq == 2
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    # 3. a package.xml beside the model's package (a ROS workspace), named differently
    (pkg / "package.xml").write_text("<package format='3'><name>my_arm_description</name></package>")
    other = pkg.parent / "arm_bringup"
    shutil.copytree(tmp_path / "arm", other)
    assert drake_mh.load_robot(other / "arm.urdf", ee_frame="hand").nq == 2
    # 4. the fallback: package://NAME/rest where rest exists under the model's folder
    fallback = write_arm(tmp_path / "cad_export", link_mesh="package://exported/meshes/link.stl")
    assert drake_mh.load_robot(fallback, ee_frame="hand").nq == 2


def test_unknown_names_and_files(tmp_path):
    with pytest.raises(UnknownRobot):
        drake_mh.load_robot("no_such_robot")
    with pytest.raises(InvalidURDF, match="no such file"):
        drake_mh.load_robot(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.stl.urdf"
    bad.write_text("<robot name='x'><link name='a'/></robot>")
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(UnsupportedModel, match="cannot tell the model format"):
        drake_mh.load_robot(tmp_path / "notes.txt")


def test_register_robot(tmp_path):
    path = write_arm(tmp_path / "arm")
    drake_mh.register_robot("test_arm_registered", path, ee_frame="hand")
    robot = drake_mh.load_robot("test_arm_registered")
    assert robot.nq == 2 and robot.ee_frame_name == "hand"
    with pytest.raises(InvalidArgument, match="bundled"):
        drake_mh.register_robot("panda", path)


# --- other formats -------------------------------------------------------------------------------


XACRO = """<?xml version="1.0"?>
<robot name="xarm2" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="length" default="0.3"/>
  <xacro:property name="L" value="$(arg length)"/>
  <xacro:macro name="seg" params="name parent z">
    <link name="${name}">
      <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
      <collision><geometry><mesh filename="package://xpkg/meshes/link.stl"/></geometry></collision>
    </link>
    <joint name="${name}_joint" type="revolute"><parent link="${parent}"/><child link="${name}"/>
      <origin xyz="0 0 ${z}"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="5" velocity="1"/></joint>
  </xacro:macro>
  <link name="base"/>
  <xacro:seg name="a" parent="base" z="0.1"/>
  <xacro:seg name="b" parent="a" z="${L}"/>
  <xacro:include filename="$(find xpkg)/tip.xacro"/>
</robot>
"""

TIP = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <link name="tip"/>
  <joint name="tip_joint" type="fixed"><parent link="b"/><child link="tip"/><origin xyz="0 0 0.2"/></joint>
</robot>
"""


def test_xacro_with_find_and_arguments(tmp_path):
    pkg = tmp_path / "xpkg"
    write_box_stl(pkg / "meshes" / "link.stl")
    (pkg / "tip.xacro").write_text(TIP)
    path = pkg / "urdf" / "arm.urdf.xacro"
    path.parent.mkdir()
    path.write_text(XACRO)
    robot = drake_mh.load_robot(path, packages={"xpkg": pkg})
    assert robot.nq == 2 and robot.ee_frame_name == "tip" and robot.name == "arm"
    np.testing.assert_allclose(robot.fk([0.0, 0.0])[:3, 3], [0, 0, 0.6], atol=1e-15)
    longer = drake_mh.load_robot(path, packages={"xpkg": pkg}, xacro_args={"length": "0.5"})
    np.testing.assert_allclose(longer.fk([0.0, 0.0])[:3, 3], [0, 0, 0.8], atol=1e-15)
    # without packages=: the folder named xpkg among the model's parents is the package
    assert drake_mh.load_robot(path).nq == 2
    assert pickle.loads(pickle.dumps(longer)).fk([0.0, 0.0])[2, 3] == pytest.approx(0.8, abs=1e-15)
    (pkg / "urdf" / "broken.xacro").write_text(XACRO.replace("${L}", "${undefined_name}"))
    with pytest.raises(InvalidURDF, match="xacro failed"):
        drake_mh.load_robot(pkg / "urdf" / "broken.xacro")


SDF = """<?xml version="1.0"?>
<sdf version="1.7">
  <model name="sdf_arm">
    <link name="base">
      <collision name="c"><geometry><mesh><uri>meshes/link.stl</uri></mesh></geometry></collision>
    </link>
    <link name="l1">
      <pose>0 0 0.1 0 0 0</pose>
      <inertial><mass>1</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz></inertia></inertial>
      <collision name="c"><geometry><mesh><uri>meshes/link.stl</uri></mesh></geometry></collision>
      <visual name="v"><geometry><mesh><uri>meshes/link.stl</uri></mesh></geometry></visual>
    </link>
    <link name="l2">
      <pose>0 0 0.3 0 0 0</pose>
      <inertial><mass>1</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz></inertia></inertial>
    </link>
    <link name="finger">
      <pose>0 0 0.3 0 0 0</pose>
      <inertial><mass>0.1</mass><inertia><ixx>0.001</ixx><iyy>0.001</iyy><izz>0.001</izz></inertia></inertial>
    </link>
    <joint name="j1" type="revolute"><parent>base</parent><child>l1</child>
      <axis><xyz>0 0 1</xyz><limit><lower>-3</lower><upper>3</upper></limit></axis></joint>
    <joint name="j2" type="revolute"><parent>l1</parent><child>l2</child>
      <axis><xyz>0 1 0</xyz><limit><lower>-2</lower><upper>2</upper></limit></axis></joint>
    <joint name="jf" type="prismatic"><parent>l1</parent><child>finger</child>
      <axis><xyz>1 0 0</xyz><limit><lower>-0.1</lower><upper>0.1</upper></limit></axis></joint>
  </model>
</sdf>
"""


def test_sdformat_with_relative_stl_and_a_locked_joint(tmp_path):
    write_box_stl(tmp_path / "meshes" / "link.stl")
    path = tmp_path / "arm.sdf"
    path.write_text(SDF)
    robot = drake_mh.load_robot(path, ee_frame="l2")
    assert robot.model_format == "sdf"
    assert robot.nq == 2 and robot.locked_joints == {"jf": 0.0}
    assert robot.collision_summary() == {"base": {"Convex": 1}, "l1": {"Convex": 1}}
    np.testing.assert_allclose(robot.fk([0.0, 0.0])[:3, 3], [0, 0, 0.3], atol=1e-15)
    with pytest.raises(UnsupportedModel, match="lock at 0 only"):
        drake_mh.load_robot(path, ee_frame="l2", locked={"jf": 0.05})


MJCF = """<mujoco model="mj_arm">
  <compiler angle="radian" meshdir="assets"/>
  <asset><mesh name="link" file="link.stl"/></asset>
  <worldbody>
    <body name="base">
      <geom type="mesh" mesh="link"/>
      <body name="l1" pos="0 0 0.1">
        <joint name="j1" type="hinge" axis="0 0 1" range="-3 3"/>
        <geom type="mesh" mesh="link"/>
        <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
        <body name="l2" pos="0 0 0.2">
          <joint name="j2" type="hinge" axis="0 1 0" range="-2 2"/>
          <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_mjcf_with_stl_assets(tmp_path):
    write_box_stl(tmp_path / "assets" / "link.stl")
    path = tmp_path / "arm.xml"
    path.write_text(MJCF)
    robot = drake_mh.load_robot(path, ee_frame="l2")
    assert robot.model_format == "mjcf" and robot.nq == 2
    np.testing.assert_allclose(robot.fk([0.0, 0.0])[:3, 3], [0, 0, 0.3], atol=1e-15)
    assert sum(sum(c.values()) for c in robot.collision_summary().values()) >= 2


def test_text_robot_with_relative_mesh_says_to_load_the_file(tmp_path):
    path = write_arm(tmp_path / "arm")
    with pytest.raises(MeshNotFound, match="load_robot"):
        drake_mh.Robot(path.read_text(), ee_frame="hand")
    robot = drake_mh.Robot(path.read_text(), ee_frame="hand", model_dir=path.parent)
    assert robot.nq == 2
    assert pickle.loads(pickle.dumps(robot)).nq == 2


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".off", ".dae"])
def test_collision_meshes_of_any_format_become_hulls(tmp_path, suffix):
    import re

    import trimesh

    from drake_mh.robot.meshes import collision_hull, visual_mesh

    box = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    path = tmp_path / f"part{suffix}"
    box.export(str(path))
    expected = np.array([[-0.05, -0.1, -0.15], [0.05, 0.1, 0.15]])
    if suffix == ".dae":  # a CAD export in millimetres: ROS tools scale by <unit meter>
        text = path.read_text()
        text = text.replace("<asset>", '<asset><unit name="millimeter" meter="0.001"/>', 1) \
            if "<unit" not in text else re.sub(r"<unit[^>]*/>", '<unit meter="0.001"/>', text)
        path.write_text(text)
        expected = expected * 1e-3
    hull = collision_hull(path)
    assert hull.suffix == ".obj" and hull == collision_hull(path)  # same cache entry
    np.testing.assert_allclose(trimesh.load(str(hull)).bounds, expected, atol=1e-12)
    shown = visual_mesh(path)
    assert shown == path if suffix in (".obj", ".dae") else shown.suffix == ".obj"


def test_unreadable_or_flat_collision_mesh(tmp_path):
    from drake_mh.errors import MeshConversionError
    from drake_mh.robot.meshes import collision_hull

    junk = tmp_path / "junk.stl"
    junk.write_bytes(b"not a mesh")
    with pytest.raises(MeshConversionError, match="junk.stl"):
        collision_hull(junk)
    flat = tmp_path / "flat.obj"
    flat.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    with pytest.raises(MeshConversionError, match="flat|hull"):
        collision_hull(flat)


def test_visual_stl_meshes_are_converted_for_meshcat():
    robot = _erd("xarm7")
    assert robot.mesh_files["visual"] and all(f.endswith("_visual.obj") for _, f in robot.mesh_files["visual"])
    assert all(f.endswith("_hull.obj") for _, f in robot.mesh_files["collision"])


def test_locking_a_revolute_joint_at_a_value_keeps_the_kinematics(panda):
    """A URDF joint locked at v: the fixed joint's origin is the joint origin composed with the
    motion at v (bundled Panda, joints 4 and 7 locked, with their transmissions)."""
    locked = drake_mh.load_robot("panda", locked={"panda_joint4": -1.2, "panda_joint7": 0.5})
    assert locked.nq == 5 and "panda_joint4" not in locked.joint_names
    assert np.isfinite(locked.effort_limits).all()  # the remaining actuators are kept
    for q in locked.random_configurations(10, 1):
        full = np.insert(q, 3, -1.2)
        full = np.append(full, 0.5)
        np.testing.assert_allclose(locked.fk(q), panda.fk(full), atol=1e-14)


def test_installed_packages_resolve_from_text():
    """package://example-robot-data/... resolves from this Python's prefixes, even from text."""
    path = erd_root() / ERD_ROBOTS["ur5"][0]
    robot = drake_mh.Robot(path.read_text(), ee_frame="tool0")  # no model folder to search
    assert robot.nq == 6 and robot.collision_summary()["shoulder_link"] == {"Convex": 1}


def test_unreadable_visual_mesh_only_warns(tmp_path, caplog):
    path = write_arm(tmp_path / "arm")
    (tmp_path / "arm" / "meshes" / "bad.ply").write_bytes(b"garbage")
    path.write_text(path.read_text().replace(
        '<visual><geometry><mesh filename="meshes/link.stl"/>',
        '<visual><geometry><mesh filename="meshes/bad.ply"/>'))
    with caplog.at_level("WARNING", logger="drake_mh.robot.loading"):
        robot = drake_mh.load_robot(path, ee_frame="hand")
    assert robot.nq == 2 and "bad.ply not shown" in caplog.text
