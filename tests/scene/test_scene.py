"""Scene: obstacles in Drake's SceneGraph, exact distances, batched conservative distances."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh.errors import FrameNotFound, SceneError, UnknownObstacle
from drake_mh.scene import Box, Capsule, Cylinder, Scene, Sphere
from sphere_fixtures import mesh_arm_urdf, no_geometry_urdf, primitive_arm_urdf

PANDA = drake_mh.load_robot("panda")


def make_scene(robot=PANDA, **kwargs):
    scene = Scene(robot, **kwargs)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    scene.add("box", Box((0.2, 0.3, 0.1)), [0.3, 0.35, 0.3], rpy=[0.3, 0.2, 0.1])
    scene.add("post", Cylinder(0.05, 0.6), [0.35, -0.35, 0.3], rpy=[0.2, 0.0, 0.0])
    return scene


def test_distance_pairs_are_consistent():
    scene = make_scene()
    pairs = scene.distances(PANDA.home)
    assert pairs and all(not p.is_self for p in pairs)
    assert [p.distance for p in pairs] == sorted(p.distance for p in pairs)
    for p in pairs:
        assert p.other in {"ball", "box", "post"} and p.link in PANDA.link_names()
        if p.distance > 1e-6:  # closest points are `distance` apart, along the normal
            gap = p.p_W_link - p.p_W_other
            assert np.linalg.norm(gap) == pytest.approx(p.distance, abs=1e-6)
            np.testing.assert_allclose(gap / np.linalg.norm(gap), p.nhat_W, atol=1e-5)


@pytest.mark.parametrize("offset", [[0.0, 0.0, 0.5], [0.2, -0.3, 0.1], [-0.4, 0.1, -0.5]])
def test_sphere_obstacle_distance_by_hand(offset):
    """A ball near the arm: its distance is, by hand, the smallest point-to-segment distance from
    its centre to a capsule's axis minus both radii (the capsules from a fresh Drake plant)."""
    from references import FreshDrake, ball_to_capsule

    scene = Scene(PANDA)
    q = PANDA.home
    centre = PANDA.fk_drake(q)[:3, 3] + offset
    scene.add("ball", Sphere(0.05), centre)
    capsules = FreshDrake(PANDA).capsules(q)
    closest = min(capsules, key=lambda capsule: ball_to_capsule(centre, 0.05, capsule))
    best = ball_to_capsule(centre, 0.05, closest)
    pair = scene.distances(q)[0]
    assert pair.distance == pytest.approx(best, abs=1e-9) and pair.link == closest[0]
    assert scene.min_distance(q) == pytest.approx(best, abs=1e-9)


def test_obstacles_move_without_rebuilding():
    scene = make_scene()
    q = PANDA.home
    before = scene.min_distance(q)
    diagram = PANDA.diagram
    scene.move("ball", [2.0, 2.0, 2.0])
    scene.move("box", [2.0, -2.0, 2.0])
    scene.move("post", [-2.0, 2.0, 2.0])
    after = scene.min_distance(q)
    assert after > before + 0.5 and PANDA.diagram is diagram
    assert scene.batch_min_distance(q[None])[0] == pytest.approx(after, abs=scene.sphere_model.bound + 1e-6)
    scene.remove("ball")
    assert set(scene.obstacles) == {"box", "post"}


def test_step_moves_obstacles_by_velocity():
    scene = Scene(PANDA)
    scene.add("ball", Sphere(0.15), [0.0, -0.4, 0.6], velocity=[0.0, 0.16, 0.0])
    for _ in range(10):
        scene.step(0.1)
    np.testing.assert_allclose(scene.obstacles["ball"].position, [0.0, -0.24, 0.6], atol=1e-12)


def test_scenes_are_independent():
    a, b = Scene(PANDA), Scene(PANDA)
    a.add("ball", Sphere(0.1), PANDA.fk(PANDA.home)[:3, 3])
    assert a.min_distance(PANDA.home) < 0 and b.min_distance(PANDA.home) == np.inf


def test_self_collision_pairs():
    scene = Scene(PANDA, self_collision=True)
    pairs = scene.distances(np.zeros(7))
    assert pairs and all(p.is_self for p in pairs)
    names = PANDA.link_names()
    adjacent = {frozenset(p) for p in zip(names, names[1:])}
    assert all(frozenset((p.link, p.other)) not in adjacent for p in pairs)
    filtered = Scene(PANDA, self_collision=True, ignore_link_pairs=[("panda_link5", "panda_link7")],
                     keep_always_close=True)
    assert all({p.link, p.other} != {"panda_link5", "panda_link7"} for p in filtered.distances(np.zeros(7)))
    assert ("panda_link1", "panda_link3") in filtered.self_link_pairs
    assert ("panda_link5", "panda_link7") not in filtered.self_link_pairs


def test_always_close_pairs_are_left_out_by_default(caplog):
    """The capsule Panda's link1-link3 spheres are 0.9 mm apart in every configuration and
    link5-link7 3.3 mm: checked, they reject most configurations; left out by default, reported."""
    from drake_mh.scene.always_close import SEPARATION, largest_separation

    with caplog.at_level("INFO", logger="drake_mh.scene.always_close"):
        default = Scene(PANDA, self_collision=True, sphere_tolerance=0.0099)  # a fresh model: logged
    assert default.always_close_pairs == (("panda_link1", "panda_link3"), ("panda_link5", "panda_link7"))
    assert "panda_link1-panda_link3" in caplog.text and "keep_always_close=True" in caplog.text
    assert not set(default.always_close_pairs) & set(default.self_link_pairs)
    keep = Scene(PANDA, self_collision=True, keep_always_close=True)
    assert keep.always_close_pairs == ()
    assert set(keep.self_link_pairs) == set(Scene(PANDA, self_collision=True).self_link_pairs) | {
        ("panda_link1", "panda_link3"), ("panda_link5", "panda_link7")}
    assert Scene(PANDA).always_close_pairs == () and Scene(PANDA).self_link_pairs == ()
    Q = PANDA.random_configurations(500, np.random.default_rng(3))
    assert Scene(PANDA, self_collision=True).collision_free(Q).mean() > 0.9
    assert keep.collision_free(Q).mean() < 0.8
    # the rule: every pair left out is never more than SEPARATION apart, every pair kept is, somewhere
    separation = largest_separation(PANDA, keep.sphere_model, keep.self_link_pairs)
    assert all((d < SEPARATION) == (pair in Scene(PANDA, self_collision=True).always_close_pairs)
               for pair, d in separation.items())
    # exact distances leave them out too
    pairs = {frozenset((p.link, p.other)) for p in Scene(PANDA, self_collision=True).distances(np.zeros(7))}
    assert frozenset(("panda_link1", "panda_link3")) not in pairs
    kept = {frozenset((p.link, p.other)) for p in keep.distances(np.zeros(7))}
    assert frozenset(("panda_link1", "panda_link3")) in kept


def _check_guarantee(scene, Q, extra_pessimism=0.0):
    """The sphere model's guarantee against the exact distance (module docstring of scene.py)."""
    exact = scene.exact_min_distance(Q)
    approx = scene.batch_min_distance(Q)
    # never more clearance than the exact distance, penetration included (1e-9: round-off)
    assert np.all(approx <= exact + 1e-9), f"model above exact by {np.max(approx - exact):.3g} m"
    # every collision Drake sees, the sphere model sees
    assert np.all(approx[exact < 0] < 0)
    # at most `bound` pessimistic where the exact distance is >= 0
    clear = exact >= 0
    assert np.all(exact[clear] - approx[clear] <= scene.sphere_model.bound + extra_pessimism + 1e-9)
    return exact, approx


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_sphere_model_is_conservative_and_tight(seed):
    scene = make_scene()
    _check_guarantee(scene, PANDA.random_configurations(40, seed), extra_pessimism=0.02 * 0.05)


def _obstacle_near_the_arm(robot, rng, kind):
    """A random obstacle centred near a random point of the arm (so that some configurations
    collide, some nearly touch)."""
    model = robot.sphere_model
    q = robot.random_configurations(1, int(rng.integers(1 << 31)))
    centre = robot.batch.sphere_centres(q)[0][rng.integers(model.num_spheres)] + rng.normal(0, 0.08, 3)
    size = rng.uniform(0.02, 0.12)
    shape = {"sphere": Sphere(size), "box": Box(rng.uniform(0.02, 0.25, 3)),
             "cylinder": Cylinder(size, rng.uniform(0.05, 0.5)), "capsule": Capsule(size, rng.uniform(0.0, 0.4))}[kind]
    return shape, centre, rng.uniform(-np.pi, np.pi, 3)


def _random_scene_check(robot, seed, n=60):
    """Random obstacles of every kind near the arm; the guarantee against Scene's exact distance.

    Allowance on the *pessimism* side only (the never-more-clearance side stays strict): a
    cylinder obstacle is handled as its circumscribed 16-gon prism (2 % of its radius). Mesh,
    box, cylinder and ellipsoid links need none since Scene's certified GJK replaced Drake's
    (seen optimistic by 7.5 mm for a mesh link and a capsule, 16 mm for an ellipsoid link and
    a box; 10 and 20 mm were allowed here before)."""
    rng = np.random.default_rng(seed)
    for kind in ("sphere", "box", "cylinder", "capsule"):
        scene = Scene(robot)
        shape, centre, rpy = _obstacle_near_the_arm(robot, rng, kind)
        scene.add("o", shape, centre, rpy=rpy)
        extra = 0.02 * shape.radius if isinstance(shape, Cylinder) else 0.0
        _check_guarantee(scene, robot.random_configurations(n, int(rng.integers(1 << 31))), extra)


@pytest.mark.parametrize("name", drake_mh.available_robots())
@settings(max_examples=3, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_sphere_model_guarantee_on_every_bundled_robot(name, seed):
    _random_scene_check(drake_mh.load_robot(name), seed)


@pytest.fixture(scope="module")
def mesh_and_primitive_robots(tmp_path_factory):
    """Robots with convex-mesh links and with cylinder/box/ellipsoid links (models built with a
    private cache)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("DRAKE_MH_CACHE", str(tmp_path_factory.mktemp("cache")))
        robots = [drake_mh.Robot(mesh_arm_urdf(tmp_path_factory.mktemp("mesh_arm"))),
                  drake_mh.Robot(primitive_arm_urdf())]
        for robot in robots:
            robot.sphere_model  # noqa: B018 (built here, under the private cache)
    return robots


@settings(max_examples=4, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_sphere_model_guarantee_on_mesh_and_primitive_robots(seed, mesh_and_primitive_robots):
    for robot in mesh_and_primitive_robots:
        _random_scene_check(robot, seed)


def test_deep_penetration_is_never_shallower_than_exact():
    """A ball centred on a Panda capsule's axis midway between two sphere centres: its depth in
    either sphere is smaller than in the capsule. The per-sphere value alone reported more
    clearance than Drake here (up to 7.8 mm on random Panda configurations)."""
    scene = Scene(PANDA)
    model = scene.sphere_model
    q = PANDA.home
    centres = scene.sphere_centres(q[None])[0]
    g = next(i for i, c in enumerate(model.geometries) if c.half_length > 0.05)
    idx = np.flatnonzero(model.geometry == g)[:2]
    midpoint = centres[idx].mean(axis=0)
    scene.add("ball", Sphere(0.02), midpoint)
    exact = scene.min_distance(q)
    per_sphere = (np.linalg.norm(centres - midpoint, axis=1) - model.radii - 0.02).min()
    assert per_sphere > exact + 1e-3  # the case is real: spheres alone are too shallow
    assert exact == pytest.approx(-model.geometries[g].radius - 0.02, abs=1e-9)
    assert scene.batch_min_distance(q[None])[0] <= exact + 1e-9


def test_no_collision_geometry_raises_instead_of_infinite_clearance():
    robot = drake_mh.Robot(no_geometry_urdf())
    scene = Scene(robot)
    scene.add("ball", Sphere(0.1), [0.3, 0.0, 0.3])
    q = np.zeros(robot.nq)
    for query in (lambda: scene.min_distance(q), lambda: scene.distances(q), lambda: scene.batch_min_distance(q[None]),
                  lambda: scene.batch_obstacle_distances(q[None]), lambda: scene.sphere_model,
                  lambda: scene.in_collision(q)):
        with pytest.raises(SceneError, match="no collision geometry"):
            query()


@pytest.mark.parametrize("method", ["pso", "drake_snopt"])
def test_ik_with_a_scene_needs_collision_geometry(method):
    robot = drake_mh.Robot(no_geometry_urdf())
    scene = Scene(robot)
    scene.add("ball", Sphere(0.05), [0.2, 0.0, 0.3])
    problem = drake_mh.IKProblem(robot=robot, target=robot.fk(np.array([0.3, 0.4]))[:3, 3], scene=scene)
    with pytest.raises(SceneError, match="no collision geometry"):
        drake_mh.solve_ik(problem, method=method, seed=0, budget=100)


def test_example_robot_data_arms_sphere_guarantee(tmp_path_factory, monkeypatch):
    """Real mesh robots as shipped (example-robot-data, a test extra: skipped by name where it is
    not installed); a robot that does not load fails the test."""
    from robot_fixtures import ERD_ROBOTS, erd_root

    root = erd_root()
    monkeypatch.setenv("DRAKE_MH_CACHE", str(tmp_path_factory.getbasetemp() / "cache"))
    for name in ("panda", "ur5"):
        rel, ee, _ = ERD_ROBOTS[name]
        robot = drake_mh.load_robot(root / rel, ee_frame=ee)
        assert robot.sphere_model.bound <= 0.01 + 1e-12
        _random_scene_check(robot, seed=7, n=25)


def test_no_obstacles_gives_infinite_clearance():
    """A robot with geometry and nothing around it: inf is the true answer (no pair)."""
    scene = Scene(PANDA)
    assert scene.min_distance(PANDA.home) == np.inf
    assert np.all(scene.batch_min_distance(PANDA.random_configurations(3, 0)) == np.inf)


def test_scene_errors():
    scene = make_scene()
    with pytest.raises(SceneError, match="already exists"):
        scene.add("ball", Sphere(0.1), [0, 0, 0])
    with pytest.raises(UnknownObstacle) as err:
        scene.move("bal", [0, 0, 0])
    assert "ball" in str(err.value)
    with pytest.raises(SceneError, match="3 finite numbers"):
        scene.add("x", Sphere(0.1), [0, 0])
    with pytest.raises(SceneError, match="Sphere, Box, Cylinder or Capsule"):
        scene.add("y", "sphere", [0, 0, 0])
    with pytest.raises(FrameNotFound):
        Scene(PANDA, self_collision=True, ignore_link_pairs=[("panda_link5", "gripper")])


def test_capsule_box_distances_are_exact_where_drake_gjk_is_not():
    """A configuration hypothesis found: Drake 1.51's GJK says 0.09119 m for panda_link5 vs the
    box; a 200,001-point sampling of the capsule axis gives 0.08503 m. Scene refines it."""
    scene = make_scene()
    Q = PANDA.random_configurations(40, 513056)
    exact = scene.exact_min_distance(Q)
    q = Q[np.argmin(np.abs(exact - 0.0850329465))]
    pair = [p for p in scene.distances(q) if p.link == "panda_link5" and p.other == "box"][0]
    assert pair.distance == pytest.approx(0.0850329465, abs=1e-8)
    assert np.linalg.norm(pair.p_W_link - pair.p_W_other) == pytest.approx(pair.distance, abs=1e-7)
    np.testing.assert_allclose((pair.p_W_link - pair.p_W_other) / pair.distance, pair.nhat_W, atol=1e-6)


def _rotation(rng):
    from scipy.spatial.transform import Rotation

    return Rotation.random(random_state=int(rng.integers(1 << 31))).as_matrix()


def test_segment_distance_matches_dense_sampling():
    from drake_mh.scene.segment_distance import capsule_distance
    from drake_mh.geometry.shapes import Capsule

    rng = np.random.default_rng(4)
    for shape in (Box((0.2, 0.3, 0.1)), Cylinder(0.05, 0.6), Capsule(0.04, 0.3), Sphere(0.1)):
        for _ in range(20):
            X_WC, X_WO = np.eye(4), np.eye(4)
            X_WC[:3, :3], X_WO[:3, :3] = _rotation(rng), _rotation(rng)
            X_WC[:3, 3] = rng.uniform(-0.5, 0.5, 3)
            d, p_c, p_o, n = capsule_distance(X_WC, 0.03, 0.2, X_WO, shape)
            axis = X_WC[:3, 3] + np.outer(np.linspace(-0.1, 0.1, 100001), X_WC[:3, 2])
            sampled = shape.signed_distance(axis @ X_WO[:3, :3]).min() - 0.03
            assert d == pytest.approx(sampled, abs=1e-7)
            if d > 1e-6:
                assert np.linalg.norm(p_c - p_o) == pytest.approx(d, abs=1e-6)


def _segment_distance_sampled(a0, a1, b0, b1, n=4001):
    """min over 4001 points of segment A of the exact point-to-segment distance to B."""
    s = np.linspace(0.0, 1.0, n)[:, None]
    P = a0 + s * (a1 - a0)
    u = b1 - b0
    t = np.clip(((P - b0) @ u) / (u @ u), 0.0, 1.0)[:, None]
    return float(np.linalg.norm(P - (b0 + t * u), axis=1).min())


def test_capsule_obstacles_never_hang_and_match_the_closed_form():
    """Drake's capsule-capsule query looped forever on collinear touching axes (reliability
    issue): those pairs are computed in closed form; checked against segment distances."""
    import signal

    from drake_mh.scene import Capsule

    def timeout(*_):
        raise TimeoutError("Scene.min_distance hung on collinear capsules")

    old = signal.signal(signal.SIGALRM, timeout)
    signal.alarm(60)
    try:
        scene = Scene(PANDA)
        scene.add("pole", Capsule(0.05, 0.2), [0.1, 0, 0.06], rpy=[0, np.pi / 2, 0])
        assert scene.min_distance(PANDA.home) < 0                    # collinear with the base capsule
        deep = Scene(PANDA)
        deep.add("big", Capsule(2.5, 1.0), [0, 0, 0.4])              # 8-10 s per pair in Drake
        assert deep.min_distance(PANDA.home) < -2.0
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    rng = np.random.default_rng(4)
    scene = Scene(PANDA)
    scene.add("rod", Capsule(0.03, 0.3), [0.4, 0.1, 0.4], rpy=[0.3, 1.1, -0.4])
    rod = scene.obstacles["rod"]
    half = 0.15 * rod.X_WO[:3, 2]
    links = {gid: c for gid, c in scene._capsule_links.items()}
    for q in PANDA.random_configurations(5, rng=rng):
        pairs = [p for p in scene.distances(q) if p.other == "rod"]
        assert pairs
        PANDA.plant.SetPositions(scene._plant_context, q)
        query = PANDA.scene_graph.get_query_output_port().Eval(scene._sg_context)
        best = np.inf
        for gid, capsule in links.items():
            X = query.GetPoseInWorld(gid).GetAsMatrix4()
            h = 0.5 * capsule.length * X[:3, 2]
            d = _segment_distance_sampled(X[:3, 3] - h, X[:3, 3] + h, rod.X_WO[:3, 3] - half, rod.X_WO[:3, 3] + half)
            best = min(best, d - capsule.radius - 0.03)
        assert min(p.distance for p in pairs) == pytest.approx(best, abs=2e-4)


@pytest.mark.parametrize("call", [
    lambda s: Sphere("abc"), lambda s: Sphere(None), lambda s: Box("abc"), lambda s: Scene(None),
    lambda s: s.add("a", Sphere(0.1), "abc"), lambda s: s.step("abc"),
    lambda s: s.distances(PANDA.home, max_distance=np.nan), lambda s: s.in_collision(PANDA.home, margin=np.nan),
    lambda s: s.add("a", Sphere(0.1), [[1, 2], [3]]), lambda s: s.add("a", Sphere(0.1), [1, 1, 1], rpy=[[0], [0, 0]]),
    lambda s: s.add("a", Sphere(0.1), [1, 1, 1j]),  # ragged: numpy's ValueError before
])
def test_bad_input_is_a_scene_error(call):
    with pytest.raises(SceneError):
        call(Scene(PANDA))


def test_an_obstacle_keeps_copies_of_its_position_and_velocity():
    """The velocity was a view of the caller's array: writing to it changed a registered obstacle's
    velocity (what step() and the planners read) without the scene knowing."""
    scene = Scene(PANDA)
    position, velocity = np.array([1.0, 1.0, 1.0]), np.array([0.0, 0.1, 0.0])
    scene.add("b", Sphere(0.1), position, velocity=velocity)
    position[0], velocity[1] = 5.0, 9.0
    assert scene.obstacles["b"].position[0] == 1.0 and scene.obstacles["b"].velocity_W[1] == 0.1
    scene.move("b", velocity=velocity)
    velocity[1] = 0.0
    assert scene.obstacles["b"].velocity_W[1] == 9.0


def test_failed_add_changes_nothing():
    scene = Scene(PANDA)
    with pytest.raises(SceneError, match="velocity"):
        scene.add("b", Sphere(0.1), [1, 1, 1], velocity=[np.nan, 0, 0])
    assert scene.obstacles == {} and scene.min_distance(PANDA.home) == np.inf   # no half-registered 'b'
    assert Box(0.3, 0.3, 0.3) == Box((0.3, 0.3, 0.3))


def test_self_capsule_pairs_are_exact():
    """Self-collision capsule pairs in closed form (Drake's GJK read up to 1.7e-4 m too much)."""
    scene = Scene(PANDA, self_collision=True)
    assert scene._self_capsule_pairs
    for q in PANDA.random_configurations(3, rng=np.random.default_rng(8)):
        pairs: dict = {}
        for p in scene.distances(q):
            if p.is_self:
                key = tuple(sorted((p.link, p.other)))
                pairs[key] = min(pairs.get(key, np.inf), p.distance)
        PANDA.plant.SetPositions(scene._plant_context, q)
        query = PANDA.scene_graph.get_query_output_port().Eval(scene._sg_context)
        inspector = query.inspector()
        by_link: dict = {}
        for a, b in scene._self_capsule_pairs:
            ends = []
            for g in (a, b):
                X = query.GetPoseInWorld(g).GetAsMatrix4()
                h = 0.5 * scene._capsule_links[g].length * X[:3, 2]
                ends.append((X[:3, 3] - h, X[:3, 3] + h, scene._capsule_links[g].radius))
            d = _segment_distance_sampled(ends[0][0], ends[0][1], ends[1][0], ends[1][1]) - ends[0][2] - ends[1][2]
            key = tuple(sorted(PANDA.plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name() for g in (a, b)))
            by_link[key] = min(by_link.get(key, np.inf), d)
        for key, d in by_link.items():
            assert pairs[key] <= d + 2e-4, key                   # other geometry of the links may be closer
            assert any(abs(p.distance - d) < 2e-4 for p in scene.distances(q)
                       if p.is_self and tuple(sorted((p.link, p.other))) == key), key


def test_a_planner_binding_is_built_once_per_key_and_again_after_the_obstacles_change():
    scene = Scene(PANDA)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    built = []

    def build(s):
        built.append(s.obstacle_arrays[2].copy())  # the obstacles' positions p_WO (K, 3)
        return len(built)

    assert scene.planner_binding("a", build) == 1 and scene.planner_binding("a", build) == 1
    assert scene.planner_binding("b", build) == 2
    scene.move("ball", [0.4, 0.0, 0.5])
    assert scene.planner_binding("a", build) == 3 and built[2][0, 0] == pytest.approx(0.4, abs=1e-15)
    scene.remove("ball")
    assert scene.planner_binding("a", build) == 4 and built[3].shape == (0, 3)
