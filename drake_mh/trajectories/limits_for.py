"""The limits one retiming enforces, each with its source: declared, user, derived or default.

A robot as shipped (a vendor URDF) declares position, velocity and effort limits and no
acceleration (URDF has no field for it). :func:`enforced_limits` turns what the robot declares
(:attr:`drake_mh.robot.Robot.limits`) into what a retiming method needs, and says where every
value came from (``trajectory.info["enforced_limits"]``):

* **velocity**: the robot's; a joint without one gets :data:`DEFAULT_VELOCITY` (source
  ``"default"``, a warning).
* **torque** (effort, through inverse dynamics with gravity): enforced on the joints that
  declare an effort limit.
* **acceleration**, toppra methods: the robot's where declared. A joint without one is left to
  the torque rows when torque bounds it — its effort limit is declared and its inertia
  ``M_jj(q)`` is not negligible (``> 1e-9`` kg·m² at every waypoint): ``M(q) q̈ = τ - C q̇ - g``
  with every ``|τ_j|`` bounded bounds ``q̈`` — else it gets :data:`DEFAULT_ACCELERATION`
  (``"default"``, a warning). With ``acceleration_scaling < 1``, the joints left to torque get
  a derived bound (below) so that there is something to scale.
* **acceleration**, ruckig (which needs one per joint): declared, else **derived** from the
  effort limits, gravity and the mass matrix along the path (:func:`derived_accelerations`),
  else :data:`DEFAULT_ACCELERATION`.
* **jerk**, ruckig: declared, else :data:`DEFAULT_JERK` (``"default"``, a warning).

Scaling as MoveIt does: ``velocity_scaling`` multiplies every velocity limit,
``acceleration_scaling`` every acceleration limit (jerk and effort are not scaled); ``None``
takes the robot's default factors (a limits file's ``default_*_scaling_factor``, else 1).

Defaults (every one logged once per robot as a warning): the values of MoveIt 2's ruckig
smoothing for joints without limits (``moveit/moveit2``,
``moveit_core/trajectory_processing/src/ruckig_traj_smoothing.cpp``: ``DEFAULT_MAX_VELOCITY = 5``
rad/s, ``DEFAULT_MAX_ACCELERATION = 10`` rad/s², ``DEFAULT_MAX_JERK = 1000`` rad/s³). They are
not a property of any robot: declare the limits (model, ``load_robot(..., limits=...)``,
``robot.*_limits = ...``) where they matter.
"""

from __future__ import annotations

import numbers

import numpy as np

from drake_mh.errors import InfeasibleTrajectory, InvalidArgument, MissingLimits
from drake_mh.robot.limits import JointLimits, limits_of

__all__ = ["enforced_limits", "derived_accelerations", "check_scaling_factor", "DEFAULT_VELOCITY",
           "DEFAULT_ACCELERATION", "DEFAULT_JERK", "DERIVED_MARGIN"]

DEFAULT_VELOCITY = 5.0
"""[rad/s] velocity limit of a joint that declares none (MoveIt 2 ruckig smoothing's default)."""
DEFAULT_ACCELERATION = 10.0
"""[rad/s²] acceleration limit of a joint that declares neither acceleration nor a usable
effort limit (MoveIt 2 ruckig smoothing's default)."""
DEFAULT_JERK = 1000.0
"""[rad/s³] jerk limit of a joint that declares none, for ruckig (MoveIt 2 ruckig smoothing's
default)."""
DERIVED_MARGIN = 0.9
"""Fraction of the acceleration bound found by :func:`derived_accelerations` that is used: the
rest of the torque head-room is left for the velocity terms ``C(q, q̇) q̇`` the rule ignores."""
MIN_INERTIA = 1e-9
"""[kg·m²] a joint whose ``M_jj(q)`` falls below this at a waypoint is not bounded by its torque
(a massless model)."""
PATH_SAMPLES = 32
"""configurations per straight segment between consecutive waypoints where the mass matrix and
gravity are evaluated (both ends included)."""

METHOD_QUANTITIES = {"toppra": ("velocity", "acceleration", "torque"),
                     "drake-toppra": ("velocity", "acceleration", "torque"),
                     "ruckig": ("velocity", "acceleration", "jerk", "torque")}


def check_scaling_factor(value, what: str) -> None:
    """Raise :class:`~drake_mh.errors.InvalidArgument` unless ``value`` is ``None`` or a number in (0, 1]."""
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not np.isfinite(value) \
            or not 0.0 < float(value) <= 1.0:
        raise InvalidArgument(f"{what} must be a number in (0, 1] (a fraction of the {what.split('_')[0]} "
                              f"limits, as MoveIt's scaling factors), got {value!r}")


def _scaling(value, default: float, what: str) -> float:
    check_scaling_factor(value, what)
    return float(default) if value is None else float(value)


def path_samples(W: np.ndarray, per_segment: int = PATH_SAMPLES) -> np.ndarray:
    """``(M, nq)`` configurations on the straight segments through the waypoints ``W (K, nq)``."""
    u = np.linspace(0.0, 1.0, per_segment)[:, None]
    return np.concatenate([W[k] + u * (W[k + 1] - W[k]) for k in range(len(W) - 1)])


def mass_matrices(robot, Q: np.ndarray) -> np.ndarray:
    """``(N, nq, nq)`` joint-space mass matrices ``M(q)`` [kg·m²] (rotor inertia included) at
    ``Q (N, nq)``, column by column from the batched inverse dynamics ``M e_i``."""
    from drake_mh.trajectories.dynamics import batch_dynamics

    dyn = batch_dynamics(robot)
    N, nq = Q.shape
    cols = dyn.inverse_dynamics(np.repeat(Q, nq, axis=0), np.zeros((N * nq, nq)), np.tile(np.eye(nq), (N, 1)),
                                gravity=False)
    return cols.reshape(N, nq, nq).transpose(0, 2, 1)


def derived_accelerations(robot, Q: np.ndarray, effort: np.ndarray, joints: np.ndarray,
                          method: str = "ruckig") -> np.ndarray:
    """Acceleration bounds [rad/s²] for ``joints`` that keep the torque within the effort limits.

    Rule (for rest-to-rest motions whose velocity terms are small; torque is certified anyway,
    and the retiming slows down where it is exceeded): with ``h_j(q) = τ_j - |g_j(q)|`` the
    torque left after holding the arm against gravity at a sampled configuration ``q``,

    1. each joint's own reach ``w_i = min_q h_i(q) / M_ii(q)`` (what joint ``i`` alone could
       accelerate with its head-room);
    2. one common factor ``t = min_{q, j} h_j(q) / Σ_i |M_ji(q)| w_i`` over the effort-limited
       rows ``j``, so that every joint accelerating at ``t w_i`` at once, in the worst sign
       combination, keeps ``Σ_i |M_ji(q)| a_i <= h_j(q)`` at every sample;
    3. ``a_i = DERIVED_MARGIN · t · w_i``.

    Args:
        robot: dynamics.
        Q: ``(N, nq)`` sampled configurations of the path.
        effort: ``(nq,)`` effort limits [N·m] (``inf`` rows are not constraints).
        joints: ``(nq,)`` bool, the joints to derive a bound for (effort-limited, with inertia).
        method: the retimer, for messages.

    Returns:
        ``(nq,)`` bounds, ``inf`` outside ``joints``.

    Raises:
        InfeasibleTrajectory: gravity alone needs the whole effort limit somewhere on the path.
    """
    from drake_mh.trajectories.toppra_time import gravity_torques

    M, G = mass_matrices(robot, Q), gravity_torques(robot, Q)
    head = effort[None, :] - np.abs(G)  # (N, nq), inf on rows without effort limits
    rows = np.isfinite(effort)
    if np.any(head[:, rows] <= 0.0):
        n, j = np.argwhere((head <= 0.0) & rows[None, :])[0]
        raise InfeasibleTrajectory(method, f"holding the arm against gravity on the path needs {abs(G[n, j]):.4g} N·m "
                                   f"on joint {robot.joint_names[j]!r}, at or above its effort limit {effort[j]:.4g} "
                                   "N·m: no speed helps; change the path or the payload")
    out = np.full(len(effort), np.inf)
    if not np.any(joints):
        return out
    diag = np.diagonal(M, axis1=1, axis2=2)  # (N, nq)
    w = np.min(head[:, joints] / diag[:, joints], axis=0)  # (J,)
    load = np.einsum("nji,i->nj", np.abs(M[:, :, joints]), w)  # (N, nq): Σ_i |M_ji| w_i
    t = float(np.min(head[:, rows] / load[:, rows]))
    out[joints] = DERIVED_MARGIN * min(t, 1.0) * w
    return out


def enforced_limits(robot, method: str, W: np.ndarray, quantities=None, velocity_scaling=None,
                    acceleration_scaling=None) -> JointLimits:
    """What ``retime(W, robot, method)`` enforces, with sources (module docstring).

    Args:
        robot: the :class:`~drake_mh.robot.Robot` (or an object with ``joint_names``, ``lower``,
            ``upper`` and the ``*_limits`` arrays).
        method: ``"toppra"``, ``"drake-toppra"`` or ``"ruckig"``.
        W: ``(K, nq)`` checked waypoints (the path the bounds are derived on).
        quantities: asked-for quantities (``velocity``, ``acceleration``, ``jerk``, ``torque``);
            ``None``: the method's defaults.
        velocity_scaling, acceleration_scaling: factors in (0, 1], or ``None`` for the robot's
            defaults.

    Returns:
        A :class:`~drake_mh.robot.limits.JointLimits` whose values are the enforced, scaled
        limits (``inf``: not enforced on that joint), with ``enforced`` and ``scaling`` set.

    Raises:
        InvalidArgument: a scaling factor outside (0, 1].
        MissingLimits: torque asked for on a robot that declares no effort limit.
        InfeasibleTrajectory: gravity alone exceeds an effort limit where a bound is derived.
    """
    table = limits_of(robot).copy()
    v_scale = _scaling(velocity_scaling, table.scaling["velocity"], "velocity_scaling")
    a_scale = _scaling(acceleration_scaling, table.scaling["acceleration"], "acceleration_scaling")
    asked = tuple(METHOD_QUANTITIES[method] if quantities is None else quantities)
    nq = table.nq
    effort = table["effort"]
    if "torque" in asked and not np.any(np.isfinite(effort)) and quantities is not None:
        raise MissingLimits(f"robot {getattr(robot, 'name', '')!r} declares no effort limits, so torque cannot be "
                            "enforced: give them (robot.effort_limits = [...] [N·m], or max_effort in a limits file "
                            "passed to load_robot(..., limits=PATH)), or leave 'torque' out of limits=")
    torque = "torque" in asked and bool(np.any(np.isfinite(effort)))
    lacking = ~table.declared("acceleration")
    if "acceleration" in asked and np.any(lacking):
        inertia = np.min(np.diagonal(mass_matrices(robot, W), axis1=1, axis2=2), axis=0) > MIN_INERTIA
        by_torque = torque & np.isfinite(effort) & inertia
        derive = lacking & by_torque if (method == "ruckig" or quantities is not None or a_scale < 1.0) \
            else np.zeros(nq, dtype=bool)
        default = lacking & ~by_torque
        table.annotate("acceleration", lacking & ~derive & ~default, "bounded through the torque limits")
        if not np.any(derive | default | ~lacking):
            asked = tuple(q for q in asked if q != "acceleration")  # torque bounds every joint
        else:
            if np.any(derive):
                values = derived_accelerations(robot, path_samples(W), effort, derive, method)
                table.set("acceleration", values[derive], "derived",
                          f"effort, gravity and mass matrix on the path, x {DERIVED_MARGIN}", joints=_names(table, derive))
            _default(table, "acceleration", default, DEFAULT_ACCELERATION, "rad/s²")
    if "velocity" in asked:
        _default(table, "velocity", ~table.declared("velocity"), DEFAULT_VELOCITY, "rad/s")
    if "jerk" in asked and method == "ruckig":
        _default(table, "jerk", ~table.declared("jerk"), DEFAULT_JERK, "rad/s³")
    for quantity, factor in (("velocity", v_scale), ("acceleration", a_scale)):
        table.scale(quantity, factor)
    if not torque:
        asked = tuple(q for q in asked if q != "torque")
    table.enforced = tuple("effort" if q == "torque" else q for q in asked)
    return table


def _names(table: JointLimits, joints: np.ndarray) -> list[str]:
    return [n for n, j in zip(table.joint_names, joints) if j]


def _default(table: JointLimits, quantity: str, joints: np.ndarray, value: float, unit: str) -> None:
    if not np.any(joints):
        return
    names = _names(table, joints)
    table.set(quantity, value, "default", "MoveIt 2's ruckig default", joints=names)
    table.warn_once(f"{quantity}-default", f"no {quantity} limit declared on joints {names}: using the default "
                    f"{value:g} {unit} (drake_mh.trajectories.limits_for); declare it in the model, a limits file "
                    f"(load_robot(..., limits=PATH)) or robot.{quantity}_limits")
