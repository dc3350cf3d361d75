"""Sanity checks of a URDF before Drake parses it.

Drake aborts the process (no Python exception) on some input, e.g. a negative velocity limit,
and silently misreads other input (a negative effort limit becomes "no limit"); these checks
turn both into :class:`drake_mh.errors.DrakeMhError` subclasses that name the joint or link.
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET

import numpy as np

from drake_mh.errors import InvalidLimits, InvalidURDF, UnsupportedModel

logger = logging.getLogger(__name__)

SUPPORTED_JOINTS = {"revolute", "continuous", "prismatic", "fixed"}

__all__ = ["check_urdf", "check_inertial", "SUPPORTED_JOINTS"]


def check_urdf(root: ET.Element, source: str) -> None:
    """Sanity-check a URDF before Drake sees it (Drake may abort on some input)."""
    if root.tag != "robot":
        raise InvalidURDF(source, f"the root element is <{root.tag}>, expected <robot>")
    links = {link.get("name") for link in root.findall("link")}
    if not links:
        raise InvalidURDF(source, "the model has no <link>")
    for joint in root.findall("joint"):
        jname, jtype = joint.get("name"), joint.get("type")
        if jtype not in SUPPORTED_JOINTS:
            raise UnsupportedModel(
                f"{source}: joint {jname!r} has type {jtype!r}; supported types are "
                f"{sorted(SUPPORTED_JOINTS)}")
        limit = joint.find("limit")
        if limit is not None and jtype in ("revolute", "prismatic"):
            try:
                lo = float(limit.get("lower", "nan"))
                hi = float(limit.get("upper", "nan"))
            except ValueError as exc:
                raise InvalidURDF(source, f"joint {jname!r}: non-numeric <limit> ({exc})") from exc
            if lo > hi:
                raise InvalidLimits(
                    f"{source}: joint {jname!r} has lower limit {lo} > upper limit {hi}; swap them")
        if limit is not None:  # Drake aborts the process on a negative velocity limit
            for key in ("velocity", "effort"):
                try:
                    value = float(limit.get(key, "0"))
                except ValueError as exc:
                    raise InvalidURDF(source, f"joint {jname!r}: non-numeric <limit {key}> ({exc})") from exc
                if not value >= 0:
                    raise InvalidLimits(f"{source}: joint {jname!r} has {key} limit {value}; a limit is a "
                                        "magnitude >= 0 (Drake would abort the process on it)")
    children: dict[str, str] = {}
    for joint in root.findall("joint"):
        child = joint.find("child")
        name = child.get("link") if child is not None else None
        if name in children:  # Drake raises deep inside; a tree needs one parent per link
            raise UnsupportedModel(f"{source}: link {name!r} is the child of joints {children[name]!r} and "
                                   f"{joint.get('name')!r} (a kinematic loop); only tree-shaped arms are supported")
        if name is not None:
            children[name] = joint.get("name")
    for link in root.findall("link"):
        check_inertial(link, source)


def check_inertial(link: ET.Element, source: str) -> None:
    """A link's mass must be >= 0 and its inertia physical (principal moments >= 0, triangle inequality)."""
    inertial = link.find("inertial")
    if inertial is None:
        return
    name = link.get("name")
    try:
        mass = float(inertial.find("mass").get("value", "0")) if inertial.find("mass") is not None else 0.0
        el = inertial.find("inertia")
        I = None
        if el is not None:
            v = {k: float(el.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
            I = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]],
                          [v["ixz"], v["iyz"], v["izz"]]])
    except ValueError as exc:
        raise InvalidURDF(source, f"link {name!r}: non-numeric <inertial> ({exc})") from exc
    if not (np.isfinite(mass) and mass >= 0):
        raise InvalidURDF(source, f"link {name!r} has mass {mass}; a mass must be a finite number >= 0 [kg]")
    if I is not None:
        if not np.all(np.isfinite(I)):
            raise InvalidURDF(source, f"link {name!r}: the inertia is not finite")
        ev = np.linalg.eigvalsh(I)
        scale = max(abs(ev).max(), 1e-12)
        if ev[0] < -1e-9 * scale or 2 * ev.max() > ev.sum() + 1e-9 * scale:
            # many shipped descriptions carry such CAD inertias (example-robot-data: 14 models);
            # kinematics and distances do not need them, so warn rather than refuse the model
            logger.warning("%s: link %r has an inertia with principal moments %s that is not physical "
                           "(each must be >= 0 and <= the sum of the other two); torques computed with it "
                           "are not trustworthy", source, name, np.round(ev, 9).tolist())
