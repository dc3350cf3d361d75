"""Trajectories that leave Python: samples at a controller's rate, files, Drake polynomials.

* :func:`sample_trajectory` (``Trajectory.sample(rate_hz, robot)``): time, positions,
  velocities, accelerations and joint torques (gravity included, from the robot's plant) at
  ``rate_hz``, the last sample exactly at the end;
* :func:`save_trajectory` / :func:`load_trajectory` (``Trajectory.save(path, robot)``): by the
  file's extension,

  - ``.json`` / ``.yaml`` / ``.yml``: the shape of ROS 2 ``trajectory_msgs/JointTrajectory``
    without its header: ``joint_names``; ``points``, each with ``positions``, ``velocities``,
    ``accelerations``, ``effort`` and ``time_from_start: {sec, nanosec}``; plus a ``metadata``
    block (robot, method, rate, the enforced limits with their sources, the certificate's
    absolute bounds);
  - ``.csv``: a header row ``time,<joint>_pos...,<joint>_vel...,<joint>_acc...,<joint>_eff...``
    then one row per sample (time in seconds);

  floats are written with Python's shortest round-trip representation, so loading returns the
  same samples (times through ``sec + nanosec``: to 1 ns). Before writing, the samples are
  checked against the limits the trajectory was certified with (:func:`check_samples`).
* :func:`to_drake` (``Trajectory.to_drake()``): a pydrake ``PiecewisePolynomial`` made of the
  trajectory's exact polynomial pieces (``q(t) = path(s(t))`` is one polynomial between two
  consecutive :attr:`~drake_mh.trajectories.trajectory.Trajectory.breaks`, :mod:`.bound`).
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidArgument, InvalidTrajectory, LimitViolation

__all__ = ["TrajectorySamples", "sample_trajectory", "save_trajectory", "load_trajectory", "check_samples",
           "to_drake", "DEFAULT_RATE_HZ", "FORMATS"]

DEFAULT_RATE_HZ = 100.0
"""[Hz] default sampling rate of exported trajectories: ROS 2's ``joint_trajectory_controller``
interpolates between points (splines through positions, velocities and accelerations), so the
points need not come at the controller's own cycle; 100 Hz keeps a few-second motion to a few
hundred points."""
FORMATS = {".json": "json", ".yaml": "yaml", ".yml": "yaml", ".csv": "csv"}
"""File extension -> format."""
EXPORT_TOLERANCE = 1e-6
"""Relative slack of :func:`check_samples` on the certified limits (the certificate's own)."""


@dataclass(frozen=True, eq=False)
class TrajectorySamples:
    """A trajectory sampled in time.

    Attributes:
        t: ``(N,)`` times [s] from the start, increasing; the last one is the end time.
        q, qd, qdd: ``(N, nq)`` positions [rad or m], velocities, accelerations.
        tau: ``(N, nq)`` joint torques [N·m] holding the motion, gravity included (``None``
            when sampled without a robot).
        joint_names: ``(nq,)``.
        metadata: what made it (robot, method, rate, limits and their sources ...).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray | None
    joint_names: tuple[str, ...]
    metadata: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(len(self.t))

    def save(self, path) -> Path:
        """Write the samples as they are (:func:`save_trajectory` for the format); returns the path."""
        return _write(self, Path(path))

    def __repr__(self) -> str:
        return (f"TrajectorySamples({len(self)} samples, {len(self.joint_names)} joints, "
                f"{float(self.t[-1]) if len(self) else 0.0:.6g} s)")


def sample_times(duration: float, rate_hz: float) -> np.ndarray:
    """``(N,)`` times ``0, 1/rate, 2/rate, ...`` up to ``duration`` [s], the last one exactly
    ``duration`` (a last step shorter than ``1/rate`` where the duration is not a whole number of
    periods; one closer than 1 ns to the end is moved onto it).

    Raises:
        InvalidArgument: ``rate_hz`` not a positive finite number.
    """
    if isinstance(rate_hz, bool) or not isinstance(rate_hz, (int, float, np.integer, np.floating)) \
            or not np.isfinite(rate_hz) or rate_hz <= 0:
        raise InvalidArgument(f"rate_hz must be a positive number of samples per second, got {rate_hz!r}")
    n = int(np.floor(duration * rate_hz + 1e-9))
    t = np.arange(n + 1) / float(rate_hz)
    t = t[t < duration - 1e-9]
    return np.append(t, float(duration))


def sample_trajectory(trajectory, rate_hz: float = DEFAULT_RATE_HZ, robot=None) -> TrajectorySamples:
    """Sample ``trajectory`` at ``rate_hz`` (:func:`sample_times`).

    Args:
        trajectory: a :class:`~drake_mh.trajectories.trajectory.Trajectory`.
        rate_hz: samples per second [Hz].
        robot: the :class:`~drake_mh.robot.Robot`, for the torques ``τ = M q̈ + C q̇ + g``
            (batched RNEA compiled from its plant, equal to Drake's inverse dynamics with
            gravity); ``None``: ``tau`` is ``None``.

    Raises:
        InvalidArgument: bad rate, or a robot with other joints.
    """
    t = sample_times(trajectory.duration, rate_hz)
    q, qd, qdd = trajectory.derivatives(trajectory.start_time + t, 2)
    tau = None
    if robot is not None:
        if tuple(robot.joint_names) != tuple(trajectory.joint_names):
            raise InvalidArgument(f"the trajectory's joints {list(trajectory.joint_names)} are not the robot's "
                                  f"{list(robot.joint_names)}")
        from drake_mh.trajectories.dynamics import batch_dynamics

        tau = batch_dynamics(robot).inverse_dynamics(q, qd, qdd)
    cert = trajectory.info.get("certificate")
    table = trajectory.info.get("enforced_limits")
    metadata = {"robot": getattr(robot, "name", None), "method": trajectory.method, "rate_hz": float(rate_hz),
                "duration": float(trajectory.duration), "samples": int(len(t))}
    if table is not None:
        metadata["limits"] = table.as_dict()
    if cert is not None:
        metadata["certificate"] = {"scale": float(cert.scale), "enforced": list(cert.enforced or ()),
                                   "bounds": {k: [float(x) if np.isfinite(x) else None for x in v]
                                              for k, v in getattr(cert, "bounds", {}).items()}}
    return TrajectorySamples(t, q, qd, qdd, tau, tuple(trajectory.joint_names), metadata)


def check_samples(samples: TrajectorySamples, limits, enforced=None, scale: float = 1.0,
                  tol: float = EXPORT_TOLERANCE) -> None:
    """Check samples against limits: position range (but on continuous joints), and ``|q̇|``,
    ``|q̈|``, ``|τ|`` within ``scale x`` the velocity, acceleration and effort limits (``1 + tol``).

    Args:
        samples: the samples.
        limits: a :class:`~drake_mh.robot.limits.JointLimits` (e.g. the trajectory's
            ``info["enforced_limits"]``).
        enforced: quantities to check (certify's names); ``None``: all of them.
        scale: the certificate's scale.
        tol: relative slack.

    Raises:
        LimitViolation: the first joint, quantity and time where a sample exceeds its limit.
    """
    enforced = ("position", "velocity", "acceleration", "torque") if enforced is None else tuple(enforced)
    lo, hi = np.asarray(limits.lower), np.asarray(limits.upper)
    if "position" in enforced:  # not on continuous joints (their range is a default, they may turn on)
        ranged = np.array([s != "default" for s in limits.sources("position")])
        half = np.where(ranged, np.maximum(0.5 * (hi - lo), 1e-12), np.inf)
        r = np.abs(samples.q - 0.5 * (hi + lo)) / half
        _raise_over(samples, r, "position", tol)
    for quantity, values in (("velocity", samples.qd), ("acceleration", samples.qdd), ("torque", samples.tau)):
        if quantity not in enforced or values is None:
            continue
        limit = scale * np.asarray(limits[quantity], dtype=float)
        _raise_over(samples, np.abs(values) / limit, quantity, tol)


def _raise_over(samples, ratios: np.ndarray, quantity: str, tol: float) -> None:
    if np.any(ratios > 1.0 + tol):
        n, j = np.unravel_index(np.argmax(ratios), ratios.shape)
        raise LimitViolation(samples.joint_names[j], quantity, float(samples.t[n]), float(ratios[n, j]), tol,
                             hint="in the exported samples; retime again (a smaller scale) before exporting")


def save_trajectory(trajectory, path, robot=None, rate_hz: float = DEFAULT_RATE_HZ) -> TrajectorySamples:
    """Sample ``trajectory`` at ``rate_hz``, check the samples against the limits it was
    certified with, and write them to ``path`` in the format of its extension (module docstring).

    Args:
        trajectory: a retimed :class:`~drake_mh.trajectories.trajectory.Trajectory`.
        path: ``.json``, ``.yaml``/``.yml`` or ``.csv``.
        robot: for the torques (``effort``) and the limits when the trajectory carries none.
        rate_hz: samples per second [Hz].

    Returns:
        The samples written.

    Raises:
        InvalidArgument: unknown extension, bad rate, or a folder that cannot be written.
        LimitViolation: a sample exceeds a certified limit (:func:`check_samples`).
    """
    path = Path(path)
    _format(path)
    samples = sample_trajectory(trajectory, rate_hz, robot)
    table, cert = trajectory.info.get("enforced_limits"), trajectory.info.get("certificate")
    if table is None and robot is not None:
        from drake_mh.robot.limits import limits_of

        table = limits_of(robot)
    if table is not None:
        enforced = None if cert is None or cert.enforced is None else cert.enforced
        check_samples(samples, table, enforced, cert.scale if cert is not None else 1.0)
    _write(samples, path)
    return samples


def _format(path: Path) -> str:
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise InvalidArgument(f"{path}: unknown trajectory file extension {path.suffix!r}; use "
                              f"{', '.join(FORMATS)} (JSON/YAML: ROS 2 JointTrajectory shape; CSV: one row per sample)")
    return fmt


def _time_from_start(t: float) -> dict:
    sec = int(np.floor(t))
    nanosec = int(round((t - sec) * 1e9))
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return {"sec": sec, "nanosec": nanosec}


def _message(samples: TrajectorySamples) -> dict:
    points = []
    for k in range(len(samples)):
        points.append({"positions": samples.q[k].tolist(), "velocities": samples.qd[k].tolist(),
                       "accelerations": samples.qdd[k].tolist(),
                       "effort": [] if samples.tau is None else samples.tau[k].tolist(),
                       "time_from_start": _time_from_start(float(samples.t[k]))})
    return {"joint_names": list(samples.joint_names), "points": points, "metadata": samples.metadata}


def _columns(names) -> list[str]:
    return ["time"] + [f"{n}_{kind}" for kind in ("pos", "vel", "acc", "eff") for n in names]


def _write(samples: TrajectorySamples, path: Path) -> Path:
    fmt = _format(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if fmt == "csv":
            names = list(samples.joint_names)
            header = _columns(names)
            tau = samples.tau
            if tau is None:
                header = header[:1 + 3 * len(names)]
            with path.open("w", newline="", encoding="utf-8") as handle:
                writer = csv.writer(handle)
                writer.writerow(header)
                for k in range(len(samples)):
                    row = [float(samples.t[k]), *samples.q[k].tolist(), *samples.qd[k].tolist(),
                           *samples.qdd[k].tolist(), *([] if tau is None else tau[k].tolist())]
                    writer.writerow([repr(float(x)) for x in row])
        elif fmt == "json":
            path.write_text(json.dumps(_message(samples), allow_nan=False), encoding="utf-8")
        else:
            import yaml

            path.write_text(yaml.safe_dump(_message(samples), sort_keys=False), encoding="utf-8")
    except OSError as exc:
        raise InvalidArgument(f"cannot write the trajectory to {path}: {exc.strerror or exc}") from exc
    return path


def load_trajectory(path) -> TrajectorySamples:
    """Read samples written by :func:`save_trajectory` (or any file of the same shape).

    Raises:
        InvalidArgument: unknown extension.
        InvalidTrajectory: unreadable file, missing fields, rows of the wrong length, times not
            increasing (the message names the file and what is wrong).
    """
    path = Path(path)
    fmt = _format(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidTrajectory(f"cannot read {path}: {exc}", "path") from exc
    if fmt == "csv":
        return _from_csv(text, path)
    import yaml

    try:
        data = json.loads(text) if fmt == "json" else yaml.safe_load(text)
    except (ValueError, yaml.YAMLError) as exc:  # json.JSONDecodeError is a ValueError
        raise InvalidTrajectory(f"{path}: not valid {fmt.upper()} ({' '.join(str(exc).split())[:200]})", "path") from exc
    return _from_message(data, path)


def _from_message(data, path: Path) -> TrajectorySamples:
    if not isinstance(data, dict) or "joint_names" not in data or "points" not in data:
        raise InvalidTrajectory(f"{path}: expected a JointTrajectory mapping with 'joint_names' and 'points'", "path")
    names = data["joint_names"]
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise InvalidTrajectory(f"{path}: 'joint_names' must be a non-empty list of names", "joint_names")
    nq, points = len(names), data["points"]
    if not isinstance(points, list) or not points:
        raise InvalidTrajectory(f"{path}: 'points' must be a non-empty list", "points")
    t, rows = [], {k: [] for k in ("positions", "velocities", "accelerations", "effort")}
    for i, point in enumerate(points):
        if not isinstance(point, dict):
            raise InvalidTrajectory(f"{path}: point {i} is not a mapping", "points")
        stamp = point.get("time_from_start")
        if not isinstance(stamp, dict) or not all(isinstance(stamp.get(k), int) for k in ("sec", "nanosec")):
            raise InvalidTrajectory(f"{path}: point {i}: time_from_start must be {{sec: int, nanosec: int}}", "points")
        t.append(stamp["sec"] + stamp["nanosec"] * 1e-9)
        for key, values in rows.items():
            value = point.get(key, [])
            if key == "effort" and value == []:
                values.append(None)
                continue
            if not isinstance(value, list) or len(value) != nq:
                raise InvalidTrajectory(f"{path}: point {i}: '{key}' must list {nq} numbers (one per joint)", key)
            values.append(value)
    effort = rows.pop("effort")
    if any(e is None for e in effort) and not all(e is None for e in effort):
        raise InvalidTrajectory(f"{path}: 'effort' is given on some points only", "effort")
    arrays = [_numbers(rows[k], path, k) for k in ("positions", "velocities", "accelerations")]
    tau = None if effort[0] is None else _numbers(effort, path, "effort")
    metadata = data.get("metadata") or {}
    return TrajectorySamples(_times(t, path), *arrays, tau, tuple(names), metadata if isinstance(metadata, dict) else {})


def _numbers(rows, path: Path, what: str) -> np.ndarray:
    try:
        arr = np.array(rows, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidTrajectory(f"{path}: '{what}' must be numbers", what) from exc
    if not np.all(np.isfinite(arr)):
        raise InvalidTrajectory(f"{path}: '{what}' contains NaN or inf", what)
    return arr


def _times(t, path: Path) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    if len(t) > 1 and np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise InvalidTrajectory(f"{path}: times must increase; sample {k + 1} is not after sample {k}", "t")
    return t


def _from_csv(text: str, path: Path) -> TrajectorySamples:
    reader = list(csv.reader(text.splitlines()))
    if len(reader) < 2:
        raise InvalidTrajectory(f"{path}: expected a header row and at least one sample row", "path")
    header = [h.strip() for h in reader[0]]
    blocks = 4 if header[-1].endswith("_eff") else 3
    if header[0] != "time" or len(header) < 1 + blocks or (len(header) - 1) % blocks:
        raise InvalidTrajectory(f"{path}: the header must be time,<joint>_pos...,<joint>_vel...,<joint>_acc..."
                                "[,<joint>_eff...]", "header")
    nq = (len(header) - 1) // blocks
    names = [h[: -len("_pos")] for h in header[1:1 + nq]]
    if header != _columns(names)[:1 + blocks * nq]:
        raise InvalidTrajectory(f"{path}: the header must be {','.join(_columns(names)[:1 + blocks * nq])}", "header")
    data = _numbers([row for row in reader[1:] if row], path, "rows")
    if data.ndim != 2 or data.shape[1] != len(header):
        raise InvalidTrajectory(f"{path}: every row needs {len(header)} values", "rows")
    cols = [data[:, 1 + k * nq: 1 + (k + 1) * nq] for k in range(blocks)]
    return TrajectorySamples(_times(data[:, 0], path), cols[0], cols[1], cols[2], cols[3] if blocks == 4 else None,
                             tuple(names), {})


# --- Drake ----------------------------------------------------------------------------------------


def piece_coefficients(trajectory) -> np.ndarray:
    """``(P, d + 1, nq)`` coefficients of ``q(t)`` on each piece between consecutive breaks, in
    ascending powers of ``t - breaks[k]`` (exact composition ``path(s(t))``, :mod:`.bound`)."""
    from numpy.polynomial import polynomial as npoly

    from drake_mh.trajectories.polynomials import shift_coefficients

    breaks = trajectory.breaks
    nq = trajectory.nq
    if trajectory.timing is None:
        path = trajectory.path
        idx = np.clip(np.searchsorted(path.x, 0.5 * (breaks[:-1] + breaks[1:]), side="right") - 1, 0, len(path.x) - 2)
        c = np.stack([shift_coefficients(path.c[:, i], b - path.x[i]) for i, b in zip(idx, breaks[:-1])])
        return c[:, ::-1, :]
    path, timing = trajectory.path, trajectory.timing
    d_p, d_s = path.c.shape[0] - 1, timing.c.shape[0] - 1
    out = np.zeros((len(breaks) - 1, d_p * d_s + 1, nq))
    mids = 0.5 * (breaks[:-1] + breaks[1:])
    j_idx = np.clip(np.searchsorted(timing.x, mids, side="right") - 1, 0, len(timing.x) - 2)
    i_idx = np.clip(np.searchsorted(path.x, timing(mids), side="right") - 1, 0, len(path.x) - 2)
    for k, (j, i) in enumerate(zip(j_idx, i_idx)):
        s = shift_coefficients(timing.c[:, j], breaks[k] - timing.x[j])[::-1].copy()  # ascending in t - b_k
        s[0] -= path.x[i]  # u = s(t) - x_i
        power = np.array([1.0])
        for m in range(d_p + 1):  # term u^m with coefficient path.c[d_p - m]
            out[k, : len(power)] += power[:, None] * path.c[d_p - m, i][None, :]
            power = npoly.polymul(power, s)
    return out


def to_drake(trajectory):
    """The trajectory as a pydrake ``PiecewisePolynomial`` (``nq x 1`` values), one exact
    polynomial per piece between :attr:`~drake_mh.trajectories.trajectory.Trajectory.breaks`
    (degree 6 for toppra, 9 for Drake's Toppra, 3 for ruckig)."""
    from pydrake.polynomial import Polynomial
    from pydrake.trajectories import PiecewisePolynomial

    coefficients = piece_coefficients(trajectory)
    polys = [np.array([[Polynomial(c[:, j])] for j in range(trajectory.nq)], dtype=object) for c in coefficients]
    return PiecewisePolynomial(polys, [float(b) for b in trajectory.breaks])
