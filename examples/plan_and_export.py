"""From a robot as shipped to a trajectory a controller can run.

Loads example-robot-data's Franka Panda with its hand exactly as shipped (its URDF declares
position, velocity and effort limits, no acceleration: URDF has no field for it), builds a small
cell of boxes, a cylinder and a sphere, plans a motion around them with ``solve_motion``'s
defaults (planned, certified collision-free, retimed under the velocity and torque limits,
certified), prints where every enforced limit came from, and writes

* ``motion.json``: the trajectory sampled at ``--rate`` in the shape of ROS 2
  ``trajectory_msgs/JointTrajectory`` (positions, velocities, accelerations, effort,
  ``time_from_start``), checked against the certified limits before writing;
* ``motion.html``: the animation with its certified clearance (opens offline).

Run::

    python examples/plan_and_export.py                  # writes into ./plan_and_export/
    python examples/plan_and_export.py --out /tmp/cell --rate 250

Needs ``example-robot-data`` (``pip install example-robot-data``; in the test extra).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import drake_mh
from drake_mh.robot.examples import example_robot_data_root
from drake_mh.planning import MotionProblem, solve_motion

CELL = (
    # (name, kind, size [m], centre in the world [m]); box size: side lengths, cylinder: (radius, length)
    ("table", "box", (0.9, 1.4, 0.04), (0.55, 0.2, -0.03)),
    ("back_wall", "box", (0.04, 1.4, 0.8), (-0.35, 0.2, 0.4)),
    ("post", "cylinder", (0.04, 0.5), (0.45, 0.32, 0.25)),
    ("ball", "sphere", 0.07, (0.42, 0.28, 0.55)),
)
"""The cell: a table under the arm, a wall behind it, a post and a ball between start and goal."""

START = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
"""MotionBenchMaker's ready configuration of the Panda [rad]."""
GOAL = np.array([1.3, 0.35, 0.0, -1.7, 0.0, 2.05, 0.785])
"""A configuration with the hand low on the left [rad]; the straight joint-space line to it
passes through the post and the ball."""


def load_panda():
    """example-robot-data's Panda with its hand, as shipped (fingers locked, not on the chain)."""
    root = example_robot_data_root()
    if root is None:
        sys.exit("example-robot-data is not installed: pip install example-robot-data")
    return drake_mh.load_robot(Path(root) / "robots/panda_description/urdf/panda.urdf", ee_frame="panda_hand_tcp")


def build_scene(robot) -> drake_mh.Scene:
    """The :data:`CELL` as a scene."""
    scene = drake_mh.Scene(robot)
    shapes = {"box": lambda s: drake_mh.Box(s), "sphere": lambda s: drake_mh.Sphere(s),
              "cylinder": lambda s: drake_mh.Cylinder(*s)}
    for name, kind, size, centre in CELL:
        scene.add(name, shapes[kind](size), list(centre))
    return scene


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="plan_and_export", help="folder for motion.json and motion.html")
    parser.add_argument("--rate", type=float, default=100.0, help="samples per second in motion.json [Hz]")
    parser.add_argument("--quick", action="store_true", help="accepted for CI; the example is already quick")
    args = parser.parse_args(argv)

    robot = load_panda()
    scene = build_scene(robot)
    problem = MotionProblem(robot, scene, START, GOAL, name="plan_and_export")
    print(f"straight joint-space line free: {scene.segment_free(START, GOAL)}")

    result = solve_motion(problem)  # defaults: rrt_connect, verified, retimed (toppra), certified
    print(result)
    if not result.success:
        return 1
    print("limits enforced (value per joint | where it came from):")
    for line in result.limits.summary():
        print(f"  {line}")

    out = Path(args.out)
    samples = result.trajectory.save(out / "motion.json", robot, rate_hz=args.rate)
    print(f"{out / 'motion.json'}: {len(samples)} samples at {args.rate:g} Hz, {samples.t[-1]:.3f} s, "
          f"joints {', '.join(samples.joint_names)}")

    from drake_mh.viz import motion_html

    (out / "motion.html").write_text(motion_html(problem, result), encoding="utf-8")
    print(f"{out / 'motion.html'}: the animation with its certified clearance")
    return 0


if __name__ == "__main__":
    sys.exit(main())
