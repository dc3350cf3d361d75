#!/usr/bin/env python
"""Generate every bundled robot model in ``drake_mh/urdf/`` from its DH table.

Run ``python scripts/generate_urdfs.py`` after changing a table below; the files are
checked in and ``tests/robot/test_urdf_models.py`` asserts they equal this script's output, so
they are never edited by hand. ``python scripts/generate_urdfs.py --check`` exits 1 when a
checked-in file is stale. Sources and interpretations are in each file's header and in
``docs/robots.md``.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

import numpy as np

from drake_mh.robot.dh import Capsule, LinkSpec, Sphere, dh_to_urdf

URDF_DIR = Path(__file__).resolve().parents[1] / "drake_mh" / "urdf"
PI = math.pi


def _tz(z: float) -> np.ndarray:
    X = np.eye(4)
    X[2, 3] = z
    return X


# --- Franka Emika Panda ------------------------------------------------------------------
# Kinematics and limits: Franka's published modified-DH table and joint limits (see
# /work/shared/REFERENCES.md "Robots"). Inertial parameters: Gaz, Cognetti, Oliva,
# Robuffo Giordano, De Luca, IEEE RA-L 4(4):4147-4154, 2019, supplementary Tables VIII-IX
# as published in github.com/marcocognetti/FrankaEmikaPandaDynModel: mass [kg], centre of
# mass in the link (= modified-DH = Franka URDF) frame [m], inertia tensor about the centre
# of mass (ixx, ixy, ixz, iyy, iyz, izz) [kg m^2]. Link 7 is the bare flange link (no hand).
PANDA_MASS = (4.970684, 0.646926, 3.228604, 3.587895, 1.225946, 1.666555, 0.735522)
PANDA_COM = (
    (3.875e-03, 2.081e-03, 0.0),
    (-3.141e-03, -2.872e-02, 3.495e-03),
    (2.7518e-02, 3.9252e-02, -6.6502e-02),
    (-5.317e-02, 1.04419e-01, 2.7454e-02),
    (-1.1953e-02, 4.1065e-02, -3.8437e-02),
    (6.0149e-02, -1.4117e-02, -1.0517e-02),
    (1.0517e-02, -4.252e-03, 6.1597e-02),
)
PANDA_INERTIA = (
    (7.0337e-01, -1.3900e-04, 6.7720e-03, 7.0661e-01, 1.9169e-02, 9.1170e-03),
    (7.9620e-03, -3.9250e-03, 1.0254e-02, 2.8110e-02, 7.0400e-04, 2.5995e-02),
    (3.7242e-02, -4.7610e-03, -1.1396e-02, 3.6155e-02, -1.2805e-02, 1.0830e-02),
    (2.5853e-02, 7.7960e-03, -1.3320e-03, 1.9552e-02, 8.6410e-03, 2.8323e-02),
    (3.5549e-02, -2.1170e-03, -4.0370e-03, 2.9474e-02, 2.2900e-04, 8.6270e-03),
    (1.9640e-03, 1.0900e-04, -1.1580e-03, 4.3540e-03, 3.4100e-04, 5.4330e-03),
    (1.2516e-02, -4.2800e-04, -1.1960e-03, 1.0027e-02, -7.4100e-04, 4.8150e-03),
)


def _c(a, b, r):
    return Capsule(tuple(map(float, a)), tuple(map(float, b)), float(r))


# Collision capsules in each link frame [m]. Our own fit; the extents were checked against
# two published approximations of the real links (facts only): Franka's self-collision
# capsules in franka_ros/franka_description (panda_arm.xacro) and cuRobo's Panda sphere set
# (NVlabs/curobo, configs/robot/spheres/franka_mesh.yml). Joint housings are capsules along
# the joint axis; the upper arm and forearm tubes lie on the axes of joints 3 and 5, so
# they cover the same volume whichever of the two links they are attached to.
PANDA_BASE = (_c((-0.09, 0, 0.06), (0.0, 0, 0.06), 0.07),)
PANDA_COLLISION = (
    # link1: column from the base top to the shoulder, and the -y half of the joint-2 housing
    (_c((0, 0, -0.26), (0, 0, -0.05), 0.06), _c((0, -0.08, 0), (0, -0.02, 0), 0.06)),
    # link2: +z half of the joint-2 housing, tube towards joint 3 (at y = -0.316)
    (_c((0, 0, 0.0), (0, 0, 0.08), 0.06), _c((0, -0.06, 0), (0, -0.18, 0), 0.055)),
    # link3: upper-arm tube on the joint-3 axis, +y half of the elbow (joint-4) housing
    (_c((0, 0, -0.18), (0, 0, -0.04), 0.06), _c((0.0825, 0.02, 0), (0.0825, 0.07, 0), 0.055)),
    # link4: +z half of the elbow housing, start of the forearm towards joint 5
    (_c((0, 0, -0.01), (0, 0, 0.06), 0.055), _c((-0.0825, 0.05, 0), (-0.0825, 0.12, 0), 0.055)),
    # link5: forearm tube on the joint-5 axis, its back bulge and plate, wrist (joint-6) housing
    (
        _c((0, 0, -0.27), (0, 0, -0.16), 0.055),
        _c((0, 0.05, -0.18), (0, 0.065, -0.155), 0.04),
        _c((0, 0.08, -0.14), (0, 0.095, -0.05), 0.033),
        _c((0, -0.01, 0), (0, 0.08, 0), 0.05),
    ),
    # link6: body from the wrist axis to the joint-7 housing (at x = 0.088, axis -y)
    (_c((0, 0, 0), (0.088, 0, 0), 0.045), _c((0.088, -0.02, 0), (0.088, 0.04, 0), 0.045)),
    # link7: flange body up to the flange face (z = 0.107) and its side feature at 45 deg
    (_c((0, 0, 0.055), (0, 0, 0.075), 0.045), _c((0, 0, 0.082), (0.042, 0.042, 0.082), 0.035)),
)

PANDA_HEADER = """\
Franka Emika Panda, 7 DOF, without hand. Kinematics: Craig's modified DH (Franka's
published table); link frames = DH frames = the Franka URDF frames; flange panda_link8
at 0.107 m along z7 (FK at q = 0: (0.088, 0, 0.926) m). Limits: Franka's published
position, velocity, acceleration, jerk and torque limits (Panda, not FR3).
Inertial parameters: Gaz, Cognetti, Oliva, Robuffo Giordano, De Luca, "Dynamic
identification of the Franka Emika Panda robot with retrieval of feasible parameters
using penalty-based optimization", IEEE RA-L 4(4), 2019 (supplementary Tables VIII-IX,
github.com/marcocognetti/FrankaEmikaPandaDynModel); expressed in the link frames.
Collision model: our capsules, sized from Franka's self-collision capsules
(franka_description) and cuRobo's Panda spheres; base link0 included."""


def panda() -> str:
    """The Franka Emika Panda (REFERENCES.md table; Gaz et al. 2019 inertias)."""
    links = [
        LinkSpec(mass=m, com=c, inertia=i, collision=g)
        for m, c, i, g in zip(PANDA_MASS, PANDA_COM, PANDA_INERTIA, PANDA_COLLISION)
    ]
    return dh_to_urdf(
        a=[0, 0, 0, 0.0825, -0.0825, 0, 0.088],
        alpha=[0, -PI / 2, PI / 2, PI / 2, -PI / 2, PI / 2, PI / 2],
        d=[0.333, 0, 0.316, 0, 0.384, 0, 0],
        lower=[-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973],
        upper=[2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973],
        convention="modified",
        name="panda",
        velocity_limits=[2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61],
        effort_limits=[87, 87, 87, 87, 12, 12, 12],
        acceleration_limits=[15, 7.5, 10, 12.5, 15, 20, 20],
        jerk_limits=[7500, 3750, 5000, 6250, 7500, 10000, 10000],
        links=links,
        base=LinkSpec(collision=PANDA_BASE),
        tool=_tz(0.107),
        prefix="panda_",
        ee_name="panda_link8",
        header=PANDA_HEADER,
        rgba="0.92 0.92 0.92 1",
    )


# --- generated arms of the seed papers ---------------------------------------------------
# Limits not given by the papers (documented choices, same for every paper arm):
PAPER_VELOCITY = PI  # [rad/s] 180 deg/s, typical of small electric arms
PAPER_ACCELERATION = 10.0  # [rad/s^2] the order of the Panda's (7.5-20)
PAPER_JERK = 5000.0  # [rad/s^3] the order of the Panda's (3750-10000)

DERIVED = """\
Masses/inertias derived: each link is its collision capsules as a solid of effective
density {rho:g} kg/m^3 (shell, motor, gear, cables averaged over the envelope).
Effort limits: {margin:g} x the worst-case static gravity torque (every outboard link
stretched horizontally), rounded up. Velocity {vel:.4f} rad/s (180 deg/s), acceleration
{acc:g} rad/s^2 and jerk {jerk:g} rad/s^3 are documented choices, not from the paper."""


def _derived(rho=1000.0, margin=2.0) -> str:
    return DERIVED.format(rho=rho, margin=margin, vel=PAPER_VELOCITY, acc=PAPER_ACCELERATION, jerk=PAPER_JERK)


def _paper_limits(n: int) -> dict:
    return dict(
        velocity_limits=PAPER_VELOCITY,
        acceleration_limits=[PAPER_ACCELERATION] * n,
        jerk_limits=[PAPER_JERK] * n,
    )


def seed000_6dof() -> str:
    """The framework paper's 6-link arm (Table 2, standard DH of its eq. (2))."""
    header = (
        "Framework paper (Sheik Masthan et al., AETiC 2024), Table 2: 6-link arm, standard\n"
        "DH of its eq. (2). The table labels d and a in mm, but the scenario (Table 3: points\n"
        "such as (0.2, 0.8, 0.3)) is in the same units as metres: values used as metres.\n"
        "Limits Table 2: +-180, +-260 (x4), +-360 deg.\n" + _derived()
    )
    deg = PI / 180
    return dh_to_urdf(
        a=[0.05, 0.4, 0.3, 0.4, 0.2, 0.0],
        alpha=[90 * deg, -90 * deg, 90 * deg, 0.0, 90 * deg, 0.0],
        d=[0.1, 0.0, 0.0, 0.0, 0.0, 0.05],
        lower=[-180 * deg] + [-260 * deg] * 4 + [-360 * deg],
        upper=[180 * deg] + [260 * deg] * 4 + [360 * deg],
        name="seed000_6dof",
        link_radius=0.035,
        header=header,
        **_paper_limits(6),
    )


def _planar(lengths, name, header, lower=None, upper=None, radius=0.02, **kw) -> str:
    n = len(lengths)
    return dh_to_urdf(
        a=list(lengths),
        alpha=[0.0] * n,
        d=[0.0] * n,
        lower=lower,
        upper=upper,
        name=name,
        link_radius=radius,
        header=header,
        **{**_paper_limits(n), **kw},
    )


def planar5() -> str:
    """The cyclic paper's planar 5-DOF arm, links 22, 20, 18, 16, 14 cm."""
    header = (
        "Cyclic paper (hyper-redundant cyclic planning with WOA), Sec. IV.A: planar 5-DOF\n"
        "arm, links 0.22, 0.20, 0.18, 0.16, 0.14 m (paper in cm), relative joint angles of\n"
        "its eq. (3); all joint axes along world z, so the arm moves in the horizontal x-y\n"
        "plane (the paper is kinematic only; gravity is perpendicular to the plane).\n"
        "Joint limits: none given, +-pi (a relative angle of pi folds a link onto the\n"
        "previous one). Capsules are coplanar: a link crossing another is a self-collision.\n"
        + _derived()
    )
    return _planar([0.22, 0.20, 0.18, 0.16, 0.14], "planar5", header)


def planar12() -> str:
    """The cyclic paper's planar 12-DOF arm, 12 links of 30 cm, eq. (27) joint limits."""
    header = (
        "Cyclic paper, Sec. IV.B: planar 12-DOF arm, 12 links of 0.30 m, joint axes along\n"
        "world z (horizontal x-y plane). Joint limits: eq. (27), 0 <= theta_k <= pi for\n"
        "k = 2, 5, 8, 11 (the middle joint of each 3-link component); the others +-pi.\n"
        + _derived()
    )
    lower = [-PI] * 12
    for k in (2, 5, 8, 11):
        lower[k - 1] = 0.0
    return _planar([0.30] * 12, "planar12", header, lower=lower, upper=[PI] * 12, radius=0.025)


def planar2r() -> str:
    """The ABC paper's 2R arm, in a vertical plane with gravity (interpretation below)."""
    header = (
        "ABC paper (Savsani & Jhala), Sec. IV: planar 2R arm, links 0.3048 m (1 ft) each,\n"
        "link masses 0.175 kg, torque limits 45 and 20 N m; position limits +-pi (eq. 21).\n"
        "Interpretation (see docs/robots.md): the arm is a human arm in a VERTICAL plane, so\n"
        "gravity acts in the plane of motion: the paper's torques start at 0 with the arm\n"
        "hanging down and grow as it rises. The base is rotated by +90 deg about world x:\n"
        "the paper's (x, y) with y up is world (x, z); joint axes are world -y; q = 0 points\n"
        "the arm along +x. The paper's start (0, -0.76) and goal (0.76, 0) are beyond the\n"
        "printed reach 0.6096 m; with the elbow straight (its Fig. 3 free-space solution)\n"
        "they are read as the full-reach points (0, -0.6096) = q (-pi/2, 0) and (0.6096, 0)\n"
        "= q (0, 0): its Table 1 Cartesian length 3.1403 is a quarter circle of radius 2 ft.\n"
        "Links are solid capsules (radius 0.025 m) scaled to 0.175 kg. Velocity limit pi\n"
        "rad/s, acceleration 10 rad/s^2, jerk 5000 rad/s^3: documented choices."
    )
    X_WB = np.eye(4)
    X_WB[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]  # Rx(+90 deg): local y -> world z
    return _planar(
        [0.3048, 0.3048],
        "planar2r",
        header,
        radius=0.025,
        effort_limits=[45.0, 20.0],
        links=[LinkSpec(mass=0.175), LinkSpec(mass=0.175)],
        X_WB=X_WB,
    )


MODELS = {
    "panda.urdf": panda,
    "seed000_6dof.urdf": seed000_6dof,
    "planar5.urdf": planar5,
    "planar12.urdf": planar12,
    "planar2r.urdf": planar2r,
}


def build_all() -> dict[str, str]:
    """File name -> URDF text of every bundled model (nothing written)."""
    return {fname: make() for fname, make in MODELS.items()}


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def model_difference(old: str, new: str, rtol: float = 1e-12, atol: float = 1e-14) -> str | None:
    """Where two model texts differ beyond float rounding, or ``None`` when they agree.

    The words must be equal and every number equal to ``atol + rtol * |number|``: the last
    printed digit may differ between CPUs (BLAS kernels, libm), the model may not.
    """
    words_old, words_new = _NUMBER.split(old), _NUMBER.split(new)
    if words_old != words_new:
        for line_old, line_new in zip(old.splitlines(), new.splitlines()):
            if _NUMBER.split(line_old) != _NUMBER.split(line_new):
                return f"text differs: {line_old.strip()!r} vs {line_new.strip()!r}"
        return "the texts have different lengths"
    for a, b in zip(_NUMBER.findall(old), _NUMBER.findall(new)):
        if abs(float(a) - float(b)) > atol + rtol * abs(float(a)):
            return f"number {a} vs {b}"
    return None


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only report stale files (exit 1)")
    args = parser.parse_args(argv)
    stale = []
    for fname, text in build_all().items():
        path = URDF_DIR / fname
        if path.exists() and model_difference(path.read_text(), text) is None:
            continue
        stale.append(fname)
        if not args.check:
            path.write_text(text)
            print(f"wrote {path}")
    if args.check and stale:
        print("stale: " + ", ".join(stale) + " (run scripts/generate_urdfs.py)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
