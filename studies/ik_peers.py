"""IK against the peers a user would pick instead, measured in the same run.

The TRAC-IK protocol (its README): a random configuration within the joint limits -> FK -> full
6-D pose IK at 1e-5 m / 1e-5 rad, 5 ms timeout, mean time including failures, no collision
check. On each robot, each target is solved by every method in turn (the order reversed on
every other target), so the methods share the machine's load; every answer is re-checked by
the same Drake verification (:func:`drake_mh.ik.verify`: Drake's FK and the joint limits).

What a Python caller pays is timed: for drake_mh, building the :class:`~drake_mh.ik.IKProblem`
plus :func:`~drake_mh.ik.solve_ik` (whose time includes its own Drake verification); for
robotics-toolbox-python, its ``ik_LM`` / ``ik_GN`` call (C++; random restarts, joint limits
enforced by rejection, ``ilimit=30``, ``slimit=100``, no timeout); for TRAC-IK and ikpy, the
quaternion conversion (TRAC-IK) and their call; the peers' Drake check untimed. Wall
and process CPU time are both recorded (CPU time is what a dedicated core would need), with
the 1-minute load average at each case; the summary names the CPU model and gives every
method's mean time as a ratio to ``rtb_ik_LM``'s in the same run.

Methods: ``hybrid``, ``pinv``, ``dls`` (drake_mh), ``rtb_ik_LM``, ``rtb_ik_GN``
(robotics-toolbox-python), ``trac_ik`` (TRAC-IK through the ``pytracik`` wheel), ``ikpy``; the
peers come with the optional extra ``peers``, and one that is not installed, or whose parser
or FK does not reproduce Drake's model of a robot (checked at grid time for TRAC-IK and ikpy),
is left out with a line in the summary. rtb's tolerance is its residual ``E = ½ eᵀe`` (e = [Δp; ω]):
``E < 5e-11`` implies ``|Δp| <= 1e-5`` and ``θ <= 1e-5``; its URDF parser rejects ``<capsule>``,
so collision and visual elements are stripped in memory, and links referred to but not
declared (``world``) are declared; TRAC-IK (KDL) gets the same text.

TRAC-IK: ``Speed`` mode (KDL's Newton and an NLopt SQP in two threads: its CPU time exceeds
its wall time), 5 ms timeout, seeded at mid-range; it bounds each of the six error
components, so its ``eps`` is ``1e-5/sqrt(3)`` (a success then meets our norm and angle
test); ``pytracik`` 0.0.3 reads URDF limits as 32-bit floats, so they are set from Drake's.
It starts two new threads per call: on a loaded machine with few cores they can wait for a
core (measured here: 0.35 ms median alone, 2-3 ms right after other busy work at load 1.5 on
2 cores, CPU time unchanged), so compare its CPU mean as well as its wall time.
ikpy: its chain from the root link to the end effector only (other branches removed in
memory), Drake's limits as its bounds, one ``inverse_kinematics_frame`` call with
``orientation_mode="all"`` from mid-range and its default SciPy least-squares settings (no
restarts, no timeout); it reports no success flag, so Drake's check is the only verdict, as
for every peer.

Robots: the bundled ``panda`` and ``seed000_6dof`` and, when ``example-robot-data`` is
installed (test extra), its UR5, xArm7 and Kinova j2s6s200 (loaded by path with
:func:`drake_mh.load_robot`). 1000 targets per robot (10 per bundled robot and 5 per other
arm with ``--quick``); the full run takes about 4 minutes here (ikpy's solves are most of it).

Run: ``drake-mh study ik_peers [--quick]`` or ``python studies/ik_peers.py [--quick]``.
"""

from __future__ import annotations

import os
import time

import numpy as np

import drake_mh
from drake_mh.errors import DrakeMhError
from drake_mh.ik import IKProblem, peers, solve_ik, verify
from drake_mh.ik.peers import PEER_MODULE, PEERS, peer_available
from drake_mh.robot.examples import example_robot_data_root, load_example_arm
from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average

TARGET_SEED = 20240605
TOL = 1e-5  # [m] and [rad]
TIMEOUT = 0.005  # [s]
OURS = ("hybrid", "pinv", "dls")
REFERENCE = "rtb_ik_LM"
BUNDLED = ("panda", "seed000_6dof")
#: arms of example-robot-data (drake_mh.robot.examples) beside the bundled ones
ERD_ARMS = ("ur5", "xarm7", "kinova")

_ROBOTS: dict = {}
_PROBLEMS: dict = {}
_WARM: set = set()


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


def peer_problem(robot_name: str, label: str) -> str | None:
    """Why peer ``label`` cannot run on robot ``robot_name`` (:func:`drake_mh.ik.peers.peer_problem`),
    checked at grid time so that a peer that cannot model a robot is left out of the grid and named
    in the summary."""
    return peers.peer_problem(_robot(robot_name), label)


def _target(robot_name: str, target: int) -> np.ndarray:
    """Target pose ``X_WT (4, 4)``: FK of a random configuration (same for every method)."""
    robot = _robot(robot_name)
    rng = np.random.default_rng([TARGET_SEED, robots().index(robot_name), int(target)])
    return robot.fk(robot.random_configurations(1, rng)[0])


def _solve(robot, label: str, X_WT: np.ndarray, seed: int):
    """One timed solve: ``(q, our IKResult or None, the method's own success flag or None)``."""
    if label in OURS:
        problem = IKProblem(robot, X_WT, position_tolerance=TOL, orientation_tolerance=TOL)
        result = solve_ik(problem, label, seed=seed, timeout=TIMEOUT)
        return result.q, result, result.success
    q, reported = peers.solve_peer(robot, label, X_WT, seed, TOL, TIMEOUT)
    return q, None, reported


def run(case: Case) -> dict:
    """Solves one target with one method (module docstring)."""
    robot = _robot(case["robot"])
    label = case["method"]
    X_WT = _target(case["robot"], case["target"])
    if (robot.name, label) not in _WARM:  # imports, compiled kernels, rtb's model: untimed
        _WARM.add((robot.name, label))
        _solve(robot, label, X_WT, 0)
    start, cpu_start = time.perf_counter(), time.process_time()
    q, result, reported = _solve(robot, label, X_WT, case.seed)
    elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu_start
    problem = IKProblem(robot, X_WT, position_tolerance=TOL, orientation_tolerance=TOL)
    checked = verify(problem, q, method=label, start=0.0, nfe=0)  # the same Drake check for all
    if result is not None and result.success != checked.success:  # pragma: no cover - a bug if it happens
        raise DrakeMhError(f"{label} reported success={result.success}, Drake's check says {checked.success}")
    return {"success": checked.success, "time": elapsed, "cpu_time": cpu,
            "error": max(checked.position_error, checked.orientation_error),
            "nfe": result.nfe if result is not None else 0, "load": load_average(), "reported": reported,
            "message": checked.message}


def peer_problems() -> dict[tuple[str, str], str]:
    """``{(robot, peer): why it is left out}`` for this run (cached; see :func:`peer_problem`)."""
    if not _PROBLEMS:
        _PROBLEMS[None] = None
        for robot in robots():
            for label in PEERS:
                why = peer_problem(robot, label)
                if why is not None:
                    _PROBLEMS[(robot, label)] = why
    return {k: v for k, v in _PROBLEMS.items() if k is not None}


def _grid(quick: bool) -> list[dict]:
    problems = peer_problems()
    cases = []
    for robot in robots():
        methods = list(OURS) + [m for m in PEERS if (robot, m) not in problems]
        n = (10 if robot in BUNDLED else 5) if quick else 1000
        for t in range(n):
            order = methods if t % 2 == 0 else methods[::-1]
            cases += [{"robot": robot, "target": t, "method": m} for m in order]
    return cases


def summarize(records: list[dict]) -> str:
    """One table per robot: success, times, CPU time, ratio to rtb's ik_LM in the same run.

    ``own flag wrong``: solves where the method's own success flag disagrees with Drake's check
    (ikpy has none).
    """
    ok = [r for r in records if r.get("status") == "ok"]
    if not ok:
        return ""
    loads = np.array([r["load"] for r in ok])
    lines = ["### IK vs peers: TRAC-IK protocol (6-D pose at 1e-5 m / 1e-5 rad, 5 ms timeout)", "",
             f"CPU: {cpu_model()} ({os.cpu_count()} logical CPUs); 1-minute load average during the run "
             f"{loads.min():.2f}-{loads.max():.2f} (mean {loads.mean():.2f}). Times include what a Python "
             "caller pays (drake_mh: IKProblem + solve_ik with its Drake verification; peers: their call, "
             "TRAC-IK's with the quaternion conversion). "
             f"`vs ik_LM` = mean time of {REFERENCE} / mean time of the method, same run, methods interleaved "
             "per target. Success re-checked by Drake for every method.", ""]
    missing = sorted({PEER_MODULE[m] for m in PEERS if not peer_available(m)})
    if missing:
        lines += [f"Not installed (`pip install -e '.[peers]'`): {', '.join(missing)}; their rows are missing.", ""]
    for (robot, label), why in sorted(peer_problems().items()):
        if peer_available(label):
            lines += [f"{label} left out on {robot}: {why}", ""]
    for robot in dict.fromkeys(r["robot"] for r in ok):
        rows = [r for r in ok if r["robot"] == robot]
        groups: dict[str, list[dict]] = {}
        for r in rows:
            groups.setdefault(r["method"], []).append(r)
        ref = groups.get(REFERENCE)
        ref_mean = np.mean([r["time"] for r in ref]) if ref else np.nan
        n = max(len(g) for g in groups.values())
        lines += [f"**{robot}** ({n} targets)", "",
                  "| method | success % | mean [ms] | median [ms] | p95 [ms] | CPU mean [ms] | vs ik_LM "
                  "| own flag wrong |", "|---|---|---|---|---|---|---|---|"]
        for method, group in groups.items():
            t = 1e3 * np.array([r["time"] for r in group])
            cpu = 1e3 * np.mean([r["cpu_time"] for r in group])
            rate = 100 * np.mean([bool(r["success"]) for r in group])
            ratio = ref_mean / (t.mean() / 1e3) if np.isfinite(ref_mean) else np.nan
            flags = [r for r in group if r.get("reported") is not None]
            wrong = f"{sum(r['reported'] != r['success'] for r in flags)}/{len(flags)}" if flags else "no flag"
            lines.append(f"| {method} | {rate:.2f} | {t.mean():.3f} | {np.median(t):.3f} | "
                         f"{np.percentile(t, 95):.3f} | {cpu:.3f} | {ratio:.2f}x | {wrong} |")
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
                  conditions=("6-D pose at 1e-5 m / 1e-5 rad, 5 ms timeout (drake_mh, TRAC-IK at eps 1e-5/sqrt(3)); "
                              "rtb: E < 5e-11, 100 searches; ikpy: one least-squares run")),
    description=(
        "IK against robotics-toolbox-python's ik_LM/ik_GN (C++), TRAC-IK and ikpy on the TRAC-IK protocol, "
        "methods interleaved per target, every answer checked by Drake, wall and CPU time and load average recorded."
    ),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
