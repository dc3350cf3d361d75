"""Robots as shipped: ``solve_motion`` with its defaults on the arms of example-robot-data.

Each arm is loaded exactly as its package ships it (``drake_mh.load_robot(path, ee_frame=...)``:
position, velocity and effort limits, no acceleration limits), problems come from
:func:`drake_mh.planning.problems.problem_set` for that robot object (start and goal certified
free, straight joint-space line usually blocked), and every problem is solved with
``solve_motion(problem)``'s defaults (``rrt_connect``, 10 s, verified, retimed, certified).

Every verified motion is re-checked independently of drake_mh: the trajectory is sampled so that
no joint moves more than 5 mrad between samples (at least 2,000 samples), and on a fresh Drake
plant parsed from the robot's model text, with the obstacles registered as world geometry,
Drake's signed distance from every robot geometry to every obstacle must be > 0; the sampled
velocities must stay within the declared velocity limits, and the torques from Drake's
``CalcInverseDynamics`` minus ``CalcGravityGeneralizedForces`` (plus joint damping) within the
declared effort limits (``1 + 1e-6``). Self-collision is not re-checked here.

The script uses only what both the code before and after limits with provenance offer, so the
same grid runs on either (``PYTHONPATH=<checkout> python studies/shipped_arms.py --out DIR``).
Recorded per problem: verified success, the message, duration, the independent re-check and its
figures, where each enforced limit came from (when the code reports it).

Run: ``drake-mh study shipped_arms [--quick]`` or ``python studies/shipped_arms.py [--quick]``.
"""

from __future__ import annotations

import os

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average

ARMS = {  # name -> (path inside example-robot-data, end-effector frame)
    "panda_hand": ("robots/panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    "ur5": ("robots/ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur10": ("robots/ur_description/urdf/ur10_robot.urdf", "tool0"),
    "xarm7": ("robots/xarm_description/urdf/xarm7.urdf", "link_eef"),
    "kinova": ("robots/kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),
}
SETS = ("table_pick", "bookshelf_small", "cage")
PROBLEMS = 4
"""problems per set and arm (full grid)."""
SET_SEED = 2024
STEP = 0.005
"""[rad] largest joint motion between two samples of the independent re-check."""

_CACHE: dict = {"robots": {}, "problems": {}}


def _robot(name: str):
    if name not in _CACHE["robots"]:
        import drake_mh
        from drake_mh.robot.examples import example_robot_data_root

        root = example_robot_data_root()
        if root is None:
            raise RuntimeError("example-robot-data is not installed (pip install example-robot-data)")
        rel, ee = ARMS[name]
        _CACHE["robots"][name] = drake_mh.load_robot(root / rel, ee_frame=ee)
    return _CACHE["robots"][name]


def _problem(arm: str, name: str, index: int):
    key = (arm, name, index)
    if key not in _CACHE["problems"]:
        from drake_mh.planning.problems import problem_set

        found = problem_set(name, _robot(arm), count=1, seed=SET_SEED, first=index)
        _CACHE["problems"][key] = (found[0], found.info[0]["straight_free"])
    return _CACHE["problems"][key]


def _fresh_plant(robot, scene):
    """A new Drake plant and scene graph of the robot's model with the scene's obstacles."""
    from pydrake.math import RigidTransform, RotationMatrix
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
    from pydrake.multibody.tree import BodyIndex, JointIndex
    from pydrake.systems.framework import DiagramBuilder

    import logging

    builder = DiagramBuilder()
    plant, graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    drake_log = logging.getLogger("drake")
    level = drake_log.level
    drake_log.setLevel(logging.ERROR)  # the parser's notes on tags it ignores were printed at the first load
    try:
        Parser(plant).AddModels(file_contents=robot.model_text,
                                file_type={"mjcf": "xml"}.get(robot.model_format, robot.model_format))
    finally:
        drake_log.setLevel(level)
    children = {plant.get_joint(JointIndex(i)).child_body().index() for i in range(plant.num_joints())}
    for i in range(1, plant.num_bodies()):
        if plant.get_body(BodyIndex(i)).index() not in children:
            plant.WeldFrames(plant.world_frame(), plant.get_body(BodyIndex(i)).body_frame())
    obstacle_ids = set()
    for name, obstacle in scene.obstacles.items():
        X = RigidTransform(RotationMatrix(obstacle.X_WO[:3, :3]), obstacle.X_WO[:3, 3])
        obstacle_ids.add(plant.RegisterCollisionGeometry(plant.world_body(), X, obstacle.shape.to_drake(), name,
                                                         CoulombFriction(0.5, 0.5)))
    plant.Finalize()
    diagram = builder.Build()
    return plant, graph, diagram, obstacle_ids


def recheck(robot, scene, trajectory) -> dict:
    """The independent re-check of the module docstring: ``{"recheck_clear", "fresh_min_distance",
    "velocity_ratio", "torque_ratio", "recheck_samples"}``."""
    from pydrake.multibody.tree import MultibodyForces

    t0, t1 = float(trajectory.start_time), float(trajectory.end_time)
    coarse = trajectory.position(np.linspace(t0, t1, 2001))
    steps = int(np.ceil(np.max(np.abs(np.diff(coarse, axis=0))) / STEP * 2000))
    t = np.linspace(t0, t1, max(2001, steps + 1))
    Q, V, A = trajectory.derivatives(t, 2)
    plant, graph, diagram, obstacle_ids = _fresh_plant(robot, scene)
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    graph_context = graph.GetMyContextFromRoot(context)
    joints = [plant.GetJointByName(n) for n in robot.joint_names]
    index = np.array([j.position_start() for j in joints])
    damping = np.array([float(np.sum(j.default_damping_vector())) for j in joints])
    effort = np.asarray(robot.effort_limits, dtype=float)
    distance, torque = np.inf, 0.0
    for q, v, a in zip(Q, V, A):
        x, xv, xa = (np.zeros(plant.num_positions()) for _ in range(3))
        x[index], xv[index], xa[index] = q, v, a
        plant.SetPositions(plant_context, x)
        plant.SetVelocities(plant_context, xv)
        query = graph.get_query_output_port().Eval(graph_context)
        for pair in query.ComputeSignedDistancePairwiseClosestPoints(0.5):
            if (pair.id_A in obstacle_ids) != (pair.id_B in obstacle_ids):
                distance = min(distance, pair.distance)
        tau = plant.CalcInverseDynamics(plant_context, xa, MultibodyForces(plant))
        tau = (tau - plant.CalcGravityGeneralizedForces(plant_context))[index] + damping * v
        torque = max(torque, float(np.max(np.abs(tau) / effort)))
    velocity = float(np.max(np.abs(V) / robot.velocity_limits))
    return {"recheck_clear": bool(distance > 0.0 and velocity <= 1 + 1e-6 and torque <= 1 + 1e-6),
            "fresh_min_distance": float(distance), "velocity_ratio": velocity, "torque_ratio": torque,
            "recheck_samples": int(len(t))}


def _sources(result) -> str:
    table = getattr(result, "limits", None)
    if table is None:
        return ""
    parts = []
    for quantity in ("velocity", "acceleration", "jerk", "effort"):
        kinds = sorted(set(table.sources(quantity)))
        enforced = table.enforced is None or quantity in table.enforced
        parts.append(f"{quantity}: {'/'.join(kinds)}" + ("" if enforced else " (not enforced)"))
    return "; ".join(parts)


def run(case: Case) -> dict:
    from drake_mh.planning import solve_motion

    problem, straight_free = _problem(case["arm"], case["set"], case["problem"])
    load = load_average()
    result = solve_motion(problem)
    record = result.record()
    record.update(time=result.planning_time, error=result.duration if result.success else float("nan"),
                  nfe=0, straight_free=bool(straight_free), message=result.message[:300], limits=_sources(result),
                  load_average=load, cpu_model=cpu_model(), recheck_clear=None)
    if result.success:
        record.update(recheck(problem.robot, problem.scene, result.trajectory))
    return record


def _merged_sources(wins: list[dict]) -> str:
    """Per quantity, every distinct source seen over the records' ``limits`` fields."""
    seen: dict = {}
    for r in wins:
        for part in filter(None, (r.get("limits") or "").split("; ")):
            quantity, text = part.split(": ", 1)
            seen.setdefault(quantity, set()).add(text)
    return "; ".join(f"{q}: {' or '.join(sorted(texts))}" for q, texts in seen.items()) or "-"


def summarize(records: list[dict]) -> str:
    ok = [r for r in records if r.get("status") == "ok"]
    lines = [f"CPU: {ok[0]['cpu_model'] if ok else '?'}; 1-min load average: "
             + (f"{min(r['load_average'] for r in ok):.1f}-{max(r['load_average'] for r in ok):.1f}" if ok else "?"),
             "", "| arm | problems | verified | re-checked clear and within limits | straight line blocked | "
             "retimed toppra / ruckig | duration median [s] | worst velocity / torque ratio (re-check) | "
             "limit sources |", "|---|---|---|---|---|---|---|---|---|"]
    for arm in ARMS:
        group = [r for r in ok if r["arm"] == arm]
        if not group:
            continue
        wins = [r for r in group if r["success"]]
        clear = [r for r in wins if r.get("recheck_clear")]
        durations = [r["duration"] for r in wins]
        ratios = (f"{max(r['velocity_ratio'] for r in wins):.3f} / {max(r['torque_ratio'] for r in wins):.3f}"
                  if wins else "-")
        retimers = [r["message"].rsplit(" ", 1)[-1] for r in wins]
        lines.append(f"| {arm} | {len(group)} | {len(wins)} | {len(clear)} | "
                     f"{sum(not r['straight_free'] for r in group)} | {retimers.count('toppra')} / "
                     f"{retimers.count('ruckig')} | {np.median(durations) if durations else float('nan'):.2f} | "
                     f"{ratios} | {_merged_sources(wins)} |")
    failures = sorted({r["message"][:160] for r in ok if not r["success"]})
    if failures:
        lines += ["", "Messages of the failures (distinct, cut to 160 characters):", ""]
        lines += [f"* {m}" for m in failures[:8]]
    errors = [r for r in records if r.get("status") != "ok"]
    if errors:
        lines += ["", f"{len(errors)} case(s) raised (e.g. no certified-free problem for an arm in a set)."]
    return "\n".join(lines)


study = Study(
    name="shipped_arms",
    run=run,
    grid={"arm": list(ARMS), "set": list(SETS), "problem": range(PROBLEMS)},
    quick_grid={"arm": ["panda_hand"], "set": ["table_pick"], "problem": range(1)},
    fields=Fields(method="arm", success="success", time="time", error="error", nfe="nfe", rank=False,
                  error_unit="s", message="message",
                  conditions="solve_motion's defaults: rrt_connect, 10 s, verified, retimed and certified"),
    description=(
        "solve_motion with its defaults on example-robot-data's arms loaded as shipped (no acceleration limits), "
        "on generated problem sets; every verified motion re-checked on a fresh Drake plant (signed distance to the "
        "obstacles, velocity and torque limits). 'time' is the planning time [s], 'error' the duration of the "
        "retimed motion [s]."
    ),
    summarize=summarize,
    max_workers=int(os.environ.get("DRAKE_MH_SHIPPED_WORKERS", "1")),
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
