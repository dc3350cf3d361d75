"""Drawing: robot links, ghosts, obstacles, paths, targets, closest-point lines (scene tree + page)."""

from __future__ import annotations

import numpy as np
import pytest
import viz_html

import drake_mh
from drake_mh.errors import InvalidArgument, InvalidConfiguration
from drake_mh.viz import View, show


@pytest.fixture
def view(meshcat, panda):
    return View(panda, meshcat=meshcat)


def test_every_link_with_geometry_is_in_the_scene_tree(view, panda):
    paths = view.link_paths()
    inspector_links = {link for link, items in view.geometry.links.items() if items}
    assert set(paths) == inspector_links
    assert set(paths) == {f"panda_link{i}" for i in range(8)}  # link8 (flange) has no geometry
    for link, path in paths.items():
        assert view.meshcat.HasPath(path), path
        for item in view.geometry.links[link]:
            assert view.meshcat.HasPath(f"{path}/{item.name}")


def test_link_transforms_are_drakes_link_poses(view, panda):
    q = panda.random_configurations(1, rng=3)[0]
    view.set_q(q)
    X = viz_html.transforms(view.html())
    for link, X_WB in panda.link_poses(q).items():
        if link in view.link_paths():
            np.testing.assert_allclose(X[view.link_paths()[link]], X_WB, atol=1e-12)


def test_ghost_is_a_transparent_copy_at_its_own_configuration(view, panda):
    q_ghost = panda.random_configurations(1, rng=4)[0]
    name = view.add_ghost(q_ghost, "start")
    ghost_paths = view.link_paths(ghost=name)
    assert all(view.meshcat.HasPath(p) for p in ghost_paths.values())
    html = view.html()
    X = viz_html.transforms(html)
    np.testing.assert_allclose(X[ghost_paths["panda_link7"]], panda.link_poses(q_ghost)["panda_link7"], atol=1e-12)
    np.testing.assert_allclose(X[view.link_paths()["panda_link7"]], panda.link_poses(panda.home)["panda_link7"],
                               atol=1e-12)
    ghost_objects = [c for c in viz_html.commands(html)
                     if c["type"] == "set_object" and c["path"].startswith(ghost_paths["panda_link3"])]
    assert ghost_objects and all(m["transparent"] and m["opacity"] < 1
                                 for c in ghost_objects for m in c["object"]["materials"])
    with pytest.raises(InvalidArgument, match="no ghost named"):
        view.link_paths(ghost="nope")


def test_obstacles_path_target_and_distances(view, panda, scene):
    assert view.add_obstacles(scene) == ["box", "ball"]
    assert view.meshcat.HasPath(view.obstacle_path("box"))
    P_W = np.array([[0.3, 0.0, 0.5], [0.4, 0.1, 0.5], [0.5, 0.1, 0.4]])
    path = view.add_path(P_W, "cartesian")
    target_point = view.add_target([0.5, 0.1, 0.4], "p")
    target_pose = view.add_target(panda.fk(panda.home), "pose")
    pairs = view.add_distances(scene, margin=0.5, max_distance=1.0)
    assert pairs and [p.distance for p in pairs] == sorted(p.distance for p in pairs)
    for p in (path, f"{target_point}/sphere", f"{target_pose}/triad/x", f"{target_pose}/triad/z",
              f"{view.prefix}/distances/close/segments"):
        assert view.meshcat.HasPath(p), p
    assert not view.meshcat.HasPath(f"{target_point}/triad")
    X = viz_html.transforms(view.html())
    np.testing.assert_allclose(X[view.obstacle_path("box")][:3, 3], [0.55, -0.3, 0.3])
    np.testing.assert_allclose(X[target_pose], panda.fk(panda.home), atol=1e-12)


def test_show_a_configuration_with_scene_draws_distances(meshcat, panda, scene):
    ik_like = type("IKResult", (), {"q": panda.home})()
    view = show(panda, ik_like, scene=scene, target=panda.fk(panda.home), ghosts=[panda.home * 0.5],
                meshcat=meshcat)
    assert view.meshcat.HasPath(f"{view.prefix}/distances")
    assert view.meshcat.HasPath(f"{view.prefix}/ghosts/ghost0")
    np.testing.assert_allclose(view.q, panda.home)
    assert view.url.startswith("http://localhost:")
    assert view.url in repr(view) and view.url in view._repr_html_()


def test_show_clears_the_previous_drawing(meshcat, panda, planar2r):
    show(panda, meshcat=meshcat).add_ghost(panda.home, "old")
    view = show(planar2r, [0.3, -0.2], meshcat=meshcat)
    assert not meshcat.HasPath("/drake_mh/ghosts/old")
    assert not meshcat.HasPath("/drake_mh/robot/panda_link1")
    assert meshcat.HasPath(view.link_paths()["link1"])


@pytest.mark.parametrize("name", drake_mh.available_robots())
def test_every_bundled_robot_can_be_drawn(meshcat, name):
    robot = drake_mh.load_robot(name)
    view = View(robot, meshcat=meshcat, role="proximity")
    assert view.link_paths() and all(meshcat.HasPath(p) for p in view.link_paths().values())


def test_drawing_errors(view, panda, scene):
    with pytest.raises(InvalidConfiguration, match=r"shape \(7,\)"):
        view.set_q(np.zeros(6))
    with pytest.raises(InvalidConfiguration):
        view.add_ghost([np.nan] * 7)
    with pytest.raises(InvalidArgument, match=r"\(N >= 2, 3\)"):
        view.add_path(np.zeros((5, 2)))
    with pytest.raises(InvalidArgument, match=r"\(N >= 2, 3\)"):
        view.add_path([[0, 0, 0]])
    with pytest.raises(InvalidArgument, match="point"):
        view.add_target([1.0, 2.0])
    with pytest.raises(InvalidArgument, match="rotation"):
        view.add_target(np.diag([2.0, 1.0, 1.0, 1.0]))
    with pytest.raises(InvalidArgument, match="radius"):
        view.add_target([0, 0, 0], radius=0)
    with pytest.raises(InvalidArgument, match=r"\(r, g, b\)"):
        view.add_ghost(panda.home, colour=(1.0, 2.0, 0.0))
    with pytest.raises(InvalidArgument, match="opacity"):
        view.add_ghost(panda.home, opacity=1.5)
    with pytest.raises(InvalidArgument, match="prefix"):
        View(panda, meshcat=view.meshcat, prefix="drake_mh")
    with pytest.raises(InvalidArgument, match="role"):
        View(panda, meshcat=view.meshcat, role="visual")
    with pytest.raises(InvalidArgument, match="scene"):
        show(panda, panda.home, distances=True, meshcat=view.meshcat)


def test_update_obstacles_follows_the_scene(view, panda, scene):
    with pytest.raises(InvalidArgument, match="add_obstacles"):
        view.update_obstacles()
    view.add_obstacles(scene)
    scene.step(2.0)  # the ball moves by 2 s x (0, -0.1, 0) m/s
    scene.remove("box")
    scene.add("wall", drake_mh.Box((0.05, 1.0, 1.0)), [0.8, 0.0, 0.5])
    view.update_obstacles()
    assert not view.meshcat.HasPath(view.obstacle_path("box"))
    assert view.meshcat.HasPath(view.obstacle_path("wall"))
    X = viz_html.transforms(view.html())
    np.testing.assert_allclose(X[view.obstacle_path("ball")][:3, 3], [0.45, 0.05, 0.55], atol=1e-12)


def test_a_bad_initial_configuration_leaves_the_drawing_alone(meshcat, panda):
    view = View(panda, meshcat=meshcat)
    with pytest.raises(InvalidConfiguration):
        View(panda, meshcat=meshcat, q=np.zeros(2))
    assert meshcat.HasPath(view.link_paths()["panda_link1"])
