"""Robot catalogue and a forward-kinematics / Jacobian / distance smoke test on every robot.

``python -m drake_mh`` (and ``drake-mh robots``) print it: for each bundled model, its joints,
end effector and limits, then on random configurations within limits the largest difference
between the batched kernel and Drake (FK and Jacobian), and the exact (Drake) vs sphere-model
clearance to a sphere obstacle placed near the arm.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


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


def smoke_row(name: str, n: int = 200, seed: int = 0) -> dict:
    """Kernel-vs-Drake and sphere-vs-exact figures for one robot."""
    import drake_mh
    from drake_mh.scene import Scene, Sphere

    robot = drake_mh.load_robot(name)
    Q = robot.random_configurations(n, seed)
    T, J = robot.batch.fk_jacobian(Q)
    fk_err = max(np.abs(T[i] - robot.fk(q)).max() for i, q in enumerate(Q))
    jac_err = max(np.abs(J[i] - robot.jacobian(q)).max() for i, q in enumerate(Q))
    scene = Scene(robot)
    p_obstacle = 0.6 * robot.fk(robot.home)[:3, 3] + np.array([0.0, 0.0, 0.25])
    scene.add("ball", Sphere(0.08), p_obstacle)
    exact = scene.exact_min_distance(Q[:50])
    spheres = scene.batch_min_distance(Q[:50])
    clear = exact >= 0
    return dict(
        name=name, fk_err=float(fk_err), jac_err=float(jac_err),
        manipulability=robot.manipulability(robot.home, translational=robot.nq >= 3),
        spheres=scene.sphere_model.num_spheres, bound=scene.sphere_model.bound,
        worst_gap=float(np.max(exact[clear] - spheres[clear])) if clear.any() else float("nan"),
        collisions=int((~clear).sum()), missed=int(np.sum(~clear & (spheres >= 0))),
    )


def run_smoke(out: Callable[[str], object] = print) -> list[dict]:
    """Print the catalogue and the smoke test of every bundled robot; returns the smoke rows."""
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
    return rows


if __name__ == "__main__":
    run_smoke()
