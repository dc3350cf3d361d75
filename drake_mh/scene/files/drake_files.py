"""SDFormat worlds, URDFs of static bodies and Drake model directives, parsed by Drake.

Drake parses the file into a scratch ``MultibodyPlant`` + ``SceneGraph``
(``Parser.AddModels``; for ``.dmd.yaml`` ``LoadModelDirectives`` + ``ProcessModelDirectives``),
the plant is finalized, and every geometry with a proximity (collision) role becomes an
obstacle at its world pose in the plant's default context, named as Drake names it
(``model::collision``; a repeated name gets ``_2``, ``_3`` ...). Visual geometry is ignored.

* ``Sphere``, ``Box``, ``Cylinder``, ``Capsule``: the same primitive.
* ``Mesh`` and ``Convex``: a :class:`drake_mh.geometry.Mesh` of the *file the model names*
  with the geometry's scale (not Drake's convex hull of it: a non-convex bin stays a bin).
  In URDF and SDFormat files every collision mesh reference is resolved by drake_mh first
  (``package://`` and ``model://`` through :class:`drake_mh.robot.packages.UriResolver`, with
  ``packages=``; relative paths from the file's folder), and Drake is shown the mesh's cached
  convex hull, so formats Drake's proximity engine does not read (``.stl``, ``.dae`` ...) work.
  Model directives name other model files, which Drake reads itself: their packages are found
  the same way, but their meshes must be ones Drake reads (``.obj``, ``.vtk``, ``.gltf``).
* ``HalfSpace`` (an SDFormat ``<plane>``): a box of :data:`HALFSPACE_SIDE` x
  :data:`HALFSPACE_SIDE` x :data:`HALFSPACE_DEPTH` m whose top face lies on the plane, centred
  below the world origin's projection onto it: the same obstacle as the half space within
  :data:`HALFSPACE_DEPTH` m of that point (far beyond any arm's reach).
* ``Ellipsoid``: refused (no obstacle shape; use a mesh).

**Bodies that can move.** A scene file describes a static cell. A body with collision
geometry that is not welded to the world (a free body, or one behind a joint with degrees of
freedom) raises :class:`~drake_mh.errors.SceneFileError` naming the bodies, unless
``movable="default_pose"``: then each is taken where the file puts it by default (a free
body's pose, a joint's default position), as a fixed obstacle.
"""

from __future__ import annotations

import contextlib
import logging
import re
from pathlib import Path

import numpy as np

from drake_mh.errors import DrakeMhError, InvalidArgument, SceneFileError
from drake_mh.scene.files.common import SceneFile, SceneFileBuilder, read_text

__all__ = ["read_drake_file", "MOVABLE", "HALFSPACE_SIDE", "HALFSPACE_DEPTH"]

logger = logging.getLogger(__name__)

MOVABLE = ("error", "default_pose")
"""What to do with bodies that can move: refuse the file, or take their default pose."""
HALFSPACE_SIDE = 20.0
"""[m] side of the box a half space becomes."""
HALFSPACE_DEPTH = 10.0
"""[m] depth of the box a half space becomes (below the plane)."""

_PACKAGE_URI = re.compile(r"(?:package|model)://([^/\s\"'<>]+)/([^\s\"'<>]*)")


class _DrakeLog(logging.Filter):
    """Drake's parser warnings (unsupported tags, half spaces in deformable contact ...) as
    drake_mh INFO messages."""

    def filter(self, record: logging.LogRecord) -> bool:
        logger.info("drake: %s", record.getMessage())
        return False


@contextlib.contextmanager
def _drake_log():
    drake_logger = logging.getLogger("drake")
    capture = _DrakeLog()
    drake_logger.addFilter(capture)
    try:
        yield
    finally:
        drake_logger.removeFilter(capture)


def _drake_message(exc: BaseException) -> str:
    return " ".join(line.strip() for line in str(exc).strip().splitlines())[:800] or type(exc).__name__


def read_drake_file(path: Path, fmt: str, packages=None, movable: str = "error") -> SceneFile:
    """The obstacles of an SDFormat (``fmt="sdformat"``), URDF (``"urdf"``) or model directives
    (``"directives"``) file (module docstring).

    Raises:
        SceneFileError: Drake cannot parse the file, a mesh or package cannot be found, a body
            with collision geometry can move (with ``movable="error"``), or an ellipsoid.
        InvalidArgument: ``movable`` not in :data:`MOVABLE`.
    """
    if movable not in MOVABLE:
        raise InvalidArgument(f"movable must be one of {MOVABLE}, got {movable!r}")
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    from drake_mh.robot.packages import UriResolver

    b = SceneFileBuilder(path, fmt)
    resolver = UriResolver(Path(path).resolve().parent, packages, source=str(path))
    hulls: dict[str, Path] = {}
    with _drake_log():
        if fmt == "directives":
            builder = DiagramBuilder()
            plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
            _directives(b, Path(path), plant, resolver)
        else:
            plant, scene_graph = _xml_model(b, Path(path), "urdf" if fmt == "urdf" else "sdf", resolver, hulls)
        try:
            plant.Finalize()
        except Exception as exc:  # Drake's RuntimeError
            raise b.error(f"Drake cannot finalize the model ({_drake_message(exc)})") from exc
    _collect(b, plant, scene_graph, hulls, movable)
    return b.result(Path(path).name.split(".")[0])


def _xml_model(b: SceneFileBuilder, path: Path, fmt: str, resolver, hulls: dict):
    """Parse a URDF or SDFormat file, its collision meshes resolved by drake_mh and shown to
    Drake as their convex hulls (``hulls``: hull file -> the model's own file)."""
    from drake_mh.errors import InvalidURDF, MeshConversionError, MeshNotFound
    from drake_mh.robot.loading import MeshReport, parse_model, parse_xml, rewrite_meshes, to_text

    try:
        root = parse_xml(read_text(path), str(path))
    except InvalidURDF as exc:
        raise b.error(exc.reason) from exc
    for parent in list(root.iter()):  # obstacles need no looks: no visual mesh is read
        for child in list(parent):
            if child.tag == "visual":
                parent.remove(child)
    report = MeshReport()
    try:
        rewrite_meshes(root, fmt, resolver, report)
    except MeshNotFound as exc:
        raise b.error(str(exc), f"mesh {exc.uri!r}") from exc
    except MeshConversionError as exc:
        raise b.error(str(exc), f"mesh {exc.path}") from exc
    for uri, hull in report.collision:
        hulls[str(hull)] = resolver.resolve(uri)
    try:
        _, plant, scene_graph = parse_model(to_text(root), fmt, resolver, str(path))
    except InvalidURDF as exc:
        raise b.error(f"Drake cannot parse it ({exc.reason})") from exc
    return plant, scene_graph


def _directives(b: SceneFileBuilder, path: Path, plant, resolver) -> None:
    """Process model directives, their ``package://`` names found by drake_mh first."""
    from pydrake.multibody.parsing import LoadModelDirectives, Parser, ProcessModelDirectives

    parser = Parser(plant)
    package_map = parser.package_map()
    seen: set[str] = set()
    texts = [(path, read_text(path))]
    while texts:  # the directives' packages, and those of the files they name
        source, text = texts.pop()
        for name, rest in _PACKAGE_URI.findall(text):
            if name in seen:
                continue
            seen.add(name)
            searched: list[str] = []
            folder = resolver.package_dir(name, rest, searched)
            if folder is None:
                if name == "drake" and package_map.Contains(name):
                    continue  # Drake's own models, installed with it
                raise b.error(f"package {name!r} (named in {source}) is not found; searched: {'; '.join(searched)}. "
                              f"Pass packages={{{name!r}: '/path/to/{name}'}} (shell: --package {name}=DIR)",
                              f"package://{name}")
            resolver.found.setdefault(name, folder)
            named = folder / rest
            if named.is_file() and named.suffix.lower() in (".yaml", ".yml", ".sdf", ".urdf", ".xml"):
                with contextlib.suppress(SceneFileError):
                    texts.append((named, read_text(named)))
    for name, folder in resolver.found.items():
        if package_map.Contains(name):
            package_map.Remove(name)  # ours first: Drake's default 'drake_models' is downloaded
        package_map.Add(name, str(folder))
    try:
        directives = LoadModelDirectives(str(path))
    except Exception as exc:  # Drake's RuntimeError from its YAML reader
        raise b.error(f"not valid model directives ({_drake_message(exc)}); see Drake's "
                      "pydrake.multibody.parsing.ModelDirectives") from exc
    try:
        ProcessModelDirectives(directives, plant, parser)
    except Exception as exc:  # Drake's RuntimeError: a file, frame or package it cannot find
        raise b.error(f"Drake cannot process the directives ({_drake_message(exc)})") from exc


def _collect(b: SceneFileBuilder, plant, scene_graph, hulls: dict, movable: str) -> None:
    """Every proximity geometry of the finalized ``plant`` as an obstacle (module docstring)."""
    from pydrake.geometry import Role

    inspector = scene_graph.model_inspector()
    context = plant.CreateDefaultContext()
    welded = {body.index() for body in plant.GetBodiesWeldedTo(plant.world_body())}
    geometries = sorted(inspector.GetAllGeometryIds(Role.kProximity), key=lambda g: g.get_value())
    moving = sorted({plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name() for g in geometries
                     if plant.GetBodyFromFrameId(inspector.GetFrameId(g)).index() not in welded})
    if moving and movable == "error":
        raise b.error(f"bodies {moving} can move (a free body, or a joint with degrees of freedom); a scene is "
                      "static: weld them to the world (URDF: a fixed joint to link 'world'; SDFormat: "
                      "<static>true</static> or a fixed joint; directives: add_weld), or pass "
                      "movable='default_pose' to take them where the file puts them by default")
    count: dict[str, int] = {}
    for gid in geometries:
        name = inspector.GetName(gid)
        count[name] = count.get(name, 0) + 1
        if count[name] > 1:
            name = f"{name}_{count[name]}"
        entry = f"collision geometry {name!r}"
        body = plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
        X_WG = (plant.EvalBodyPoseInWorld(context, body) @ inspector.GetPoseInFrame(gid)).GetAsMatrix4()
        shape, X_GO = _shape(b, inspector.GetShape(gid), X_WG, hulls, entry)
        b.add(name, shape, X_WG @ X_GO, entry)


def _shape(b: SceneFileBuilder, shape, X_WG: np.ndarray, hulls: dict, entry: str) -> tuple:
    """``(drake_mh shape, X_GO (4, 4))``: the obstacle and its frame O in the geometry's frame G."""
    from pydrake.geometry import Convex, Ellipsoid, HalfSpace, Mesh

    from drake_mh.geometry.shapes import Box, from_drake

    if isinstance(shape, (Mesh, Convex)):
        source = shape.source()
        if not source.is_path():
            raise b.error("an in-memory mesh has no file to read; name a mesh file in the model", entry)
        file = hulls.get(str(source.path()), Path(source.path()))
        return b.mesh(file, tuple(shape.scale3()), entry), np.eye(4)
    if isinstance(shape, HalfSpace):
        # the plane is z = 0 of G, the half space z <= 0; the box's centre goes below the
        # world origin's projection onto the plane
        p_GWo = -X_WG[:3, :3].T @ X_WG[:3, 3]
        X_GO = np.eye(4)
        X_GO[:3, 3] = [p_GWo[0], p_GWo[1], -0.5 * HALFSPACE_DEPTH]
        return b.shape(Box, HALFSPACE_SIDE, HALFSPACE_SIDE, HALFSPACE_DEPTH, entry=entry), X_GO
    if isinstance(shape, Ellipsoid):
        raise b.error("an ellipsoid is not an obstacle shape drake_mh checks; describe it as a mesh (or a sphere, box "
                      "or capsule around it)", entry)
    try:
        return from_drake(shape), np.eye(4)
    except DrakeMhError as exc:
        raise b.error(str(exc), entry) from exc
