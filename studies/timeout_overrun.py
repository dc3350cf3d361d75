"""Timeout overrun: how long after its timeout each IK and motion-planning method returns.

The unit tests check that a timeout ends a search (the stop reason, and a bound on the CPU time
of 40 times the timeout, which load cannot inflate); how *promptly* it ends is a wall-clock
figure, measured here. Every case is a search that cannot succeed and has no budget to end it
otherwise, so it runs until its timeout:

* IK (``hybrid``, ``pso``, ``drake_snopt``): the capsule Panda, a position tolerance below
  round-off (``1e-300`` m); the returned ``IKResult.time`` is the wall time.
* Motion planning (``rrt_connect``, ``lazy_prm_star``, ``mh_pso``, ``drake_kto``, and
  ``ompl_rrtconnect`` where OMPL is installed): ``planar2r`` with a ball above and below the
  shoulder, so that its first joint cannot turn from 0 to 3 rad either way
  (``MotionResult.planning_time``, no retiming), but ``drake_kto`` between two compartments
  of a bookshelf (on the planar goal SNOPT gives up early); ``mh_pso_long``: ``mh_pso`` on the
  Panda behind a ball with generations of 2,000 individuals x 256 samples (over a second each),
  the case whose generation once overran a 10 s timeout by 1.3 s.

Each method runs once before the clock (kernels compiled and loaded, as ``prepare`` does for a
user's first call). Recorded: the returned time [s], the overrun past the timeout [s] and the
CPU seconds; the runner adds the CPU model and the load average beside them (the machines are
shared: absolute times drift). A case succeeds when the overrun is within :data:`SLACK` (its
message says why it ended).

Run: ``drake-mh study timeout_overrun [--quick]`` or ``python studies/timeout_overrun.py [--quick]``.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.study import Case, Fields, Study

#: [s] the overrun a case may have (what the unit tests asserted before they stopped timing)
SLACK = 0.5
IK_METHODS = ("hybrid", "pso", "drake_snopt")
MOTION_METHODS = ("rrt_connect", "lazy_prm_star", "mh_pso", "mh_pso_long", "drake_kto", "ompl_rrtconnect")


def _ik(method: str, timeout: float) -> tuple[float, float, str]:
    import drake_mh
    from drake_mh.ik import IKProblem, solve_ik

    panda = drake_mh.load_robot("panda")
    problem = IKProblem(panda, [0.3, 0.0, 0.6], position_tolerance=1e-300)  # below round-off
    solve_ik(problem, method, seed=0, budget=50)  # loaded before the clock
    cpu = time.process_time()
    result = solve_ik(problem, method, seed=0, timeout=timeout)
    return result.time, time.process_time() - cpu, result.message


def _blocked_planar():
    import drake_mh
    from drake_mh.planning import MotionProblem
    from drake_mh.scene import Scene, Sphere

    robot = drake_mh.load_robot("planar2r")
    scene = Scene(robot)
    scene.add("up", Sphere(0.05), [0.0, 0.0, 0.16])
    scene.add("down", Sphere(0.05), [0.0, 0.0, -0.16])
    return MotionProblem(robot, scene, np.zeros(2), np.array([3.0, 0.0]))


def _blocked_panda():
    import drake_mh
    from drake_mh.planning import MotionProblem
    from drake_mh.scene import Scene, Sphere

    panda = drake_mh.load_robot("panda")
    middle, goal = panda.home.copy(), panda.home.copy()
    middle[0] += 0.75
    goal[0] += 1.5
    scene = Scene(panda)
    scene.add("wall", Sphere(0.08), panda.fk(middle)[:3, 3])
    return MotionProblem(panda, scene, panda.home, goal)


def _bookshelf_panda():
    """Between two compartments of a bookshelf: SNOPT runs into its 1000 major iterations here
    (about 30 s), so drake_kto runs until its timeout (on the walled-off planar goal it gives up
    early)."""
    import drake_mh
    from drake_mh.planning import MotionProblem
    from drake_mh.scene import Box, Scene

    scene = Scene(drake_mh.load_robot("panda"))
    scene.add("table", Box((0.6, 1.0, 0.04)), [0.6, -0.1, 0.08])
    scene.add("back", Box((0.6, 0.02, 1.0)), [0.4, 0.8, 0.5])
    scene.add("side_a", Box((0.02, 0.35, 1.0)), [0.1, 0.625, 0.5])
    scene.add("side_b", Box((0.02, 0.35, 1.0)), [0.7, 0.625, 0.5])
    for i, z in enumerate((0.1, 0.42, 0.74, 1.0)):
        scene.add(f"board{i}", Box((0.6, 0.35, 0.02)), [0.4, 0.625, z])
    return MotionProblem(scene.robot, scene, [0.0972, 0.9756, 1.5217, -1.5073, 0.2653, 3.1593, 0.3317],
                         [0.0603, 1.7535, 1.5162, -1.6875, -0.3699, 3.3293, 0.1854])


def _motion(method: str, timeout: float) -> tuple[float, float, str]:
    from drake_mh.planning import available_motion_methods, solve_motion

    options = {"budget": 10 ** 7} if method.startswith("mh_") else {}
    if method == "mh_pso_long":
        problem, method = _blocked_panda(), "mh_pso"
        options.update(pop_size=2000, samples=256)
    elif method == "drake_kto":
        problem = _bookshelf_panda()
    else:
        problem = _blocked_planar()
    if method not in available_motion_methods():
        raise RuntimeError(f"{method} is not registered here (an optional peer that is not installed)")
    solve_motion(problem, method, seed=0, timeout=0.05, retime=False)  # compiled before the clock
    result = solve_motion(problem, method, seed=0, timeout=timeout, retime=False, **options)
    return result.planning_time, result.cpu_time, result.message


def run(case: Case) -> dict:
    """One search that runs into its timeout; how long after the timeout it returned."""
    timeout = float(case["timeout"])
    kind = "ik" if case["method"] in IK_METHODS else "motion"
    returned, cpu, message = (_ik if kind == "ik" else _motion)(case["method"], timeout)
    overrun = returned - timeout
    return {
        "kind": kind,
        "success": bool(overrun <= SLACK),
        "time": returned,
        "error": overrun,
        "cpu_time": cpu,
        "message": message,
    }


def summarize(records: list[dict]) -> str:
    """Per method and timeout: median and largest overrun."""
    ok = [r for r in records if r.get("status") == "ok"]
    lines = [f"Overrun = returned time - timeout [s]; a case passes within {SLACK} s.",
             "",
             "| method | timeout [s] | cases | median overrun [s] | largest overrun [s] | median CPU [s] | pass |",
             "|---|---|---|---|---|---|---|"]
    for method in (*IK_METHODS, *MOTION_METHODS):
        for timeout in sorted({r["timeout"] for r in ok}):
            group = [r for r in ok if r["method"] == method and r["timeout"] == timeout]
            if not group:
                continue
            over = [r["error"] for r in group]
            lines.append(f"| {method} | {timeout:g} | {len(group)} | {np.median(over):.3f} | {max(over):.3f} | "
                         f"{np.median([r['cpu_time'] for r in group]):.3f} | "
                         f"{sum(r['success'] for r in group)}/{len(group)} |")
    return "\n".join(lines)


def _methods() -> list[str]:
    from drake_mh.planning import available_motion_methods

    motion = [m for m in MOTION_METHODS if m == "mh_pso_long" or m in available_motion_methods()]
    return [*IK_METHODS, *motion]


study = Study(
    name="timeout_overrun",
    run=run,
    grid={"method": _methods(), "timeout": [0.05, 0.3, 1.0], "rep": range(3)},
    quick_grid={"method": ["hybrid", "rrt_connect", "mh_pso"], "timeout": [0.05], "rep": range(1)},
    fields=Fields(method="method", success="success", time="time", error="error", nfe="cpu_time", rank=False,
                  error_unit="s", message="message",
                  conditions=f"a search that cannot succeed, ended by its timeout; success = overrun <= {SLACK} s"),
    description=(
        "How long after its timeout each IK and motion-planning method returns, on searches that "
        "cannot succeed (an IK tolerance below round-off; a planar arm whose goal is walled off). "
        "'time' is the returned wall time [s], 'error' the overrun past the timeout [s]."
    ),
    summarize=summarize,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
