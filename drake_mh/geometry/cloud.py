"""Point-cloud obstacles: the union of balls of one radius around measured points.

:class:`PointCloud` holds ``points (N, 3)`` [m] in its own frame O and a ``radius`` [m]: the
obstacle is every point within ``radius`` of some cloud point (``radius = 0``: the points
themselves). Points that are not finite (a depth camera writes NaN where it saw nothing) are
**dropped**, and their number kept in :attr:`PointCloud.dropped` (and shown in the repr): a
NaN point is no measurement, and a cloud that is all NaN is refused.

Preparing a camera's cloud for a scene (each returns a new cloud):

* :meth:`PointCloud.cropped` / :meth:`PointCloud.cropped_to_reach`: keep the points a ball (or
  the robot's reach) holds;
* :meth:`PointCloud.voxel_downsampled`: one point per occupied voxel (its points' centroid),
  the radius grown by the largest distance of a point from its centroid, so the new union of
  balls covers the old one (never less conservative);
* :meth:`PointCloud.without_robot`: drop the points on the robot itself at a configuration
  (exact distances from Drake's point query on the robot's collision geometry).

Files: :meth:`PointCloud.from_file` (:mod:`drake_mh.geometry.cloud_files`).
"""

from __future__ import annotations

import numpy as np

from drake_mh.errors import ObstacleFileError, SceneError

__all__ = ["PointCloud"]


def _length(value, what: str, allow_zero: bool) -> float:
    ok = not isinstance(value, (bool, str, bytes)) and value is not None and not np.iscomplexobj(value)
    try:
        value = float(value) if ok else np.nan
    except (TypeError, ValueError):
        value = np.nan
    if not np.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        raise SceneError(f"{what} must be a finite number {'>=' if allow_zero else '>'} 0 [m], got {value!r}")
    return value


class PointCloud:
    """A point-cloud obstacle: the balls of ``radius`` [m] around ``points (N, 3)`` [m].

    Args:
        points: ``(N, 3)`` coordinates [m] in the obstacle's frame O (any array-like of
            numbers); rows with a NaN or an infinity are dropped and counted.
        radius: the balls' radius [m], >= 0 (a depth camera's noise, or half its voxel size).
        source: where the points came from (a file name), shown in the repr.

    Attributes:
        points: ``(N, 3)`` read-only float64, the finite points.
        radius: [m].
        dropped: how many rows were not finite and left out.

    Raises:
        SceneError: ``points`` is not ``(N, 3)`` numbers, no row is finite, or a bad ``radius``.
    """

    def __init__(self, points, radius: float, source: str | None = None, _dropped: int = 0):
        if isinstance(points, (str, bytes)) or np.iscomplexobj(points):
            raise SceneError(f"points must be an (N, 3) array of coordinates [m], got {type(points).__name__}")
        try:
            arr = np.array(points, dtype=np.float64)
        except (TypeError, ValueError):
            raise SceneError("points must be an (N, 3) array of numbers [m]") from None
        if arr.ndim != 2 or arr.shape[1] != 3:
            raise SceneError(f"points must have shape (N, 3), got {arr.shape}")
        finite = np.isfinite(arr).all(axis=1)
        self.radius = _length(radius, "PointCloud radius", allow_zero=True)
        if not finite.any():
            raise SceneError(f"the point cloud{' ' + source if source else ''} has no finite point "
                             f"({len(arr)} rows, all with a NaN or an infinity)")
        arr = np.ascontiguousarray(arr[finite])
        arr.setflags(write=False)
        self.points = arr
        self.dropped = int(_dropped + np.count_nonzero(~finite))
        self.source = source

    @classmethod
    def from_file(cls, path, radius: float, scale: float = 1.0) -> PointCloud:
        """Read a ``.ply``, ``.pcd``, ``.xyz`` or ``.npy`` file (:mod:`drake_mh.geometry.cloud_files`).

        Args:
            path: the file.
            radius: the points' radius [m].
            scale: a positive factor applied to the file's coordinates (millimetres: 0.001).

        Raises:
            ObstacleFileNotFound: no such file.
            ObstacleFileError: unknown format, malformed file, a bad scale, or no finite point.
            SceneError: a bad radius.
        """
        from drake_mh.geometry.cloud_files import read_points
        from drake_mh.geometry.mesh import _checked_path

        path = _checked_path(path)
        if isinstance(scale, bool) or not isinstance(scale, (int, float, np.number)) or not (
                np.isfinite(scale) and scale > 0):
            raise ObstacleFileError(path, f"scale must be a positive number, got {scale!r}")
        radius = _length(radius, "PointCloud radius", allow_zero=True)
        points = read_points(path) * float(scale)
        if not np.isfinite(points).all(axis=1).any():
            raise ObstacleFileError(path, f"the file holds no finite point ({len(points)} rows)")
        return cls(points, radius, source=path.name)

    def __len__(self) -> int:
        return len(self.points)

    def _derived(self, points, radius=None) -> PointCloud:
        if len(points) == 0:
            raise SceneError("no point of the cloud is left; crop less (a larger radius, another centre)")
        return PointCloud(points, self.radius if radius is None else radius, self.source, _dropped=self.dropped)

    def cropped(self, center, radius: float) -> PointCloud:
        """The points within ``radius`` [m] of ``center (3,)`` [m] (in O).

        Raises:
            SceneError: a bad centre or radius, or no point left.
        """
        try:
            c = np.asarray(center, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            c = np.full(1, np.nan)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise SceneError(f"center must be 3 finite numbers [m], got {center!r}")
        r = _length(radius, "crop radius", allow_zero=False)
        keep = np.einsum("ij,ij->i", self.points - c, self.points - c) <= r * r
        return self._derived(self.points[keep])

    def cropped_to_reach(self, scene, X_WO=None, margin: float = 0.0) -> PointCloud:
        """The points some link of ``scene``'s robot can come within ``margin`` [m] of, anywhere
        in its joint limits: those inside a link's reach ball
        (:attr:`drake_mh.scene.batch.CollisionModel.reach_balls`) grown by the link's bounding
        radius, the points' radius and ``margin``. A point outside every such ball can never be
        within ``margin`` of the robot, so cropping changes no check at clearances up to it.

        Args:
            scene: a :class:`drake_mh.scene.Scene` (its robot's sphere model).
            X_WO: ``(4, 4)`` pose of the cloud's frame in the world (default identity).
            margin: [m] >= 0, the largest clearance the checks will ask.
        """
        margin = _length(margin, "margin", allow_zero=True)
        X = np.eye(4) if X_WO is None else np.asarray(X_WO, dtype=float).reshape(4, 4)
        p_W = self.points @ X[:3, :3].T + X[:3, 3]
        model = scene.collision_model
        centre, reach = model.reach_balls
        lim = reach + model.model_arrays[2] + self.radius + margin
        keep = np.zeros(len(p_W), bool)
        for c, r in zip(centre, lim):
            keep |= np.einsum("ij,ij->i", p_W - c, p_W - c) <= r * r
        return self._derived(self.points[keep])

    def voxel_downsampled(self, voxel: float) -> PointCloud:
        """One point per occupied cube of side ``voxel`` [m] (the centroid of its points), the
        radius grown by the largest distance of a point from its voxel's centroid: every ball
        of the old cloud lies inside a ball of the new one (the obstacle only grows).

        Raises:
            SceneError: ``voxel`` not a positive length.
        """
        voxel = _length(voxel, "voxel size", allow_zero=False)
        cells = np.floor(self.points / voxel).astype(np.int64)
        _, inverse, counts = np.unique(cells, axis=0, return_inverse=True, return_counts=True)
        inverse = inverse.reshape(-1)
        centroids = np.zeros((len(counts), 3))
        np.add.at(centroids, inverse, self.points)
        centroids /= counts[:, None]
        grow = float(np.sqrt(np.max(np.einsum("ij,ij->i", self.points - centroids[inverse],
                                              self.points - centroids[inverse]))))
        return self._derived(centroids, self.radius + grow)

    def without_robot(self, robot, q, margin: float = 0.01, X_WO=None) -> PointCloud:
        """The cloud without the points on the robot at configuration ``q``: those whose signed
        distance to the robot's collision geometry is below ``margin`` [m].

        The points near some sphere of the robot's sphere model (which covers its geometry) are
        the candidates; Drake's ``QueryObject.ComputeSignedDistanceToPoint`` on a fresh context
        of the robot decides each (exact for its shapes).

        Args:
            robot: a :class:`drake_mh.robot.Robot`.
            q: ``(nq,)`` its configuration [rad, m].
            margin: [m] >= 0 (a depth camera's noise).
            X_WO: ``(4, 4)`` pose of the cloud's frame in the world (default identity).

        Raises:
            InvalidConfiguration: a bad ``q``; SceneError: a bad margin, or no point left.
        """
        from scipy.spatial import cKDTree

        margin = _length(margin, "margin", allow_zero=True)
        q = robot.check_q(q)
        X = np.eye(4) if X_WO is None else np.asarray(X_WO, dtype=float).reshape(4, 4)
        p_W = self.points @ X[:3, :3].T + X[:3, 3]
        model = robot.sphere_model
        centres = robot.batch.points(q.reshape(1, -1), *robot.batch.compile_points(list(model.links),
                                                                                    model.centres_B))[0]
        tree = cKDTree(p_W)
        candidates = set()
        for c, r in zip(centres, model.radii):
            candidates.update(tree.query_ball_point(c, r + margin))
        drop = np.zeros(len(p_W), bool)
        if candidates:
            context = robot.diagram.CreateDefaultContext()
            robot.plant.SetPositions(robot.plant.GetMyMutableContextFromRoot(context), q)
            query = robot.scene_graph.get_query_output_port().Eval(robot.scene_graph.GetMyContextFromRoot(context))
            for i in sorted(candidates):
                drop[i] = any(d.distance < margin for d in query.ComputeSignedDistanceToPoint(p_W[i], margin))
        return self._derived(self.points[~drop])

    @property
    def digest(self) -> str:
        """SHA-256 of the points and the radius: names the cloud (in reprs and caches)."""
        if "_digest" not in self.__dict__:
            from drake_mh._support.cache import content_hash

            self._digest = content_hash("drake_mh-point-cloud", self.points.tobytes(), repr(self.radius))
        return self._digest

    @property
    def circumradius(self) -> float:
        """Radius [m] of the smallest origin-centred ball that holds every ball of the cloud."""
        return float(np.sqrt(np.max(np.einsum("ij,ij->i", self.points, self.points)))) + self.radius

    def signed_distance(self, p_O: np.ndarray) -> np.ndarray:
        """Exact signed distance ``(...)`` [m] of points ``p_O (..., 3)`` (in O) to the union of
        the balls: the distance to the nearest point (scipy's ``cKDTree``) minus the radius."""
        from scipy.spatial import cKDTree

        if "_tree" not in self.__dict__:
            self._tree = cKDTree(self.points)
        p = np.asarray(p_O, dtype=float)
        return self._tree.query(p.reshape(-1, 3))[0].reshape(p.shape[:-1]) - self.radius

    def __repr__(self) -> str:
        extra = f", dropped={self.dropped}" if self.dropped else ""
        source = f", source={self.source!r}" if self.source else ""
        return (f"PointCloud({len(self.points)} points, radius={self.radius!r}{extra}{source}, "
                f"digest={self.digest[:12]!r})")
