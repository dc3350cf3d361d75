"""From a model file to the text Drake parses: formats, xacro, meshes, locked joints.

:func:`drake_mh.load_robot` reads a model with :func:`read_model`, then :class:`drake_mh.Robot`
prepares it with :func:`rewrite_meshes` and :func:`lock_joints` before Drake sees it:

* **formats**: URDF (``.urdf``), SDFormat (``.sdf``), MJCF (``.xml`` whose root is
  ``<mujoco>``) and xacro (``.xacro``, evaluated in memory with the ``xacro`` package; its
  ``$(find NAME)`` uses the same package search as the meshes, see :mod:`drake_mh.robot.packages`).
* **meshes**: every mesh reference is resolved to an existing file (or a
  :class:`~drake_mh.errors.MeshNotFound` naming every place searched) and rewritten as an
  absolute ``file://`` URI; collision meshes point at their cached convex hull ``.obj`` and
  are declared convex (:mod:`drake_mh.robot.meshes`). So the text parses the same from a string.
* **arm chain**: joints that are not on the path from the root to the end-effector frame
  (gripper fingers, a second arm ...) are turned into fixed joints at their locked value —
  in the text, before Drake builds the plant, so the plant has only the chain's degrees of
  freedom and contiguous joint indices. URDF joints lock at any value (the joint origin is
  composed with the joint's motion); SDFormat and MJCF joints lock at 0 only.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidURDF, MeshConversionError, MeshNotFound, UnsupportedModel
from drake_mh.robot.packages import UriResolver

logger = logging.getLogger(__name__)

DRAKE_NS = "http://drake.mit.edu"
"""XML namespace of Drake's own model extensions (e.g. ``drake:declare_convex``)."""
DRAKE_MH_NS = "https://github.com/drake-mh/ns"
"""XML namespace of drake_mh's own URDF attributes (e.g. ``drake_mh:jerk``); Drake ignores it."""
FORMATS = ("urdf", "sdf", "mjcf")


@dataclass
class ModelText:
    """A model's text ready for :class:`drake_mh.Robot`.

    Attributes:
        text: the model (URDF, SDFormat or MJCF text; xacro already evaluated).
        format: ``"urdf"``, ``"sdf"`` or ``"mjcf"``.
        source: where it came from (file path or ``"<string>"``).
        model_dir: folder relative references resolve against (``None`` for text).
        name: model name (file stem).
    """

    text: str
    format: str
    source: str
    model_dir: Path | None
    name: str


@dataclass
class MeshReport:
    """What :func:`rewrite_meshes` did: ``{kind: [(uri, file used), ...]}`` and counts."""

    collision: list[tuple[str, str]] = field(default_factory=list)
    visual: list[tuple[str, str]] = field(default_factory=list)


# --- reading -------------------------------------------------------------------------------


def detect_format(path: Path, text: str | None = None) -> str:
    """``"urdf"``, ``"sdf"``, ``"mjcf"`` or ``"xacro"`` from the suffix (and root for ``.xml``)."""
    suffix = path.suffix.lower()
    if suffix == ".xacro":
        return "xacro"
    if suffix == ".urdf":
        return "urdf"
    if suffix == ".sdf":
        return "sdf"
    head = (text or "")[:4000]
    if re.search(r"<\s*mujoco\b", head):
        return "mjcf"
    if re.search(r"<\s*sdf\b", head):
        return "sdf"
    if re.search(r"<\s*robot\b", head):
        return "urdf"
    raise UnsupportedModel(
        f"{path}: cannot tell the model format (suffix {suffix!r}, root element not <robot>, "
        "<sdf> or <mujoco>); drake_mh reads URDF (.urdf), xacro (.xacro), SDFormat (.sdf) and "
        "MJCF (.xml with <mujoco>)")


@contextlib.contextmanager
def _xacro_find(resolver: UriResolver):
    """Make xacro's ``$(find NAME)`` use drake_mh's package search instead of ROS's index."""
    from xacro import substitution_args as sa

    def find(name: str) -> str:
        searched: list[str] = []
        folder = resolver.package_dir(name, "", searched)
        if folder is None:
            from drake_mh.errors import UnknownPackage

            raise UnknownPackage(name, f"$(find {name})", searched, resolver.source)
        resolver.found.setdefault(name, folder)
        return str(folder)

    old_func, old_dict = sa._eval_find, sa._eval_dict.get("find")
    sa._eval_find = find
    sa._eval_dict["find"] = find
    try:
        yield
    finally:
        sa._eval_find = old_func
        sa._eval_dict["find"] = old_dict


def run_xacro(path: Path, resolver: UriResolver, args: dict | None = None) -> str:
    """Evaluate a ``.xacro`` file to URDF text (in memory; includes resolve from its folder).

    Raises:
        InvalidURDF: xacro reports an error (the message says which).
    """
    try:
        import xacro
    except ImportError as exc:  # pragma: no cover - dependency
        raise InvalidURDF(str(path), "the 'xacro' package is needed for .xacro files "
                          "(pip install xacro)") from exc
    mappings = {str(k): str(v) for k, v in (args or {}).items()}
    err = io.StringIO()
    try:
        with _xacro_find(resolver), contextlib.redirect_stderr(err):
            doc = xacro.process_file(str(path), mappings=mappings)
    except MeshNotFound:
        raise
    except BaseException as exc:  # xacro raises XacroException, SystemExit, NameError ...
        if isinstance(exc, KeyboardInterrupt):
            raise
        detail = err.getvalue().strip().replace("\n", " ")
        raise InvalidURDF(str(path), f"xacro failed: {type(exc).__name__}: {exc} {detail}".strip()
                          + "; pass xacro arguments with xacro_args={'name': 'value'}") from exc
    return doc.toprettyxml(indent="  ")


def read_model(path: Path, resolver: UriResolver, xacro_args: dict | None = None) -> ModelText:
    """Read a model file of any supported format.

    Raises:
        InvalidURDF: unreadable file or xacro error.
        UnsupportedModel: unknown format.
    """
    try:
        raw = path.read_text() if path.suffix.lower() != ".xacro" else ""
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidURDF(str(path), f"cannot read the file ({exc})") from exc
    fmt = detect_format(path, raw)
    name = path.name.split(".")[0] or "robot"
    if fmt == "xacro":
        return ModelText(run_xacro(path, resolver, xacro_args), "urdf", str(path), path.parent, name)
    return ModelText(raw, fmt, str(path), path.parent, name)


# --- XML with the namespace prefixes kept ------------------------------------------------------


def parse_xml(text: str, source: str) -> ET.Element:
    """Parse ``text``, registering its namespace prefixes so that writing it back keeps them."""
    try:
        for _, (prefix, uri) in ET.iterparse(io.StringIO(text), events=("start-ns",)):
            if prefix and not re.fullmatch(r"ns\d+", prefix):
                with contextlib.suppress(ValueError):
                    ET.register_namespace(prefix, uri)
        return ET.fromstring(text)
    except ET.ParseError as exc:
        raise InvalidURDF(source, f"malformed XML ({exc})") from exc


def to_text(root: ET.Element) -> str:
    ET.register_namespace("drake", DRAKE_NS)
    return ET.tostring(root, encoding="unicode")


# --- meshes ----------------------------------------------------------------------------------


def _file_uri(path: Path) -> str:
    return "file://" + str(path)


def _declare_convex(mesh: ET.Element) -> None:
    if mesh.find(f"{{{DRAKE_NS}}}declare_convex") is None:
        ET.SubElement(mesh, f"{{{DRAKE_NS}}}declare_convex")


def rewrite_meshes(root: ET.Element, fmt: str, resolver: UriResolver,
                   report: MeshReport) -> bool:
    """Point every mesh reference of ``root`` at an existing file Drake accepts (in place).

    Returns:
        Whether anything was changed.

    Raises:
        MeshNotFound, UnknownPackage: a reference resolves nowhere.
        MeshConversionError: a collision mesh cannot be turned into a convex hull.
    """
    from drake_mh.robot.meshes import collision_hull, visual_mesh

    changed = False
    if fmt in ("urdf", "sdf"):
        for kind in ("collision", "visual"):
            for elem in root.iter(kind):
                for mesh in elem.iter("mesh"):
                    uri_elem = mesh if fmt == "urdf" else mesh.find("uri")
                    uri = (mesh.get("filename") if fmt == "urdf"
                           else (uri_elem.text if uri_elem is not None else None))
                    if not uri:
                        continue
                    path = resolver.resolve(uri)
                    if kind == "collision":
                        new = collision_hull(path)
                        _declare_convex(mesh)
                        report.collision.append((uri, str(new)))
                    else:
                        try:
                            new = visual_mesh(path)
                        except MeshConversionError as exc:  # only looks: keep the robot usable
                            logger.warning("%s: visual mesh %s not shown (%s)", resolver.source, uri,
                                           exc.reason)
                            new = path
                        report.visual.append((uri, str(new)))
                    if fmt == "urdf":
                        mesh.set("filename", _file_uri(new))
                    else:
                        uri_elem.text = _file_uri(new)
                    changed = True
        if fmt == "sdf":
            for inc in root.iter("include"):
                uri_elem = inc.find("uri")
                text = (uri_elem.text or "").strip() if uri_elem is not None else ""
                if text.startswith(("package://", "model://")):  # Drake resolves it: find the package
                    name, _, rest = text.split("://", 1)[1].partition("/")
                    folder = resolver.package_dir(name, rest, [])
                    if folder is not None:
                        resolver.found.setdefault(name, folder)
                if uri_elem is not None and uri_elem.text and "://" not in uri_elem.text:
                    path = Path(uri_elem.text.strip()).expanduser()
                    if not path.is_absolute() and resolver.model_dir is not None:
                        uri_elem.text = _file_uri(resolver.model_dir / path)
                        changed = True
    elif fmt == "mjcf":
        compiler = root.find("compiler")
        meshdir = ""
        if compiler is not None:
            meshdir = compiler.get("meshdir") or compiler.get("assetdir") or ""
        for asset in root.iter("asset"):
            for mesh in asset.iter("mesh"):
                uri = mesh.get("file")
                if not uri:
                    continue
                rel = uri if os.path.isabs(uri) else os.path.join(meshdir, uri)
                path = resolver.resolve(rel)
                new = path if path.suffix.lower() == ".obj" else visual_mesh(path)
                mesh.set("file", str(new))
                report.collision.append((uri, str(new)))
                changed = True
        if compiler is not None and changed:
            for key in ("meshdir", "assetdir"):
                compiler.attrib.pop(key, None)
    return changed


# --- locking joints ---------------------------------------------------------------------------


def _xyz_rpy(elem: ET.Element | None) -> tuple[np.ndarray, np.ndarray]:
    def vec(key):
        if elem is None or not elem.get(key):
            return np.zeros(3)
        v = np.array([float(x) for x in elem.get(key).split()], dtype=float)
        if v.shape != (3,):
            raise ValueError(f"{key}={elem.get(key)!r} needs 3 numbers")
        return v

    return vec("xyz"), vec("rpy")


def _lock_urdf_joint(joint: ET.Element, value: float, source: str) -> None:
    """Turn a URDF joint into a fixed joint at ``value`` [rad or m] (origin ∘ motion)."""
    from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
    from pydrake.common.eigen_geometry import AngleAxis

    name, jtype = joint.get("name"), joint.get("type")
    try:
        xyz, rpy = _xyz_rpy(joint.find("origin"))
        axis = np.array([float(x) for x in (joint.find("axis").get("xyz") if joint.find("axis")
                                            is not None else "1 0 0").split()])
    except (ValueError, AttributeError) as exc:
        raise InvalidURDF(source, f"joint {name!r}: bad <origin> or <axis> ({exc})") from exc
    norm = float(np.sqrt(np.sum(axis * axis)))
    if axis.shape != (3,) or norm == 0.0:
        raise InvalidURDF(source, f"joint {name!r}: <axis xyz> must be a non-zero 3-vector")
    axis = axis / norm
    X_PJ = RigidTransform(RollPitchYaw(rpy), xyz)
    if jtype in ("revolute", "continuous"):
        X_JC = RigidTransform(RotationMatrix(AngleAxis(value, axis)), np.zeros(3))
    else:
        X_JC = RigidTransform(axis * value)
    X_PC = X_PJ.multiply(X_JC)
    for child in list(joint):
        if child.tag not in ("parent", "child", "origin"):
            joint.remove(child)
    origin = joint.find("origin")
    if origin is None:
        origin = ET.SubElement(joint, "origin")
    origin.set("xyz", " ".join(repr(float(v)) for v in X_PC.translation()))
    origin.set("rpy", " ".join(repr(float(v)) for v in RollPitchYaw(X_PC.rotation()).vector()))
    joint.set("type", "fixed")


def lock_joints(root: ET.Element, fmt: str, values: dict[str, float], source: str) -> None:
    """Turn the joints ``values`` names into fixed joints at those values (in place).

    Raises:
        UnsupportedModel: SDFormat/MJCF joint locked at a value other than 0.
    """
    if fmt != "urdf":
        bad = {k: v for k, v in values.items() if v != 0.0}
        if bad:
            raise UnsupportedModel(
                f"{source}: joints {sorted(bad)} would be locked at {bad}; {fmt.upper()} joints "
                "lock at 0 only (pass locked={name: 0.0}, or convert the model to URDF)")
    if fmt == "urdf":
        for joint in root.findall("joint"):
            if joint.get("name") in values:
                _lock_urdf_joint(joint, float(values[joint.get("name")]), source)
        for trans in list(root.findall("transmission")):
            names = {j.get("name") for j in trans.iter("joint")}
            if names & set(values):
                root.remove(trans)
    elif fmt == "sdf":
        for joint in root.iter("joint"):
            if joint.get("name") in values:
                joint.set("type", "fixed")
                for child in list(joint):
                    if child.tag not in ("parent", "child", "pose"):
                        joint.remove(child)
    elif fmt == "mjcf":
        for parent in list(root.iter()):
            for child in list(parent):
                if child.tag == "joint" and child.get("name") in values and parent.tag == "body":
                    parent.remove(child)
                elif any(child.get(k) in values for k in ("joint", "joint1", "joint2")):
                    parent.remove(child)  # actuators / equality constraints on a locked joint


def dedupe_urdf_materials(root: ET.Element) -> bool:
    """Rename inline ``<material>`` definitions that reuse a name with another colour/texture.

    ROS tools accept a material name defined twice with different colours (the nearest one
    wins); Drake rejects the model. Renaming the later definition keeps both colours.

    Returns:
        Whether anything was renamed.
    """
    def definition(mat):
        color, tex = mat.find("color"), mat.find("texture")
        return ((color.get("rgba") or "").split() if color is not None else None,
                tex.get("filename") if tex is not None else None)

    seen: dict[str, tuple] = {}
    for mat in root.findall("material"):
        if mat.get("name"):
            seen.setdefault(mat.get("name"), definition(mat))
    changed = False
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            for mat in visual.findall("material"):
                name = mat.get("name")
                if not name or (mat.find("color") is None and mat.find("texture") is None):
                    continue
                d = definition(mat)
                if name not in seen:
                    seen[name] = d
                elif seen[name] != d:
                    k = 2
                    while f"{name}_{k}" in seen:
                        k += 1
                    mat.set("name", f"{name}_{k}")
                    seen[f"{name}_{k}"] = d
                    changed = True
    return changed


def urdf_mimics(root: ET.Element) -> dict[str, tuple[str, float, float]]:
    """``{joint: (master, multiplier, offset)}`` of the URDF's ``<mimic>`` elements."""
    out = {}
    for joint in root.findall("joint"):
        mimic = joint.find("mimic")
        if mimic is not None:
            out[joint.get("name")] = (mimic.get("joint"), float(mimic.get("multiplier", "1")),
                                      float(mimic.get("offset", "0")))
    return out


def strip_mimics(root: ET.Element) -> None:
    """Remove ``<mimic>`` elements (drake_mh handles mimic joints by locking them)."""
    for joint in root.findall("joint"):
        for mimic in joint.findall("mimic"):
            joint.remove(mimic)


# --- Drake -------------------------------------------------------------------------------------


class _DrakeLogCapture(logging.Filter):
    """Turns Drake's parser warnings (unsupported tags ...) into drake_mh INFO messages."""

    def filter(self, record: logging.LogRecord) -> bool:
        logger.info("drake: %s", record.getMessage())
        return False


def parse_model(text: str, model_format: str, resolver, source: str):
    """Parse ``text`` into a new plant + scene graph (not finalized): ``(builder, plant, sg)``."""
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    parser = Parser(plant)
    resolver.populate(parser.package_map())
    drake_logger = logging.getLogger("drake")
    capture = _DrakeLogCapture()
    drake_logger.addFilter(capture)
    try:
        parser.AddModels(file_contents=text, file_type={"mjcf": "xml"}.get(model_format, model_format))
    except Exception as exc:  # Drake raises RuntimeError/ValueError with a parser message
        message = " ".join(line.strip() for line in str(exc).strip().splitlines())
        raise InvalidURDF(source, message[:800]) from exc
    finally:
        drake_logger.removeFilter(capture)
    return builder, plant, scene_graph


def weld_free_bodies(plant) -> None:
    """Weld every body with no inboard joint to the world at its default pose (fixed base)."""
    from pydrake.multibody.tree import BodyIndex, JointIndex

    children = {plant.get_joint(JointIndex(i)).child_body().index() for i in range(plant.num_joints())}
    for i in range(1, plant.num_bodies()):
        body = plant.get_body(BodyIndex(i))
        if body.index() not in children:
            logger.info("welding root link %r to the world (fixed base)", body.name())
            plant.WeldFrames(plant.world_frame(), body.body_frame(), plant.GetDefaultFloatingBaseBodyPose(body))


def read_extra_limits(root: ET.Element, source: str) -> dict[str, dict[str, float]]:
    """Jerk limits (``drake_mh:jerk``) and raw ``<limit effort>`` per joint from the URDF."""
    jerk_key = f"{{{DRAKE_MH_NS}}}jerk"
    jerk, effort = {}, {}
    for joint in root.findall("joint"):
        limit = joint.find("limit")
        if limit is None:
            continue
        try:
            if limit.get(jerk_key) is not None:
                jerk[joint.get("name")] = float(limit.get(jerk_key))
            if limit.get("effort") is not None and float(limit.get("effort")) > 0:
                effort[joint.get("name")] = float(limit.get("effort"))
        except ValueError as exc:
            raise InvalidURDF(source, f"joint {joint.get('name')!r}: non-numeric limit ({exc})") from exc
    return {"jerk": jerk, "effort": effort}
