"""Self-collision of meshed links: the pruned sphere-pair clearance (scene/kernels/pairs.py)
against the full product of sphere pairs, on the Panda with its hand (778 spheres, up to 131
per link, where the pruning matters)."""

import numpy as np
import pytest

from drake_mh.planning.problems import load_problem_robot
from drake_mh.scene import Scene


@pytest.fixture(scope="module")
def scene():
    return Scene(load_problem_robot("panda_hand_mbm"), self_collision=True)


@pytest.fixture(scope="module")
def configurations(scene):
    robot = scene.robot
    rng = np.random.default_rng(11)
    Q = robot.random_configurations(300, rng=rng)
    # folded configurations: the hand close to the forearm and the base
    folded = robot.random_configurations(300, rng=rng)
    folded[:, 3] = robot.lower[3] + 0.05
    folded[:, 5] = rng.uniform(robot.upper[5] - 0.6, robot.upper[5], 300)
    return np.concatenate([Q, folded])


def full_product(scene, Q) -> np.ndarray:
    """``(N, P)``: every checked link pair's smallest sphere-pair clearance, with numpy."""
    model = scene.collision_model
    centres = scene.sphere_centres(Q)
    links, radii = np.asarray(scene.sphere_model.links), scene.sphere_model.radii
    out = []
    for a, b in model.self_pairs:
        ia, ib = np.flatnonzero(links == a), np.flatnonzero(links == b)
        d = np.linalg.norm(centres[:, ia, None, :] - centres[:, None, ib, :], axis=-1)
        out.append((d - radii[ia, None] - radii[None, ib]).min(axis=(1, 2)))
    return np.stack(out, axis=1)


def test_pair_values_equal_the_full_product(scene, configurations):
    model, Q = scene.collision_model, configurations
    reference = full_product(scene, Q)
    assert np.mean(reference.min(axis=1) < 0.0) > 0.05, "some configurations must collide with themselves"
    QT = np.ascontiguousarray(Q.T)
    G = model.num_links
    exact = model.clearances(QT, scene.obstacle_arrays, per_obstacle=False)[:, G:]
    np.testing.assert_allclose(exact, reference, atol=1e-12)
    coarse = model.clearances(QT, scene.obstacle_arrays, per_obstacle=False, fine_below=0.05)[:, G:]
    below = reference < 0.05
    np.testing.assert_allclose(coarse[below], reference[below], atol=1e-12)  # exact where needed
    assert np.all(coarse <= reference + 1e-12)  # a lower bound elsewhere ...
    assert np.all(coarse[~below] >= 0.05 - 1e-12)  # ... that still says "not below 5 cm"


@pytest.mark.parametrize("self_clearance", [0.0, 0.004, 0.008])
def test_collision_free_and_the_one_configuration_path(scene, configurations, self_clearance):
    Q = configurations
    reference = full_product(scene, Q).min(axis=1)
    free = scene.collision_free(Q, 0.0, self_clearance)
    expected = reference >= max(self_clearance, 1e-12)
    tie = np.abs(reference - self_clearance) < 1e-9
    assert np.all((free == expected) | tie)
    assert 0 < free.sum() < len(Q)
    one = [scene.collision_free(q, 0.0, self_clearance) for q in Q[:200]]
    np.testing.assert_array_equal(one, free[:200])
