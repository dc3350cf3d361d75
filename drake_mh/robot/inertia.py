"""Mass properties of solid capsules, and their sum (the links :func:`drake_mh.robot.dh.dh_to_urdf` generates).

Computed without BLAS (``math.hypot``, ``math.fsum``) so that generated models are the same
text on every CPU (see :func:`drake_mh.robot.dh._mul`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["capsule_inertia", "combine_inertias"]


def capsule_inertia(p_A, p_B, radius: float, density: float):
    """Mass, centre of mass and rotational inertia of a solid capsule of uniform density.

    Cylinder of length ``L = |B - A|`` and two hemispherical caps of radius ``r``:
    ``m = rho (pi r^2 L + 4/3 pi r^3)``; about the centre, with axis ``u``,
    ``I_axial = m_c r^2/2 + 2 m_h (2 r^2/5)`` and
    ``I_perp = m_c (L^2/12 + r^2/4) + 2 m_h (2 r^2/5 + L^2/4 + 3 L r/8)``,
    ``m_c`` the cylinder and ``m_h`` one hemisphere mass (parallel axis through the caps'
    centroid at ``3r/8``). Tested against Drake's ``SpatialInertia.SolidCapsuleWithDensity``.

    Args:
        p_A, p_B: axis end points [m] (equal: a sphere).
        radius: [m]. density: [kg/m^3].

    Returns:
        ``(mass [kg], p_Cm (3,) [m], I_Cm (3, 3) [kg m^2])`` about the centre of mass.
    """
    p_A, p_B = np.asarray(p_A, float), np.asarray(p_B, float)
    axis = p_B - p_A
    length = math.hypot(*axis)  # not np.linalg.norm: its result depends on the BLAS kernel
    r = float(radius)
    m_c = density * math.pi * r**2 * length
    m_h = density * 2.0 / 3.0 * math.pi * r**3
    i_ax = m_c * r**2 / 2 + 2 * m_h * (2 * r**2 / 5)
    i_perp = m_c * (length**2 / 12 + r**2 / 4) + 2 * m_h * (
        2 * r**2 / 5 + length**2 / 4 + 3 * length * r / 8
    )
    u = axis / length if length > 0 else np.array([0.0, 0.0, 1.0])
    uu = np.outer(u, u)
    inertia = i_perp * (np.eye(3) - uu) + i_ax * uu
    return m_c + 2 * m_h, (p_A + p_B) / 2, inertia


def combine_inertias(parts):
    """Sum ``(m, p_Cm, I_Cm)`` parts into one body about its common centre of mass."""
    mass = sum(m for m, _, _ in parts)
    com = sum(m * c for m, c, _ in parts) / mass
    inertia = np.zeros((3, 3))
    for m, c, i_c in parts:
        d = c - com
        inertia += i_c + m * (math.fsum(d * d) * np.eye(3) - np.outer(d, d))  # no BLAS (see _mul)
    return mass, com, inertia


# --- DH transforms --------------------------------------------------------------------
