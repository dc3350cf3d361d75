"""Compiling the planning kernels in the background while other work runs (``drake-mh demo``).

From an empty numba cache, the quick ``motion_benchmark`` would spend minutes compiling: the
verification, retiming and certificate kernels on its first case and ``rrt_connect``'s kernel on
its second (about a minute or two each), one after the other on one core, while the machine's
second core idles. :func:`start` compiles them in two separate processes (numba's disk cache then
serves the study) while the demo's other studies run; :func:`wait` joins them before
the study that needs them. A warm cache makes the process cheap (loading only, a few seconds).
Nothing here is timed or reported: a failure only means the study compiles for itself.
"""

from __future__ import annotations

import logging
import multiprocessing
import time

logger = logging.getLogger(__name__)

#: [s] the longest the demo waits for the background compilation before going on without it
WAIT_TIMEOUT = 300.0


def _planner_kernel() -> None:
    """Compiles ``rrt_connect``'s kernel (:func:`drake_mh.planning.rrt_connect.planner.prepare`)
    on a small problem of the capsule Panda (the quick ``motion_benchmark``'s robot).

    ``prepare`` reads only the problem's robot, scene, start and clearances: they are given
    here without a :class:`~drake_mh.planning.MotionProblem`, whose checks would compile the
    scene's boolean kernels too (32 s), which the other process compiles already."""
    from types import SimpleNamespace

    import numpy as np

    import drake_mh
    from drake_mh.planning.rrt_connect import planner
    from drake_mh.scene import Box, Scene

    robot = drake_mh.load_robot("panda")
    scene = Scene(robot)
    scene.add("table", Box((1.0, 1.0, 0.05)), [0.6, 0.0, -0.2])
    home = np.clip(np.zeros(robot.nq), robot.lower, robot.upper)
    planner.prepare(SimpleNamespace(robot=robot, scene=scene, q_start=home, clearance=0.0, self_clearance=0.0))


def _verification_kernels() -> None:
    """Compiles the kernels of a problem set's generation and of a motion's verification,
    retiming and certificate: ``straight`` on the quick ``motion_benchmark``'s problem."""
    from drake_mh.planning import solve_motion
    from drake_mh.planning.problems import problem_set

    solve_motion(problem_set("table_pick", "panda", count=1)[0], "straight", seed=0, timeout=1.0)


def _run(target) -> None:
    try:
        target()
    except Exception:  # noqa: BLE001 - the study then compiles for itself
        logger.debug("background compilation failed", exc_info=True)


def start() -> list:
    """Starts the compilations in two new processes (``spawn``), one per kernel family; an
    empty list if processes cannot start."""
    processes = []
    for target in (_planner_kernel, _verification_kernels):
        try:
            process = multiprocessing.get_context("spawn").Process(target=_run, args=(target,),
                                                                   name="drake_mh-warmup", daemon=True)
            process.start()
            processes.append(process)
        except (OSError, RuntimeError) as exc:
            logger.debug("no background compilation: %s", exc)
    return processes


def wait(processes, timeout: float = WAIT_TIMEOUT) -> None:
    """Waits for :func:`start`'s processes (at most ``timeout`` seconds in all, then stops them)."""
    deadline = time.monotonic() + timeout
    for process in processes or ():
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            logger.warning("background compilation still running after %.0f s; stopping it", timeout)
            process.terminate()
            process.join(5.0)
