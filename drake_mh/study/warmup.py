"""Compiling the package's kernels ahead of their first use: ``drake-mh warmup``, the demo's
background compilation and the ``first_call`` study's measurements.

From an empty numba cache each family of kernels compiles on its first call, for seconds to
minutes (``docs/first_use.md``). :data:`GROUPS` names the families, each with a small workload
that calls the kernels as the library does (same argument types, so the same compiled
specializations): :func:`warmup` runs them in parallel processes, numba's disk cache then serves
every later process. :func:`start` / :func:`wait` compile the planning kernels in the background
while the demo's other studies run. ``python -m drake_mh.study.warmup`` runs one group or one
kernel in this process and writes what compiled (the study's probe, :func:`main`).
"""

from __future__ import annotations

import concurrent.futures
import json
import logging
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Iterable

logger = logging.getLogger(__name__)

#: [s] the longest the demo waits for the background compilation before going on without it
WAIT_TIMEOUT = 300.0


def _panda_scene():
    import drake_mh
    from drake_mh.scene import Box, Scene, Sphere

    robot = drake_mh.load_robot("panda")
    scene = Scene(robot)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    scene.add("table", Box(1.0, 1.0, 0.05), [0.5, 0.0, -0.05])
    return robot, scene


def _motion_problem() -> None:
    """A :class:`~drake_mh.planning.MotionProblem` checks its ends: the scene's boolean kernels
    (one configuration, and a batch)."""
    import numpy as np

    from drake_mh.planning import MotionProblem

    robot, scene = _panda_scene()
    MotionProblem(robot, scene, robot.home.copy(), np.array([1.0, 0.3, 0.0, -1.5, 0.0, 1.8, 0.7]), clearance=0.01)
    scene.collision_free(np.tile(robot.home, (3, 1)))


def _rrt_connect() -> None:
    """``rrt_connect``'s kernel (:func:`drake_mh.planning.rrt_connect.planner.prepare`) and its
    motion check from Python (``certify_motions``). ``prepare`` reads only the problem's robot,
    scene, start and clearances: they are given without a MotionProblem, whose checks belong to
    :func:`_motion_problem`. Where the compiled core is built both run in C++: nothing compiles
    (``DRAKE_MH_COMPILED_CORE=0``: the numba kernels)."""
    from types import SimpleNamespace

    from drake_mh.planning.rrt_connect import planner

    robot, scene = _panda_scene()
    planner.prepare(SimpleNamespace(robot=robot, scene=scene, q_start=robot.home.copy(), clearance=0.0,
                                    self_clearance=0.0))
    planner.certify_motions(scene, robot.home[None], robot.home[None])


def _verification() -> None:
    """A motion's verification, retiming and certificates (:func:`drake_mh.planning.verify_motion`
    of the free straight motion of a first plan; the problem is given without a MotionProblem,
    whose checks belong to :func:`_motion_problem`)."""
    from types import SimpleNamespace

    import numpy as np

    from drake_mh.planning import verify_motion

    robot, scene = _panda_scene()
    goal = np.array([1.0, 0.3, 0.0, -1.5, 0.0, 1.8, 0.7])
    problem = SimpleNamespace(robot=robot, scene=scene, q_start=robot.home.copy(), goal_configurations=goal[None],
                              goal_pose=None, frame=None, clearance=0.01, self_clearance=0.0)
    result = verify_motion(problem, np.array([robot.home, goal]), "straight")
    if result.trajectory is None:
        raise RuntimeError(f"the warm-up motion was not retimed ({result.message}): its kernels did not all compile")


def _lazy_prm_star() -> None:
    """``lazy_prm_star``'s kernel (its ``prepare``, which loads ``rrt_connect``'s too)."""
    from types import SimpleNamespace

    from drake_mh.planning.lazy_prm_star import planner

    robot, scene = _panda_scene()
    planner.prepare(SimpleNamespace(robot=robot, scene=scene, q_start=robot.home.copy(), clearance=0.0,
                                    self_clearance=0.0))


def _kinematics() -> None:
    """Batched and one-configuration forward kinematics and Jacobians."""
    import numpy as np

    import drake_mh

    robot = drake_mh.load_robot("panda")
    Q = np.tile(robot.home, (4, 1))
    robot.batch.fk(Q)
    robot.batch.jacobian(Q)
    robot.fk(robot.home)
    robot.jacobian(robot.home)


def _ik() -> None:
    """IK: the hybrid metaheuristic + Levenberg-Marquardt solver, with and without a scene."""
    from drake_mh.ik import IKProblem, solve_ik

    robot, scene = _panda_scene()
    pose = robot.fk(robot.home)
    solve_ik(IKProblem(robot, pose), "hybrid", seed=0, timeout=1.0)
    solve_ik(IKProblem(robot, pose, scene=scene), "hybrid", seed=0, timeout=1.0)


def _optimizers() -> None:
    """Every metaheuristic's compiled steps, on a small sphere function."""
    import numpy as np

    from drake_mh.optim import available_methods, minimize

    bounds = np.array([[-1.0, 1.0]] * 3)
    for method in available_methods():
        minimize(lambda X: np.sum(X * X, axis=1), bounds, method=method, budget=200, seed=0)


def _distances() -> None:
    """Exact distances and the clearance queries that correct penetration."""
    import numpy as np

    robot, scene = _panda_scene()
    Q = np.tile(robot.home, (2, 1))
    scene.min_distance(robot.home)
    scene.batch_min_distance(Q)
    scene.exact_min_distance(Q)


GROUPS: dict[str, tuple[str, Callable[[], None]]] = {
    "motion_problem": ("collision checks of a MotionProblem's ends", _motion_problem),
    "rrt_connect": ("rrt_connect's planner kernel and motion check", _rrt_connect),
    "verification": ("a motion's verification, retiming and certificates", _verification),
    "lazy_prm_star": ("lazy_prm_star's planner kernel", _lazy_prm_star),
    "kinematics": ("forward kinematics and Jacobians", _kinematics),
    "ik": ("hybrid IK (Levenberg-Marquardt)", _ik),
    "optimizers": ("every metaheuristic's steps", _optimizers),
    "distances": ("exact distances and clearance queries", _distances),
}
"""Kernel families: ``name -> (what compiles, workload that calls those kernels)``."""

FIRST_PLAN = ("motion_problem", "rrt_connect", "verification")
"""The groups a first ``MotionProblem`` + ``solve_motion(problem, "rrt_connect")`` compiles."""


def run_group(name: str) -> dict:
    """Runs one group's workload in this process: ``{"group", "seconds", "cpu", "error"}``
    (``error`` None or the exception's text)."""
    wall, cpu = time.perf_counter(), time.process_time()
    error = None
    try:
        GROUPS[name][1]()
    except Exception as exc:  # noqa: BLE001 - reported per group; the other groups still compile
        error = f"{type(exc).__name__}: {exc}"
        logger.debug("warm-up group %s failed", name, exc_info=True)
    return {"group": name, "seconds": time.perf_counter() - wall, "cpu": time.process_time() - cpu, "error": error}


def check_groups(groups: Iterable[str] | None = None, processes: int | None = None) -> tuple[list[str], int]:
    """``(group names, worker processes)`` of a :func:`warmup` call, checked.

    Raises:
        InvalidArgument: an unknown group name, or fewer than 1 process.
    """
    from drake_mh.errors import InvalidArgument

    names = list(GROUPS if groups is None else groups)
    unknown = [name for name in names if name not in GROUPS]
    if unknown:
        raise InvalidArgument(f"unknown kernel family {unknown}; families are {list(GROUPS)} (drake-mh warmup --list)")
    if processes is not None and (isinstance(processes, bool) or not isinstance(processes, int) or processes < 1):
        raise InvalidArgument(f"processes must be an integer >= 1, got {processes!r}")
    return names, max(1, min(len(names), processes or os.cpu_count() or 1))


def warmup(groups: Iterable[str] | None = None, processes: int | None = None,
           progress: Callable[[dict], None] | None = None) -> list[dict]:
    """Compiles the kernels of ``groups`` (default: all of :data:`GROUPS`) in ``processes``
    parallel processes (default: the CPU count), each group in its own process; numba's disk
    cache keeps them for every later process.

    Args:
        groups: names of :data:`GROUPS`.
        processes: worker processes (at least 1).
        progress: called with each group's result as it finishes.

    Returns:
        One :func:`run_group` result per group, in the order they finished.

    Raises:
        InvalidArgument: an unknown group name, or fewer than 1 process.
    """
    names, workers = check_groups(groups, processes)
    results = []
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool:
        futures = [pool.submit(run_group, name) for name in names]
        for future in concurrent.futures.as_completed(futures):
            result = future.result()
            results.append(result)
            if progress is not None:
                progress(result)
    return results


def _demo_planning() -> None:
    """The quick ``motion_benchmark``'s kernels besides the planner's: its problem set's generation
    (IK, exact distances) and a motion's verification and retiming."""
    from drake_mh.planning import solve_motion
    from drake_mh.planning.problems import problem_set

    solve_motion(problem_set("table_pick", "panda", count=1)[0], "straight", seed=0, timeout=1.0)
    _verification()


def _run(target) -> None:
    try:
        target()
    except Exception:  # noqa: BLE001 - the study then compiles for itself
        logger.debug("background compilation failed", exc_info=True)


def start() -> list:
    """Starts the compilation of the quick ``motion_benchmark``'s kernels in two new processes
    (``spawn``): ``rrt_connect``'s, and its problem set's and verification's; an empty list
    if processes cannot start. Nothing here is timed or reported: a failure only means the
    study compiles for itself."""
    processes = []
    for target in (_rrt_connect, _demo_planning):
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


def _recorder() -> list:
    """Records every top-level compile of the package's kernels: ``[module, qualname, argument
    types, wall s, CPU s]`` (the kernels Python calls, their callees' compiles included)."""
    from numba.core import event

    records, stack = [], []

    class Recorder(event.Listener):
        def on_start(self, ev):
            stack.append((time.perf_counter(), time.process_time()))

        def on_end(self, ev):
            wall, cpu = stack.pop()
            function = ev.data["dispatcher"].py_func
            if not stack and function.__module__.startswith("drake_mh."):
                records.append([function.__module__, function.__qualname__, tuple(ev.data["args"]),
                                time.perf_counter() - wall, time.process_time() - cpu])

    event.register("numba:compile", Recorder())
    return records


def main(argv: list[str] | None = None) -> int:
    """``python -m drake_mh.study.warmup (--group NAME | --kernel MODULE:QUALNAME --signatures
    FILE) --out FILE``: run one group's workload (recording the kernels that compiled, pickled to
    ``--signatures`` if given), or compile one kernel for the signatures a group recorded, in
    this process; writes a JSON record to ``--out`` (the ``first_call`` study's probe)."""
    import argparse
    import importlib
    import pickle

    parser = argparse.ArgumentParser(prog="python -m drake_mh.study.warmup")
    parser.add_argument("--group")
    parser.add_argument("--kernel")
    parser.add_argument("--signatures")
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)
    import drake_mh  # noqa: F401 - numba's cache folder, before numba compiles anything

    records = _recorder()
    if args.group:
        out = run_group(args.group)
        kernels: dict = {}  # (module, qualname) -> [specializations, wall s, CPU s]
        for m, q, _, w, c in records:
            entry = kernels.setdefault((m, q), [0, 0.0, 0.0])
            entry[0], entry[1], entry[2] = entry[0] + 1, entry[1] + w, entry[2] + c
        out["kernels"] = [[m, q, *entry] for (m, q), entry in kernels.items()]
        if args.signatures:
            with open(args.signatures, "wb") as fh:
                pickle.dump([(m, q, a) for m, q, a, _, _ in records], fh)
    else:
        module, qualname = args.kernel.split(":")
        with open(args.signatures, "rb") as fh:
            signatures = [a for m, q, a in pickle.load(fh) if (m, q) == (module, qualname)]
        dispatcher = getattr(importlib.import_module(module), qualname)
        wall, cpu = time.perf_counter(), time.process_time()
        for signature in signatures:
            dispatcher.compile(signature)
        out = {"kernel": args.kernel, "seconds": time.perf_counter() - wall, "cpu": time.process_time() - cpu,
               "signatures": len(signatures), "compiled": bool(records)}
    with open(args.out, "w") as fh:
        json.dump(out, fh)
    return 0 if out.get("error") is None else 1


if __name__ == "__main__":
    sys.exit(main())
