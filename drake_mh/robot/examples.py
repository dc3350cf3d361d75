"""Real robot descriptions with meshes from the ``example-robot-data`` package (offline test data).

``example-robot-data`` (installed by the test extra) ships URDFs whose meshes are referenced as
``package://example-robot-data/robots/...``; :func:`drake_mh.load_robot` finds that package among
this Python's installed prefixes. Studies and tests use these arms as "the user's own robot".
"""

from __future__ import annotations

from pathlib import Path

from drake_mh.errors import MeshNotFound

__all__ = ["EXAMPLE_ARMS", "example_robot_data_root", "load_example_arm"]

#: name -> (path inside the package, end-effector frame)
EXAMPLE_ARMS = {
    "panda_hand": ("robots/panda_description/urdf/panda.urdf", "panda_hand_tcp"),   # fingers locked: nq 7
    "ur5": ("robots/ur_description/urdf/ur5_robot.urdf", "tool0"),
    "xarm7": ("robots/xarm_description/urdf/xarm7.urdf", "link_eef"),
    "kinova": ("robots/kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),  # continuous joints
    "z1": ("robots/z1_description/urdf/z1.urdf", "gripperMover"),
    "so100": ("robots/so_arm_description/urdf/so100.urdf", "jaw"),
}


def example_robot_data_root() -> Path | None:
    """The installed ``example-robot-data`` folder, or ``None`` when it is not installed."""
    from drake_mh.robot.packages import installed_package_dir

    folder = installed_package_dir("example-robot-data")
    return folder if folder is not None and (Path(folder) / "robots").is_dir() else None


def load_example_arm(name: str):
    """Load one of :data:`EXAMPLE_ARMS` as shipped.

    Raises:
        MeshNotFound: ``example-robot-data`` is not installed.
        KeyError: unknown name.
    """
    import drake_mh

    root = example_robot_data_root()
    if root is None:
        raise MeshNotFound("example-robot-data", ["this Python's prefixes"],
                           hint="pip install example-robot-data (in the test extra: pip install -e '.[test]')")
    rel, ee = EXAMPLE_ARMS[name]
    return drake_mh.load_robot(Path(root) / rel, ee_frame=ee)
