"""Small robots for the sphere-model and scene tests: convex .obj mesh links (written with
trimesh), primitive links Drake reads from URDF (cylinder, box, ellipsoid), and no geometry."""

from __future__ import annotations

from pathlib import Path

_INERTIA = ('<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" '
            'iyz="0"/></inertial>')


def _chain(name: str, links: dict[str, str]) -> str:
    """A serial arm: one revolute joint per link (z first, then y), links 0.3 m apart."""
    body, joints, parent = ['<link name="base"/>'], [], "base"
    for i, (link, collision) in enumerate(links.items()):
        body.append(f'<link name="{link}">{_INERTIA}{collision}</link>')
        axis, z = ("0 0 1", 0.05) if i == 0 else ("0 1 0", 0.3)
        joints.append(f'<joint name="j{i + 1}" type="revolute"><parent link="{parent}"/><child link="{link}"/>'
                      f'<origin xyz="0 0 {z}"/><axis xyz="{axis}"/>'
                      '<limit lower="-2.5" upper="2.5" effort="10" velocity="2"/></joint>')
        parent = link
    return (f'<robot name="{name}" xmlns:drake="http://drake.mit.edu">' + "".join(body) + "".join(joints)
            + "</robot>")


def mesh_arm_urdf(folder: Path) -> str:
    """3-DOF arm whose links are convex .obj meshes: a 20-gon prism, a box, a stretched icosphere.

    The meshes are referenced by absolute ``file://`` URI, so the text loads with
    ``drake_mh.Robot(urdf)``; Drake uses a mesh's convex hull for distances.
    """
    import trimesh

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    meshes = {"l1": trimesh.creation.cylinder(radius=0.05, height=0.3, sections=20),
              "l2": trimesh.creation.box((0.08, 0.06, 0.3)),
              "l3": trimesh.creation.icosphere(subdivisions=2, radius=0.04)}
    meshes["l3"].apply_scale([1.0, 1.0, 2.0])
    links = {}
    for link, mesh in meshes.items():
        path = folder / f"{link}.obj"
        mesh.export(path)
        links[link] = (f'<collision><origin xyz="0 0 0.15" rpy="0.1 0 0"/><geometry>'
                       f'<mesh filename="file://{path}"/></geometry></collision>')
    return _chain("mesh_arm", links)


def primitive_arm_urdf() -> str:
    """3-DOF arm with a cylinder, a box and an ellipsoid link."""
    return _chain("primitive_arm", {
        "cyl": '<collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.05" length="0.3"/></geometry></collision>',
        "box": '<collision><origin xyz="0 0 0.15"/><geometry><box size="0.08 0.06 0.3"/></geometry></collision>',
        "ell": ('<collision><origin xyz="0 0 0.1"/><geometry><drake:ellipsoid a="0.04" b="0.05" c="0.1"/>'
                '</geometry></collision>'),
    })


def no_geometry_urdf() -> str:
    """2-DOF arm without any collision element."""
    return _chain("bare_arm", {"a": "", "b": ""})
