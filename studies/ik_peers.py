"""IK against the peers a user would pick instead, measured in the same run (issue 17).

The TRAC-IK protocol (its README): a random configuration within the joint limits -> FK -> full
6-D pose IK at 1e-5 m / 1e-5 rad, 5 ms timeout, mean time including failures, no collision
check. On each robot, each target is solved by every method in turn (the order reversed on
every other target), so the methods share the machine's load; every answer is re-checked by
the same Drake verification (:func:`drake_mh.ik.verify`: Drake's FK and the joint limits).

What a Python caller pays is timed: for drake_mh, building the :class:`~drake_mh.ik.IKProblem`
plus :func:`~drake_mh.ik.solve_ik` (whose time includes its own Drake verification); for
robotics-toolbox-python, its ``ik_LM`` / ``ik_GN`` call (C++; random restarts, joint limits
enforced by rejection, ``ilimit=30``, ``slimit=100``, no timeout), its Drake check untimed. Wall
and process CPU time are both recorded (CPU time is what a dedicated core would need), with
the 1-minute load average at each case; the summary names the CPU model and gives every
method's mean time as a ratio to ``rtb_ik_LM``'s in the same run.

Methods: ``hybrid``, ``pinv``, ``dls`` (drake_mh), ``rtb_ik_LM``, ``rtb_ik_GN``
(robotics-toolbox-python, the optional extra ``peers``; left out, with a line in the summary,
when it is not installed). rtb's tolerance is its residual ``E = ½ eᵀe`` (e = [Δp; ω]):
``E < 5e-11`` implies ``|Δp| <= 1e-5`` and ``θ <= 1e-5``; its URDF parser rejects ``<capsule>``,
so collision and visual elements are stripped in memory, and links referred to but not
declared (``world``) are declared.

Robots: the bundled ``panda`` and ``seed000_6dof`` and, when ``example-robot-data`` is
installed (test extra), its UR5, xArm7 and Kinova j2s6s200 (loaded by path with
:func:`drake_mh.load_robot`). 1000 targets per robot (10 per bundled robot and 5 per other
arm with ``--quick``); the full run takes about a minute here.

Run: ``drake-mh study ik_peers [--quick]`` or ``python studies/ik_peers.py [--quick]``.
"""

from __future__ import annotations

import os
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

import drake_mh
from drake_mh.ik import IKProblem, solve_ik, verify
from drake_mh.example_arms import example_robot_data_root, load_example_arm
from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model

TARGET_SEED = 20240605
TOL = 1e-5  # [m] and [rad]
TIMEOUT = 0.005  # [s]
RTB_TOL = 0.5 * TOL**2  # E = ½(|Δp|² + θ²) < RTB_TOL  =>  |Δp|, θ <= TOL
OURS = ("hybrid", "pinv", "dls")
PEERS = ("rtb_ik_LM", "rtb_ik_GN")
REFERENCE = "rtb_ik_LM"
BUNDLED = ("panda", "seed000_6dof")
#: arms of example-robot-data (drake_mh.example_arms) beside the bundled ones
ERD_ARMS = ("ur5", "xarm7", "kinova")

_ROBOTS: dict = {}
_RTB: dict = {}
_WARM: set = set()


def rtb_available() -> bool:
    """Whether robotics-toolbox-python is installed (the optional extra ``peers``; not imported here)."""
    import importlib.util

    return importlib.util.find_spec("roboticstoolbox") is not None


def robots() -> list[str]:
    """The robots of this run: the bundled ones, then the example-robot-data arms if installed."""
    return list(BUNDLED) + (list(ERD_ARMS) if example_robot_data_root() is not None else [])


def _robot(name: str):
    if name not in _ROBOTS:
        if name in ERD_ARMS:
            _ROBOTS[name] = load_example_arm(name)
        else:
            _ROBOTS[name] = drake_mh.load_robot(name)
    return _ROBOTS[name]


def rtb_robot(robot):
    """robotics-toolbox-python's model of ``robot`` (same URDF text, collision/visual stripped).

    Raises:
        RuntimeError: its FK differs from Drake's by more than 1e-9 at a random configuration.
    """
    if robot.name in _RTB:
        return _RTB[robot.name]
    import roboticstoolbox as rtb
    from roboticstoolbox.models.URDF.URDFRobot import URDF_read

    root = ET.fromstring(robot.model_text)
    for link in root.findall("link"):
        for tag in ("collision", "visual"):
            for element in link.findall(tag):
                link.remove(element)
    declared = {link.get("name") for link in root.findall("link")}
    referred = {j.find("parent").get("link") for j in root.findall("joint")}
    for name in sorted(referred - declared):  # e.g. <joint><parent link="world"/> with no <link name="world"/>
        root.insert(0, ET.Element("link", {"name": name}))
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "robot.urdf")
        Path(path).write_text(ET.tostring(root, encoding="unicode"))
        links, name = URDF_read(path)[:2]
    model = rtb.Robot(links, name=name)
    q = robot.random_configurations(1, 0)[0]
    gap = float(np.abs(model.fkine(q, end=robot.ee_frame_name).A - robot.fk(q)).max())
    if gap > 1e-9:
        raise RuntimeError(f"robotics-toolbox's FK of {robot.name} differs from Drake's by {gap:.2e}")
    _RTB[robot.name] = model
    return model


def _target(robot_name: str, target: int) -> np.ndarray:
    """Target pose ``X_WT (4, 4)``: FK of a random configuration (same for every method)."""
    robot = _robot(robot_name)
    rng = np.random.default_rng([TARGET_SEED, robots().index(robot_name), int(target)])
    return robot.fk(robot.random_configurations(1, rng)[0])


def _solve(robot, label: str, X_WT: np.ndarray, seed: int):
    """One timed solve: ``(q, our IKResult or None)``."""
    if label in OURS:
        problem = IKProblem(robot, X_WT, position_tolerance=TOL, orientation_tolerance=TOL)
        result = solve_ik(problem, label, seed=seed, timeout=TIMEOUT)
        return result.q, result
    model = rtb_robot(robot)
    np.random.seed(seed % 2**32)  # rtb's restarts
    solver = model.ik_LM if label == "rtb_ik_LM" else model.ik_GN
    solution = solver(X_WT, end=robot.ee_frame_name, tol=RTB_TOL, joint_limits=True)
    return np.asarray(solution.q, dtype=float), None


def run(case: Case) -> dict:
    """Solves one target with one method (module docstring)."""
    robot = _robot(case["robot"])
    label = case["method"]
    X_WT = _target(case["robot"], case["target"])
    if (robot.name, label) not in _WARM:  # imports, compiled kernels, rtb's model: untimed
        _WARM.add((robot.name, label))
        _solve(robot, label, X_WT, 0)
    start, cpu_start = time.perf_counter(), time.process_time()
    q, result = _solve(robot, label, X_WT, case.seed)
    elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu_start
    problem = IKProblem(robot, X_WT, position_tolerance=TOL, orientation_tolerance=TOL)
    checked = verify(problem, q, method=label, start=0.0, nfe=0)  # the same Drake check for all
    if result is not None and result.success != checked.success:  # pragma: no cover - a bug if it happens
        raise RuntimeError(f"{label} reported success={result.success}, Drake's check says {checked.success}")
    return {"success": checked.success, "time": elapsed, "cpu_time": cpu,
            "error": max(checked.position_error, checked.orientation_error),
            "nfe": result.nfe if result is not None else 0, "load": os.getloadavg()[0],
            "message": checked.message}


def _grid(quick: bool) -> list[dict]:
    methods = list(OURS) + (list(PEERS) if rtb_available() else [])
    cases = []
    for robot in robots():
        n = (10 if robot in BUNDLED else 5) if quick else 1000
        for t in range(n):
            order = methods if t % 2 == 0 else methods[::-1]
            cases += [{"robot": robot, "target": t, "method": m} for m in order]
    return cases


def summarize(records: list[dict]) -> str:
    """One table per robot: success, times, CPU time, ratio to rtb's ik_LM in the same run."""
    ok = [r for r in records if r.get("status") == "ok"]
    if not ok:
        return ""
    loads = np.array([r["load"] for r in ok])
    lines = ["### IK vs peers: TRAC-IK protocol (6-D pose at 1e-5 m / 1e-5 rad, 5 ms timeout)", "",
             f"CPU: {cpu_model()} ({os.cpu_count()} logical CPUs); 1-minute load average during the run "
             f"{loads.min():.2f}-{loads.max():.2f} (mean {loads.mean():.2f}). Times include what a Python "
             "caller pays (drake_mh: IKProblem + solve_ik with its Drake verification; rtb: its ik_* call). "
             f"`vs ik_LM` = mean time of {REFERENCE} / mean time of the method, same run, methods interleaved "
             "per target. Success re-checked by Drake for every method.", ""]
    if not rtb_available():
        lines += ["robotics-toolbox-python is not installed (`pip install -e '.[peers]'`): the peers' rows "
                  "are missing.", ""]
    for robot in dict.fromkeys(r["robot"] for r in ok):
        rows = [r for r in ok if r["robot"] == robot]
        groups: dict[str, list[dict]] = {}
        for r in rows:
            groups.setdefault(r["method"], []).append(r)
        ref = groups.get(REFERENCE)
        ref_mean = np.mean([r["time"] for r in ref]) if ref else np.nan
        n = max(len(g) for g in groups.values())
        lines += [f"**{robot}** ({n} targets)", "",
                  "| method | success % | mean [ms] | median [ms] | p95 [ms] | CPU mean [ms] | vs ik_LM |",
                  "|---|---|---|---|---|---|---|"]
        for method, group in groups.items():
            t = 1e3 * np.array([r["time"] for r in group])
            cpu = 1e3 * np.mean([r["cpu_time"] for r in group])
            rate = 100 * np.mean([bool(r["success"]) for r in group])
            ratio = ref_mean / (t.mean() / 1e3) if np.isfinite(ref_mean) else np.nan
            lines.append(f"| {method} | {rate:.2f} | {t.mean():.3f} | {np.median(t):.3f} | "
                         f"{np.percentile(t, 95):.3f} | {cpu:.3f} | {ratio:.2f}x |")
        lines.append("")
    return "\n".join(lines)


study = Study(
    name="ik_peers",
    run=run,
    grid=_grid(quick=False),
    quick_grid=_grid(quick=True),
    seed=0,
    fields=Fields(method="method", success="success", time="time", error="error", nfe="nfe", rank=False,
                  group_by=("robot",), error_unit="m",
                  conditions="6-D pose at 1e-5 m / 1e-5 rad, 5 ms timeout (drake_mh); rtb: E < 5e-11, 100 searches"),
    description=(
        "IK against robotics-toolbox-python's ik_LM/ik_GN (C++) on the TRAC-IK protocol, methods interleaved "
        "per target, every answer checked by Drake, wall and CPU time and load average recorded."
    ),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    study.main()
