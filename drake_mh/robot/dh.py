"""Denavit-Hartenberg table -> URDF text that Drake loads.

A serial arm of revolute joints described by a DH table (framework paper, eqs. (1)-(2);
Craig's modified convention for the Panda) is written out as a URDF with everything the
rest of drake_mh needs from a robot model:

* kinematics: one ``revolute`` joint per DH row, a fixed joint welding the base link to
  ``world`` and a terminal end-effector link (``ee``) welded at the last DH frame times an
  optional tool offset. The end effector is the unique leaf link of the tree.
* limits: ``<limit lower upper velocity effort>`` plus ``drake:acceleration`` (parsed by
  Drake) and ``drake_mh:jerk`` (ignored by Drake, read by drake_mh).
* actuators: one ``SimpleTransmission`` per joint, without which Drake creates no actuator
  and ``MultibodyPlant.GetEffortUpperLimits()`` is empty.
* inertia: an ``<inertial>`` on every moving link, given per link or derived from the
  link's collision capsules as a solid of uniform effective density (see
  :func:`capsule_inertia`).
* geometry: capsules and spheres only (collision and identical visual elements), by
  default one capsule of radius ``link_radius`` per straight piece of the link, from joint
  to joint, so that the sphere model and Drake's exact signed distance are cheap and tight.

Frames (Drake monogram notation): ``W`` world, ``B`` base link, ``L_i`` the body frame of
link i, ``N`` the last DH frame, ``E`` the end effector. Units: metres, radians, kilograms.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument, InvalidDHTable, InvalidLimits
from drake_mh.robot.inertia import capsule_inertia, combine_inertias
from drake_mh.robot.loading import DRAKE_MH_NS, DRAKE_NS

__all__ = [
    "Capsule",
    "Sphere",
    "LinkSpec",
    "dh_to_urdf",
    "dh_transform",
    "capsule_inertia",
    "DRAKE_NS",
    "DRAKE_MH_NS",
]

CONVENTIONS = ("standard", "modified")

#: Default effective density of a link [kg/m^3] when its mass is not given: the solid
#: capsule envelope stands for shell, motor, gear and cables averaged over the volume.
#: The Panda's identified masses (Gaz et al. 2019) over the volume of its bundled capsules
#: give the same order (see docs/robots.md), and 1000 kg/m^3 keeps the numbers legible.
DEFAULT_DENSITY = 1000.0
#: Default joint speed limit [rad/s] (180 deg/s, typical of small arms) when none is given:
#: URDF requires ``velocity`` and Drake reads ``velocity="0"`` as a locked joint.
DEFAULT_VELOCITY = math.pi
#: Default factor applied to the worst-case static gravity torque to size effort limits.
DEFAULT_EFFORT_MARGIN = 2.0
GRAVITY = 9.81  # [m/s^2]


# --- geometry -------------------------------------------------------------------------


@dataclass(frozen=True)
class Capsule:
    """A capsule: all points within ``radius`` of the segment A-B, in the link frame L.

    Attributes:
        p_LA: first end point of the axis [m].
        p_LB: second end point of the axis [m] (equal to ``p_LA`` gives a sphere).
        radius: radius [m], > 0.
    """

    p_LA: tuple[float, float, float]
    p_LB: tuple[float, float, float]
    radius: float


@dataclass(frozen=True)
class Sphere:
    """A sphere of ``radius`` [m] centred at ``p_LC`` [m] in the link frame L."""

    p_LC: tuple[float, float, float]
    radius: float


@dataclass(frozen=True)
class LinkSpec:
    """Optional per-link overrides of what :func:`dh_to_urdf` derives.

    Attributes:
        mass: link mass [kg]. Without ``inertia`` the derived inertia is scaled to it.
        com: centre of mass ``p_LCm`` in the link frame [m]; default: derived.
        inertia: ``(ixx, ixy, ixz, iyy, iyz, izz)`` [kg m^2], tensor entries about the
            centre of mass, axes of the link frame (URDF convention). Needs ``mass``.
        collision: shapes replacing the default joint-to-joint capsules.
    """

    mass: float | None = None
    com: tuple[float, float, float] | None = None
    inertia: tuple[float, float, float, float, float, float] | None = None
    collision: tuple[Capsule | Sphere, ...] | None = None


def _mul(*mats) -> np.ndarray:
    """Product of 4x4 matrices, each entry an exactly rounded sum (``math.fsum``), no BLAS.

    The generated URDF text must not depend on the CPU: numpy's ``@`` goes through BLAS, whose
    kernels (AVX2 vs AVX-512) round differently in the last bit, which then shows in the
    printed numbers. Products of IEEE doubles and ``fsum`` are the same on every CPU.
    """
    out = np.asarray(mats[0], float)
    for M in mats[1:]:
        M = np.asarray(M, float)
        out = np.array([[math.fsum(out[i, k] * M[k, j] for k in range(4)) for j in range(4)]
                        for i in range(4)])
    return out


def _rx(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rz(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _tr(x, y, z):
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def dh_transform(a: float, alpha: float, d: float, theta: float, convention="standard"):
    """One DH link transform ``X_{i-1,i}`` (4x4).

    ``standard``: framework paper eq. (2), ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``.
    ``modified`` (Craig): ``Rx(alpha) Tx(a) Rz(theta) Tz(d)`` with ``a, alpha`` the row's
    values, i.e. Craig's ``a_{i-1}, alpha_{i-1}`` (as in the Panda table of REFERENCES.md).
    """
    if convention == "standard":
        return _mul(_rz(theta), _tr(0, 0, d), _tr(a, 0, 0), _rx(alpha))
    if convention == "modified":
        return _mul(_rx(alpha), _tr(a, 0, 0), _rz(theta), _tr(0, 0, d))
    raise InvalidDHTable(f"unknown DH convention {convention!r}; use one of {CONVENTIONS}")


def _rpy(R) -> tuple[float, float, float]:
    """URDF roll-pitch-yaw of R = Rz(yaw) Ry(pitch) Rx(roll)."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) < 1e-12:  # gimbal lock: put everything in yaw
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


def _num(x: float) -> str:
    """Shortest round-trip text of a float; |x| < 1e-14 (cos(pi/2) residue) -> 0."""
    x = float(x)
    return "0" if abs(x) < 1e-14 else repr(x).removesuffix(".0")


def _vec(v) -> str:
    return " ".join(_num(x) for x in v)


def _origin(X) -> str:
    """``<origin>`` of a 4x4 pose; rpy exact for pure x rotations (the DH twists)."""
    R = X[:3, :3]
    if abs(R[0, 0] - 1) < 1e-15 and not R[0, 1:].any() and not R[1:, 0].any():
        rpy = (math.atan2(R[2, 1], R[1, 1]), 0.0, 0.0)
    else:
        rpy = _rpy(R)
    return f'<origin xyz="{_vec(X[:3, 3])}" rpy="{_vec(rpy)}"/>'


# --- validation -----------------------------------------------------------------------


#: largest magnitude accepted in a DH table or its limits (1e200 m overflowed the reach sums)
MAX_MAGNITUDE = 1e6


def _column(values, name, n=None, default=None, error=InvalidDHTable, positive=False):
    if values is None:
        if default is None:
            return None
        values = default
    if np.iscomplexobj(values):
        raise error(f"{name} must be real numbers, got complex values")
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{name} must be numbers (one per joint), got {values!r}") from None
    if arr.ndim == 0 and n is not None:
        arr = np.full(n, float(arr))
    if arr.ndim != 1:
        raise error(f"{name} must be a 1-D sequence (one value per joint), got shape {arr.shape}")
    if n is not None and len(arr) != n:
        raise error(
            f"{name} has {len(arr)} values but the DH table has {n} rows; "
            f"give exactly one value per joint (or a scalar for all)"
        )
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise error(f"{name}[{int(bad[0])}] = {arr[bad[0]]} is not finite; give finite numbers")
    huge = np.flatnonzero(np.abs(arr) > MAX_MAGNITUDE)
    if huge.size:
        raise error(f"{name}[{int(huge[0])}] = {arr[huge[0]]:g} is beyond {MAX_MAGNITUDE:g} (metres, radians, "
                    "kg, N m ...): check the units")
    if positive and (arr <= 0).any():
        i = int(np.flatnonzero(arr <= 0)[0])
        raise error(
            f"{name}[{i}] = {arr[i]} must be > 0 (0 locks the joint or drops its actuator "
            "in Drake); pass None to use the documented default"
        )
    return arr


def _pose(X, name):
    if X is None:
        return np.eye(4)
    X = np.asarray(X, dtype=float)
    if X.shape != (4, 4) or not np.isfinite(X).all():
        raise InvalidArgument(f"{name} must be a finite 4x4 homogeneous transform, got shape {X.shape}")
    R = X[:3, :3]
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0 or not np.allclose(
        X[3], [0, 0, 0, 1]
    ):
        raise InvalidArgument(f"{name} is not a rigid transform (orthonormal rotation, last row 0 0 0 1)")
    return X


def _check_shapes(shapes, where):
    for s in shapes:
        pts = (s.p_LA, s.p_LB) if isinstance(s, Capsule) else (s.p_LC,) if isinstance(s, Sphere) else None
        if pts is None:
            raise InvalidArgument(f"{where}: collision shapes must be Capsule or Sphere, got {type(s).__name__}")
        if not (np.isfinite(np.asarray(pts, float)).all() and np.isfinite(s.radius) and s.radius > 0):
            raise InvalidArgument(f"{where}: shape {s} needs finite points and a radius > 0")


# --- the generator --------------------------------------------------------------------


def dh_to_urdf(
    a,
    alpha,
    d,
    offset=None,
    lower=None,
    upper=None,
    *,
    convention: str = "standard",
    name: str = "dh_robot",
    velocity_limits=None,
    effort_limits=None,
    acceleration_limits=None,
    jerk_limits=None,
    link_radius=0.04,
    density: float = DEFAULT_DENSITY,
    links: Sequence[LinkSpec | None] | None = None,
    base: LinkSpec | None = None,
    tool=None,
    X_WB=None,
    prefix: str = "",
    ee_name: str = "ee",
    effort_margin: float = DEFAULT_EFFORT_MARGIN,
    header: str = "",
    rgba: str = "0.85 0.55 0.1 1",
) -> str:
    """Write a URDF of a revolute serial arm from its DH table.

    Joint i (1-based) has variable ``q_i`` and DH angle ``theta_i = q_i + offset_i``.
    Link frames: ``standard`` (framework paper eq. (2), ``X_{i-1,i} = Rz(theta_i) Tz(d_i)
    Tx(a_i) Rx(alpha_i)``): the body frame of link i is DH frame i-1 rotated by
    ``theta_i`` (it sits on joint i's axis); the last DH frame N is fixed in link n.
    ``modified`` (Craig, ``X_{i-1,i} = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)``):
    the body frame of link i is DH frame i (for the Panda: the Franka URDF frames, in which
    Gaz et al. give their inertias). ``FK(ee) = X_WB * prod_i X_{i-1,i} * tool``.

    Args:
        a: link lengths [m], one per joint. For ``modified`` row i holds Craig's a_{i-1}.
        alpha: link twists [rad]. For ``modified`` row i holds Craig's alpha_{i-1}.
        d: link offsets [m] along joint i's axis.
        offset: joint angle offsets [rad]; default 0 (theta = q).
        lower, upper: position limits [rad]; default -pi, +pi (one turn each side of
            the zero is the usual range of a revolute joint without published limits).
        convention: ``"standard"`` or ``"modified"``.
        name: robot name in the URDF.
        velocity_limits: [rad/s], scalar or one per joint; default pi rad/s
            (:data:`DEFAULT_VELOCITY`) because URDF requires it and 0 locks the joint.
        effort_limits: [N m], scalar or one per joint; default ``effort_margin`` times a
            worst-case static gravity torque bound: ``g * sum_{j>=i} m_j r_ij`` with
            ``r_ij`` the chain length from joint i to the centre of mass of link j (every
            outboard link stretched horizontally), rounded up to 2 significant digits.
            Needed: without it Drake creates no actuator.
        acceleration_limits: [rad/s^2] -> ``drake:acceleration``; default: omitted.
        jerk_limits: [rad/s^3] -> ``drake_mh:jerk``; default: omitted.
        link_radius: radius [m] of the default capsules (scalar or one per link).
        density: effective density [kg/m^3] for derived masses (:data:`DEFAULT_DENSITY`).
        links: per-link :class:`LinkSpec` overrides (``None`` entries keep defaults).
        base: :class:`LinkSpec` for the base link (geometry only; default: a sphere of
            ``link_radius[0]`` at the base origin).
        tool: 4x4 pose ``X_NE`` of the end effector in the last DH frame; default identity.
        X_WB: 4x4 pose of the base link in world; default identity.
        prefix: name prefix: links ``{prefix}link0..n``, joints ``{prefix}joint1..n``.
        ee_name: name of the end-effector link (``ee``; ``panda_link8`` for the Panda).
        effort_margin: factor of the default effort limits.
        header: text put in the leading XML comment (provenance, interpretations).
        rgba: colour of the visual capsules.

    Returns:
        The URDF text (declares ``xmlns:drake`` and ``xmlns:drake_mh``).

    Raises:
        InvalidDHTable: columns of different lengths, an empty table, non-finite values,
            unknown convention.
        InvalidLimits: lower > upper, non-finite position limits, non-positive or
            non-finite velocity/effort/acceleration/jerk limits, wrong number of values.
        InvalidArgument: bad tool/X_WB pose, bad link overrides, radius or density <= 0.
    """
    if convention not in CONVENTIONS:
        raise InvalidDHTable(
            f"unknown DH convention {convention!r}; use 'standard' (framework paper eq. (2)) "
            "or 'modified' (Craig, e.g. the Panda)"
        )
    cols = {"a": a, "alpha": alpha, "d": d}
    arrs = {k: _column(v, k) for k, v in cols.items()}
    lengths = {k: len(v) for k, v in arrs.items()}
    if len(set(lengths.values())) != 1:
        raise InvalidDHTable(
            f"DH columns have different lengths {lengths}; every column needs one value per joint"
        )
    n = lengths["a"]
    if n == 0:
        raise InvalidDHTable("the DH table is empty; give at least one row (joint)")
    a, alpha, d = arrs["a"], arrs["alpha"], arrs["d"]
    offset = _column(offset, "offset", n, default=0.0)
    lo = _column(lower, "lower", n, default=-math.pi, error=InvalidLimits)
    hi = _column(upper, "upper", n, default=math.pi, error=InvalidLimits)
    bad = np.flatnonzero(lo > hi)
    if bad.size:
        i = int(bad[0])
        raise InvalidLimits(
            f"joint {i + 1}: lower limit {lo[i]} > upper limit {hi[i]} [rad]; swap them or fix the table"
        )
    lim = dict(error=InvalidLimits, positive=True)
    vel = _column(velocity_limits, "velocity_limits", n, default=DEFAULT_VELOCITY, **lim)
    eff = _column(effort_limits, "effort_limits", n, **lim)
    acc = _column(acceleration_limits, "acceleration_limits", n, **lim)
    jerk = _column(jerk_limits, "jerk_limits", n, **lim)
    radius = _column(link_radius, "link_radius", n, error=InvalidArgument, positive=True)
    if not (np.isfinite(density) and density > 0):
        raise InvalidArgument(f"density must be a positive number of kg/m^3, got {density}")
    if not (np.isfinite(effort_margin) and effort_margin > 0):
        raise InvalidArgument(f"effort_margin must be > 0, got {effort_margin}")
    links = list(links) if links is not None else [None] * n
    if len(links) != n:
        raise InvalidArgument(f"links has {len(links)} entries for {n} joints; give one (or None) per link")
    tool = _pose(tool, "tool")
    X_WB = _pose(X_WB, "X_WB")

    # Joint origins X_{L(i-1), J_i} and each link's joint-to-joint polyline (link frame).
    origins, paths = [], []
    for i in range(n):
        if convention == "standard":
            prev = np.eye(4) if i == 0 else _mul(_tr(a[i - 1], 0, d[i - 1]), _rx(alpha[i - 1]))
            origins.append(_mul(prev, _rz(offset[i])))
        else:
            origins.append(_mul(_rx(alpha[i]), _tr(a[i], 0, 0), _tr(0, 0, d[i]), _rz(offset[i])))
    X_LnN = _mul(_tr(a[-1], 0, d[-1]), _rx(alpha[-1])) if convention == "standard" else np.eye(4)
    X_LnE = _mul(X_LnN, tool)
    for i in range(n):
        if convention == "standard":
            pts = [(0, 0, 0), (0, 0, d[i]), (a[i], 0, d[i])]
            if i == n - 1:
                pts.append(tuple(X_LnE[:3, 3]))
        elif i < n - 1:
            nxt = origins[i + 1][:3, 3]
            pts = [(0, 0, 0), (a[i + 1], 0, 0), tuple(nxt)]
        else:
            pts = [(0, 0, 0), tuple(X_LnE[:3, 3])]
        paths.append([np.asarray(p, float) for p in pts])

    # Shapes, inertials.
    shapes, inertials, path_len = [], [], []
    for i in range(n):
        spec = links[i] or LinkSpec()
        if not isinstance(spec, LinkSpec):
            raise InvalidArgument(f"links[{i}] must be a LinkSpec or None, got {type(spec).__name__}")
        pts = paths[i]
        segs = [(p, q) for p, q in zip(pts, pts[1:]) if math.hypot(*(q - p)) > 1e-12]
        path_len.append(sum(math.hypot(*(q - p)) for p, q in segs))
        default = tuple(Capsule(tuple(p), tuple(q), float(radius[i])) for p, q in segs) or (
            Sphere((0.0, 0.0, 0.0), float(radius[i])),
        )
        shp = tuple(spec.collision) if spec.collision is not None else default
        _check_shapes(shp, f"link {i + 1}")
        shapes.append(shp)
        parts = [
            capsule_inertia(s.p_LA, s.p_LB, s.radius, density)
            if isinstance(s, Capsule)
            else capsule_inertia(s.p_LC, s.p_LC, s.radius, density)
            for s in shp
        ]
        m, com, I = combine_inertias(parts)
        if spec.inertia is not None and spec.mass is None:
            raise InvalidArgument(f"links[{i}]: an inertia needs its mass; give LinkSpec(mass=..., inertia=...)")
        if spec.mass is not None:
            if not (np.isfinite(spec.mass) and spec.mass > 0):
                raise InvalidArgument(f"links[{i}].mass = {spec.mass} must be > 0 [kg]")
            I = I * (spec.mass / m)
            m = float(spec.mass)
        if spec.com is not None:
            com = np.asarray(spec.com, float)
        if spec.inertia is not None:
            ixx, ixy, ixz, iyy, iyz, izz = (float(v) for v in spec.inertia)
            I = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        ev = np.linalg.eigvalsh(I)
        if not np.isfinite(I).all() or ev[0] < 0 or 2 * ev.max() > ev.sum() * (1 + 1e-9):
            raise InvalidArgument(
                f"links[{i}]: inertia {I.tolist()} is not physical (principal moments must be "
                "non-negative and satisfy the triangle inequality)"
            )
        inertials.append((m, com, I))

    if eff is None:
        eff = np.empty(n)
        for i in range(n):
            torque, reach = 0.0, 0.0
            for j in range(i, n):
                m_j, com_j, _ = inertials[j]
                torque += GRAVITY * m_j * (reach + math.hypot(*com_j))
                reach += path_len[j]
            eff[i] = _round_up(effort_margin * torque)

    L = [f"{prefix}link{i}" for i in range(n + 1)]
    J = [f"{prefix}joint{i}" for i in range(1, n + 1)]
    base = base or LinkSpec()
    base_shapes = base.collision if base.collision is not None else (Sphere((0.0, 0.0, 0.0), float(radius[0])),)
    _check_shapes(base_shapes, "base")

    out = ['<?xml version="1.0"?>', "<!--"]
    out += [
        f"  {name}: generated by drake_mh.robot.dh.dh_to_urdf ({convention} DH), do not edit by hand.",
        f"  The end effector is the link '{ee_name}', the unique leaf link of the tree, welded at",
        "  the last DH frame (times the tool offset). Units: metres, radians, kilograms.",
        "  Limits: velocity [rad/s], effort [N m], drake:acceleration [rad/s^2],",
        "  drake_mh:jerk [rad/s^3]. Geometry: capsules and spheres only.",
    ]
    out += ["  " + line if line else "" for line in header.strip("\n").splitlines()]
    out += ["-->", f'<robot name="{name}" xmlns:drake="{DRAKE_NS}" xmlns:drake_mh="{DRAKE_MH_NS}">']
    out.append(f'  <material name="{name}_colour"><color rgba="{rgba}"/></material>')
    out.append(f'  <link name="{L[0]}">')
    out += _shape_xml(base_shapes, L[0], name)
    out.append("  </link>")
    out.append(f'  <joint name="{prefix}world_weld" type="fixed">')
    out.append(f'    <parent link="world"/><child link="{L[0]}"/>')
    out.append(f"    {_origin(X_WB)}")
    out.append("  </joint>")
    for i in range(n):
        m, com, I = inertials[i]
        out.append(f'  <link name="{L[i + 1]}">')
        out.append("    <inertial>")
        out.append(f'      <origin xyz="{_vec(com)}" rpy="0 0 0"/>')
        out.append(f'      <mass value="{_num(m)}"/>')
        out.append(
            f'      <inertia ixx="{_num(I[0, 0])}" ixy="{_num(I[0, 1])}" ixz="{_num(I[0, 2])}" '
            f'iyy="{_num(I[1, 1])}" iyz="{_num(I[1, 2])}" izz="{_num(I[2, 2])}"/>'
        )
        out.append("    </inertial>")
        out += _shape_xml(shapes[i], L[i + 1], name)
        out.append("  </link>")
        out.append(f'  <joint name="{J[i]}" type="revolute">')
        out.append(f'    <parent link="{L[i]}"/><child link="{L[i + 1]}"/>')
        out.append(f"    {_origin(origins[i])}")
        out.append('    <axis xyz="0 0 1"/>')
        extra = f' drake:acceleration="{_num(acc[i])}"' if acc is not None else ""
        extra += f' drake_mh:jerk="{_num(jerk[i])}"' if jerk is not None else ""
        out.append(
            f'    <limit lower="{_num(lo[i])}" upper="{_num(hi[i])}" velocity="{_num(vel[i])}" '
            f'effort="{_num(eff[i])}"{extra}/>'
        )
        out.append("  </joint>")
    out.append(f'  <link name="{ee_name}"/>')
    out.append(f'  <joint name="{prefix}ee_fixed" type="fixed">')
    out.append(f'    <parent link="{L[n]}"/><child link="{ee_name}"/>')
    out.append(f"    {_origin(X_LnE)}")
    out.append("  </joint>")
    for j in J:
        out += [
            f'  <transmission name="{j}_transmission">',
            "    <type>transmission_interface/SimpleTransmission</type>",
            f'    <joint name="{j}"><hardwareInterface>hardware_interface/EffortJointInterface'
            "</hardwareInterface></joint>",
            f'    <actuator name="{j}_motor"><mechanicalReduction>1</mechanicalReduction></actuator>',
            "  </transmission>",
        ]
    out.append("</robot>")
    return "\n".join(out) + "\n"


def _round_up(x: float, digits: int = 2) -> float:
    """Round ``x > 0`` up to ``digits`` significant digits (e.g. 23.41 -> 24)."""
    if x <= 0:
        return 1.0
    scale = 10 ** (math.floor(math.log10(x)) - digits + 1)
    return round(math.ceil(x / scale - 1e-9) * scale, 12)


def _shape_xml(shapes, link: str, robot: str) -> list[str]:
    """``<collision>`` and identical ``<visual>`` elements of capsules and spheres."""
    out = []
    for k, s in enumerate(shapes):
        if isinstance(s, Sphere) or np.allclose(s.p_LA, s.p_LB, atol=1e-12):
            c = s.p_LC if isinstance(s, Sphere) else s.p_LA
            origin = f'<origin xyz="{_vec(c)}" rpy="0 0 0"/>'
            geom = f'<sphere radius="{_num(s.radius)}"/>'
            kind = "sphere"
        else:
            A, B = np.asarray(s.p_LA, float), np.asarray(s.p_LB, float)
            length = math.hypot(*(B - A))
            u = (B - A) / length
            X = np.eye(4)
            X[:3, :3] = _z_to(u)
            X[:3, 3] = (A + B) / 2
            origin = _origin(X)
            geom = f'<capsule radius="{_num(s.radius)}" length="{_num(length)}"/>'
            kind = "capsule"
        for tag in ("collision", "visual"):
            mat = f'<material name="{robot}_colour"/>' if tag == "visual" else ""
            out.append(
                f'    <{tag} name="{link}_{kind}{k}">{origin}<geometry>{geom}</geometry>{mat}</{tag}>'
            )
    return out


def _z_to(u):
    """A rotation whose z axis is the unit vector u (exact for the coordinate axes)."""
    u = np.asarray(u, float)
    if np.allclose(u, [0, 0, 1], atol=1e-15):
        return np.eye(3)
    if np.allclose(u, [0, 0, -1], atol=1e-15):
        return np.diag([1.0, -1.0, -1.0])
    for k in (0, 1):  # along x or y: an exact quarter turn about y or x
        e_k = np.eye(3)[k] * math.copysign(1.0, u[k])
        if np.abs(u - e_k).max() < 1e-15:
            if k == 0:
                return _ry3(math.copysign(math.pi / 2, u[0]))
            return _rx(-math.copysign(math.pi / 2, u[1]))[:3, :3]
    z = u
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= math.hypot(*x)
    return np.column_stack([x, np.cross(z, x), z])


def _ry3(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
