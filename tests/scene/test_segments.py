"""Certified straight joint-space segments (Scene.certify_segments / segment_free / certify_path):
never certify what dense sampling with the exact distance, or with Drake's own query on a fresh
plant, finds in collision."""

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import SceneError
from drake_mh.scene import Box, Cylinder, Scene, Sphere
from drake_mh.scene.segments import refine_path
from references import FreshDrake, dense_path
from test_collision_free import PANDA, cluttered


def free_pairs(scene, seed, count, step):
    rng = np.random.default_rng(seed)
    Q = rng.uniform(PANDA.lower, PANDA.upper, (20 * count, PANDA.nq))
    QA = Q[scene.collision_free(Q)][:count]
    QB = np.clip(QA + rng.normal(0.0, step, QA.shape), PANDA.lower, PANDA.upper)
    return QA, QB


def dense(QA, QB, points):
    t = np.linspace(0.0, 1.0, points)[:, None]
    return QA + t * (QB - QA)


def test_reach_bounds_the_motion_of_every_sphere():
    """The Lipschitz constants: no sphere moves farther than reach · |Δq| on a short segment."""
    scene = Scene(PANDA)
    model = scene.collision_model
    rng = np.random.default_rng(0)
    start = model.model_arrays[3]
    for _ in range(30):
        qa = rng.uniform(PANDA.lower, PANDA.upper)
        qb = np.clip(qa + rng.normal(0, 0.4, PANDA.nq), PANDA.lower, PANDA.upper)
        centres = scene.sphere_centres(dense(qa, qb, 400))[:, model.sphere_order]
        path = np.linalg.norm(np.diff(centres, axis=0), axis=2).sum(axis=0)  # (S,) path lengths
        for g in range(model.num_links):
            bound = model.reach[g] @ np.abs(qb - qa)
            assert np.all(path[start[g]:start[g + 1]] <= bound + 1e-9)


#: (scene seed, pair seed, step [rad]) of the explicit examples below: seven scenes, three step sizes
EXAMPLES = [(seed % 7, seed, step) for seed, step in zip(range(12), [0.05, 0.3, 1.0] * 4)]


def test_certified_segments_are_exactly_free():
    """Every certified segment, sampled at 2 mrad of its fastest joint, keeps its certified lower
    bound under the exact distance (tested against Drake in tests/scene/test_exact.py; the
    certificate is the sphere model's); a blocked one names a configuration the model finds in
    collision. 12 explicit examples, at least 40 certified and 10 blocked segments checked."""
    certified = blocked = 0
    for scene_seed, seed, step in EXAMPLES:
        scene = cluttered(scene_seed)
        QA, QB = free_pairs(scene, seed, 12, step)
        cert = scene.certify_segments(QA, QB)
        for i in range(len(QA)):
            if cert.certified[i]:
                exact = scene.exact_min_distance(dense_path(np.stack([QA[i], QB[i]]), 0.002))
                assert exact.min() >= cert.lower[i] - 1e-9 and cert.lower[i] >= 0
                certified += 1
            elif cert.status[i] == 0:  # blocked: the configuration it names is not free under the model
                q = QA[i] + cert.t_stop[i] * (QB[i] - QA[i])
                assert not scene.collision_free(q)
                blocked += 1
    assert certified >= 40 and blocked >= 10, (certified, blocked)


def drake_scene(seed: int, count: int = 6) -> Scene:
    """``count`` spheres, boxes and cylinders in the Panda's workspace (no capsules: Drake's
    capsule-capsule query is no reference, tests/references.py)."""
    rng = np.random.default_rng(seed)
    shapes = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4)]
    scene = Scene(PANDA)
    for i in range(count):
        scene.add(f"o{i}", shapes[i % 3], rng.uniform([-0.7, -0.7, 0.0], [0.7, 0.7, 0.9]), rpy=rng.uniform(-3, 3, 3))
    return scene


@pytest.mark.parametrize("seed", range(3))
def test_segment_free_agrees_with_dense_drake_sampling(seed):
    """``Scene.segment_free`` against Drake's own query on a fresh plant with the obstacles
    anchored in it: a segment said free at a clearance keeps it at every sample (2 mrad of its
    fastest joint; Drake may only be optimistic for boxes and cylinders, so a shortfall it finds
    is real). Per seed at least 8 free and 4 refused segments, over clearances 0 and 2 cm."""
    scene = drake_scene(seed)
    drake = FreshDrake(PANDA, scene)
    rng = np.random.default_rng(100 + seed)
    Q = PANDA.random_configurations(300, rng=rng)
    QA = Q[scene.collision_free(Q, 0.02)][:10]
    free = refused = 0
    for step in (0.2, 0.8):
        QB = np.clip(QA + rng.normal(0.0, step, QA.shape), PANDA.lower, PANDA.upper)
        for clearance in (0.0, 0.02):
            for a, b in zip(QA, QB):
                if not scene.segment_free(a, b, clearance):
                    refused += 1
                    continue
                free += 1
                sampled = drake.min_distances(dense_path(np.stack([a, b]), 0.002), max_distance=clearance + 0.01)
                assert sampled.min() >= clearance - 1e-9, (clearance, sampled.min())
    assert free >= 8 and refused >= 4, (free, refused)


def test_self_clearance_is_kept_by_drakes_self_distance():
    """``self_clearance > 0``: a configuration said free at 1 cm of self-clearance, and every
    sample of a segment said free at it, is at least 1 cm from itself by Drake's own query on a
    fresh plant (Drake's default filter of adjacent links, the scene's always-close pairs left
    out as the scene does). The scene's exact self-distance is never above Drake's and within
    5e-5 m of it (Drake's capsule GJK is optimistic: 2.6e-5 m measured). At least 20
    configurations and 6 segments."""
    scene = Scene(PANDA, self_collision=True)
    drake = FreshDrake(PANDA, (), self_collision=True, ignore_link_pairs=scene.always_close_pairs)
    rng = np.random.default_rng(8)
    Q = PANDA.random_configurations(200, rng=rng)
    free = Q[scene.collision_free(Q, 0.0, 0.01)][:30]
    assert len(free) >= 20
    d = drake.min_distances(free)
    assert d.min() >= 0.01
    np.testing.assert_allclose(scene.exact_min_distance(free), d, atol=5e-5)
    assert np.all(scene.exact_min_distance(free) <= d + 1e-9)
    QB = np.clip(free + rng.normal(0.0, 0.3, free.shape), PANDA.lower, PANDA.upper)
    checked = 0
    for a, b in zip(free, QB):
        if scene.segment_free(a, b, 0.0, 0.01):
            checked += 1
            assert drake.min_distances(dense_path(np.stack([a, b]), 0.002), max_distance=0.02).min() >= 0.01
    assert checked >= 6, checked


def test_agrees_with_dense_model_sampling():
    """Certified => no densely sampled configuration is below the clearance under the model;
    blocked => the configuration it names is below it."""
    scene = cluttered(1)
    QA, QB = free_pairs(scene, 11, 150, 0.3)
    for clearance in (0.0, 0.03):
        cert = scene.certify_segments(QA, QB, clearance)
        assert 20 < cert.certified.sum() < 150
        for i in range(len(QA)):
            sampled_free = scene.collision_free(dense(QA[i], QB[i], 801), clearance).all()
            if cert.certified[i]:
                assert sampled_free
            elif cert.status[i] == 0:
                q = QA[i] + cert.t_stop[i] * (QB[i] - QA[i])
                assert not scene.collision_free(q, clearance)


def test_tight_lower_bound_with_tolerance():
    scene = cluttered(2)
    QA, QB = free_pairs(scene, 3, 40, 0.3)
    cert = scene.certify_segments(QA, QB, tolerance=1e-3)
    for i in np.flatnonzero(cert.certified):
        sampled = scene.batch_min_distance(dense(QA[i], QB[i], 801)).min()
        assert cert.lower[i] <= sampled + 1e-9
        assert cert.lower[i] >= sampled - 1e-3 - 1e-9


@pytest.mark.parametrize("fine", [False, True])
def test_path_tolerance_bounds_the_whole_path_minimum(fine):
    """Paths of three chained segments from the free pairs, or (``fine``) one pair cut into 120
    short segments, a retimed trajectory's shape, whose segments are refined by certificates at a
    raised clearance: the bound is within the tolerance of the densely sampled minimum, never above."""
    scene = cluttered(2)
    QA, QB = free_pairs(scene, 5 if fine else 4, 40, 0.3)
    checked = 0
    for i in range(12) if fine else range(0, 30, 3):
        Q = dense(QA[i], QB[i], 121) if fine else np.vstack([QA[i], QB[i], QA[i + 1], QB[i + 1]])
        loose, tight = scene.certify_path(Q), scene.certify_path(Q, tolerance=1e-3)
        assert loose.certified == tight.certified
        if not tight.certified:
            continue
        points = 41 if fine else 801
        sampled = scene.batch_min_distance(np.vstack([dense(a, b, points) for a, b in zip(Q[:-1], Q[1:])])).min()
        assert loose.min_clearance <= tight.min_clearance <= sampled + 1e-9
        assert tight.min_clearance >= sampled - 1e-3 - 1e-9
        assert np.all(tight.segments.lower >= loose.segments.lower)
        checked += 1
    assert checked >= 3


def test_self_collision_segments():
    scene = Scene(PANDA, self_collision=True)
    rng = np.random.default_rng(8)
    Q = rng.uniform(PANDA.lower, PANDA.upper, (400, PANDA.nq))
    QA = Q[scene.collision_free(Q)][:30]
    QB = np.clip(QA + rng.normal(0, 0.6, QA.shape), PANDA.lower, PANDA.upper)
    cert = scene.certify_segments(QA, QB)
    assert cert.certified.any() and not cert.certified.all()
    for i in np.flatnonzero(cert.certified)[:8]:
        assert scene.exact_min_distance(dense_path(np.stack([QA[i], QB[i]]), 0.002)).min() >= -1e-9
        assert cert.lower_self[i] >= 0


def test_moving_obstacle_is_certified_where_it_will_be():
    """A ball that moves into the arm's path during the segment blocks it; standing still it
    does not; dense sampling with the ball moved along agrees."""
    scene = Scene(PANDA)
    qa = PANDA.home
    qb = qa.copy()
    qb[0] += 0.05
    p = PANDA.fk(qb)[:3, 3]  # the ball ends where the flange ends
    scene.add("ball", Sphere(0.05), p + [0.0, 0.0, 0.4], velocity=[0.0, 0.0, -0.4])
    assert scene.segment_free(qa, qb)
    moving = scene.certify_segments(qa, qb, duration=1.0)
    assert not moving.certified[0]
    slow = scene.certify_segments(qa, qb, duration=0.2)
    assert slow.certified[0]
    for t in np.linspace(0, 1, 21):  # the ball 8 cm lower at the end: still clear, densely
        scene.move("ball", p + [0.0, 0.0, 0.4 - 0.08 * t])
        assert scene.min_distance(qa + t * (qb - qa)) >= slow.lower[0] - 1e-9
    scene.move("ball", p + [0.0, 0.0, 0.4])
    path = scene.certify_path(np.stack([qa, qb, qa]), durations=[0.2, 0.2])
    assert path.certified and np.allclose(scene.obstacles["ball"].position, p + [0, 0, 0.4])


def wall_across():
    """``(scene, q0, q1)``: a ball halfway along the straight motion from home to ``q1``."""
    scene = Scene(PANDA)
    q0 = PANDA.home
    q1 = q0.copy()
    q1[1] += 0.8
    scene.add("wall", Sphere(0.1), PANDA.fk(0.5 * (q0 + q1))[:3, 3])
    return scene, q0, q1


def test_certify_path_reports_the_first_failure():
    scene, q0, q1 = wall_across()
    path = scene.certify_path(np.stack([q0, q0, q1]))
    assert not path.certified and path.first_failure == 1 and np.isnan(path.min_clearance)
    assert "blocked" in repr(path)
    single = scene.certify_path(q0[None])
    assert single.certified == scene.collision_free(q0)


def test_bad_arguments_are_scene_errors():
    scene = cluttered(1, 2)
    q = PANDA.home
    with pytest.raises(SceneError, match="same number"):
        scene.certify_segments(np.stack([q, q]), q[None])
    with pytest.raises(SceneError, match="tolerance"):
        scene.certify_segments(q, q, tolerance=0.0)
    with pytest.raises(SceneError, match="clearance"):
        scene.segment_free(q, q, clearance=-1)
    with pytest.raises(SceneError, match="durations"):
        scene.certify_path(np.stack([q, q, q]), durations=[0.1])
    with pytest.raises(SceneError, match="duration"):
        scene.certify_segments(q, q, duration=-1.0)
    with pytest.raises(drake_mh.errors.DrakeMhError):
        scene.certify_segments(q[:3], q[:3])


def test_an_empty_path_is_refused_not_certified():
    """certify_path of no configuration read certified=True with a NaN clearance."""
    scene = cluttered(1, 2)
    with pytest.raises(SceneError, match="at least one configuration"):
        scene.certify_path(np.zeros((0, PANDA.nq)))


def test_segment_free_checks_one_segment_and_refuses_several():
    """(2, nq) inputs used to check the first row only and answer True while the second collides."""
    scene, q0, q1 = wall_across()
    assert scene.certify_segments(np.stack([q0, q0]), np.stack([q0, q1])).certified.tolist() == [True, False]
    with pytest.raises(SceneError, match="one segment.*certify_segments"):
        scene.segment_free(np.stack([q0, q0]), np.stack([q0, q1]))
    with pytest.raises(drake_mh.errors.DrakeMhError, match="numeric"):
        scene.segment_free([[1, 2], [3]], q0)
    assert scene.segment_free(q0, q0) and not scene.segment_free(q0, q1)


def test_refining_a_path_certificate_gives_the_refined_certificate():
    scene = cluttered(2)
    QA, QB = free_pairs(scene, 4, 40, 0.3)
    checked = 0
    for i in range(0, 30, 3):
        Q = np.vstack([QA[i], QB[i], QA[i + 1], QB[i + 1]])
        loose = scene.certify_path(Q)
        if not loose.certified:
            continue
        refined, tight = refine_path(scene, Q, loose, 1e-3), scene.certify_path(Q, tolerance=1e-3)
        np.testing.assert_allclose(refined.segments.lower, tight.segments.lower, rtol=0, atol=1e-12)
        assert refined.min_clearance >= loose.min_clearance
        checked += 1
    assert checked >= 3
    with pytest.raises(SceneError, match="segments"):
        refine_path(scene, Q[:3], loose, 1e-3)
    with pytest.raises(SceneError, match="tolerance"):
        refine_path(scene, Q, loose, 0.0)


def test_smallest_clearance_at_rows_reads_only_rows_that_can_hold_it_down(monkeypatch):
    """The smallest sphere-model clearance over a path's rows, from the rows whose segments'
    certified bounds leave them below the smallest found: the same value as every row's, from
    fewer rows on a path of many short segments."""
    from drake_mh.scene import segments

    scene = cluttered(2)
    QA, QB = free_pairs(scene, 5, 40, 0.3)
    checked = fewer = 0
    for i in range(12):
        Q = dense(QA[i], QB[i], 121)
        cert = scene.certify_path(Q)
        if not cert.certified:
            continue
        read = []
        original = type(scene).batch_min_distance
        monkeypatch.setattr(type(scene), "batch_min_distance", lambda self, X: read.append(len(X)) or original(self, X))
        smallest = segments._smallest_above(scene, Q, segments._row_floors(cert.segments.lower))
        monkeypatch.undo()
        assert smallest == float(np.min(scene.batch_min_distance(Q)))
        assert sum(read) <= len(Q)
        fewer += sum(read) < len(Q)
        checked += 1
    assert checked >= 3 and fewer >= 1
