"""Robots as Drake models: :class:`Robot` and :func:`load_robot`.

A :class:`Robot` wraps a Drake ``MultibodyPlant`` + ``SceneGraph`` diagram built from a URDF.
Drake is the single source of truth: forward kinematics, Jacobians, inverse dynamics and
(through :class:`drake_mh.scene.Scene`) signed distances all come from it. The batched kernel
:attr:`Robot.batch` is compiled from the same plant (see :mod:`drake_mh.kinematics`).

Conventions:
    * ``q`` is a joint configuration ``(nq,)`` in [rad] (revolute) or [m] (prismatic),
      ordered as Drake's generalized positions (``joint_names`` gives the order).
    * ``X_WE`` is the pose of the end-effector frame E in the world W as a ``(4, 4)``
      homogeneous matrix.
    * Jacobians are ``(6, nq)`` with angular rows first, then translational (Drake's order),
      expressed in W, for the origin of E.

Only fixed-base arms made of revolute, continuous, prismatic and fixed joints are supported.
A model whose root link is not welded to ``world`` is welded at its default pose (a floating
base would add quaternion coordinates that the rest of the library does not handle).

Models with meshes load as shipped: :func:`load_robot` reads URDF, xacro, SDFormat and MJCF
files, resolves ``package://`` and relative mesh references (:mod:`drake_mh.robot.packages`),
turns collision meshes into cached convex hulls (:mod:`drake_mh.robot.meshes`) and locks the joints
that are not on the way to the end effector (:mod:`drake_mh.robot.chain`); see
``docs/robots.md``, "Your own robot".
"""

from __future__ import annotations

import functools
import logging
import os
from pathlib import Path

import numpy as np

from drake_mh.errors import (
    FrameNotFound,
    InvalidArgument,
    InvalidConfiguration,
    InvalidLimits,
    InvalidURDF,
    UnknownRobot,
    UnsupportedModel,
)
from drake_mh.robot.checks import check_urdf
from drake_mh.robot.limits import LimitAttribute, apply_limits, declared_limits

logger = logging.getLogger(__name__)

URDF_DIR = Path(__file__).resolve().parents[1] / "urdf"
"""Folder of the bundled robot models (``urdf/`` at the repository root links here)."""

_MODEL_SUFFIXES = (".urdf", ".xacro", ".sdf", ".xml")


_REGISTERED: dict[str, dict] = {}


def register_robot(name: str, path: str | Path, *, ee_frame: str | None = None, packages=None,
                   locked: dict[str, float] | None = None,
                   xacro_args: dict[str, str] | None = None) -> None:
    """Give a model file and its load options a name that :func:`load_robot` accepts.

    Code that loads robots by name (the app, studies, process-pool workers that re-register
    in their initializer) then uses your robot: ``register_robot("my_arm", "arm.urdf",
    ee_frame="tool0")``, then ``load_robot("my_arm")``. Registering a path under its own text
    attaches options to that path. The file is loaded (and checked) on first use.

    Raises:
        InvalidArgument: ``name`` is empty or a bundled robot's name.
    """
    if not isinstance(name, str) or not name.strip():
        raise InvalidArgument(f"register_robot: name must be a non-empty string, got {name!r}")
    if name in available_robots():
        raise InvalidArgument(f"register_robot: {name!r} is a bundled robot; choose another name")
    _REGISTERED[name] = dict(name_or_path=str(Path(path).expanduser()), ee_frame=ee_frame,
                             packages=dict(packages) if packages else None,
                             locked=dict(locked) if locked else None,
                             xacro_args=dict(xacro_args) if xacro_args else None)


def available_robots() -> list[str]:
    """Names of the bundled robot models (the ``*.urdf`` files in ``urdf/``)."""
    return sorted(p.stem for p in URDF_DIR.glob("*.urdf"))


def load_robot(name_or_path: str | Path, ee_frame: str | None = None, packages=None,
               locked: dict[str, float] | None = None,
               xacro_args: dict[str, str] | None = None, limits=None) -> Robot:
    """Load a bundled robot by name, or a robot model file (with its meshes) by path.

    Args:
        name_or_path: a bundled name (see :func:`available_robots`, e.g. ``"panda"``) or the
            path of a model: URDF (``.urdf``), xacro (``.xacro``), SDFormat (``.sdf``) or MJCF
            (``.xml`` whose root is ``<mujoco>``).
        ee_frame: name of the end-effector frame; default: the unique moving tip link (a model
            with several tips, e.g. an arm with a two-finger hand, needs it).
        packages: ``{"NAME": "/folder"}`` for ``package://NAME/...`` references; otherwise
            they are found through ``package.xml`` files up the tree, ``ROS_PACKAGE_PATH`` /
            ``AMENT_PREFIX_PATH``, then the model's folder and its parents.
        locked: ``{"joint": value}`` [rad or m] for joints to hold fixed. Joints off the path
            from the root to ``ee_frame`` are always locked (at 0 clipped into their limits
            unless given here); :attr:`Robot.locked_joints` says which.
        xacro_args: ``name:=value`` arguments of a ``.xacro`` file.
        limits: a MoveIt-style ``joint_limits.yaml`` path (or the same structure as a dict):
            velocity, acceleration, jerk and effort limits and default scaling factors, set with
            source ``"user"`` (:mod:`drake_mh.robot.limits`; ``robot.limits`` shows them).

    Returns:
        The loaded :class:`Robot` (it pickles by these arguments, so process pools reload it).

    Raises:
        UnknownRobot: the name is neither bundled nor an existing file.
        InvalidURDF: the file cannot be read, parsed or evaluated (xacro).
        MeshNotFound, UnknownPackage: a mesh reference resolves nowhere (the message lists
            every place searched and how to pass ``packages=``).
        MeshConversionError: a collision mesh cannot be turned into a convex hull.
        FrameNotFound: ``ee_frame`` (or a ``locked`` joint) is not in the model.
        InvalidArgument: no ``ee_frame`` and several tip links (listed in the message).
        InvalidLimits: a bad limits file (the message names the file, the joint and the key).
    """
    text = str(name_or_path)
    if text in _REGISTERED:
        options = dict(_REGISTERED[text])
        given = dict(ee_frame=ee_frame, packages=packages, locked=locked, xacro_args=xacro_args, limits=limits)
        options.update({k: v for k, v in given.items() if v is not None})
        return _load_file(**options)
    return _load_file(text, ee_frame, packages, locked, xacro_args, limits)


def _load_file(name_or_path, ee_frame=None, packages=None, locked=None, xacro_args=None, limits=None) -> Robot:
    """:func:`load_robot` without the registry look-up."""
    from drake_mh.robot.packages import UriResolver
    from drake_mh.robot.loading import read_model

    text = str(name_or_path)
    bundled = text in available_robots()
    path = URDF_DIR / f"{text}.urdf" if bundled else Path(text).expanduser()
    if not bundled and not path.exists():
        if path.suffix.lower() in _MODEL_SUFFIXES or os.sep in text:
            raise InvalidURDF(str(path), "no such file (give an existing model path or a bundled "
                              "name: " + ", ".join(available_robots()) + ")")
        raise UnknownRobot(text, available_robots())
    if not path.is_file():
        raise InvalidURDF(str(path), "not a file (give a .urdf, .xacro, .sdf or MJCF .xml file)")
    path = path.resolve()
    resolver = UriResolver(path.parent, packages, str(path))
    model = read_model(path, resolver, xacro_args)
    reload = dict(name_or_path=text if bundled else str(path), ee_frame=ee_frame,
                  packages=dict(packages) if packages else None,
                  locked=dict(locked) if locked else None,
                  xacro_args=dict(xacro_args) if xacro_args else None)
    robot = Robot(model.text, ee_frame=ee_frame, source=str(path), name=model.name,
                  packages=packages, locked=locked, model_format=model.format,
                  model_dir=model.model_dir, _resolver=resolver, _reload=reload)
    if limits is not None:
        apply_limits(robot, limits)
    return robot


def _reload_robot(spec: dict, limits=None) -> Robot:
    """Unpickle a file-based :class:`Robot` by loading it again (see ``Robot.__reduce__``);
    ``limits``: its limits table, user settings and sources included."""
    robot = _load_file(**spec)
    if limits is not None:
        robot.limits = limits
    return robot


def _rebuild_robot(spec: dict, limits=None) -> Robot:
    """Unpickle a text-based :class:`Robot`."""
    robot = Robot(**spec)
    if limits is not None:
        robot.limits = limits
    return robot


class Robot:
    """A fixed-base robot arm backed by a Drake ``MultibodyPlant`` + ``SceneGraph``.

    Not thread-safe: the queries reuse one Drake context. Use one ``Robot`` per thread or
    process (it pickles by how it was loaded — file path and arguments, or its model text —
    so process pools receive a fresh copy).

    Args:
        urdf: the model text (URDF unless ``model_format`` says ``"sdf"`` or ``"mjcf"``).
        ee_frame: end-effector frame; default the unique moving tip link.
        source: where the text came from, for messages.
        name: model name.
        packages: ``{"NAME": folder}`` for ``package://`` references (see :func:`load_robot`).
        locked: ``{"joint": value}`` joints to hold fixed (see :func:`load_robot`).
        model_format: ``"urdf"``, ``"sdf"`` or ``"mjcf"``.
        model_dir: folder relative mesh paths resolve against (``None``: only absolute,
            ``file://`` and ``package://`` references resolve).

    Attributes:
        name: model name.
        source: where the model came from (path or ``"<string>"``).
        urdf: the model text as given; ``model_text`` is what Drake parsed (meshes rewritten,
            locked joints fixed).
        model_format: ``"urdf"``, ``"sdf"`` or ``"mjcf"``.
        plant, scene_graph, diagram: the Drake systems.
        nq: number of joints (generalized positions).
        joint_names: ``(nq,)`` names in the order of ``q``.
        locked_joints: ``{name: value}`` [rad or m] of the joints held fixed (off the chain to
            the end effector, or asked for); empty when none.
        lower, upper: ``(nq,)`` position limits [rad or m]; continuous joints get ∓π.
        continuous: ``(nq,)`` bool, joints without position limits in the URDF.
        velocity_limits, acceleration_limits, jerk_limits, effort_limits: ``(nq,)`` symmetric
            magnitudes [rad/s, rad/s², rad/s³, N·m]; ``inf`` where the model declares none.
            The arrays of :attr:`limits`; assigning one marks its joints ``"user"``.
        limits: :class:`~drake_mh.robot.limits.JointLimits`, every limit with its source
            (declared by the model, user, default); ``print(robot.limits.table())``.
        ee_frame_name: name of the end-effector frame.
        mesh_files: ``{"collision": [(uri, file used)], "visual": [...]}`` of the model's meshes.
    """

    lower = LimitAttribute("lower")
    upper = LimitAttribute("upper")
    velocity_limits = LimitAttribute("velocity")
    acceleration_limits = LimitAttribute("acceleration")
    jerk_limits = LimitAttribute("jerk")
    effort_limits = LimitAttribute("effort")

    def __init__(self, urdf: str, ee_frame: str | None = None, source: str = "<string>",
                 name: str | None = None, *, packages=None, locked: dict[str, float] | None = None,
                 model_format: str = "urdf", model_dir: str | Path | None = None,
                 _resolver=None, _reload: dict | None = None):
        from drake_mh.robot.packages import UriResolver
        from drake_mh.robot.chain import default_ee, plan_locks, read_tree
        from drake_mh.robot.loading import (
            FORMATS, MeshReport, dedupe_urdf_materials, lock_joints, parse_model, parse_xml, rewrite_meshes,
            read_extra_limits, strip_mimics, to_text, urdf_mimics, weld_free_bodies,
        )

        if model_format not in FORMATS:
            raise InvalidArgument(f"model_format must be one of {FORMATS}, got {model_format!r}")
        if not isinstance(urdf, str) or not urdf.strip():
            raise InvalidURDF(source, "the model text is empty")
        self._init_args = dict(urdf=urdf, ee_frame=ee_frame, source=source, name=name,
                               packages=dict(packages) if packages else None,
                               locked=dict(locked) if locked else None, model_format=model_format,
                               model_dir=str(model_dir) if model_dir is not None else None)
        self._reload = _reload
        self.urdf = urdf
        self.source = source
        self.model_format = model_format
        root = parse_xml(urdf, source)
        if model_format == "urdf":
            check_urdf(root, source)
        self.name = name or root.get("name") or "robot"
        extra = read_extra_limits(root, source) if model_format == "urdf" else {"jerk": {}, "effort": {}}
        resolver = _resolver or UriResolver(Path(model_dir) if model_dir is not None else None,
                                            packages, source)
        report = MeshReport()
        changed = rewrite_meshes(root, model_format, resolver, report)
        if model_format == "urdf" and dedupe_urdf_materials(root):
            changed = True
        mimics = urdf_mimics(root) if model_format == "urdf" else {}
        if mimics:
            strip_mimics(root)
            changed = True
        self.mesh_files = {"collision": report.collision, "visual": report.visual}
        text = to_text(root) if changed else urdf

        builder, plant, scene_graph = parse_model(text, model_format, resolver, source)
        tree = read_tree(plant)
        self.ee_frame_name = ee_frame if ee_frame is not None else default_ee(tree, source)
        self.locked_joints = plan_locks(tree, self.ee_frame_name, locked, mimics, source)
        if self.locked_joints:
            lock_joints(root, model_format, self.locked_joints, source)
            text = to_text(root)
            builder, plant, scene_graph = parse_model(text, model_format, resolver, source)
        self.model_text = text
        weld_free_bodies(plant)
        plant.Finalize()
        # a geometry source for obstacles added at run time by drake_mh.scene.Scene
        self.obstacle_source_id = scene_graph.RegisterSource("drake_mh.obstacles")
        self.plant = plant
        self.scene_graph = scene_graph
        self.diagram = builder.Build()
        self.diagram_context = self.diagram.CreateDefaultContext()
        self.plant_context = plant.GetMyMutableContextFromRoot(self.diagram_context)
        if plant.num_positions() != plant.num_velocities():
            raise UnsupportedModel(
                f"{source}: {plant.num_positions()} positions but {plant.num_velocities()} "
                "velocities (floating or ball joints); only fixed-base arms are supported")
        self.nq = plant.num_positions()
        if self.nq == 0:
            raise UnsupportedModel(f"{source}: the model has no movable joint on the chain to "
                                   f"{self.ee_frame_name!r}")

        self._joints = _ordered_joints(plant)
        self.joint_names = [j.name() for j in self._joints]
        lower = np.array(plant.GetPositionLowerLimits(), dtype=float)
        upper = np.array(plant.GetPositionUpperLimits(), dtype=float)
        self.continuous = ~(np.isfinite(lower) & np.isfinite(upper))
        values = {"velocity": np.array(plant.GetVelocityUpperLimits(), dtype=float),
                  "acceleration": np.array(plant.GetAccelerationUpperLimits(), dtype=float),
                  "jerk": np.array([extra["jerk"].get(n, np.inf) for n in self.joint_names]),
                  "effort": self._effort_limits(extra["effort"])}
        for what, arr in values.items():
            if np.any(arr <= 0):
                bad = [n for n, v in zip(self.joint_names, arr) if v <= 0]
                raise InvalidLimits(f"{source}: {what} limits must be positive; joints {bad}")
        self.limits = declared_limits(self.joint_names, lower, upper, values, Path(source).name)

        self._frames = {f.name(): f for f in _all_frames(plant)}
        if self.ee_frame_name not in self._frames:
            raise FrameNotFound(self.ee_frame_name, self._frames)
        self.ee_frame = self._frames[self.ee_frame_name]

    # --- construction helpers -------------------------------------------------------------

    @classmethod
    def from_dh(cls, a, alpha, d, offset=None, lower=None, upper=None, *, name: str = "dh_robot",
                ee_frame: str | None = None, **dh_kwargs) -> Robot:
        """Build a robot from a Denavit-Hartenberg table (framework paper eqs. (1)-(2)).

        Args:
            a, alpha, d, offset, lower, upper: DH columns, one entry per joint [m, rad].
            name: model name.
            ee_frame: end-effector frame; default the generated ``ee`` link.
            **dh_kwargs: passed to :func:`drake_mh.robot.dh.dh_to_urdf` (``convention``, limits ...).

        Raises:
            InvalidDHTable, InvalidLimits: the table is inconsistent.
        """
        from drake_mh.robot.dh import dh_to_urdf

        import inspect

        unknown = sorted(set(dh_kwargs) - set(inspect.signature(dh_to_urdf).parameters))
        if unknown:
            raise InvalidArgument(f"Robot.from_dh got unknown options {unknown}; it accepts "
                                  f"{sorted(set(inspect.signature(dh_to_urdf).parameters) - {'a', 'alpha', 'd'})}")
        urdf = dh_to_urdf(a, alpha, d, offset, lower, upper, name=name, **dh_kwargs)
        return cls(urdf, ee_frame=ee_frame, source=f"<DH table {name}>", name=name)

    def __reduce__(self):
        if self._reload is not None:
            return (_reload_robot, ({**self._reload, "ee_frame": self.ee_frame_name}, self.limits))
        return (_rebuild_robot, ({**self._init_args, "ee_frame": self.ee_frame_name}, self.limits))

    def __repr__(self) -> str:
        locked = f", locked={sorted(self.locked_joints)}" if self.locked_joints else ""
        return f"Robot({self.name!r}, nq={self.nq}, ee={self.ee_frame_name!r}{locked})"

    def collision_summary(self) -> dict[str, dict[str, int]]:
        """Collision geometries per link by shape: ``{link: {"Convex": 1, "Capsule": 2}}``."""
        from pydrake.multibody.tree import BodyIndex

        inspector = self.scene_graph.model_inspector()
        out: dict[str, dict[str, int]] = {}
        for i in range(1, self.plant.num_bodies()):
            body = self.plant.get_body(BodyIndex(i))
            body_name = body.name()
            counts: dict[str, int] = {}
            for gid in self.plant.GetCollisionGeometriesForBody(body):
                kind = type(inspector.GetShape(gid)).__name__
                counts[kind] = counts.get(kind, 0) + 1
            if counts:
                out[body_name] = counts
        return out

    def _effort_limits(self, urdf_effort: dict[str, float]) -> np.ndarray:
        """Effort limits per joint: Drake's actuators first, else the URDF ``<limit effort>``."""
        from pydrake.multibody.tree import JointActuatorIndex

        limits = np.array([urdf_effort.get(n, np.inf) for n in self.joint_names])
        upper = self.plant.GetEffortUpperLimits()
        for i in range(self.plant.num_actuators()):
            actuator = self.plant.get_joint_actuator(JointActuatorIndex(i))
            joint = actuator.joint()
            if joint.num_velocities() == 1:
                limits[joint.velocity_start()] = upper[actuator.input_start()]
        return limits

    # --- input checks -----------------------------------------------------------------------

    def check_q(self, q, name: str = "q") -> np.ndarray:
        """Return ``q`` as a float array ``(nq,)``, or raise :class:`InvalidConfiguration`.

        The array may share memory with ``q``: a caller that keeps it copies it."""
        try:
            complex_ = np.iscomplexobj(q)  # numpy raises ValueError on ragged nested lists
            arr = None if complex_ else np.asarray(q, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidConfiguration(f"{name} must be numeric, got {q!r}", name) from exc
        if complex_:
            raise InvalidConfiguration(f"{name} must be real [rad or m], got complex values", name)
        if arr.shape != (self.nq,):
            raise InvalidConfiguration(
                f"{name} must have shape ({self.nq},) for {self.name} (joints {self.joint_names}), "
                f"got shape {arr.shape}", name, f"({self.nq},)", arr.shape)
        if not np.all(np.isfinite(arr)):
            bad = [self.joint_names[i] for i in np.flatnonzero(~np.isfinite(arr))]
            raise InvalidConfiguration(f"{name} contains NaN or inf at joints {bad}", name)
        return arr

    def check_Q(self, Q, name: str = "Q") -> np.ndarray:
        """Return a batch as a C-contiguous float array ``(N, nq)`` or raise (it may share
        memory with ``Q``)."""
        try:
            complex_ = np.iscomplexobj(Q)  # numpy raises ValueError on ragged nested lists
            arr = None if complex_ else np.ascontiguousarray(Q, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidConfiguration(f"{name} must be numeric (one number per joint in every row)", name) from exc
        if complex_:
            raise InvalidConfiguration(f"{name} must be real [rad or m], got complex values", name)
        if arr.ndim == 1 and arr.shape[0] == self.nq:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.nq:
            raise InvalidConfiguration(
                f"{name} must have shape (N, {self.nq}) for {self.name}, got {arr.shape}",
                name, f"(N, {self.nq})", arr.shape)
        if not np.all(np.isfinite(arr)):
            rows = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))[:5].tolist()
            raise InvalidConfiguration(f"{name} contains NaN or inf (rows {rows}...)", name)
        return arr

    def within_limits(self, q, tol: float = 0.0) -> bool:
        """Whether ``q`` respects the position limits (continuous joints always do)."""
        q = self.check_q(q)
        ok = (q >= self.lower - tol) & (q <= self.upper + tol)
        return bool(np.all(ok | self.continuous))

    def random_configurations(self, n: int, rng: np.random.Generator | int | None = None) -> np.ndarray:
        """``(n, nq)`` configurations drawn uniformly within ``[lower, upper]``."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
            raise InvalidArgument(f"n must be a whole number of configurations >= 0, got {n!r}")
        from drake_mh.optim.base import make_rng

        return make_rng(rng, "rng").uniform(self.lower, self.upper, size=(int(n), self.nq))

    @property
    def home(self) -> np.ndarray:
        """Mid-range configuration ``(nq,)``."""
        return 0.5 * (self.lower + self.upper)

    # --- Drake queries --------------------------------------------------------------------------

    def _set(self, q) -> None:
        self.plant.SetPositions(self.plant_context, self.check_q(q))

    def frame_names(self) -> list[str]:
        """Names of every frame of the model (usable as ``ee_frame``)."""
        return sorted(self._frames)

    def link_names(self) -> list[str]:
        """Names of the bodies (links), world excluded, in Drake's index order."""
        from pydrake.multibody.tree import BodyIndex

        return [self.plant.get_body(BodyIndex(i)).name() for i in range(1, self.plant.num_bodies())]

    def fk(self, q, frame: str | None = None) -> np.ndarray:
        """Pose ``X_WF (4, 4)`` of the end effector (or ``frame``) at ``q``.

        Computed by the single-configuration kernel compiled from this plant
        (:meth:`BatchKinematics.one`, ~1-2 µs from Python), equal to Drake's to 1e-12 (tests);
        :meth:`fk_drake` is Drake's own (the reference that verification uses).
        """
        if frame is None:
            function = self.__dict__.get("_fk_ee")  # the common call, without any lookup
            if function is None:
                function = self._fk_ee = self.batch.one_function(None)
            return function(q)
        self._frame(frame)  # FrameNotFound / InvalidArgument with the frame list
        return self.batch.one_function(frame)(q)

    def fk_drake(self, q, frame: str | None = None) -> np.ndarray:
        """Pose ``X_WF (4, 4)`` from Drake (``SetPositions`` + ``CalcPoseInWorld``, ~6 µs)."""
        self._set(q)
        return self._frame(frame).CalcPoseInWorld(self.plant_context).GetAsMatrix4()

    def link_poses(self, q) -> dict[str, np.ndarray]:
        """Poses ``X_WB (4, 4)`` of every link at ``q``, keyed by link name."""
        from pydrake.multibody.tree import BodyIndex

        self._set(q)
        out = {}
        for i in range(1, self.plant.num_bodies()):
            body = self.plant.get_body(BodyIndex(i))
            out[body.name()] = self.plant.EvalBodyPoseInWorld(self.plant_context, body).GetAsMatrix4()
        return out

    def jacobian(self, q, frame: str | None = None) -> np.ndarray:
        """Geometric Jacobian ``(6, nq)`` of the frame origin: rows ``[ω_W; v_W]`` (Drake's order).

        Compiled single-configuration kernel like :meth:`fk`; :meth:`jacobian_drake` is Drake's.
        """
        if frame is None:
            function = self.__dict__.get("_jacobian_ee")
            if function is None:
                function = self._jacobian_ee = self.batch.one_function(None, want_jac=True)
            return function(q)
        self._frame(frame)
        return self.batch.one_function(frame, want_jac=True)(q)

    def jacobian_drake(self, q, frame: str | None = None) -> np.ndarray:
        """Geometric Jacobian ``(6, nq)`` from Drake's ``CalcJacobianSpatialVelocity``."""
        from pydrake.multibody.tree import JacobianWrtVariable

        self._set(q)
        return self.plant.CalcJacobianSpatialVelocity(
            self.plant_context, JacobianWrtVariable.kQDot, self._frame(frame), np.zeros(3),
            self.plant.world_frame(), self.plant.world_frame())

    def manipulability(self, q, translational: bool = True) -> float:
        """Yoshikawa's manipulability ``μ = sqrt(det(J Jᵀ))`` (ESM paper eq. (3)).

        Args:
            q: configuration ``(nq,)``.
            translational: use the ``3 x nq`` translational Jacobian (as the ESM paper does for
                position tracking); ``False`` uses the full ``6 x nq`` Jacobian.
        """
        J = self.jacobian(q)
        J = J[3:] if translational else J
        return float(np.sqrt(max(np.linalg.det(J @ J.T), 0.0)))

    def inverse_dynamics(self, q, v, a) -> np.ndarray:
        """Joint torques ``τ = M(q) a + C(q, v) v + g(q)`` [N·m], gravity **included**.

        Drake's ``CalcInverseDynamics`` omits gravity unless it is given the force elements'
        contribution, so it is computed first with ``CalcForceElementsContribution``.
        """
        from pydrake.multibody.tree import MultibodyForces

        q = self.check_q(q, "q")
        v = self.check_q(v, "v")
        a = self.check_q(a, "a")
        self.plant.SetPositions(self.plant_context, q)
        self.plant.SetVelocities(self.plant_context, v)
        forces = MultibodyForces(self.plant)
        self.plant.CalcForceElementsContribution(self.plant_context, forces)
        tau = self.plant.CalcInverseDynamics(self.plant_context, a, forces)
        if not np.all(np.isfinite(tau)):
            raise InvalidConfiguration(
                "inverse dynamics overflowed (torque not finite): q, v and a must be physically "
                f"meaningful, got max |q| {np.abs(q).max():.3g}, |v| {np.abs(v).max():.3g}, |a| {np.abs(a).max():.3g}", "q")
        return tau

    def gravity_torques(self, q) -> np.ndarray:
        """Static holding torques ``g(q)`` [N·m] (inverse dynamics at rest)."""
        zeros = np.zeros(self.nq)
        return self.inverse_dynamics(q, zeros, zeros)

    def _frame(self, frame: str | None):
        if frame is None:
            return self.ee_frame
        if not isinstance(frame, str):
            raise InvalidArgument(f"frame must be a frame name (str) or None, got {frame!r}; "
                                  f"frames: {', '.join(self.frame_names()[:20])} ...")
        if frame not in self._frames:
            raise FrameNotFound(frame, self._frames)
        return self._frames[frame]

    @functools.cached_property
    def sphere_model(self):
        """:class:`drake_mh.geometry.spheres.SphereModel` covering the collision geometry (default tolerance)."""
        from drake_mh.geometry.spheres import SphereModel

        return SphereModel.from_robot(self)

    # --- batched kernel ----------------------------------------------------------------------

    @functools.cached_property
    def batch(self):
        """:class:`drake_mh.kinematics.BatchKinematics` compiled from this plant."""
        from drake_mh.kinematics import BatchKinematics

        return BatchKinematics(self)


# --- URDF helpers -------------------------------------------------------------------------------


def _ordered_joints(plant) -> list:
    """Single-DOF joints sorted by their position index."""
    from pydrake.multibody.tree import JointIndex

    joints = [plant.get_joint(JointIndex(i)) for i in range(plant.num_joints())]
    moving = [j for j in joints if j.num_positions() > 0]
    for j in moving:
        if j.num_positions() != 1 or j.type_name() not in ("revolute", "prismatic"):
            raise UnsupportedModel(f"joint {j.name()!r} of type {j.type_name()!r} is not supported")
    return sorted(moving, key=lambda j: j.position_start())


def _all_frames(plant) -> list:
    from pydrake.multibody.tree import FrameIndex

    return [plant.get_frame(FrameIndex(i)) for i in range(plant.num_frames())]
