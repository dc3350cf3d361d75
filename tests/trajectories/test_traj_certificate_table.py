"""The certificate table says which quantities were not enforced and where no limit exists."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from traj_helpers import random_waypoints

import drake_mh
from drake_mh.errors import InvalidArgument
from drake_mh.trajectories import QUANTITIES, certify, retime


def _rows(table: str) -> dict[str, list[str]]:
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in table.splitlines()[2:]]
    return {r[0]: r[1:] for r in rows}


def test_toppra_jerk_is_labelled_not_enforced(panda):
    W = random_waypoints(panda, np.random.default_rng(13), k=3)
    traj = retime(W, panda, "toppra", gridpoints=50)
    cert = traj.info["certificate"]
    assert cert.enforced == ("position", "velocity", "acceleration", "torque")
    rows = _rows(cert.table())
    assert set(rows) == {"position", "velocity", "acceleration", "jerk (not enforced)", "torque"}
    assert all(cell.startswith("inf @") for cell in rows["jerk (not enforced)"])
    assert cert.ok() and cert.ok(cert.enforced)           # by default only enforced quantities count
    assert not cert.ok(list(cert.ratios))                 # the inf is reported, not hidden
    # certifying it again checks what its maker enforced; enforced=QUANTITIES counts everything
    assert "jerk (not enforced)" in certify(traj, panda).table()
    assert "not enforced" not in certify(traj, panda, enforced=QUANTITIES).table()


def test_joints_without_a_limit_read_no_limit():
    robot = copy.copy(drake_mh.load_robot("planar2r"))
    robot.jerk_limits = np.array([robot.jerk_limits[0], np.inf])    # joint 2 declares no jerk limit
    W = random_waypoints(robot, np.random.default_rng(0), k=3)
    traj = retime(W, robot, "ruckig", limits=("velocity", "acceleration"))
    cert = certify(traj, robot, quantities=("velocity", "jerk"), enforced=("velocity", "jerk"))
    cells = _rows(cert.table())["jerk"]
    assert cells[0].endswith(" s") and cells[1] == "no limit" and cert.ratios["jerk"][1] == 0.0
    with pytest.raises(InvalidArgument, match="enforced"):
        certify(traj, robot, enforced=("speed",))
