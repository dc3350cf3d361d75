"""Limits with provenance: what the model declares, what the user sets, what a limits file says."""

from __future__ import annotations

import copy
import pickle
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from robot_fixtures import erd_root

import drake_mh
from drake_mh.errors import InvalidLimits

LIMITS_YAML = """default_velocity_scaling_factor: 0.5
default_acceleration_scaling_factor: 0.25
joint_limits:
  panda_joint1:
    has_velocity_limits: true
    max_velocity: 1.5
    has_acceleration_limits: true
    max_acceleration: 4.0
    has_jerk_limits: true
    max_jerk: 500
    has_effort_limits: true
    max_effort: 60
  panda_joint2:
    has_velocity_limits: false
    max_velocity: 0
    has_acceleration_limits: true
    max_acceleration: 3
  panda_finger_joint1:
    has_velocity_limits: true
    max_velocity: 0.2
"""


def _urdf_limits(path, joint):
    """``<limit>`` attributes of ``joint`` read from the URDF itself (the reference)."""
    for elem in ET.parse(path).getroot().iter("joint"):
        if elem.get("name") == joint:
            return {k: float(v) for k, v in elem.find("limit").attrib.items()}
    raise KeyError(joint)


@pytest.fixture(scope="module")
def erd_panda_path():
    from drake_mh.robot.examples import EXAMPLE_ARMS

    return erd_root() / EXAMPLE_ARMS["panda_hand"][0]


def test_a_vendor_urdf_reports_what_it_declares_and_what_it_does_not(erd_panda_path):
    robot = drake_mh.load_robot(erd_panda_path, ee_frame="panda_hand_tcp")
    limits = robot.limits
    for j, name in enumerate(robot.joint_names):
        declared = _urdf_limits(erd_panda_path, name)
        assert robot.velocity_limits[j] == declared["velocity"] and robot.effort_limits[j] == declared["effort"]
        assert (robot.lower[j], robot.upper[j]) == (declared["lower"], declared["upper"])
    assert set(limits.sources("velocity")) == {"declared"} and set(limits.sources("effort")) == {"declared"}
    assert set(limits.sources("acceleration")) == {"none"} and not np.any(np.isfinite(robot.acceleration_limits))
    assert set(limits.details("velocity")) == {"panda.urdf"}
    text = "\n".join(limits.summary())
    assert "acceleration [rad/s²]: - - - - - - - | none on all 7 joints" in text
    assert "velocity [rad/s]: 2.175" in text and "declared (panda.urdf) on all 7 joints" in text
    assert "| velocity [rad/s] | 2.175 (declared)" in limits.table()
    assert "acceleration: none" in repr(limits)


def test_a_continuous_joint_gets_a_default_range_said_so(tmp_path):
    urdf = tmp_path / "c.urdf"
    urdf.write_text("""<robot name="c"><link name="base"/><link name="l1">
      <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j1" type="continuous"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
      <limit effort="5" velocity="1"/></joint></robot>""")
    robot = drake_mh.load_robot(urdf)
    assert robot.limits.sources("position") == ("default",) and (robot.lower[0], robot.upper[0]) == (-np.pi, np.pi)


def test_assigning_marks_user_and_copies_keep_their_own(panda):
    robot = copy.copy(panda)
    robot.acceleration_limits = np.full(7, 3.0)
    assert robot.limits.sources("acceleration") == ("user",) * 7
    assert panda.limits.sources("acceleration") == ("declared",) * 7 and panda.acceleration_limits[0] == 15.0
    assert robot.acceleration_limits is robot.acceleration_limits           # one array, as an attribute was
    with pytest.raises(InvalidLimits, match=r"panda_joint2"):
        robot.velocity_limits = [1, -1, 1, 1, 1, 1, 1]
    with pytest.raises(InvalidLimits, match="7 positive numbers"):
        robot.velocity_limits = [1, 2]
    assert robot.limits.sources("velocity") == ("declared",) * 7            # a failed call changes nothing
    again = pickle.loads(pickle.dumps(robot))
    assert np.array_equal(again.acceleration_limits, robot.acceleration_limits)
    assert again.limits.sources("acceleration") == ("user",) * 7


def test_a_limits_file_sets_user_limits_naming_the_file(tmp_path, erd_panda_path):
    path = tmp_path / "joint_limits.yaml"
    path.write_text(LIMITS_YAML)
    robot = drake_mh.load_robot(erd_panda_path, ee_frame="panda_hand_tcp", limits=path)
    lim = robot.limits
    assert robot.velocity_limits[0] == 1.5 and lim.sources("velocity")[:2] == ("user", "declared")
    assert robot.velocity_limits[1] == _urdf_limits(erd_panda_path, "panda_joint2")["velocity"]  # has_...: false keeps it
    assert robot.acceleration_limits[:2].tolist() == [4.0, 3.0] and lim.details("acceleration")[0] == "joint_limits.yaml"
    assert robot.jerk_limits[0] == 500 and robot.effort_limits[0] == 60 and lim.sources("effort")[1] == "declared"
    assert lim.scaling == {"velocity": 0.5, "acceleration": 0.25}
    assert "user (joint_limits.yaml) on panda_joint1" in "\n".join(lim.summary())
    again = pickle.loads(pickle.dumps(robot))                                 # process pools keep them
    assert again.acceleration_limits[0] == 4.0 and again.limits.scaling["acceleration"] == 0.25


@pytest.mark.parametrize("text, words", [
    ("joint_limits:\n  elbow:\n    max_velocity: 1\n", ["unknown joint 'elbow'", "panda_joint1"]),
    ("joint_limits:\n  panda_joint3:\n    max_velocity: fast\n", ["panda_joint3", "max_velocity", "'fast'"]),
    ("joint_limits:\n  panda_joint3:\n    has_acceleration_limits: true\n    max_acceleration: -2\n",
     ["panda_joint3", "max_acceleration", "> 0"]),
    ("joint_limits:\n  panda_joint3:\n    has_jerk_limits: yes please\n", ["panda_joint3", "has_jerk_limits"]),
    ("joint_limits:\n  panda_joint3:\n    has_effort_limits: true\n", ["panda_joint3", "max_effort is missing"]),
    ("joint_limits:\n  panda_joint3:\n    max_velocitty: 1\n", ["panda_joint3", "unknown key 'max_velocitty'"]),
    ("joint_limits:\n  panda_joint3:\n    has_position_limits: true\n    min_position: 0\n",
     ["panda_joint3", "has_position_limits"]),
    ("default_velocity_scaling_factor: 1.5\n", ["default_velocity_scaling_factor", "(0, 1]"]),
    ("joint_limit:\n  panda_joint3: {}\n", ["unknown top-level key", "joint_limit"]),
    ("joint_limits: [1, 2]\n", ["'joint_limits' must map"]),
    ("joint_limits: {panda_joint1: {max_velocity: 1}\n", ["not valid YAML"]),
])
def test_bad_limits_files_name_the_file_joint_and_key(tmp_path, panda, text, words):
    path = tmp_path / "bad_limits.yaml"
    path.write_text(text)
    with pytest.raises(InvalidLimits) as err:
        drake_mh.load_robot("panda", limits=path)
    message = str(err.value)
    assert str(path) in message
    for word in words:
        assert word in message, message


def test_a_missing_limits_file_and_a_dict(panda, tmp_path):
    with pytest.raises(InvalidLimits, match="cannot read the limits file"):
        drake_mh.load_robot("panda", limits=tmp_path / "nope.yaml")
    robot = drake_mh.load_robot("panda", limits={"joint_limits": {"panda_joint7": {"max_velocity": 1.0}}})
    assert robot.velocity_limits[6] == 1.0 and robot.limits.details("velocity")[6] == "limits dict"
    with pytest.raises(InvalidLimits, match="path of a MoveIt-style"):
        drake_mh.load_robot("panda", limits=3)
