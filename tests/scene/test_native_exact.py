"""The compiled core's exact distances (``cpp/exact.hpp``, ``cpp/gjk.hpp``) and penetration
correction (``cpp/penetration.hpp``) against their numba kernels (the same arrays in, the same
numbers out) and the exact distances against Drake's on an independent plant."""

from pathlib import Path

import numpy as np
import pytest

import drake_mh
from drake_mh._support.native import ENVIRONMENT, compiled_core
from drake_mh.geometry.cloud import PointCloud
from drake_mh.scene import Box, Capsule, Cylinder, Mesh, Scene, Sphere
from drake_mh.scene.kernels import exact as X
from drake_mh.scene.kernels import gjk
from references import FreshDrake
from sphere_fixtures import mesh_arm_urdf, primitive_arm_urdf

CORE = compiled_core()
pytestmark = pytest.mark.skipif(
    CORE is None, reason="the compiled core drake_mh._native is not built or switched off (DRAKE_MH_COMPILED_CORE=0)")

PANDA = drake_mh.load_robot("panda")
BRACKET = Mesh(Path(__file__).resolve().parents[1] / "data" / "bracket.obj", scale=2.0)
SHAPES = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4), Capsule(0.04, 0.3), BRACKET]


def _scene(robot, seed: int, reach: float, n: int = 10, self_collision: bool = False) -> Scene:
    """n obstacles cycling through every primitive kind and a mesh (its convex pieces)."""
    scene = Scene(robot, self_collision=self_collision)
    rng = np.random.default_rng(seed)
    for i in range(n):
        scene.add(f"o{i}", SHAPES[i % len(SHAPES)], rng.uniform([-reach, -reach, 0.0], [reach, reach, reach + 0.2]),
                  rpy=rng.uniform(-3, 3, 3))
    return scene


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    """The capsule Panda, the Panda with its meshed hand, a convex-mesh arm and a
    cylinder/box/ellipsoid arm, with their reach."""
    from drake_mh.robot.examples import load_example_arm

    return [(PANDA, 0.7), (load_example_arm("panda_hand"), 0.7),
            (drake_mh.Robot(mesh_arm_urdf(tmp_path_factory.mktemp("mesh_arm"))), 0.4),
            (drake_mh.Robot(primitive_arm_urdf()), 0.4)]


def _kernel(function, exact, state, q, max_distance, min_only):
    """One call of ``function`` (the numba kernel or the compiled core's) on fresh outputs."""
    out, status = np.full_like(state.out, np.nan), np.full_like(state.status, -7)
    need, order = np.zeros_like(state.need), np.zeros_like(state.order)
    R_WG, p_WG = np.zeros_like(exact.R_WG), np.zeros_like(exact.p_WG)
    best, n_need, n_rows = function(q, *exact._chain, exact.g_int, exact.g_float, state.vertices, state.o_int,
                                    state.o_float, exact.self_pairs, max_distance, min_only, gjk.TOLERANCE, R_WG, p_WG,
                                    out, status, need, order)
    return best, n_need, n_rows, out, status, need[:n_need], order[:n_rows], R_WG, p_WG


def _tolerances(exact, state) -> np.ndarray:
    """Per row: 1e-12, or 1e-9 where the certified GJK answers. Its poses differ from the numba
    kernel's in the last bit (``test_rows_at_the_same_poses_are_the_numba_kernels``: none of
    the rest does), and on two curved cores that can end the search on round-off, keeping a
    bound a few 1e-10 below the other's (gjk.py: a search that stops short keeps its bound)."""
    G, K = len(exact.gids), state.K
    g, k = np.divmod(np.arange(G * K), K)
    searched = (exact.g_int[g, 1] == X.LINK_GJK) | (state.o_int[k, 1] == gjk.HULL)
    return np.r_[np.where(searched, 1e-9, 1e-12), np.full(len(exact.self_pairs), 1e-12)]


def _assert_same(ours, theirs, tol):
    best, n_need, n_rows, out, status, need, order, R_WG, p_WG = ours
    np.testing.assert_allclose(R_WG, theirs[7], rtol=0, atol=1e-14)
    np.testing.assert_allclose(p_WG, theirs[8], rtol=0, atol=1e-14)
    np.testing.assert_array_equal(status, theirs[4])
    assert (n_need, n_rows) == theirs[1:3]
    assert best == pytest.approx(theirs[0], abs=tol.max())
    assert sorted(need) == sorted(theirs[5])
    rows = status != X.SKIPPED
    np.testing.assert_array_equal(np.isinf(out[rows, 0]), np.isinf(theirs[3][rows, 0]))  # inf: left to Drake
    finite = rows & np.isfinite(out[:, 0])
    assert (np.abs(out[finite, 0] - theirs[3][finite, 0]) <= tol[finite]).all()
    # the closest points and normals of the closed forms and the golden-section search (whose
    # argmin along a flat minimum is settled to the square root of round-off only); GJK's are
    # not unique where faces meet faces: each answer's own points are checked below
    closed = finite & (tol < 1e-11)
    np.testing.assert_allclose(out[closed, 1:], theirs[3][closed, 1:], rtol=0, atol=1e-6)
    apart = finite & (out[:, 0] > 1e-6)  # points `distance` apart along the normal
    gap = out[apart, 1:4] - out[apart, 4:7]
    np.testing.assert_allclose(np.linalg.norm(gap, axis=1), out[apart, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(gap / out[apart, :1], out[apart, 7:], rtol=0, atol=1e-6)
    # closest first: the same rows, in the same order up to ties within round-off
    assert sorted(order) == sorted(theirs[6])
    np.testing.assert_allclose(out[order, 0], theirs[3][theirs[6], 0], rtol=0, atol=tol.max())
    assert (np.diff(out[order, 0]) >= 0).all()


@pytest.mark.parametrize("self_collision", [False, True])
def test_exact_pairs_equal_the_numba_kernel(robots, self_collision):
    """Every robot, obstacle kind and mode (the smallest only; every pair; pairs within 5 cm):
    the same statuses, distances, lists and poses as the numba kernel."""
    seen = set()
    for robot, reach in robots:
        for seed in range(2):
            scene = _scene(robot, seed, reach, self_collision=self_collision)
            scene.min_distance(robot.home)
            exact, state = scene._exact, scene._exact.state()
            assert (state.o_int[:, 1] == gjk.HULL).any()  # the mesh's pieces are rows
            tol = _tolerances(exact, state)
            for q in robot.random_configurations(25, seed):
                for max_distance, min_only in ((np.inf, True), (np.inf, False), (0.05, False)):
                    ours = _kernel(CORE.exact_pairs, exact, state, q, max_distance, min_only)
                    _assert_same(ours, _kernel(X.exact_pairs, exact, state, q, max_distance, min_only), tol)
                    seen.update(ours[4].tolist())
    assert seen == {X.SKIPPED, X.EXACT, X.NEEDS_DRAKE}  # pruned pairs and penetrations were met


def test_rows_at_the_same_poses_are_the_numba_kernels(robots):
    """Step for step: given the compiled core's geometry poses, the numba kernel's pair_distance
    writes the same rows and statuses (the certified GJK, the golden-section search, the closed
    forms)."""
    for robot, reach in robots:
        scene = _scene(robot, 7, reach, self_collision=True)
        scene.min_distance(robot.home)
        exact, state = scene._exact, scene._exact.state()
        G, K = len(exact.gids), state.K
        work = np.empty((9, 3))
        for q in robot.random_configurations(25, 7):
            _, _, _, out, status, _, _, R_WG, p_WG = _kernel(CORE.exact_pairs, exact, state, q, np.inf, False)
            rows = np.flatnonzero(status[:G * K] != X.SKIPPED)
            assert len(rows)
            theirs = np.full_like(out, np.nan)
            for i in rows:
                st = X.pair_distance(i // K, i % K, exact.g_int, exact.g_float, state.vertices, state.o_int,
                                     state.o_float, R_WG, p_WG, theirs, i, work, gjk.TOLERANCE)
                assert st == status[i]
            np.testing.assert_allclose(out[rows], theirs[rows], rtol=0, atol=1e-15)


def test_exact_pairs_of_a_configuration_that_is_not_finite():
    scene = _scene(PANDA, 0, 0.7)
    scene.min_distance(PANDA.home)
    exact, state = scene._exact, scene._exact.state()
    for q in (np.full(7, np.nan), np.r_[np.zeros(6), np.inf]):
        best, n_need, n_rows = _kernel(CORE.exact_pairs, exact, state, q, np.inf, True)[:3]
        assert np.isnan(best) and (n_need, n_rows) == (-1, 0)
    with pytest.raises(ValueError):  # outputs of the wrong size
        CORE.exact_pairs(PANDA.home, *exact._chain, exact.g_int, exact.g_float, state.vertices, state.o_int,
                         state.o_float, exact.self_pairs, np.inf, True, gjk.TOLERANCE, exact.R_WG, exact.p_WG,
                         state.out[:-1], state.status, state.need, state.order)


def _per_obstacle(pairs) -> dict:
    out = {}
    for p in pairs:
        if not p.is_self:
            out[p.other] = min(out.get(p.other, np.inf), p.distance)
    return out


def _drake_per_obstacle(robot, scene):
    """``q -> {obstacle: smallest signed distance}`` from Drake's query on a fresh plant holding
    the robot and the scene's primitive obstacles (a mesh has no Drake reference there)."""
    primitives = [name for name, o in scene.obstacles.items() if not isinstance(o.shape, Mesh)]
    drake = FreshDrake(robot, [(scene.obstacles[n].shape, scene.obstacles[n].X_WO) for n in primitives])
    inspector = drake.scene_graph.model_inspector()
    obstacle_of = {}  # Drake's geometry id -> our obstacle name (in the order they were given)
    for gid in inspector.GetAllGeometryIds():
        for i, name in enumerate(primitives):
            if inspector.GetName(gid).endswith(f"reference_obstacle_{i}"):
                obstacle_of[gid] = name
    assert len(obstacle_of) == len(primitives)

    def per_obstacle(q) -> dict:
        out = {}
        for pair in drake.pairs(q):
            other = obstacle_of.get(pair.id_A, obstacle_of.get(pair.id_B))
            if other is not None:
                out[other] = min(out.get(other, np.inf), pair.distance)
        return out

    return per_obstacle


def test_scene_distances_equal_with_either_backend_and_drakes_where_exact(monkeypatch, robots):
    """``Scene.distances`` and ``min_distance`` with the compiled core and with the numba kernels
    (``DRAKE_MH_COMPILED_CORE=0``) agree; against Drake's signed distances on a fresh plant they
    are equal for ball obstacles (Drake's closed form) and never above Drake's for the other
    kinds (Drake's GJK is optimistic there). The hand's model names a ROS package that a fresh
    parser is not given: it is compared with the numba kernels only."""
    for robot, reach in robots:
        compiled = _scene(robot, 3, reach, self_collision=True)
        monkeypatch.setenv(ENVIRONMENT, "0")
        numba_scene = _scene(robot, 3, reach, self_collision=True)
        numba_scene._exact  # built now: it reads the switch
        monkeypatch.delenv(ENVIRONMENT)
        assert compiled._exact._core is CORE and numba_scene._exact._core is None
        drake = _drake_per_obstacle(robot, compiled) if robot is not robots[1][0] else None
        balls = {name for name, o in compiled.obstacles.items() if isinstance(o.shape, Sphere)}
        for q in robot.random_configurations(15, 4):
            ours, theirs = compiled.distances(q), numba_scene.distances(q)
            assert sorted((p.link, p.other) for p in ours) == sorted((p.link, p.other) for p in theirs)
            # 1e-9 where GJK answers (a mesh's pieces, the small arms' links): see _tolerances
            np.testing.assert_allclose([p.distance for p in ours], [p.distance for p in theirs], rtol=0, atol=1e-9)
            assert compiled.min_distance(q) == pytest.approx(numba_scene.min_distance(q), abs=1e-9)
            if drake is None:
                continue
            found = _per_obstacle(ours)
            for name, d in drake(q).items():
                assert found[name] <= d + 1e-9, name
                if name in balls and robot is PANDA:
                    assert found[name] == pytest.approx(d, abs=1e-9), name


def _penetration_scene(robot, reach):
    scene = _scene(robot, 5, reach, n=5)
    rng = np.random.default_rng(5)
    scene.add("cloud", PointCloud(rng.uniform([-reach, -reach, 0.0], [reach, reach, reach], (400, 3)), 0.01))
    return scene


def test_penetration_correction_equals_the_numba_kernel(monkeypatch, robots):
    """Every obstacle kind (a mesh's pieces and a cloud too) and both core kinds (the Panda's
    capsule segments, the small arms' polytopes): the corrected values of every configuration
    whose spheres penetrate, with the compiled core and with the numba kernel."""
    checked = 0
    for robot, reach in robots:
        scene = _penetration_scene(robot, reach)
        Q = robot.random_configurations(300, 6)
        K = len(scene.obstacle_owners)
        for values in (np.full((len(Q), K), -1.0), scene._sphere_clearances(Q, overall=False)[1]):
            deep = np.flatnonzero((values < 0).any(axis=1))
            compiled, numba_values = values[deep].copy(), values[deep].copy()
            scene._correct_penetrations(Q[deep], compiled)
            monkeypatch.setenv(ENVIRONMENT, "0")
            scene._correct_penetrations(Q[deep], numba_values)
            monkeypatch.delenv(ENVIRONMENT)
            np.testing.assert_array_equal(np.isinf(compiled), np.isinf(numba_values))
            np.testing.assert_allclose(compiled, numba_values, rtol=0, atol=1e-12)
            changed = compiled != values[deep]
            checked += int(changed.sum())
    assert checked > 100  # the correction did work on many pairs
