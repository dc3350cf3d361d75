"""Exact distances (drake_mh.scene.exact): consistency, Drake where Drake is exact, never above
Drake where it is optimistic, and refined values against independent dense computations."""

import numpy as np
import pytest
from scipy.spatial import ConvexHull

import drake_mh
from pydrake.math import RollPitchYaw, RotationMatrix
from drake_mh.errors import DrakeMhError, InvalidConfiguration, SceneError
from drake_mh.scene import Box, Capsule, Cylinder, Scene, Sphere
from drake_mh.scene.kernels import exact as X
from drake_mh.scene.kernels import gjk
from drake_mh.scene.exact import drake_reference
from drake_mh.geometry.shapes import ConvexPolytope, Ellipsoid
from sphere_fixtures import mesh_arm_urdf, primitive_arm_urdf

PANDA = drake_mh.load_robot("panda")
SHAPES = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4), Capsule(0.04, 0.3)]


def mixed_scene(robot, seed=1, n=10, reach=0.8, **kwargs):
    """n obstacles of the four kinds in the arm's workspace."""
    scene = Scene(robot, **kwargs)
    rng = np.random.default_rng(seed)
    for i in range(n):
        scene.add(f"o{i}", SHAPES[i % 4], rng.uniform([-reach, -reach, 0.0], [reach, reach, reach + 0.2]),
                  rpy=rng.uniform(-3, 3, 3))
    return scene


@pytest.fixture(scope="module")
def small_robots(tmp_path_factory):
    """A convex-mesh arm and a cylinder/box/ellipsoid arm (sphere models never built here)."""
    return [drake_mh.Robot(mesh_arm_urdf(tmp_path_factory.mktemp("mesh_arm"))), drake_mh.Robot(primitive_arm_urdf())]


def _check_pairs(scene, q):
    pairs = scene.distances(q)
    d = [p.distance for p in pairs]
    assert d == sorted(d)
    links = set(scene.robot.link_names())
    for p in pairs:
        assert p.link in links and (p.other in links) == p.is_self
        assert p.is_self or p.other in scene.obstacles
        if p.distance > 1e-6:  # closest points `distance` apart along the normal
            gap = p.p_W_link - p.p_W_other
            assert np.linalg.norm(gap) == pytest.approx(p.distance, abs=1e-7)
            np.testing.assert_allclose(gap / np.linalg.norm(gap), p.nhat_W, atol=1e-6)
    assert scene.min_distance(q) == (d[0] if d else np.inf)
    return pairs


@pytest.mark.parametrize("self_collision", [False, True])
def test_min_distance_is_the_smallest_pair(self_collision, small_robots):
    for robot in [PANDA, drake_mh.load_robot("planar5"), *small_robots]:
        scene = mixed_scene(robot, reach=0.4, self_collision=self_collision)
        for q in robot.random_configurations(15, 3):
            _check_pairs(scene, q)
        np.testing.assert_array_equal(scene.exact_min_distance(robot.random_configurations(4, 5)),
                                      [scene.min_distance(q) for q in robot.random_configurations(4, 5)])


def _per_link_obstacle(pairs, names=None):
    out = {}
    for p in pairs:
        if names is not None:  # a Drake pair: geometry ids, robot side first
            a, b = names[p.id_A], names[p.id_B]
            key = (a, b) if b.startswith("o") else (b, a)
            d = p.distance
        else:
            key, d = (p.link, p.other), p.distance
        out[key] = min(out.get(key, np.inf), d)
    return out


def test_equals_drake_where_exact_and_never_above_it(small_robots):
    """Sphere obstacles vs capsule links: Drake's closed form, the same to 1e-9. Every other
    (link, obstacle) pair: never more than Drake's value (Drake's GJK is optimistic)."""
    for robot in [PANDA, *small_robots]:
        scene = mixed_scene(robot, reach=0.4 if robot is not PANDA else 0.8)
        drake = drake_reference(scene)
        spheres = {name for name, o in scene.obstacles.items() if isinstance(o.shape, Sphere)}
        for q in robot.random_configurations(20, 11):
            ours = _per_link_obstacle(scene.distances(q))
            theirs = _per_link_obstacle(drake(q), drake.names)
            assert set(theirs) <= set(ours)
            for key, d in theirs.items():
                assert ours[key] <= d + 1e-9, key
                if robot is PANDA and key[1] in spheres:
                    assert ours[key] == pytest.approx(d, abs=1e-9), key


def test_capsule_rows_equal_the_segment_search():
    """Capsule links vs boxes, cylinders, capsules: the compiled rows are
    segment_distance.capsule_distance's values (that function is tested against sampling)."""
    from drake_mh.scene.segment_distance import capsule_distance

    scene = mixed_scene(PANDA)
    exact = scene._exact
    for q in PANDA.random_configurations(10, 2):
        scene.distances(q)
        state = exact.state()
        for i in np.flatnonzero(state.status == X.EXACT):
            g, k = divmod(int(i), state.K)
            if i >= len(exact.gids) * state.K or isinstance(list(scene.obstacles.values())[k].shape, Sphere):
                continue
            _, capsule = scene._link_kinds[exact.gids[g]]
            X_WG = np.eye(4)
            X_WG[:3, :3], X_WG[:3, 3] = exact.R_WG[g], exact.p_WG[g]
            obstacle = list(scene.obstacles.values())[k]
            d = capsule_distance(X_WG, capsule.radius, capsule.length, obstacle.X_WO, obstacle.shape)[0]
            assert state.out[i, 0] == pytest.approx(d, abs=1e-12)


def test_geometry_poses_match_drake(small_robots):
    for robot in [PANDA, *small_robots]:
        scene = mixed_scene(robot, n=1)
        exact = scene._exact
        for q in robot.random_configurations(3, 0):
            scene.min_distance(q)
            robot.plant.SetPositions(scene._plant_context, q)
            query = robot.scene_graph.get_query_output_port().Eval(scene._sg_context)
            for g, gid in enumerate(exact.gids):
                X_WG = query.GetPoseInWorld(gid).GetAsMatrix4()
                np.testing.assert_allclose(exact.R_WG[g], X_WG[:3, :3], atol=1e-12)
                np.testing.assert_allclose(exact.p_WG[g], X_WG[:3, 3], atol=1e-12)


# --- refined values against independent computations --------------------------------------------

def _patches(shape):
    """Parametrized surface patches ``f(U (M, 2)) -> points (M, 3)`` over [0, 1]^2 of a link shape."""
    if isinstance(shape, ConvexPolytope):
        V = shape.vertices
        return [lambda U, a=V[i], b=V[j], c=V[k]: a + U[:, :1] * (b - a) + (U[:, :1] * U[:, 1:]) * (c - b)
                for i, j, k in ConvexHull(V).simplices]
    if isinstance(shape, Box):
        h = 0.5 * np.asarray(shape.size)
        out = []
        for axis in range(3):
            for sign in (-1.0, 1.0):
                i, j = [a for a in range(3) if a != axis]

                def face(U, axis=axis, sign=sign, i=i, j=j):
                    p = np.empty((len(U), 3))
                    p[:, axis], p[:, i], p[:, j] = sign * h[axis], (2 * U[:, 0] - 1) * h[i], (2 * U[:, 1] - 1) * h[j]
                    return p
                out.append(face)
        return out
    if isinstance(shape, Cylinder):
        r, h = shape.radius, 0.5 * shape.length

        def side(U):
            t = 2 * np.pi * U[:, 0]
            return np.stack([r * np.cos(t), r * np.sin(t), (2 * U[:, 1] - 1) * h], 1)

        def cap(U, s):
            t = 2 * np.pi * U[:, 1]
            return np.stack([r * U[:, 0] * np.cos(t), r * U[:, 0] * np.sin(t), np.full(len(U), s * h)], 1)
        return [side, lambda U: cap(U, -1.0), lambda U: cap(U, 1.0)]
    if isinstance(shape, Ellipsoid):
        abc = np.array([shape.a, shape.b, shape.c])

        def surface(U):
            t, f = 2 * np.pi * U[:, 0], np.pi * U[:, 1]
            return abc * np.stack([np.sin(f) * np.cos(t), np.sin(f) * np.sin(t), np.cos(f)], 1)
        return [surface]
    raise TypeError(shape)


def _dense_distance(shape, R_WG, p_WG, obstacle) -> float:
    """min over the link's surface of the obstacle's exact SDF, by sampling only: a 32 x 32 grid
    on every patch, then around the 8 best points a 33 x 33 grid over +-2 cells, zoomed 14 times
    (an upper bound of the distance — a surface point's value — that reaches it as it zooms)."""
    R_WO, p_WO = obstacle.X_WO[:3, :3], obstacle.X_WO[:3, 3]

    def values(patch, U):
        return obstacle.shape.signed_distance(((patch(U) @ R_WG.T + p_WG) - p_WO) @ R_WO)

    axis = np.linspace(0, 1, 32)
    grid = np.stack(np.meshgrid(axis, axis), -1).reshape(-1, 2)
    starts = []
    for patch in _patches(shape):
        v = values(patch, grid)
        starts += [(v[j], patch, grid[j]) for j in np.argsort(v)[:2]]
    starts.sort(key=lambda s: s[0])
    best = starts[0][0]
    for value, patch, u in starts[:8]:
        half = 2.0 / 31
        for _ in range(14):
            axis = np.linspace(-half, half, 33)
            U = np.clip(u + np.stack(np.meshgrid(axis, axis), -1).reshape(-1, 2), 0.0, 1.0)
            v = values(patch, U)
            j = int(np.argmin(v))
            u, value = U[j], min(value, v[j])
            half /= 8
        best = min(best, value)
    return float(best)


def _point_to_hull(V_W, c) -> float:
    """Exact distance from a point c outside conv(V_W): the nearest of the hull's triangles
    (the projection where it falls inside a triangle, else the nearest edge point)."""
    tris = V_W[ConvexHull(V_W).simplices]
    a, b, t = tris[:, 0], tris[:, 1], tris[:, 2]
    n = np.cross(b - a, t - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    foot = c - ((c - a) * n).sum(1)[:, None] * n
    inside = np.ones(len(tris), bool)
    for p0, p1 in ((a, b), (b, t), (t, a)):
        inside &= (np.cross(p1 - p0, foot - p0) * n).sum(1) >= 0
    best = np.where(inside, np.linalg.norm(c - foot, axis=1), np.inf)
    for p0, p1 in ((a, b), (b, t), (t, a)):
        u = p1 - p0
        s = np.clip(((c - p0) * u).sum(1) / (u * u).sum(1), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(c - (p0 + s[:, None] * u), axis=1))
    return float(best.min())


def _gjk_rows(scene, q):
    """``[(link shape, R_WG, p_WG, obstacle, value)]`` for the GJK rows of one configuration."""
    scene.distances(q)
    exact = scene._exact
    state = exact.state()
    obstacles = list(scene.obstacles.values())
    rows = []
    for g, gid in enumerate(exact.gids):
        kind, shape = scene._link_kinds[gid]
        if kind != X.LINK_GJK:
            continue
        for k, obstacle in enumerate(obstacles):
            i = g * state.K + k
            if state.status[i] == X.EXACT:
                rows.append((shape, exact.R_WG[g].copy(), exact.p_WG[g].copy(), obstacle, state.out[i, 0]))
    return rows


def _check_gjk_rows(robots, small_robots) -> int:
    """Every GJK row of two configurations per robot against the dense computation; returns the
    number of rows checked."""
    checked = 0
    for robot in robots:
        scene = mixed_scene(robot, seed=4, reach=0.45 if robot in small_robots else 0.8)
        for q in robot.random_configurations(2, 9):
            for shape, R_WG, p_WG, obstacle, value in _gjk_rows(scene, q):
                if value < 1e-4:
                    continue  # penetration: Drake's depth, not the search checked here
                if isinstance(obstacle.shape, Sphere) and isinstance(shape, ConvexPolytope):
                    truth = _point_to_hull(shape.vertices @ R_WG.T + p_WG, obstacle.X_WO[:3, 3]) - obstacle.shape.radius
                    assert value == pytest.approx(truth, abs=1e-9)
                    continue
                dense = _dense_distance(shape, R_WG, p_WG, obstacle)
                assert value <= dense + 1e-9
                assert dense - value <= 1e-7, (type(shape).__name__, type(obstacle.shape).__name__, dense, value)
                checked += 1
    return checked


@pytest.mark.slow
def test_gjk_rows_match_dense_computation(small_robots):
    """Mesh, box, cylinder and ellipsoid links vs every obstacle kind: never above the dense
    value (a surface point's exact SDF), at most 1e-7 m below it (measured: 6e-9); sphere obstacles against
    hulls: the exact point-to-hull distance (nearest hull triangle) to 1e-9."""
    assert _check_gjk_rows(small_robots, small_robots) > 20


@pytest.mark.slow
def test_gjk_rows_of_a_shipped_mesh_robot_match_dense_computation(small_robots):
    """The same on example-robot-data's Panda (convex hulls of its STL meshes; a test extra,
    skipped by name where it is not installed)."""
    from robot_fixtures import ERD_ROBOTS, erd_root

    rel, ee, _ = ERD_ROBOTS["panda"]
    robot = drake_mh.load_robot(erd_root() / rel, ee_frame=ee)
    assert _check_gjk_rows([robot], small_robots) > 20


def test_gjk_certificate_on_random_pairs():
    """Every core pair kind: status, gap and the lower bound against sampled surfaces."""
    rng = np.random.default_rng(0)
    out = np.empty(8)
    for trial in range(600):
        kind_a = [gjk.HULL, gjk.ELLIPSOID, gjk.BOX, gjk.CYLINDER, gjk.SEGMENT, gjk.POINT][trial % 6]
        vertices = rng.normal(size=(30, 3)) * 0.1
        vertices = np.ascontiguousarray(vertices[ConvexHull(vertices).vertices])
        dims_a = rng.uniform(0.03, 0.2, 3)
        kind_b, dims_b = [(gjk.BOX, rng.uniform(0.05, 0.2, 3)), (gjk.CYLINDER, np.array([0.05, 0.15, 0.0])),
                          (gjk.SEGMENT, np.array([0.15, 0.0, 0.0])), (gjk.POINT, np.zeros(3))][(trial // 6) % 4]
        R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        p = rng.normal(size=3)
        p *= rng.uniform(0.0, 0.8) / np.linalg.norm(p)
        status = gjk.gjk(kind_a, dims_a, R, p, vertices, 0, len(vertices), kind_b, dims_b, 1e-10, out)
        lb, ub = out[0], out[1]
        assert lb <= ub + 1e-15
        if status == gjk.SEPARATED:
            assert ub - lb <= 1e-10
            assert np.linalg.norm(out[2:5] - out[5:8]) == pytest.approx(ub, abs=1e-12)
        elif status == gjk.NOT_CONVERGED and lb > 0:  # round-off stalled a curved pair
            assert ub - lb <= 1e-8
        # sampled points of A (in B's frame) vs B's support: lb never above any sampled distance
        directions = rng.normal(size=(2000, 3))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        local, a_pt, b_pt = np.empty(3), np.empty(3), np.empty(3)
        for d in directions[:50]:
            gjk._support_a(kind_a, dims_a, R, p, vertices, 0, len(vertices), *d, local, a_pt)
            gjk.support(kind_b, dims_b, vertices, 0, 0, *(-d), b_pt)
            assert lb <= np.linalg.norm(a_pt - b_pt) + 1e-12


def test_penetration_takes_drakes_depth():
    """A slab across a capsule's axis: the axis search no longer gives the depth, so Drake's
    penetration depth of that pair is asked for and the deeper value kept (as before the kernels)."""
    from drake_mh.scene.segment_distance import capsule_distance

    q = PANDA.home
    probe = Scene(PANDA)
    probe.add("far", Sphere(0.01), [5.0, 5.0, 5.0])
    probe.min_distance(q)
    exact = probe._exact
    g = max(range(len(exact.gids)), key=lambda g: exact.g_float[g, 12])  # the longest capsule
    axis = exact.R_WG[g][:, 2]
    scene = Scene(PANDA)
    rpy = RollPitchYaw(RotationMatrix.MakeFromOneVector(axis, 2)).vector()
    scene.add("slab", Box((0.4, 0.4, 0.01)), exact.p_WG[g], rpy=rpy)  # thin, across the axis
    link = exact.links[g]
    pair = min((p for p in scene.distances(q) if p.link == link), key=lambda p: p.distance)
    _, capsule = scene._link_kinds[exact.gids[g]]
    X_WG = np.eye(4)
    X_WG[:3, :3], X_WG[:3, 3] = exact.R_WG[g], exact.p_WG[g]
    slab = scene.obstacles["slab"]
    searched = capsule_distance(X_WG, capsule.radius, capsule.length, slab.X_WO, slab.shape)[0]
    PANDA.plant.SetPositions(scene._plant_context, q)
    query = PANDA.scene_graph.get_query_output_port().Eval(scene._sg_context)
    drakes = query.ComputeSignedDistancePairClosestPoints(exact.gids[g], scene._ids["slab"][0]).distance
    assert searched < 0 and drakes < searched - 1e-3  # the case is real: Drake's depth is deeper
    assert pair.distance == pytest.approx(min(searched, drakes), abs=1e-12)
    assert scene.min_distance(q) <= pair.distance


def test_obstacle_changes_rebuild_the_arrays():
    scene = Scene(PANDA)
    q = PANDA.home
    assert scene.min_distance(q) == np.inf and scene.distances(q) == []
    scene.add("ball", Sphere(0.05), [0.6, 0.0, 0.4])
    before = scene.min_distance(q)
    scene.move("ball", [0.6, 0.0, 1.4])
    assert scene.min_distance(q) > before + 0.1
    scene.add("box", Box((0.1, 0.1, 0.1)), [0.6, 0.0, 0.4])
    assert {p.other for p in scene.distances(q)} == {"ball", "box"}
    scene.remove("ball")
    assert {p.other for p in scene.distances(q)} == {"box"}
    assert len(scene.distances(q, max_distance=0.0)) <= len(scene.distances(q, max_distance=0.3))


def test_max_distance_keeps_exactly_the_pairs_within():
    scene = mixed_scene(PANDA)
    for q in PANDA.random_configurations(5, 1):
        every = scene.distances(q)
        for limit in (0.0, 0.05, 0.2):
            within = scene.distances(q, max_distance=limit)
            assert [p.distance for p in within] == [p.distance for p in every if p.distance <= limit]


def test_bad_configurations_raise():
    scene = mixed_scene(PANDA, n=2)
    for q in (np.full(7, np.nan), np.zeros(6), "abc", [0.0] * 7 + [1.0]):
        for call in (scene.min_distance, scene.distances, scene.in_collision):
            with pytest.raises(InvalidConfiguration):
                call(q)
    assert issubclass(InvalidConfiguration, DrakeMhError)
    assert scene.min_distance([0.0] * 7) == scene.min_distance(np.zeros(7))  # lists accepted
    assert scene.min_distance(np.zeros((7, 2))[:, 0]) == scene.min_distance(np.zeros(7))  # strided view
    with pytest.raises(SceneError):
        scene.distances(np.zeros(7), max_distance=-1.0)
