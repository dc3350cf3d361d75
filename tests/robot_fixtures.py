"""Small robot models with meshes written into a test's folder, and the installed test data.

``example-robot-data`` (a test extra) installs URDFs whose meshes are referenced as
``package://example-robot-data/robots/...`` under ``site-packages/cmeel.prefix/share/``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from drake_mh.robot.examples import EXAMPLE_ARMS


def erd_root() -> Path:
    """The ``example-robot-data`` package folder, or skip the test when it is not installed."""
    from drake_mh.robot.packages import installed_package_dir

    folder = installed_package_dir("example-robot-data")
    if folder is None or not (folder / "robots").is_dir():
        pytest.skip("example-robot-data is not installed (pip install -e '.[test]')")
    return folder


ERD_ROBOTS = {
    # name: (path inside the package, end-effector frame, nq); Kinova: continuous joints, and
    # material names defined twice with different colours
    name: (*EXAMPLE_ARMS[arm], nq)
    for name, arm, nq in (("panda", "panda_hand", 7), ("ur5", "ur5", 6), ("xarm7", "xarm7", 7), ("kinova", "kinova", 6))
}


def write_box_stl(path: Path, extents=(0.05, 0.05, 0.2), offset=(0.0, 0.0, 0.1)) -> Path:
    """A box mesh as binary STL (what CAD tools export)."""
    import trimesh

    path.parent.mkdir(parents=True, exist_ok=True)
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(offset)
    mesh.export(str(path))
    return path


ARM_URDF = """<?xml version="1.0"?>
<robot name="{name}">
  <link name="base">
    <collision><geometry><mesh filename="{base_mesh}"/></geometry></collision>
  </link>
  <link name="link1">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="{link_mesh}"/></geometry></visual>
    <collision><geometry><mesh filename="{link_mesh}"/></geometry></collision>
  </link>
  <link name="link2">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><mesh filename="{link_mesh}" scale="0.5 0.5 0.5"/></geometry></collision>
  </link>
  <link name="hand"/>
  <link name="finger_left"><collision><geometry><box size="0.01 0.01 0.04"/></geometry></collision></link>
  <link name="finger_right"><collision><geometry><box size="0.01 0.01 0.04"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="2"/></joint>
  <joint name="hand_joint" type="fixed"><parent link="link2"/><child link="hand"/><origin xyz="0 0 0.1"/></joint>
  <joint name="finger_joint_left" type="prismatic"><parent link="hand"/><child link="finger_left"/>
    <origin xyz="0 0 0.05"/><axis xyz="0 1 0"/><limit lower="0.01" upper="0.04" effort="10" velocity="0.1"/></joint>
  <joint name="finger_joint_right" type="prismatic"><parent link="hand"/><child link="finger_right"/>
    <origin xyz="0 0 0.05"/><axis xyz="0 -1 0"/><limit lower="0.01" upper="0.04" effort="10" velocity="0.1"/>
    <mimic joint="finger_joint_left"/></joint>
</robot>
"""


def write_arm(folder: Path, name: str = "arm", base_mesh: str = "meshes/base.stl",
              link_mesh: str = "meshes/link.stl", meshes: bool = True) -> Path:
    """A 2-joint arm with a two-finger hand (one finger mimics the other), meshes as STL."""
    folder.mkdir(parents=True, exist_ok=True)
    if meshes:
        write_box_stl(folder / "meshes" / "base.stl", (0.1, 0.1, 0.1), (0, 0, 0.05))
        write_box_stl(folder / "meshes" / "link.stl")
    path = folder / f"{name}.urdf"
    path.write_text(ARM_URDF.format(name=name, base_mesh=base_mesh, link_mesh=link_mesh))
    return path
