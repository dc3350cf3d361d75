"""``drake-mh robots``: the robot catalogue and a forward-kinematics / Jacobian / distance smoke
test on every robot, or one robot's entry.

``drake-mh robots`` (also ``python -m drake_mh`` and ``python -m drake_mh.smoke``) prints, for each
bundled model, its joints, end effector and limits, then on random configurations within limits
the largest difference between the batched kernel and Drake (FK and Jacobian), and the exact
(Drake) vs sphere-model clearance to a sphere obstacle placed near the arm.
``drake-mh robots PATH_OR_NAME`` describes one robot in full (:func:`catalogue_entry`).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

import numpy as np

from drake_mh.cli.options import add_robot_options, load_robot_from_args
from drake_mh.errors import DrakeMhError

__all__ = ["register", "cmd_robots", "run_smoke", "catalogue_entry", "robot_catalogue", "smoke_row", "kernel_errors",
           "sphere_check"]


def robot_catalogue() -> list[dict]:
    """One summary row per bundled robot."""
    import drake_mh

    rows = []
    for name in drake_mh.available_robots():
        robot = drake_mh.load_robot(name)
        rows.append(dict(
            name=name, nq=robot.nq, ee=robot.ee_frame_name,
            reach=float(np.linalg.norm(robot.fk(robot.home)[:3, 3])),
            max_velocity=float(np.max(robot.velocity_limits)),
            max_effort=float(np.max(robot.effort_limits)),
        ))
    return rows


def catalogue_entry(robot) -> list[str]:
    """The catalogue entry of one robot: DOF, joints and limits, end effector, locked joints,
    collision geometry per link by shape, meshes, and the sphere model (count and bound)."""
    lines = [f"{robot.name}: {robot.model_format.upper()} from {robot.source}",
             f"  DOF {robot.nq}, end effector {robot.ee_frame_name!r}, |p_WE| at mid-range "
             f"{float(np.linalg.norm(robot.fk(robot.home)[:3, 3])):.3f} m"]
    lines.append(f"  {'joint':<24}{'lower':>10}{'upper':>10}{'max vel':>10}{'max effort':>12}")
    for i, name in enumerate(robot.joint_names):
        lo, hi = ("continuous", "") if robot.continuous[i] else (f"{robot.lower[i]:.4f}",
                                                                  f"{robot.upper[i]:.4f}")
        lines.append(f"  {name:<24}{lo:>10}{hi:>10}{robot.velocity_limits[i]:>10.3f}"
                     f"{robot.effort_limits[i]:>12.1f}")
    lines.append("  (limits in rad or m, rad/s or m/s, N m or N; inf: not declared)")
    lines.append("  where the limits come from:")
    lines += [f"    {line.split(': ', 1)[0]}: {line.rsplit(' | ', 1)[1]}" for line in robot.limits.summary()]
    locked = ", ".join(f"{k} = {v:g}" for k, v in robot.locked_joints.items())
    lines.append(f"  locked joints: {locked or 'none'}")
    summary = robot.collision_summary()
    if summary:
        total: dict[str, int] = {}
        for counts in summary.values():
            for kind, n in counts.items():
                total[kind] = total.get(kind, 0) + n
        lines.append(f"  collision geometry: {sum(total.values())} on {len(summary)} links ("
                     + ", ".join(f"{n} {k}" for k, n in sorted(total.items())) + ")")
        for link, counts in summary.items():
            lines.append(f"    {link:<24}" + ", ".join(f"{n} {k}" for k, n in sorted(counts.items())))
    else:
        lines.append("  collision geometry: none (distance queries and obstacle-aware planning "
                     "need <collision> elements)")
    meshes = robot.mesh_files
    if meshes["collision"] or meshes["visual"]:
        from drake_mh._support.cache import cache_dir

        lines.append(f"  meshes: {len(meshes['collision'])} collision (as convex hulls), "
                     f"{len(meshes['visual'])} visual; converted files in {cache_dir('meshes')}")
    try:
        model = robot.sphere_model
        lines.append(f"  sphere model: {model.num_spheres} spheres, bound {model.bound:.4f} m "
                     "(reports at most this much less clearance than the exact distance)")
    except DrakeMhError as exc:
        lines.append(f"  sphere model: not available ({_short(exc)})")
    return lines


def _short(exc: Exception, limit: int = 240) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: " + (text if len(text) <= limit else text[:limit] + " ...")


def kernel_errors(robot, n: int = 200, seed: int = 0) -> tuple[float, float]:
    """Largest |batched kernel - Drake| over ``n`` random configurations: ``(FK, Jacobian)``."""
    Q = robot.random_configurations(n, seed)
    T, J = robot.batch.fk_jacobian(Q)
    fk_err = max(np.abs(T[i] - robot.fk_drake(q)).max() for i, q in enumerate(Q))
    jac_err = max(np.abs(J[i] - robot.jacobian_drake(q)).max() for i, q in enumerate(Q))
    return float(fk_err), float(jac_err)


def sphere_check(robot, n: int = 50, seed: int = 0) -> dict:
    """Sphere model vs exact (Drake) clearance to a sphere obstacle placed near the arm."""
    from drake_mh.scene import Scene, Sphere

    Q = robot.random_configurations(n, seed)
    scene = Scene(robot)
    p_obstacle = 0.6 * robot.fk(robot.home)[:3, 3] + np.array([0.0, 0.0, 0.25])
    scene.add("ball", Sphere(0.08), p_obstacle)
    exact = scene.exact_min_distance(Q)
    spheres = scene.batch_min_distance(Q)
    clear = exact >= 0
    return dict(
        spheres=scene.sphere_model.num_spheres, bound=scene.sphere_model.bound,
        worst_gap=float(np.max(exact[clear] - spheres[clear])) if clear.any() else float("nan"),
        collisions=int((~clear).sum()), missed=int(np.sum(~clear & (spheres >= 0))),
    )


def smoke_row(name, n: int = 200, seed: int = 0) -> dict:
    """Kernel-vs-Drake and sphere-vs-exact figures for one robot (a name or a ``Robot``)."""
    import drake_mh

    robot = drake_mh.load_robot(name) if isinstance(name, str) else name
    fk_err, jac_err = kernel_errors(robot, n, seed)
    return dict(name=robot.name, fk_err=fk_err, jac_err=jac_err,
                manipulability=robot.manipulability(robot.home, translational=robot.nq >= 3),
                **sphere_check(robot, min(n, 50), seed))


def run_smoke(out: Callable[[str], object] = print) -> list[dict]:
    """Print the catalogue and the smoke test of every bundled robot; returns the smoke rows.

    Also what ``python -m drake_mh`` and ``drake-mh robots`` (without a name) print.
    """
    out("drake_mh robots (urdf/):")
    out(f"  {'name':<14}{'nq':>3}  {'end effector':<14}{'|p_WE| home [m]':>16}"
        f"{'max vel [rad/s]':>17}{'max effort [N m]':>18}")
    for r in robot_catalogue():
        out(f"  {r['name']:<14}{r['nq']:>3}  {r['ee']:<14}{r['reach']:>16.3f}"
            f"{r['max_velocity']:>17.3f}{r['max_effort']:>18.1f}")
    out("")
    out("Smoke test on 200 random configurations per robot (kernel vs Drake; a sphere obstacle):")
    out(f"  {'name':<14}{'max|ΔFK|':>10}{'max|ΔJ|':>10}{'spheres':>9}{'bound [m]':>11}"
        f"{'worst gap [m]':>15}{'collisions':>12}{'missed':>8}")
    rows = []
    for r in robot_catalogue():
        s = smoke_row(r["name"])
        rows.append(s)
        out(f"  {s['name']:<14}{s['fk_err']:>10.1e}{s['jac_err']:>10.1e}{s['spheres']:>9}{s['bound']:>11.4f}"
            f"{s['worst_gap']:>15.4f}{s['collisions']:>12}{s['missed']:>8}")
    out("")
    out("max|ΔFK|, max|ΔJ|: batched kernel vs Drake. worst gap: exact (Drake) minus sphere-model clearance,")
    out("never above the bound (plus Drake's GJK error on capsule-box pairs); missed: collisions the")
    out("sphere model did not see (must be 0).")
    out("")
    out("Your own robot: drake-mh robots PATH [--ee-frame NAME] [--package NAME=DIR] "
        "(URDF, xacro, SDFormat, MJCF; meshes load as shipped).")
    return rows


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds the ``robots`` subcommand."""
    p = subparsers.add_parser(
        "robots",
        parents=[common],
        help="the robot catalogue and smoke test, or one robot's entry (bundled name or model file)",
        description="Without NAME: the catalogue of the bundled robots and the smoke test (batched "
        "kernel vs Drake FK/Jacobian, sphere model vs exact distances). With NAME (a bundled name or "
        "the path of a .urdf, .xacro, .sdf or MJCF .xml file): that robot's entry: DOF, joints and "
        "limits, end effector, locked joints, collision geometry per link, sphere model and bound.",
    )
    p.add_argument("name", nargs="?", metavar="PATH_OR_NAME", help="bundled robot name or model file")
    add_robot_options(p)
    p.add_argument("--check", action="store_true",
                   help="also run the smoke test (FK, Jacobian, distances) on that robot")
    p.set_defaults(func=cmd_robots)


def cmd_robots(args: argparse.Namespace) -> int:
    """``drake-mh robots [PATH_OR_NAME] [--ee-frame NAME] [--package NAME=DIR] [--check]``."""
    from drake_mh.errors import InvalidArgument

    if args.name is None:
        if args.ee_frame or args.package:
            raise InvalidArgument("--ee-frame and --package describe one robot: give its PATH_OR_NAME "
                                  "(drake-mh robots path/to/robot.urdf --ee-frame tool0)")
        run_smoke(out=print)
        return 0
    robot = load_robot_from_args(args, args.name)
    for line in catalogue_entry(robot):
        print(line)
    if args.check:
        fk_err, jac_err = kernel_errors(robot)
        print(f"  smoke test, batched kernel vs Drake on 200 random configurations: max|ΔFK| "
              f"{fk_err:.1e}, max|ΔJ| {jac_err:.1e}")
        try:
            s = sphere_check(robot)
            print(f"  sphere model vs exact distance to a sphere obstacle (50 configurations): worst "
                  f"gap {s['worst_gap']:.4f} m, {s['collisions']} collisions, {s['missed']} missed")
        except DrakeMhError as exc:
            print(f"  sphere model vs exact distance: not available ({_short(exc)})")
    return 0
