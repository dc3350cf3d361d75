"""The verification's retiming: robots without acceleration limits, scaling, and what a failure says."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.planning import MotionProblem, solve_motion
from drake_mh.scene import Scene, Sphere


def test_a_robot_without_acceleration_limits_is_verified_under_velocity_and_torque():
    """A DH arm declares velocity and effort, no acceleration (as URDF allows): retimed and verified
    by default, and the result says where each enforced limit came from."""
    arm = drake_mh.Robot.from_dh([0.3, 0.3, 0.2], [np.pi / 2, 0.0, 0.0], [0.2, 0.0, 0.0])
    assert not np.any(np.isfinite(arm.acceleration_limits))
    goal = arm.home + np.array([0.8, -0.5, 0.6])
    for retime in (True, "toppra", "ruckig"):
        result = solve_motion(MotionProblem(arm, Scene(arm), arm.home, goal), "straight", retime=retime)
        assert result.success and result.duration > 0, result.message
        sources = result.limits.sources("acceleration")
        assert set(sources) == ({"derived"} if result.trajectory.method == "ruckig" else {"none"}), sources
        assert result.limits.sources("velocity") == ("declared",) * 3
        assert result.limits is result.trajectory.info["enforced_limits"]


def test_scaling_reaches_the_trajectory_and_bad_factors_are_refused():
    panda = drake_mh.load_robot("panda")
    goal = panda.home + 0.6
    problem = MotionProblem(panda, Scene(panda), panda.home, goal)
    full = solve_motion(problem, "straight")
    slow = solve_motion(problem, "straight", velocity_scaling=0.3, acceleration_scaling=0.3)
    assert slow.success and slow.duration > full.duration
    assert np.allclose(slow.limits["velocity"], 0.3 * panda.velocity_limits)
    with pytest.raises(InvalidArgument, match="acceleration_scaling must be a number in"):
        solve_motion(problem, "straight", acceleration_scaling=2)


def test_a_path_that_cannot_be_retimed_says_so_briefly_and_how_to_get_it():
    """Gravity needs more than joint 2's effort limit: the certified path has no trajectory. The
    message is short, names each retimer once, says retime=False gives the path, and sends nobody
    to benchmark helpers or to options solve_motion lacks; the repr does not say 'failed after'."""
    weak = drake_mh.load_robot("panda")
    effort = weak.effort_limits.copy()
    effort[1] = 1.0  # holding the arm at home needs about 30 N·m on joint 2
    weak.effort_limits = effort
    scene = Scene(weak)
    scene.add("ball", Sphere(0.05), [0.6, 0.5, 0.1])
    goal = weak.home.copy()
    goal[0] += 0.5
    result = solve_motion(MotionProblem(weak, scene, weak.home, goal), "straight")
    assert not result.success and result.path is not None
    message = result.message
    assert message.startswith("certified path (2 waypoints), but no certified trajectory")
    assert message.count("retime=False") == 1 and "load_problem_robot" not in message and "limits=" not in message
    assert message.count("toppra:") == 1 and message.count("ruckig:") == 1 and "panda_joint2" in message
    assert len(message) < 700, len(message)
    assert "failed after" not in repr(result) and "not verified" in repr(result)
    alone = solve_motion(MotionProblem(weak, scene, weak.home, goal), "straight", retime=False)
    assert alone.success and alone.trajectory is None
