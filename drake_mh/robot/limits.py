"""Joint limits with provenance: every value says where it came from.

A :class:`JointLimits` holds, per joint, the position range and the symmetric velocity,
acceleration, jerk and effort limits, each with a **source**:

* ``"declared"``: the model file (URDF ``<limit lower upper velocity effort>``,
  ``drake:acceleration``, ``drake_mh:jerk``; Drake's actuator effort limits);
* ``"derived"``: computed by drake_mh for one retiming (an acceleration bound from the effort
  limits, gravity and the mass matrix along the path: :mod:`drake_mh.trajectories.limits_for`);
* ``"default"``: a documented default used where nothing is declared (a warning is logged);
* ``"user"``: set in code (``robot.acceleration_limits = ...``) or read from a limits file
  (:func:`read_limits_file`; the detail names the file);
* ``"none"``: not declared (value ``inf``: no limit).

:attr:`drake_mh.robot.Robot.limits` is the robot's table; ``Robot.velocity_limits`` etc. read
it as ``(nq,)`` arrays (read-only views) and assigning them marks the joints ``"user"``. A
retimed trajectory carries the limits it enforced, with their sources, as
``trajectory.info["enforced_limits"]`` (the same class).

Limits files have the shape of MoveIt's ``joint_limits.yaml``::

    default_velocity_scaling_factor: 0.5        # optional, in (0, 1]
    default_acceleration_scaling_factor: 0.5    # optional, in (0, 1]
    joint_limits:
      panda_joint1:
        has_velocity_limits: true
        max_velocity: 2.175                     # [rad/s] or [m/s]
        has_acceleration_limits: true
        max_acceleration: 15.0                  # [rad/s²]
        has_jerk_limits: true
        max_jerk: 7500.0                        # [rad/s³]
        has_effort_limits: true
        max_effort: 87.0                        # [N·m] or [N]

``has_X_limits: false`` keeps what the model declares (a file never removes a limit); a
``max_X`` without its ``has_X_limits`` is applied. Joints the robot locked (fingers, mimic
joints) are skipped; position keys are accepted only with ``has_position_limits: false``
(position limits belong in the model, which every planner and sampler reads).
"""

from __future__ import annotations

import logging
import numbers
from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidLimits

__all__ = ["JointLimits", "LimitAttribute", "declared_limits", "limits_of", "read_limits_file", "apply_limits", "LIMITED", "UNITS", "SOURCES"]

_log = logging.getLogger(__name__)

LIMITED = ("velocity", "acceleration", "jerk", "effort")
"""The symmetric limits (magnitudes); position is a range ``[lower, upper]``."""
UNITS = {"position": "rad", "velocity": "rad/s", "acceleration": "rad/s²", "jerk": "rad/s³", "effort": "N·m"}
SOURCES = ("declared", "derived", "default", "user", "none")
_ALIASES = {"torque": "effort"}  # certify's and retime's name for the effort quantity


def _quantity(name: str) -> str:
    name = _ALIASES.get(name, name)
    if name not in LIMITED and name != "position":
        raise InvalidLimits(f"unknown limit quantity {name!r}; choose from position, {', '.join(LIMITED)} (or torque)")
    return name


class JointLimits:
    """Per-joint limits and where each came from.

    Args:
        joint_names: ``(nq,)`` names.
        lower, upper: ``(nq,)`` position range [rad or m].
        values: quantity -> ``(nq,)`` magnitudes (``inf``: no limit), for :data:`LIMITED`.
        sources: quantity -> ``(nq,)`` source names (:data:`SOURCES`), ``"position"`` included.
        details: quantity -> ``(nq,)`` short free text (the file, the rule ...).
        scaling: ``{"velocity": f, "acceleration": f}`` factors in (0, 1]: on a robot, the
            defaults a retiming uses when it is given none (a limits file's
            ``default_*_scaling_factor``); on a trajectory's table, the factors that were applied
            (the values are then already scaled).
        enforced: on a trajectory's table, the quantities the retiming enforced (``None`` on a
            robot's).
    """

    def __init__(self, joint_names, lower, upper, values: dict, sources: dict, details: dict | None = None,
                 scaling: dict | None = None, enforced: tuple | None = None):
        self.joint_names = tuple(joint_names)
        nq = len(self.joint_names)
        self.lower = np.array(lower, dtype=float).reshape(nq)
        self.upper = np.array(upper, dtype=float).reshape(nq)
        self._values = {q: np.array(values[q], dtype=float).reshape(nq) for q in LIMITED}
        self._sources = {q: list(sources[q]) for q in ("position",) + LIMITED}
        details = details or {}
        self._details = {q: list(details.get(q, [""] * nq)) for q in ("position",) + LIMITED}
        self.scaling = {"velocity": 1.0, "acceleration": 1.0, **(scaling or {})}
        self.enforced = None if enforced is None else tuple(enforced)
        self._warned: set = set()

    @classmethod
    def from_arrays(cls, robot_like, source: str = "declared", detail: str = "") -> JointLimits:
        """Limits read from an object with ``joint_names``, ``lower``, ``upper`` and the
        ``*_limits`` arrays (a robot without a table), every finite value marked ``source``."""
        names = tuple(robot_like.joint_names)
        values = {q: np.asarray(getattr(robot_like, f"{q}_limits"), dtype=float) for q in LIMITED}
        sources = {q: [source if np.isfinite(v) else "none" for v in values[q]] for q in LIMITED}
        sources["position"] = [source] * len(names)
        details = {q: [detail] * len(names) for q in ("position",) + LIMITED}
        return cls(names, robot_like.lower, robot_like.upper, values, sources, details)

    # --- reading -----------------------------------------------------------------------------

    @property
    def nq(self) -> int:
        """Number of joints."""
        return len(self.joint_names)

    def __getitem__(self, quantity: str) -> np.ndarray:
        """``(nq,)`` values of ``quantity`` (``"torque"`` is ``"effort"``), read-only."""
        view = self._values[_quantity(quantity)].view()
        view.flags.writeable = False
        return view

    def sources(self, quantity: str) -> tuple[str, ...]:
        """``(nq,)`` source names of ``quantity``."""
        return tuple(self._sources[_quantity(quantity)])

    def details(self, quantity: str) -> tuple[str, ...]:
        """``(nq,)`` details of ``quantity`` (file, rule ...)."""
        return tuple(self._details[_quantity(quantity)])

    def declared(self, quantity: str) -> np.ndarray:
        """``(nq,)`` bool: a finite limit whatever its source."""
        return np.isfinite(self[quantity])

    # --- writing -----------------------------------------------------------------------------

    def set(self, quantity: str, values, source: str = "user", detail: str = "", joints=None) -> None:
        """Set ``quantity`` on every joint (``values`` ``(nq,)`` or a scalar), or on ``joints``.

        Raises:
            InvalidLimits: wrong shape, NaN, or a value ``<= 0`` (``inf`` means no limit), or an
                unknown joint name.
        """
        quantity = _quantity(quantity)
        if quantity == "position":
            raise InvalidLimits("position limits are set with robot.lower / robot.upper")
        if source not in SOURCES:
            raise InvalidLimits(f"unknown limit source {source!r}; choose from {SOURCES}")
        index = list(range(self.nq)) if joints is None else [self._index(j) for j in joints]
        arr = _positive_array(values, len(index), f"{quantity} limits", [self.joint_names[i] for i in index])
        for k, i in enumerate(index):
            self._values[quantity][i] = arr[k]
            finite = np.isfinite(arr[k])
            self._sources[quantity][i] = source if finite or source != "declared" else "none"
            self._details[quantity][i] = detail

    def set_range(self, lower, upper, source: str = "user", detail: str = "") -> None:
        """Set the position range ``[lower, upper]`` ``(nq,)`` [rad or m] of every joint.

        Raises:
            InvalidLimits: wrong shape, non-finite, or ``lower > upper``.
        """
        lo = _finite_array(lower, self.nq, "lower position limits", self.joint_names)
        hi = _finite_array(upper, self.nq, "upper position limits", self.joint_names)
        bad = [n for n, a, b in zip(self.joint_names, lo, hi) if a > b]
        if bad:
            raise InvalidLimits(f"lower position limit above the upper one on joints {bad}")
        self.lower, self.upper = lo, hi
        self._sources["position"] = [source] * self.nq
        self._details["position"] = [detail] * self.nq

    def scale(self, quantity: str, factor: float) -> None:
        """Multiply ``quantity``'s values by ``factor`` and record it in :attr:`scaling`."""
        quantity = _quantity(quantity)
        self._values[quantity] = self._values[quantity] * float(factor)
        self.scaling[quantity] = float(factor)

    def annotate(self, quantity: str, joints, detail: str) -> None:
        """Set the detail of ``quantity`` on the joints where ``joints`` ``(nq,)`` is true."""
        for j in np.flatnonzero(np.asarray(joints, dtype=bool)):
            self._details[_quantity(quantity)][j] = detail

    def _index(self, joint: str) -> int:
        if joint not in self.joint_names:
            raise InvalidLimits(f"unknown joint {joint!r}; joints: {', '.join(self.joint_names)}")
        return self.joint_names.index(joint)

    def copy(self) -> JointLimits:
        """An independent copy (its warnings, :meth:`warn_once`, are shared with this table)."""
        out = JointLimits(self.joint_names, self.lower, self.upper, self._values, self._sources, self._details,
                          dict(self.scaling), self.enforced)
        out._warned = self._warned
        return out

    def warn_once(self, key: str, message: str) -> None:
        """Log ``message`` as a warning the first time ``key`` is seen for this table."""
        if key not in self._warned:
            self._warned.add(key)
            _log.warning(message)

    # --- showing -----------------------------------------------------------------------------

    def summary(self, quantities=None) -> list[str]:
        """One line per quantity: values, and which joints got them from where.

        ``"velocity [rad/s]: 2.175 2.175 ... | declared (robot.urdf) on all 7 joints"``.
        """
        lines = []
        for q in quantities or ("position",) + LIMITED:
            q = _quantity(q)
            if q == "position":
                values = " ".join(f"[{a:.4g}, {b:.4g}]" for a, b in zip(self.lower, self.upper))
            else:
                values = " ".join(f"{v:.4g}" if np.isfinite(v) else "-" for v in self._values[q])
            label = q if self.enforced is None or q == "position" or q in self.enforced else f"{q} (not enforced)"
            factor = self.scaling.get(q, 1.0) if self.enforced is not None else 1.0
            scaled = f" (x {factor:g} scaling)" if factor != 1.0 else ""
            lines.append(f"{label} [{UNITS[q]}]: {values} | {self._provenance(q)}{scaled}")
        return lines

    def _provenance(self, quantity: str) -> str:
        groups: dict = {}
        for name, source, detail in zip(self.joint_names, self._sources[quantity], self._details[quantity]):
            groups.setdefault((source, detail), []).append(name)
        parts = []
        for (source, detail), names in groups.items():
            where = f"{source} ({detail})" if detail else source
            on = f"all {len(names)} joints" if len(names) == self.nq else ", ".join(names)
            parts.append(f"{where} on {on}")
        return "; ".join(parts)

    def table(self) -> str:
        """Markdown table: one row per quantity, one column per joint: ``value (source)``."""
        head = "| quantity | " + " | ".join(self.joint_names) + " |"
        lines = [head, "|" + "---|" * (self.nq + 1)]
        for q in ("position",) + LIMITED:
            if q == "position":
                cells = [f"[{a:.4g}, {b:.4g}] ({s})" for a, b, s in zip(self.lower, self.upper, self._sources[q])]
            else:
                cells = [(f"{v:.4g} ({s})" if np.isfinite(v) else f"- ({s})")
                         for v, s in zip(self._values[q], self._sources[q])]
            lines.append(f"| {q} [{UNITS[q]}] | " + " | ".join(cells) + " |")
        return "\n".join(lines)

    def as_dict(self) -> dict:
        """JSON-ready: ``{quantity: {"values", "sources", "details"}, "scaling", "enforced",
        "joint_names"}``; ``inf`` is written as ``None``."""
        out = {"joint_names": list(self.joint_names), "scaling": dict(self.scaling),
               "enforced": None if self.enforced is None else list(self.enforced),
               "position": {"lower": self.lower.tolist(), "upper": self.upper.tolist(),
                            "sources": list(self._sources["position"]), "details": list(self._details["position"])}}
        for q in LIMITED:
            out[q] = {"values": [float(v) if np.isfinite(v) else None for v in self._values[q]],
                      "sources": list(self._sources[q]), "details": list(self._details[q])}
        return out

    def __repr__(self) -> str:
        parts = []
        for q in ("position",) + LIMITED:
            counts: dict = {}
            for s in self._sources[q]:
                counts[s] = counts.get(s, 0) + 1
            parts.append(f"{q}: " + ", ".join(s if n == self.nq else f"{s} x{n}" for s, n in counts.items()))
        return f"JointLimits({'; '.join(parts)})"


def _positive_array(values, n: int, what: str, joints) -> np.ndarray:
    if np.iscomplexobj(values):
        raise InvalidLimits(f"{what} must be real numbers, got complex values")
    try:
        arr = np.broadcast_to(np.asarray(values, dtype=float), (n,)).copy()
    except (TypeError, ValueError) as exc:
        raise InvalidLimits(f"{what} must be {n} positive numbers (one per joint {list(joints)}) or inf, "
                            f"got {values!r}") from exc
    bad = [j for j, v in zip(joints, arr) if not v > 0]  # NaN, 0 and negatives
    if bad:
        raise InvalidLimits(f"{what} must be > 0 (inf: no limit); joints {bad} got "
                            f"{[float(v) for j, v in zip(joints, arr) if j in bad]}")
    return arr


def _finite_array(values, n: int, what: str, joints) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidLimits(f"{what} must be {n} numbers, got {values!r}") from exc
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise InvalidLimits(f"{what} must be {n} finite numbers (joints {list(joints)}), got {values!r}")
    return arr.copy()


def limits_of(robot) -> JointLimits:
    """``robot.limits``, or a table read from the arrays of an object that has none (a stand-in
    robot with ``joint_names``, ``lower``, ``upper`` and ``*_limits``, sources ``"declared"``)."""
    table = getattr(robot, "limits", None)
    return table if isinstance(table, JointLimits) else JointLimits.from_arrays(robot)


def declared_limits(joint_names, lower, upper, values: dict, model: str) -> JointLimits:
    """The table of a freshly loaded model: finite values ``"declared"`` (detail: the model
    file's name), infinite ones ``"none"``; a joint without a position range (continuous) gets
    ``[-π, π]``, source ``"default"``.

    Args:
        joint_names: ``(nq,)``.
        lower, upper: ``(nq,)`` position limits as Drake reads them (``∓inf``: none).
        values: quantity -> ``(nq,)`` for :data:`LIMITED`.
        model: the model file's name, for the details.
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    ranged = np.isfinite(lower) & np.isfinite(upper)
    sources = {q: ["declared" if np.isfinite(v) else "none" for v in values[q]] for q in LIMITED}
    details = {q: [model if np.isfinite(v) else "" for v in values[q]] for q in LIMITED}
    sources["position"] = ["declared" if r else "default" for r in ranged]
    details["position"] = [model if r else "continuous joint: one turn each way" for r in ranged]
    return JointLimits(joint_names, np.where(ranged, lower, -np.pi), np.where(ranged, upper, np.pi), values,
                       sources, details)


class LimitAttribute:
    """``Robot.lower``, ``Robot.velocity_limits`` etc.: the robot's :class:`JointLimits` arrays
    (the same array object on every read, as a plain attribute was); an assignment marks the
    joints ``"user"`` (``robot.acceleration_limits = np.array([...])``). An in-place edit
    (``robot.velocity_limits[0] = 1.0``) changes the value but not its recorded source: assign
    the whole array."""

    def __init__(self, quantity: str):
        self.quantity = quantity

    def __get__(self, robot, owner=None):
        if robot is None:
            return self
        if self.quantity in ("lower", "upper"):
            return getattr(robot.limits, self.quantity)
        return robot.limits._values[self.quantity]

    def __set__(self, robot, value) -> None:
        table = robot.limits.copy()  # copy on write: a copy.copy(robot) keeps its own limits
        if self.quantity in ("lower", "upper"):
            lower = value if self.quantity == "lower" else table.lower
            upper = value if self.quantity == "upper" else table.upper
            table.set_range(lower, upper, "user", "set in code")
        else:
            table.set(self.quantity, value, "user", "set in code")
        robot.limits = table


# --- limits files --------------------------------------------------------------------------------

_KEYS = {"velocity": ("has_velocity_limits", "max_velocity"),
         "acceleration": ("has_acceleration_limits", "max_acceleration"),
         "jerk": ("has_jerk_limits", "max_jerk"),
         "effort": ("has_effort_limits", "max_effort")}
_POSITION_KEYS = ("has_position_limits", "min_position", "max_position")
_SCALING_KEYS = {"default_velocity_scaling_factor": "velocity", "default_acceleration_scaling_factor": "acceleration"}


def read_limits_file(spec, joint_names, locked=()) -> tuple[dict, dict, str]:
    """Read a MoveIt-style limits file (or the same structure as a dict).

    Args:
        spec: path of a ``.yaml``/``.yml`` file, or a dict with the file's structure.
        joint_names: the robot's joints.
        locked: joints the robot locked (their entries are skipped).

    Returns:
        ``(limits, scaling, where)``: ``{quantity: {joint: value}}``, ``{"velocity": f,
        "acceleration": f}`` (only the factors the file gives) and the file's path (``"dict"``).

    Raises:
        InvalidLimits: unreadable file, not a mapping, unknown joint or key, wrong type,
            a value ``<= 0`` where a limit is on, a scaling factor outside (0, 1] (the message
            names the file, the joint and the key).
    """
    where, data = _load(spec)
    if not isinstance(data, dict):
        raise InvalidLimits(f"{where}: expected a mapping with a 'joint_limits' key, got {type(data).__name__}")
    unknown = [k for k in data if k not in ("joint_limits", *_SCALING_KEYS, "cartesian_limits")]
    if unknown:
        raise InvalidLimits(f"{where}: unknown top-level key(s) {unknown}; expected 'joint_limits', "
                            f"{', '.join(_SCALING_KEYS)}")
    scaling = {}
    for key, quantity in _SCALING_KEYS.items():
        if key in data:
            value = data[key]
            if not _number(value) or not 0.0 < float(value) <= 1.0:
                raise InvalidLimits(f"{where}: {key} must be a number in (0, 1], got {value!r}")
            scaling[quantity] = float(value)
    joints = data.get("joint_limits", {})
    if not isinstance(joints, dict):
        raise InvalidLimits(f"{where}: 'joint_limits' must map joint names to their limits, got {type(joints).__name__}")
    out: dict = {q: {} for q in _KEYS}
    for joint, entry in joints.items():
        if joint in locked:
            _log.info("%s: joint %r is locked in this robot; its limits are not used", where, joint)
            continue
        if joint not in joint_names:
            raise InvalidLimits(f"{where}: unknown joint {joint!r}; the robot's joints are {', '.join(joint_names)}")
        if not isinstance(entry, dict):
            raise InvalidLimits(f"{where}: joint {joint!r}: expected a mapping of limit keys, got {entry!r}")
        known = {k for pair in _KEYS.values() for k in pair} | set(_POSITION_KEYS)
        for key in entry:
            if key not in known:
                raise InvalidLimits(f"{where}: joint {joint!r}: unknown key {key!r}; expected {sorted(known)}")
        if entry.get("has_position_limits") not in (None, False):
            raise InvalidLimits(f"{where}: joint {joint!r}: has_position_limits: position limits come from the "
                                "robot model (edit its <limit lower upper>); set it to false or leave it out")
        for quantity, (has_key, max_key) in _KEYS.items():
            has = entry.get(has_key)
            if has is not None and not isinstance(has, bool):
                raise InvalidLimits(f"{where}: joint {joint!r}: {has_key} must be true or false, got {has!r}")
            if has is False or (has is None and max_key not in entry):
                continue
            if max_key not in entry:
                raise InvalidLimits(f"{where}: joint {joint!r}: {has_key} is true but {max_key} is missing")
            value = entry[max_key]
            if not _number(value) or not np.isfinite(float(value)) or float(value) <= 0:
                raise InvalidLimits(f"{where}: joint {joint!r}: {max_key} must be a finite number > 0, got {value!r}")
            out[quantity][joint] = float(value)
    return out, scaling, where


def _number(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _load(spec) -> tuple[str, object]:
    if isinstance(spec, dict):
        return "limits dict", spec
    if not isinstance(spec, (str, Path)):
        raise InvalidLimits(f"limits must be the path of a MoveIt-style joint_limits.yaml or a dict, got "
                            f"{type(spec).__name__}")
    import yaml

    path = Path(spec).expanduser()
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidLimits(f"cannot read the limits file {path}: {exc}") from exc
    try:
        return str(path), yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InvalidLimits(f"{path}: not valid YAML ({' '.join(str(exc).split())})") from exc


def apply_limits(robot, spec) -> None:
    """Set the limits of a file or dict (:func:`read_limits_file`) on ``robot``, source ``"user"``
    with the file as detail; the file's default scaling factors become ``robot.limits.scaling``.

    All or nothing: a bad file changes nothing.

    Raises:
        InvalidLimits: see :func:`read_limits_file`.
    """
    values, scaling, where = read_limits_file(spec, robot.joint_names, tuple(robot.locked_joints))
    detail = Path(where).name if where != "limits dict" else where
    table = robot.limits.copy()
    for quantity, per_joint in values.items():
        if per_joint:
            table.set(quantity, list(per_joint.values()), "user", detail, joints=list(per_joint))
    table.scaling.update(scaling)
    robot.limits = table
