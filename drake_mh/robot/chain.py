"""The kinematic tree of a parsed (not yet finalized) plant: tips, the arm chain, locked joints.

drake_mh plans for one serial chain, from the root to the end-effector frame. Every other
movable joint (gripper fingers, a second arm, a pan-tilt head ...) is *locked*: turned into a
fixed joint at a value (default 0 clipped into its limits, or ``locked={"joint": value}``) so
it is not part of ``q``. Mimic joints (URDF ``<mimic>``) off the chain lock at
``multiplier · value(master) + offset``; a mimic joint on the chain is rejected.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import FrameNotFound, InvalidArgument, UnsupportedModel

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class JointInfo:
    """One joint of the tree: name, Drake type name, parent/child body indices, limits."""

    name: str
    type: str
    parent: int
    child: int
    num_positions: int
    lower: float
    upper: float


@dataclass
class Tree:
    """Joints, body names and ``{frame name: body index}`` read from a plant before Finalize."""

    joints: list[JointInfo]
    bodies: dict[int, str]
    frames: dict[str, int]

    def inboard(self) -> dict[int, JointInfo]:
        return {j.child: j for j in self.joints}

    def path_joints(self, body: int) -> list[JointInfo]:
        """Joints from the root to ``body`` (root first)."""
        inboard, out, seen = self.inboard(), [], set()
        while body in inboard and body not in seen:
            seen.add(body)
            out.append(inboard[body])
            body = inboard[body].parent
        return out[::-1]


def read_tree(plant) -> Tree:
    """Read the tree of ``plant`` (works before ``Finalize``)."""
    from pydrake.multibody.tree import BodyIndex, FrameIndex, JointIndex

    joints = []
    for i in range(plant.num_joints()):
        j = plant.get_joint(JointIndex(i))
        n = j.num_positions()
        lo = float(j.position_lower_limits()[0]) if n == 1 else -np.inf
        hi = float(j.position_upper_limits()[0]) if n == 1 else np.inf
        joints.append(JointInfo(j.name(), j.type_name(), int(j.parent_body().index()),
                                int(j.child_body().index()), n, lo, hi))
    bodies = {i: plant.get_body(BodyIndex(i)).name() for i in range(plant.num_bodies())}
    frames = {}
    for i in range(plant.num_frames()):
        f = plant.get_frame(FrameIndex(i))
        frames.setdefault(f.name(), int(f.body().index()))
    return Tree(joints, bodies, frames)


def tip_links(tree: Tree) -> list[str]:
    """Leaf links that move (a leaf welded to the base, such as UR's ``base``, is no tip)."""
    parents = {j.parent for j in tree.joints}
    tips = []
    for index, name in tree.bodies.items():
        if index == 0 or index in parents:
            continue
        if any(j.num_positions > 0 for j in tree.path_joints(index)):
            tips.append(name)
    return tips


def default_ee(tree: Tree, source: str) -> str:
    """The unique moving tip link, or an error listing the candidates.

    Raises:
        InvalidArgument: zero or several tips (the message lists them and says pass ee_frame=).
    """
    tips = tip_links(tree)
    if len(tips) == 1:
        return tips[0]
    if not tips:  # no movable joint at all: let the caller report "no movable joint"
        leaves = [n for i, n in tree.bodies.items() if i and i not in {j.parent for j in tree.joints}]
        if len(leaves) == 1:
            return leaves[0]
    raise InvalidArgument(
        f"{source}: cannot choose the end effector, the model has {len(tips)} tip links "
        f"({', '.join(tips) or 'none'}); pass ee_frame=<one of them> (shell: --ee-frame NAME); "
        "joints that are not on the way to it are locked")


def plan_locks(tree: Tree, ee_frame: str, locked: dict | None,
               mimics: dict[str, tuple[str, float, float]], source: str) -> dict[str, float]:
    """Values of every joint to lock: off the root → ``ee_frame`` chain, or named in ``locked``.

    Args:
        tree: the model's tree.
        ee_frame: end-effector frame name.
        locked: ``{joint: value}`` given by the user (locks chain joints too).
        mimics: ``{joint: (master, multiplier, offset)}``.
        source: model name for messages.

    Returns:
        ``{joint: value}`` [rad or m].

    Raises:
        FrameNotFound: ``ee_frame`` or a ``locked`` name does not exist.
        InvalidArgument: a locked value is not finite or outside the joint's limits.
        UnsupportedModel: a mimic joint on the chain.
    """
    if ee_frame not in tree.frames:
        raise FrameNotFound(ee_frame, tree.frames)
    movable = {j.name: j for j in tree.joints if j.num_positions > 0}
    locked = dict(locked or {})
    for name, value in locked.items():
        if name not in movable:
            raise FrameNotFound(name, movable, what="movable joint")
        try:
            value = float(value)
        except (TypeError, ValueError) as exc:
            raise InvalidArgument(f"locked[{name!r}] must be a number, got {value!r}") from exc
        j = movable[name]
        if not np.isfinite(value) or not (j.lower - 1e-12 <= value <= j.upper + 1e-12):
            raise InvalidArgument(
                f"locked[{name!r}] = {value} is outside the joint's limits [{j.lower}, {j.upper}]")
        locked[name] = value
    chain = {j.name for j in tree.path_joints(tree.frames[ee_frame]) if j.num_positions > 0}
    for name in sorted(chain - set(locked)):
        if name in mimics:
            master = mimics[name][0]
            raise UnsupportedModel(
                f"{source}: joint {name!r} on the chain to {ee_frame!r} mimics {master!r}; drake_mh "
                "plans with independent joints only: lock it with locked={" + repr(name)
                + ": value}, choose another ee_frame, or remove the <mimic> element")
    values: dict[str, float] = {}
    for name, j in movable.items():
        if name in locked:
            values[name] = locked[name]
        elif name not in chain:
            if j.num_positions != 1:
                raise UnsupportedModel(
                    f"{source}: joint {name!r} ({j.type}) is off the chain to {ee_frame!r} and has "
                    f"{j.num_positions} positions; only 1-DOF joints can be locked")
            values[name] = float(np.clip(0.0, j.lower, j.upper))
    for name, (master, mult, offset) in mimics.items():
        if name in values and name not in locked and master in values:
            values[name] = float(np.clip(mult * values[master] + offset, movable[name].lower,
                                         movable[name].upper))
        elif name in values and name not in locked and master in chain and master not in locked:
            raise UnsupportedModel(
                f"{source}: joint {name!r} (off the chain) mimics {master!r} (on the chain); "
                f"pass locked={{{name!r}: value}} to fix it at a value")
    if values:
        logger.info("%s: locked joints %s (not on the chain to %r)", source, values, ee_frame)
    return values
