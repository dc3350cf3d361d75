"""Random robot models for property tests (URDF chains with arbitrary axes, DH tables)."""

from __future__ import annotations

import numpy as np


def random_chain_urdf(n: int, seed: int, prismatic_every: int = 0, branch: bool = False) -> str:
    """A URDF serial chain (optionally with a side branch) with random joint origins and axes.

    Args:
        n: number of moving joints on the main chain.
        seed: random seed.
        prismatic_every: make every k-th joint prismatic (0: none).
        branch: add a two-joint side branch on link 1 (the tip stays the end of the main chain,
            so the model has two leaves and needs ``ee_frame="tip"``).
    """
    rng = np.random.default_rng(seed)
    inertial = ('<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
                'ixy="0" ixz="0" iyz="0"/></inertial>')
    collision = '<collision><geometry><capsule radius="0.03" length="0.2"/></geometry></collision>'
    parts = ['<?xml version="1.0"?>', '<robot name="chain">', '<link name="base"/>']

    def joint(name, parent, child, kind):
        xyz = rng.uniform(-0.3, 0.3, 3)
        rpy = rng.uniform(-np.pi, np.pi, 3)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        return (f'<link name="{child}">{inertial}{collision}</link>'
                f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
                f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/>'
                f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
                f'<limit lower="-2" upper="2" velocity="1" effort="5"/></joint>')

    parent = "base"
    for i in range(n):
        kind = "prismatic" if prismatic_every and i % prismatic_every == prismatic_every - 1 else "revolute"
        parts.append(joint(f"j{i}", parent, f"l{i}", kind))
        parent = f"l{i}"
    if branch and n > 1:
        parts.append(joint("b0", "l1", "b0_link", "revolute"))
        parts.append(joint("b1", "b0_link", "b1_link", "revolute"))
    parts.append(f'<link name="tip"/><joint name="tip_weld" type="fixed"><parent link="{parent}"/>'
                 '<child link="tip"/><origin xyz="0.1 0.05 0.2" rpy="0.3 0.2 0.1"/></joint>')
    parts.append("</robot>")
    return "\n".join(parts)
