"""``drake-mh ik``: JSON output, exit codes, one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from drake_mh.cli import main


def test_ik_json(capsys):
    # a generous timeout: in a fresh checkout the first solve also compiles the numba kernels
    # (seconds, once per machine: they are cached on disk), which counts against the timeout
    code = main(["ik", "--robot", "panda", "--position", "0.5", "0.1", "0.4", "--rpy", "3.1416", "0", "0",
                 "--method", "hybrid", "--seed", "3", "--timeout", "60", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and data["success"] is True and data["method"] == "hybrid"
    assert data["position_error"] <= 1e-5 and data["orientation_error"] <= 1e-5
    assert len(data["q"]) == 7 and data["joint_names"][0] == "panda_joint1"
    import drake_mh
    from references import FreshDrake
    from scipy.spatial.transform import Rotation

    X = FreshDrake(drake_mh.load_robot("panda")).fk(data["q"], "panda_link8")  # Drake on a fresh plant
    assert np.linalg.norm(X[:3, 3] - [0.5, 0.1, 0.4]) <= 1e-5
    R_WT = Rotation.from_euler("xyz", [3.1416, 0, 0]).as_matrix()  # --rpy: fixed axes x, y, z
    assert Rotation.from_matrix(X[:3, :3] @ R_WT.T).magnitude() <= 1e-5


def test_ik_text_position_only(capsys):
    code = main(["ik", "--robot", "seed000_6dof", "--position", "0.4", "0.2", "0.5", "--method", "dls"])
    out = capsys.readouterr().out
    assert code == 0 and out.startswith("success: dls on seed000_6dof")


@pytest.mark.parametrize("argv, words", [
    (["ik", "--robot", "nope", "--position", "0", "0", "0.5"], "unknown robot 'nope': bundled robots are panda"),
    (["ik", "--method", "nope", "--position", "0", "0", "0.5"], "unknown IK method 'nope'; available: abc"),
    (["ik", "--position", "0", "zero", "0.5"], "--position"),
    (["ik"], "--position"),
])
def test_ik_errors_exit_2_with_one_line(capsys, argv, words):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("drake-mh: error:") and words in err


def test_unreachable_exits_1(capsys):
    code = main(["ik", "--position", "3", "0", "0", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 1 and data["success"] is False and "out of reach" in data["message"] and data["nfe"] == 0
