"""Robot: loading, limits, Drake queries, errors."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import (
    FrameNotFound,
    InvalidArgument,
    InvalidConfiguration,
    InvalidDHTable,
    InvalidLimits,
    InvalidURDF,
    UnknownRobot,
    UnsupportedModel,
)
from drake_mh.robot import Robot

from random_models import random_chain_urdf

PANDA_TABLE_LIMITS = {
    "lower": [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973],
    "upper": [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973],
    "velocity": [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61],
    "acceleration": [15, 7.5, 10, 12.5, 15, 20, 20],
    "jerk": [7500, 3750, 5000, 6250, 7500, 10000, 10000],
    "effort": [87, 87, 87, 87, 12, 12, 12],
}
ESM_THETA0 = [0.481, 0.703, 0.093, -0.800, -0.364, 0.992, 0.026]


@pytest.fixture(scope="module")
def panda():
    return drake_mh.load_robot("panda")


def test_every_bundled_robot_loads():
    names = drake_mh.available_robots()
    assert {"panda", "seed000_6dof", "planar5", "planar12", "planar2r"} <= set(names)
    nq = {"panda": 7, "seed000_6dof": 6, "planar5": 5, "planar12": 12, "planar2r": 2}
    for name, n in nq.items():
        robot = drake_mh.load_robot(name)
        assert robot.nq == n
        assert np.all(robot.lower < robot.upper)
        assert np.all(np.isfinite(robot.effort_limits)), f"{name}: effort limits missing (transmissions?)"


def test_panda_limits_match_the_published_table(panda):
    np.testing.assert_allclose(panda.lower, PANDA_TABLE_LIMITS["lower"])
    np.testing.assert_allclose(panda.upper, PANDA_TABLE_LIMITS["upper"])
    np.testing.assert_allclose(panda.velocity_limits, PANDA_TABLE_LIMITS["velocity"])
    np.testing.assert_allclose(panda.acceleration_limits, PANDA_TABLE_LIMITS["acceleration"])
    np.testing.assert_allclose(panda.jerk_limits, PANDA_TABLE_LIMITS["jerk"])
    np.testing.assert_allclose(panda.effort_limits, PANDA_TABLE_LIMITS["effort"])


def test_panda_flange_and_esm_initial_configuration(panda):
    np.testing.assert_allclose(panda.fk(np.zeros(7))[:3, 3], [0.088, 0.0, 0.926], atol=1e-12)
    # the ESM paper's θ0 puts the flange on its target [0.6, 0.3, 0.5]: measured 1.4e-4 m away,
    # consistent with θ0 printed to 3 decimals (±5e-4 rad per joint moves the flange ~1e-3 m)
    assert np.linalg.norm(panda.fk(ESM_THETA0)[:3, 3] - [0.6, 0.3, 0.5]) < 2e-4
    assert panda.manipulability(ESM_THETA0) == pytest.approx(0.108, abs=1e-3)


def test_jacobian_matches_finite_differences_of_fk(panda):
    q = np.array([0.3, -0.4, 0.5, -1.2, 0.2, 1.1, -0.3])
    J = panda.jacobian(q)
    h = 1e-6
    for i in range(7):
        dq = np.zeros(7)
        dq[i] = h
        Tp, Tm = panda.fk(q + dq), panda.fk(q - dq)
        np.testing.assert_allclose((Tp[:3, 3] - Tm[:3, 3]) / (2 * h), J[3:, i], atol=1e-7)
        dR = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ panda.fk(q)[:3, :3].T  # skew(ω)
        np.testing.assert_allclose([dR[2, 1], dR[0, 2], dR[1, 0]], J[:3, i], atol=1e-7)


def test_manipulability_variants(panda):
    q = np.array(ESM_THETA0)
    J = panda.jacobian(q)
    assert panda.manipulability(q, translational=False) == pytest.approx(np.sqrt(np.linalg.det(J @ J.T)))
    assert panda.manipulability(q) == pytest.approx(np.sqrt(np.linalg.det(J[3:] @ J[3:].T)))


def test_inverse_dynamics_includes_gravity(panda):
    q = np.array([0.1, -0.5, 0.3, -1.5, 0.2, 1.2, 0.4])
    v = np.linspace(-0.5, 0.5, 7)
    a = np.linspace(1.0, -1.0, 7)
    plant, ctx = panda.plant, panda.plant_context
    tau = panda.inverse_dynamics(q, v, a)
    plant.SetPositions(ctx, q)
    plant.SetVelocities(ctx, v)
    expected = plant.CalcMassMatrix(ctx) @ a + plant.CalcBiasTerm(ctx) - plant.CalcGravityGeneralizedForces(ctx)
    np.testing.assert_allclose(tau, expected, atol=1e-9)
    assert np.linalg.norm(panda.gravity_torques(q)) > 1.0  # gravity is really there


TWO_LINK_VERTICAL = """<robot name="two_link">
  <link name="base"/>
  <link name="l1"><inertial><origin xyz="0.5 0 0"/><mass value="1"/>
    <inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="l2"><inertial><origin xyz="0.5 0 0"/><mass value="1"/>
    <inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 -1 0"/>
    <limit lower="-3" upper="3" velocity="1" effort="100"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="1 0 0"/>
    <axis xyz="0 -1 0"/><limit lower="-3" upper="3" velocity="1" effort="100"/></joint>
  <joint name="t" type="fixed"><parent link="l2"/><child link="tip"/><origin xyz="1 0 0"/></joint>
</robot>"""


def test_two_link_holding_torques_include_gravity():
    # 1 kg at the middle of each 1 m link, arm horizontal in a vertical plane:
    # τ = [m g (l/2) + m g (l + l/2), m g l/2] = [19.62, 4.905] N·m (REFERENCES.md)
    robot = Robot(TWO_LINK_VERTICAL)
    np.testing.assert_allclose(robot.gravity_torques([0.0, 0.0]), [19.62, 4.905], atol=1e-6)


def test_from_dh_framework_paper_two_link_example():
    robot = Robot.from_dh([1.0, 1.0], [0.0, 0.0], [0.0, 0.0])
    p = robot.fk(np.radians([30.0, 45.0]))[:3, 3]
    np.testing.assert_allclose(p, [1.1248, 1.4659, 0.0], atol=1e-4)


def test_pickles_by_urdf(panda):
    import pickle

    clone = pickle.loads(pickle.dumps(panda))
    q = panda.home
    np.testing.assert_array_equal(clone.fk(q), panda.fk(q))


@pytest.mark.parametrize("name, rebuild", [("robot_by_name_main.pkl", "_reload_robot"),
                                           ("robot_by_text_main.pkl", "_rebuild_robot")])
def test_robots_pickled_by_the_older_layout_still_load(name, rebuild):
    """Pickles made when ``drake_mh.robot`` was one module (tests/data: a bundled robot by name, a
    DH robot by its text) name ``drake_mh.robot.<rebuild>``; they load, and give the FK of the
    same robot built now."""
    import pickle
    from pathlib import Path

    data = (Path(__file__).resolve().parents[1] / "data" / name).read_bytes()
    assert b"drake_mh.robot\x94" in data and rebuild.encode() in data  # the old class path, as stored
    robot = pickle.loads(data)
    fresh = drake_mh.load_robot("planar2r") if "name" in name else \
        Robot.from_dh([0.4, 0.3], [0.0, 0.0], [0.0, 0.0], name="two_dh")
    q = np.array([0.3, -0.2])
    assert robot.name == fresh.name and robot.nq == 2
    np.testing.assert_allclose(robot.fk(q), fresh.fk(q), rtol=0, atol=1e-15)


def test_user_urdf_path(tmp_path):
    path = tmp_path / "chain.urdf"
    path.write_text(random_chain_urdf(3, seed=1))
    robot = drake_mh.load_robot(str(path))
    assert robot.nq == 3 and robot.ee_frame_name == "tip"


# --- bad input ----------------------------------------------------------------------------


def test_unknown_robot_lists_the_available_ones():
    with pytest.raises(UnknownRobot) as err:
        drake_mh.load_robot("pandaa")
    assert "panda" in str(err.value) and "planar5" in str(err.value)
    assert isinstance(err.value, LookupError)


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(InvalidURDF, match="no such file"):
        drake_mh.load_robot(tmp_path / "nope.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(InvalidURDF):
        drake_mh.load_robot(bad)


@pytest.mark.parametrize("text, match", [
    ("", "empty"),
    ("<robot name='x'><link name='a'></robot>", "malformed XML"),
    ("<sdf/>", "expected <robot>"),
    ("<robot name='x'/>", "no <link>"),
    ("<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
     "<child link='missing'/><axis xyz='0 0 1'/><limit lower='-1' upper='1'/></joint></robot>", "cannot load"),
])
def test_malformed_urdf(text, match):
    with pytest.raises(InvalidURDF, match=match):
        Robot(text)


def test_unsupported_joint_type():
    text = ("<robot name='x'><link name='a'/><link name='b'/><joint name='j' type='floating'>"
            "<parent link='a'/><child link='b'/></joint></robot>")
    with pytest.raises(UnsupportedModel, match="floating"):
        Robot(text)


def test_lower_above_upper_in_urdf():
    text = random_chain_urdf(2, seed=0).replace('lower="-2" upper="2"', 'lower="2" upper="-2"', 1)
    with pytest.raises(InvalidLimits, match="lower limit 2.0 > upper limit -2.0"):
        Robot(text)


def test_end_effector_frame_not_found_lists_frames():
    with pytest.raises(FrameNotFound) as err:
        drake_mh.load_robot("panda", ee_frame="hand")
    assert "panda_link8" in str(err.value)


def test_ambiguous_end_effector_needs_a_name():
    text = random_chain_urdf(3, seed=2, branch=True)
    with pytest.raises(InvalidArgument, match="ee_frame"):
        Robot(text)
    assert Robot(text, ee_frame="tip").ee_frame_name == "tip"


@pytest.mark.parametrize("q, match", [
    (np.zeros(6), r"shape \(7,\)"),
    (np.zeros((7, 1)), r"shape \(7,\)"),
    ([0, 0, 0, np.nan, 0, 0, 0], "NaN or inf"),
    ([0, 0, 0, 0, np.inf, 0, 0], "NaN or inf"),
    ("abc", "numeric"),
    ([[0, 0, 0], [0, 0, 0, 0]], "numeric"),  # ragged: numpy's ValueError before
    (np.zeros(7) + 1j, "real"),
])
def test_bad_configurations(panda, q, match):
    with pytest.raises(InvalidConfiguration, match=match):
        panda.fk(q)
    with pytest.raises(InvalidConfiguration, match="numeric|real|shape|NaN"):
        panda.check_Q(q)


def test_bad_batches(panda):
    with pytest.raises(InvalidConfiguration, match=r"\(N, 7\)"):
        panda.batch.fk(np.zeros((4, 6)))
    Q = np.zeros((3, 7))
    Q[1, 2] = np.nan
    with pytest.raises(InvalidConfiguration, match="NaN"):
        panda.batch.jacobian(Q)


def test_dh_columns_of_different_lengths():
    with pytest.raises(InvalidDHTable):
        Robot.from_dh([1.0, 1.0], [0.0], [0.0, 0.0])


def test_dh_lower_above_upper():
    with pytest.raises(InvalidLimits):
        Robot.from_dh([1.0], [0.0], [0.0], lower=[1.0], upper=[-1.0])


def test_within_limits_and_random_configurations(panda):
    Q = panda.random_configurations(50, rng=3)
    assert all(panda.within_limits(q) for q in Q)
    q = panda.home.copy()
    q[3] = 0.5  # joint 4 must stay negative
    assert not panda.within_limits(q)


@pytest.mark.parametrize("call, error", [
    (lambda r: r.random_configurations(2.7), "InvalidArgument"),
    (lambda r: r.random_configurations(-1), "InvalidArgument"),
    (lambda r: r.fk(r.home, frame=["a"]), "InvalidArgument"),
    (lambda r: r.fk(r.home + 1j), "InvalidConfiguration"),
    (lambda r: r.batch.fk(r.random_configurations(2, rng=0) + 1j), "InvalidConfiguration"),
    (lambda r: r.inverse_dynamics(r.home, np.full(r.nq, 1e300), np.zeros(r.nq)), "InvalidConfiguration"),
    (lambda r: drake_mh.Robot.from_dh(a="abc", alpha=[0], d=[0]), "InvalidDHTable"),
    (lambda r: drake_mh.Robot.from_dh(a=[1e200, 1e200], alpha=[0, 0], d=[0, 0]), "InvalidDHTable"),
    (lambda r: drake_mh.Robot.from_dh(a=[1], alpha=[0], d=[0], bogus=1), "InvalidArgument"),
])
def test_bad_input_gets_a_named_error(panda, call, error):
    """Reliability battery: each of these raised a numpy/Python error or returned garbage."""
    with pytest.raises(drake_mh.errors.DrakeMhError) as info:
        call(panda)
    assert type(info.value).__name__ == error


_ONE_JOINT = ('<robot name="r"><link name="world"/><link name="a"><inertial><mass value="MASS"/>'
              '<inertia ixx="IXX" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>'
              '<collision><geometry><sphere radius="0.05"/></geometry></collision></link>'
              '<link name="b"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" '
              'ixz="0" iyz="0"/></inertial></link><joint name="j0" type="fixed"><parent link="world"/>'
              '<child link="a"/></joint><joint name="j1" type="revolute"><parent link="a"/><child link="b"/>'
              '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="EFF" velocity="VEL"/></joint>EXTRA</robot>')


def _model(**values):
    text = _ONE_JOINT
    for key, value in {"MASS": "1", "IXX": "0.01", "EFF": "10", "VEL": "1", "EXTRA": "", **values}.items():
        text = text.replace(key, value)
    return text


@pytest.mark.parametrize("values, error, words", [
    ({"EFF": "-5"}, "InvalidLimits", "effort limit -5"),        # was read as 'no torque limit'
    ({"VEL": "-1"}, "InvalidLimits", "velocity limit -1"),      # Drake aborted the process
    ({"MASS": "-1"}, "InvalidURDF", "mass -1"),
    ({"EXTRA": '<joint name="loop" type="fixed"><parent link="world"/><child link="b"/></joint>'},
     "UnsupportedModel", "kinematic loop"),
])
def test_questionable_models_are_refused(values, error, words):
    with pytest.raises(drake_mh.errors.DrakeMhError, match=words) as info:
        Robot(_model(**values))
    assert type(info.value).__name__ == error


def test_unphysical_inertia_loads_with_a_warning(caplog):
    robot = Robot(_model(IXX="1.0"))                     # 1.0 > 0.01 + 0.01: triangle inequality broken
    assert robot.nq == 1 and "not physical" in caplog.text


@pytest.mark.parametrize("name", drake_mh.available_robots())
def test_fk_and_jacobian_equal_drake(name):
    """Robot.fk / jacobian run the compiled single-configuration kernel; Drake is the reference."""
    robot = drake_mh.load_robot(name)
    frames = [None, robot.link_names()[len(robot.link_names()) // 2]]
    for q in robot.random_configurations(30, rng=5):
        for frame in frames:
            np.testing.assert_allclose(robot.fk(q, frame), robot.fk_drake(q, frame), atol=1e-12, rtol=0)
            np.testing.assert_allclose(robot.jacobian(q, frame), robot.jacobian_drake(q, frame), atol=1e-12, rtol=0)
    q = robot.home
    np.testing.assert_allclose(robot.fk(list(q)), robot.fk_drake(q), atol=1e-12)         # lists take the slow path
    np.testing.assert_allclose(robot.fk(q[::-1][::-1].copy()), robot.fk(q), atol=0)
    np.testing.assert_allclose(robot.fk(np.asfortranarray(np.c_[q, q])[:, 0]), robot.fk(q), atol=0)  # strided view
    T = robot.fk(q)
    T[0, 0] = 99.0
    assert robot.fk(q)[0, 0] != 99.0                                                     # a fresh array each call
    bad = q.copy()
    bad[0] = np.nan
    with pytest.raises(InvalidConfiguration, match="NaN"):
        robot.fk(bad)
