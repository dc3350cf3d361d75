"""Exceptions raised by drake_mh.

Every exception a user can trigger with bad input derives from :class:`DrakeMhError`
and says what was wrong and how to fix it. Exceptions carry the offending data as
attributes so that programs can react without parsing messages.

Mixins with the matching builtin (``ValueError``, ``LookupError``, ``FileNotFoundError``)
keep ``except ValueError`` style code working.
"""

from __future__ import annotations

from collections.abc import Iterable


def _names(names: Iterable[str]) -> str:
    names = list(names)
    return ", ".join(names) if names else "(none)"


class DrakeMhError(Exception):
    """Base class of every error raised by drake_mh on purpose."""


# --- robots -------------------------------------------------------------------------


class UnknownRobot(DrakeMhError, LookupError):
    """A robot name is neither a bundled model nor a path to a URDF file.

    Attributes:
        name: the name that was asked for.
        available: the bundled robot names.
    """

    def __init__(self, name: str, available: Iterable[str]):
        self.name = name
        self.available = sorted(available)
        super().__init__(
            f"unknown robot {name!r}: bundled robots are {_names(self.available)}; "
            "or pass the path of a model file (.urdf, .xacro, .sdf, MJCF .xml)"
        )

    def __str__(self) -> str:  # LookupError would quote the message otherwise
        return self.args[0]


class InvalidURDF(DrakeMhError, ValueError):
    """A robot model file (URDF, xacro, SDFormat, MJCF) could not be read or Drake rejected it.

    Attributes:
        source: path (or ``"<string>"``) of the model.
        reason: what went wrong, as reported by the reader or Drake.
    """

    def __init__(self, source: str, reason: str):
        self.source = source
        self.reason = reason
        kind = "URDF" if str(source).lower().endswith((".urdf", "<string>")) else "robot model"
        super().__init__(f"cannot load {kind} {source}: {reason}")


class UnsupportedModel(DrakeMhError, ValueError):
    """The model loads but is not a kind of robot drake_mh supports (e.g. floating base)."""


class MeshNotFound(DrakeMhError, FileNotFoundError):
    """A mesh (or other file) referenced by a robot model cannot be found.

    Attributes:
        uri: the reference as written in the model (``package://...``, relative path ...).
        searched: every place that was looked at, in order.
        source: the model that refers to it.
    """

    def __init__(self, uri: str, searched: Iterable[str], source: str = "", hint: str = ""):
        self.uri = uri
        self.searched = list(searched)
        self.source = source
        where = "; ".join(self.searched) if self.searched else "(nowhere)"
        super().__init__(
            f"{source + ': ' if source else ''}cannot find {uri!r}; searched: {where}. "
            + (hint or "Pass the folder of the package with packages={'NAME': '/path/to/NAME'} "
               "(shell: --package NAME=DIR) or set ROS_PACKAGE_PATH"))

    def __str__(self) -> str:
        return self.args[0]


class UnknownPackage(MeshNotFound):
    """A ``package://NAME/...`` reference names a package that no search place provides.

    Attributes:
        package: the package name.
    """

    def __init__(self, package: str, uri: str, searched: Iterable[str], source: str = ""):
        self.package = package
        super().__init__(
            uri, searched, source,
            hint=f"unknown package {package!r}: pass packages={{{package!r}: '/path/to/{package}'}} "
                 f"(shell: --package {package}=DIR), or set ROS_PACKAGE_PATH / AMENT_PREFIX_PATH")


class MeshConversionError(DrakeMhError, ValueError):
    """A mesh file exists but cannot be read or turned into a convex hull.

    Attributes:
        path: the mesh file.
        reason: what the mesh reader said.
    """

    def __init__(self, path: str, reason: str):
        self.path = path
        self.reason = reason
        super().__init__(
            f"cannot convert mesh {path}: {reason}; export it as .obj or .stl from your CAD tool, "
            "or replace the <collision> geometry by primitives (box, cylinder, sphere)")


class FrameNotFound(DrakeMhError, LookupError):
    """A frame (link) name does not exist in the robot model.

    Attributes:
        frame: the requested name.
        available: the frame names that do exist.
    """

    def __init__(self, frame: str, available: Iterable[str], what: str = "frame"):
        self.frame = frame
        self.available = sorted(available)
        super().__init__(
            f"{what} {frame!r} not found in the model; available {what}s: {_names(self.available)}"
        )

    def __str__(self) -> str:
        return self.args[0]


class InvalidConfiguration(DrakeMhError, ValueError):
    """A joint configuration (or velocity, acceleration) has the wrong shape or non-finite values.

    Attributes:
        name: the argument name (``q``, ``Q``, ``v`` ...).
        expected: a description of the expected shape.
        got: the received shape.
    """

    def __init__(self, message: str, name: str = "q", expected: str = "", got: object = None):
        self.name = name
        self.expected = expected
        self.got = got
        super().__init__(message)


class InvalidDHTable(DrakeMhError, ValueError):
    """A Denavit-Hartenberg table is inconsistent (column lengths, limits, values)."""


class InvalidLimits(DrakeMhError, ValueError):
    """Joint limits are inconsistent (lower > upper, negative velocity limits, NaN)."""


class MissingLimits(DrakeMhError, LookupError):
    """A quantity needs limits that the robot model does not declare (e.g. effort limits)."""


# --- scenes ---------------------------------------------------------------------------


class SceneError(DrakeMhError, ValueError):
    """An obstacle or scene request is invalid (bad size, duplicate or unknown name)."""


class ObstacleFileError(SceneError):
    """An obstacle file (a mesh, a point cloud) is missing, unreadable, empty or of a format
    drake_mh does not read, or its scale is not valid.

    Attributes:
        path: the file.
        reason: what was wrong, and how to fix it.
    """

    def __init__(self, path, reason: str):
        self.path = str(path)
        self.reason = reason
        super().__init__(f"obstacle file {self.path}: {reason}")


class ObstacleFileNotFound(ObstacleFileError, FileNotFoundError):
    """An obstacle file does not exist (or is not a file)."""

    def __str__(self) -> str:  # FileNotFoundError would format its own message otherwise
        return self.args[0]


class UnknownObstacle(DrakeMhError, LookupError):
    """An obstacle name is not in the scene.

    Attributes:
        name: the requested name.
        available: the obstacle names in the scene.
    """

    def __init__(self, name: str, available: Iterable[str]):
        self.name = name
        self.available = sorted(available)
        super().__init__(f"no obstacle named {name!r}; obstacles in the scene: {_names(self.available)}")

    def __str__(self) -> str:
        return self.args[0]


class UnsupportedGeometry(DrakeMhError, ValueError):
    """A collision shape cannot be handled by the requested computation."""


class SceneFileError(SceneError):
    """A scene file (drake_mh scene YAML, SDFormat, URDF, model directives, MoveIt ``.scene``,
    MoveIt planning-scene YAML, cuRobo world YAML) is malformed, of a format drake_mh does not
    read, or holds an entry it does not support; or a scene cannot be saved.

    Attributes:
        path: the file.
        entry: where in the file (``"obstacle 'table'"``, ``"line 12"``; ``""``: the whole file).
        reason: what was wrong and what is expected.
    """

    def __init__(self, path, reason: str, entry: str = ""):
        self.path = str(path)
        self.entry = entry
        self.reason = reason
        super().__init__(f"scene file {self.path}{', ' + entry if entry else ''}: {reason}")


class SceneFileNotFound(SceneFileError, FileNotFoundError):
    """A scene file does not exist (or is not a file)."""

    def __str__(self) -> str:  # FileNotFoundError would format its own message otherwise
        return self.args[0]


# --- optimizers and methods -------------------------------------------------------------


class UnknownMethod(DrakeMhError, LookupError):
    """A method (optimizer, IK solver, retimer ...) name is not known.

    Attributes:
        name: the requested name.
        available: the valid names.
    """

    def __init__(self, name: str, available: Iterable[str], what: str = "method"):
        self.name = name
        self.available = sorted(available)
        super().__init__(f"unknown {what} {name!r}; available: {_names(self.available)}")

    def __str__(self) -> str:
        return self.args[0]


class InvalidArgument(DrakeMhError, ValueError):
    """An argument value is out of its valid range or of the wrong type."""


# --- studies and reports ----------------------------------------------------------------


class UnknownStudy(DrakeMhError, LookupError):
    """A study name is neither a script in the studies folder nor a path to a ``.py`` file.

    Attributes:
        name: the requested name.
        available: the study names found in the studies folder.
    """

    def __init__(self, name: str, available: Iterable[str], folder: str = "studies/"):
        self.name = name
        self.available = sorted(available)
        super().__init__(
            f"unknown study {name!r}; studies in {folder}: {_names(self.available)}; "
            "or pass the path of a study .py file"
        )

    def __str__(self) -> str:
        return self.args[0]


class InvalidStudy(DrakeMhError, ValueError):
    """A study declaration is inconsistent (grid, fields, missing ``Study`` object ...)."""


class ResultsMismatch(DrakeMhError, ValueError):
    """A results folder was made by a different study, seed, quick flag or grid.

    Attributes:
        folder: the results folder.
        differences: ``{setting: (in_folder, requested)}``.
    """

    def __init__(self, folder: str, differences: dict):
        self.folder = folder
        self.differences = dict(differences)
        diff = "; ".join(f"{k}: folder has {a!r}, requested {b!r}" for k, (a, b) in differences.items())
        super().__init__(
            f"results folder {folder} was made with other settings ({diff}); "
            "pass another --out or delete the folder to start over"
        )


class NoResults(DrakeMhError, FileNotFoundError):
    """A folder holds no study results (``records.jsonl``) to report on."""


class ResultsFolderError(DrakeMhError, OSError):
    """A results folder cannot be used: a file is in the way, no permission, damaged study.json."""


class ResultsLocked(DrakeMhError, RuntimeError):
    """Another process is writing into the same results folder (two runs would record every
    case twice)."""


# --- optimizer protocol (drake_mh.optim) ----------------------------------------------------


class AskTellError(DrakeMhError, RuntimeError):
    """The ask/tell protocol was misused (ask twice, tell without ask, tell after the end)."""


class InvalidObjective(DrakeMhError, ValueError):
    """An objective returned something other than one float per row of the population ``(P,)``."""


class NoFiniteValue(InvalidObjective):
    """Every point a run evaluated scored NaN or +inf: there is no best point to return."""


# --- visualisation (drake_mh.viz) --------------------------------------------------------------


class InvalidTrajectory(DrakeMhError, ValueError):
    """Sampled trajectory data are inconsistent: times not increasing, ``len(t) != len(Q)`` ...

    Attributes:
        name: the offending argument (``t``, ``Q``, ``trajectory`` ...).
        expected: the expected shape or kind, if known.
        got: what was received, if known.
    """

    def __init__(self, message: str, name: str = "t", expected: object = None, got: object = None):
        self.name = name
        self.expected = expected
        self.got = got
        super().__init__(message)


class VisualizationError(DrakeMhError, RuntimeError):
    """The Meshcat viewer cannot do what was asked (server cannot start, wrong thread ...)."""


# --- trajectories (drake_mh.trajectories) -----------------------------------------------------


class InfeasibleTrajectory(DrakeMhError, ValueError):
    """A time parameterization (or a trajectory request) cannot satisfy the limits.

    Raised instead of returning ``None`` (toppra's and Drake's ``Toppra`` convention) so that
    a failure always says why.

    Attributes:
        method: the retimer (``"toppra"``, ``"ruckig"``, ``"drake-toppra"`` ...).
        reason: what made it infeasible and how to fix it.
    """

    def __init__(self, method: str, reason: str):
        self.method = method
        self.reason = reason
        super().__init__(f"{method}: infeasible trajectory: {reason}")


class LimitViolation(DrakeMhError, ValueError):
    """A trajectory exceeds a joint limit (found by :func:`drake_mh.trajectories.certify`).

    Attributes:
        joint: name of the joint.
        quantity: ``"position"``, ``"velocity"``, ``"acceleration"``, ``"jerk"`` or ``"torque"``.
        time: time [s] of the worst sample.
        ratio: value / limit at that time (position: normalized distance from the range centre,
            1 on the limit); ``> 1`` means violated.
    """

    def __init__(self, joint: str, quantity: str, time: float, ratio: float, tolerance: float = 0.0,
                 hint: str = ""):
        self.joint = joint
        self.quantity = quantity
        self.time = float(time)
        self.ratio = float(ratio)
        self.tolerance = float(tolerance)
        super().__init__(
            f"joint {joint!r} exceeds its {quantity} limit at t = {self.time:.6g} s: ratio "
            f"{self.ratio:.9g} > 1 + {self.tolerance:g}"
            + (f"; {hint}" if hint else "; slow the trajectory down (scale the limits) or "
               "use more gridpoints"))


# --- inverse kinematics (drake_mh.ik) ----------------------------------------------------------


class InvalidIKProblem(DrakeMhError, ValueError):
    """An inverse-kinematics problem is ill-posed (target shape, tolerances, weights, scene).

    The message names the offending argument and the expected form.
    """


class InfeasibleComponent(DrakeMhError, ValueError):
    """No constant orientation angle ``k`` keeps a 3-link component feasible over the period.

    Attributes:
        component: the component's name.
        reason: why (unreachable samples, limits, obstacles) and how to fix it.
    """

    def __init__(self, component: str, reason: str):
        self.component = component
        self.reason = reason
        super().__init__(f"component {component!r}: no feasible constant k: {reason}")


class InvalidMotionProblem(DrakeMhError, ValueError):
    """A point-to-point motion problem is ill-posed (start or goal shape, limits, collisions,
    clearance, scene of another robot). The message names the argument and how to fix it."""
