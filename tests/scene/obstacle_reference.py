"""Independent references for mesh and point-cloud obstacles: the robot's collision geometry
posed by Drake on a fresh context, its exact signed distance to points by the closed forms of
drake_mh.geometry.shapes (sphere, box, cylinder, capsule links), and dense samples of the
original (not decomposed) mesh surface."""

from __future__ import annotations

import numpy as np
import trimesh

from drake_mh.geometry.shapes import from_drake


class PointDistance:
    """``min over robot geometries and points of sd_geometry(point)`` for configurations."""

    def __init__(self, robot):
        from pydrake.geometry import Role

        self.robot = robot
        self.context = robot.diagram.CreateDefaultContext()
        self.plant_context = robot.plant.GetMyMutableContextFromRoot(self.context)
        self.sg_context = robot.scene_graph.GetMyContextFromRoot(self.context)
        inspector = robot.scene_graph.model_inspector()
        self.geometries = [(gid, from_drake(inspector.GetShape(gid)))
                           for gid in inspector.GetAllGeometryIds(Role.kProximity)
                           if inspector.GetFrameId(gid) != inspector.world_frame_id()]

    def __call__(self, q, points_W: np.ndarray) -> float:
        """Smallest signed distance [m] of the robot at ``q`` to ``points_W (n, 3)``."""
        self.robot.plant.SetPositions(self.plant_context, q)
        query = self.robot.scene_graph.get_query_output_port().Eval(self.sg_context)
        best = np.inf
        for gid, shape in self.geometries:
            X = query.GetPoseInWorld(gid)
            R, p = X.rotation().matrix(), X.translation()
            best = min(best, float(shape.signed_distance((points_W - p) @ R).min()))
        return best


def surface_samples(mesh, X_WO: np.ndarray, count: int = 20000, seed: int = 0) -> np.ndarray:
    """``(count, 3)`` points of the mesh's surface in W (even sampling, deterministic)."""
    surface = trimesh.Trimesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), process=False)
    points, _ = trimesh.sample.sample_surface(surface, count, seed=seed)
    return np.asarray(points) @ X_WO[:3, :3].T + X_WO[:3, 3]


def near_configurations(scene, seed: int, count: int = 200) -> np.ndarray:
    """``(count, nq)`` configurations of the scene's robot, half of them near an obstacle (the
    sphere model's clearance between -1 and 5 cm), the rest farther."""
    robot = scene.robot
    rng = np.random.default_rng(seed)
    Q = rng.uniform(robot.lower, robot.upper, (20 * count, robot.nq))
    d = scene.batch_min_distance(Q)
    near, far = Q[(d > -0.01) & (d < 0.05)], Q[d >= 0.05]
    return np.vstack([near[:count // 2], far[:count - min(len(near), count // 2)]])


def check_certified_segments(scene, points_W: np.ndarray, rho: float, seed: int) -> None:
    """Certify 12 segments from free configurations near the obstacles (joint steps of σ = 0.3
    rad) and assert that 40 configurations along each certified one keep its certified lower
    bound from ``points_W`` (balls of radius ``rho``), by :class:`PointDistance`."""
    robot = scene.robot
    rng = np.random.default_rng(seed)
    QA = near_configurations(scene, seed, 60)
    QA = QA[scene.collision_free(QA)][:12]
    QB = np.clip(QA + rng.normal(0.0, 0.3, QA.shape), robot.lower, robot.upper)
    cert = scene.certify_segments(QA, QB)
    assert cert.certified.any()
    reference = PointDistance(robot)
    for i in np.flatnonzero(cert.certified):
        for t in np.linspace(0.0, 1.0, 40):
            assert reference(QA[i] + t * (QB[i] - QA[i]), points_W) - rho >= cert.lower[i] - 1e-9
