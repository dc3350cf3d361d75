"""IK peers a user would pick instead, as optional adapters: robotics-toolbox-python (``rtb_ik_LM``,
``rtb_ik_GN``), TRAC-IK (``trac_ik``, through the ``pytracik`` wheel) and ikpy (``ikpy``).

Each peer gets the robot's own URDF text (:attr:`~drake_mh.robot.Robot.model_text`), adapted
in memory to what its parser takes (:func:`stripped_urdf`: rtb's and KDL's parsers reject
``<capsule>``, and KDL needs every parent link declared; ikpy gets the chain from the root to
the end effector only), and its forward kinematics is checked against Drake's before use
(:func:`check_fk`: 1e-9 at a random configuration). The peers come with the optional extra
``peers``; none is imported until used, and one that is not installed is reported by
:func:`peer_available` / :func:`peer_problem`, not raised at import. :func:`solve_peer` solves
one target; the answers are not verified here (:func:`drake_mh.ik.verify` does it for every
method alike). ``studies/ik_peers.py`` compares them with drake_mh's methods.

Peers' settings (what each one's call gets): rtb's tolerance is its residual ``E = ½ eᵀe``
(``e = [Δp; ω]``): ``E < ½ tol²`` implies ``|Δp| <= tol`` and ``θ <= tol``; TRAC-IK runs in
``Speed`` mode (KDL's Newton and an NLopt SQP in two threads), its joint limits set from
Drake's (``pytracik`` 0.0.3 reads URDF limits as 32-bit floats); ikpy's active joints are
bounded by Drake's limits and it runs ``inverse_kinematics_frame(orientation_mode="all")``
once.
"""

from __future__ import annotations

import os
import tempfile
import weakref
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from drake_mh.errors import UnknownMethod, UnsupportedModel

__all__ = ["PEERS", "PEER_MODULE", "peer_available", "peer_problem", "solve_peer", "rtb_robot", "tracik_solver",
           "ikpy_chain", "stripped_urdf", "chain_joints", "check_fk"]

PEERS = ("rtb_ik_LM", "rtb_ik_GN", "trac_ik", "ikpy")
"""The peers' labels."""
PEER_MODULE = {"rtb_ik_LM": "roboticstoolbox", "rtb_ik_GN": "roboticstoolbox", "trac_ik": "pytracik", "ikpy": "ikpy"}
"""The module each peer needs (optional extra ``peers``)."""

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Each robot's peer models, built once (weakly: a dropped robot drops them)."""


def peer_available(label: str) -> bool:
    """Whether the library of peer ``label`` is installed (not imported here)."""
    import importlib.util

    return importlib.util.find_spec(PEER_MODULE[label]) is not None


def stripped_urdf(robot) -> ET.Element:
    """``robot``'s URDF as an element tree, collision/visual removed and every parent link declared.

    rtb's and KDL's parsers reject ``<capsule>``, and KDL needs ``<link name="world"/>`` declared
    when a joint refers to it; neither needs the geometry for kinematics.
    """
    root = ET.fromstring(robot.model_text)
    for link in root.findall("link"):
        for tag in ("collision", "visual"):
            for element in link.findall(tag):
                link.remove(element)
    declared = {link.get("name") for link in root.findall("link")}
    referred = {j.find("parent").get("link") for j in root.findall("joint")}
    for name in sorted(referred - declared):  # e.g. <joint><parent link="world"/> with no <link name="world"/>
        root.insert(0, ET.Element("link", {"name": name}))
    return root


def chain_joints(root: ET.Element, tip: str) -> list[ET.Element]:
    """The joints from the URDF's root link to link ``tip``, root first."""
    by_child = {j.find("child").get("link"): j for j in root.findall("joint")}
    joints, link = [], tip
    while link in by_child:
        joints.append(by_child[link])
        link = by_child[link].find("parent").get("link")
    return joints[::-1]


def check_fk(robot, label: str, fk) -> None:
    """Raises UnsupportedModel when the peer's FK differs from Drake's by > 1e-9 at a random configuration."""
    q = robot.random_configurations(1, 0)[0]
    gap = float(np.abs(np.asarray(fk(q)) - robot.fk(q)).max())
    if not gap <= 1e-9:
        raise UnsupportedModel(f"{label}'s FK of {robot.name} differs from Drake's by {gap:.2e}")


def rtb_robot(robot):
    """robotics-toolbox-python's model of ``robot`` (same URDF text, collision/visual stripped).

    Raises:
        UnsupportedModel: its FK differs from Drake's by more than 1e-9 at a random configuration.
    """
    cache = _CACHE.setdefault(robot, {})
    if "rtb" in cache:
        return cache["rtb"]
    import roboticstoolbox as rtb
    from roboticstoolbox.models.URDF.URDFRobot import URDF_read

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "robot.urdf")
        Path(path).write_text(ET.tostring(stripped_urdf(robot), encoding="unicode"))
        links, name = URDF_read(path)[:2]
    model = rtb.Robot(links, name=name)
    check_fk(robot, "robotics-toolbox", lambda q: model.fkine(q, end=robot.ee_frame_name).A)
    cache["rtb"] = model
    return model


def _peer_chain(robot, peer: str):
    """The stripped URDF of ``robot`` and its joints from the root to the end effector.

    Raises:
        UnsupportedModel: no joint leads to the end effector.
    """
    root = stripped_urdf(robot)
    joints = chain_joints(root, robot.ee_frame_name)
    if not joints:
        raise UnsupportedModel(f"{peer}: no joint leads to {robot.ee_frame_name!r} in {robot.name}'s URDF")
    return root, joints


def tracik_solver(robot, timeout: float = 0.005, tolerance: float = 1e-5):
    """A ``pytracik.TRAC_IK`` solver for ``robot``: Speed mode, ``timeout`` [s], and ``eps =
    tolerance / sqrt(3)`` (TRAC-IK bounds each of the six error components: a success then meets
    ``|Δp| <= tolerance`` [m] and ``θ <= tolerance`` [rad]).

    Its joint limits are set from Drake's (the wheel reads the URDF's as 32-bit floats, which can
    lie outside Drake's by ~1e-8 rad and fail our check at a limit).

    Raises:
        UnsupportedModel: KDL did not find the chain, or its FK differs from Drake's.
    """
    cache = _CACHE.setdefault(robot, {})
    key = ("trac_ik", float(timeout), float(tolerance))
    if key in cache:
        return cache[key]
    import pytracik

    root, joints = _peer_chain(robot, "TRAC-IK")
    base = joints[0].find("parent").get("link")
    if any(link.get("name") == base and link.find("inertial") is not None for link in root.findall("link")):
        # KDL ignores a root link's inertia with a warning on stdout: give it a massless parent
        root.insert(0, ET.Element("link", {"name": "ik_peers_root"}))
        joint = ET.SubElement(root, "joint", {"name": "ik_peers_root_weld", "type": "fixed"})
        ET.SubElement(joint, "parent", {"link": "ik_peers_root"})
        ET.SubElement(joint, "child", {"link": base})
        base = "ik_peers_root"
    solver = pytracik.TRAC_IK(base, robot.ee_frame_name, ET.tostring(root, encoding="unicode"),
                              float(timeout), tolerance / np.sqrt(3), pytracik.SolveType.Speed)
    if pytracik.get_num_joints(solver) != robot.nq:
        raise UnsupportedModel(f"TRAC-IK's chain of {robot.name} has {pytracik.get_num_joints(solver)} joints, "
                               f"Drake's {robot.nq}")
    pytracik.set_joint_limits(solver, [float(x) for x in robot.lower], [float(x) for x in robot.upper])
    check_fk(robot, "TRAC-IK", lambda q: pytracik.fk(solver, q))
    cache[key] = solver
    return solver


def ikpy_chain(robot):
    """ikpy's chain of ``robot``: the URDF's joints from its root to the end effector only.

    Fixed joints are inactive; the active joints' bounds are Drake's limits (ikpy leaves a
    continuous joint unbounded).

    Raises:
        UnsupportedModel: its active joints are not Drake's, or its FK differs from Drake's.
    """
    cache = _CACHE.setdefault(robot, {})
    if "ikpy" in cache:
        return cache["ikpy"]
    import warnings

    import ikpy.chain

    root, joints = _peer_chain(robot, "ikpy")
    keep = {joints[0].find("parent").get("link")} | {j.find("child").get("link") for j in joints}
    for element in list(root):
        if (element.tag == "link" and element.get("name") not in keep) or (element.tag == "joint"
                                                                           and element not in joints):
            root.remove(element)
    with tempfile.TemporaryDirectory() as folder, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "fixed link set as active" before the mask below is given
        path = os.path.join(folder, "robot.urdf")
        Path(path).write_text(ET.tostring(root, encoding="unicode"))
        chain = ikpy.chain.Chain.from_urdf_file(path, base_elements=[joints[0].find("parent").get("link")],
                                                symbolic=False)
        mask = [False] + [link.joint_type != "fixed" for link in chain.links[1:]]
        chain = ikpy.chain.Chain(chain.links, active_links_mask=mask, name=robot.name)
    if sum(mask) != robot.nq:
        raise UnsupportedModel(f"ikpy's chain of {robot.name} has {sum(mask)} active joints, Drake's {robot.nq}")
    active = [link for link, on in zip(chain.links, mask) if on]
    for link, lo, hi in zip(active, robot.lower, robot.upper):
        link.bounds = (float(lo), float(hi))
    check_fk(robot, "ikpy", lambda q: chain.forward_kinematics(chain.active_to_full(q, np.zeros(len(mask)))))
    cache["ikpy"] = chain
    return chain


def peer_problem(robot, label: str) -> str | None:
    """Why peer ``label`` cannot run on ``robot`` (not installed, model rejected); ``None`` if it can.

    TRAC-IK's and ikpy's models are built here (milliseconds) so that a peer that cannot model a
    robot can be left out before any solve, and said so; rtb's model is built on its first solve
    (importing it takes seconds).
    """
    if not peer_available(label):
        return f"{PEER_MODULE[label]} is not installed"
    if label not in ("trac_ik", "ikpy"):
        return None
    try:
        (tracik_solver if label == "trac_ik" else ikpy_chain)(robot)
    except Exception as exc:  # noqa: BLE001 - any failure of the peer's parser means: left out, said so
        return f"{type(exc).__name__}: {str(exc)[:200]}"
    return None


def _quaternion(R: np.ndarray) -> np.ndarray:
    """``(w, x, y, z)`` of the rotation matrix ``R`` (Drake's conversion)."""
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RotationMatrix

    quat: Quaternion = RotationMatrix(R).ToQuaternion()
    return np.array([quat.w(), quat.x(), quat.y(), quat.z()])


def solve_peer(robot, label: str, X_WT: np.ndarray, seed: int, tolerance: float = 1e-5,
               timeout: float = 0.005) -> tuple[np.ndarray, bool | None]:
    """Solves the full-pose IK of ``X_WT (4, 4)`` on ``robot`` with peer ``label`` (:data:`PEERS`).

    Args:
        robot: the :class:`~drake_mh.robot.Robot`.
        label: ``"rtb_ik_LM"``, ``"rtb_ik_GN"`` (robotics-toolbox-python: random restarts, joint
            limits by rejection, residual ``E = ½ eᵀe < ½ tolerance²``), ``"trac_ik"`` (Speed
            mode, ``timeout``, seeded at :attr:`~drake_mh.robot.Robot.home`) or ``"ikpy"`` (one
            least-squares run from ``home``, no restarts, no timeout).
        X_WT: target pose of the end effector in the world.
        seed: seed of rtb's restarts (numpy's global generator, which it uses).
        tolerance: [m] and [rad].
        timeout: [s], TRAC-IK's.

    Returns:
        ``(q (nq,), the peer's own success flag)``; ikpy has no flag (``None``). The answer is
        not verified here: check it with :func:`drake_mh.ik.verify`, as for every method.

    Raises:
        UnsupportedModel: the peer's model of ``robot`` differs from Drake's.
        ImportError: the peer is not installed (:func:`peer_available`).
    """
    if label == "trac_ik":
        import pytracik

        w, x, y, z = _quaternion(X_WT[:3, :3])
        p = X_WT[:3, 3]
        out = pytracik.ik(tracik_solver(robot, timeout, tolerance), robot.home, p[0], p[1], p[2], x, y, z, w)
        return (out[1:] if out[0] >= 0 else robot.home.copy()), bool(out[0] >= 0)  # else out[1:] unset
    if label == "ikpy":
        chain = ikpy_chain(robot)
        start = chain.active_to_full(robot.home, np.zeros(len(chain.links)))
        full = chain.inverse_kinematics_frame(X_WT, initial_position=start, orientation_mode="all")
        return np.asarray(chain.active_from_full(full), dtype=float), None  # ikpy has no flag
    if label not in ("rtb_ik_LM", "rtb_ik_GN"):
        raise UnknownMethod(label, PEERS, what="IK peer")
    model = rtb_robot(robot)
    np.random.seed(seed % 2**32)  # rtb's restarts
    solver = model.ik_LM if label == "rtb_ik_LM" else model.ik_GN
    solution = solver(X_WT, end=robot.ee_frame_name, tol=0.5 * tolerance**2, joint_limits=True)
    return np.asarray(solution.q, dtype=float), bool(solution.success)
