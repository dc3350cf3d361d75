"""Animations (recorded joint trajectories, moving obstacles) and self-contained HTML export."""

from __future__ import annotations

import re

import numpy as np
import pytest
import viz_html

from drake_mh.errors import InvalidArgument, InvalidConfiguration, InvalidTrajectory, UnknownObstacle
from drake_mh.viz import View, animation_html, save_animation, show


def _motion(robot, duration=2.0, K=21):
    t = np.linspace(0.0, duration, K)
    Q = robot.home + 0.4 * np.sin(np.pi * t / duration)[:, None] * np.linspace(1, -1, robot.nq)
    return t, Q


def _quaternion_to_matrix(xyzw):
    from pydrake.common.eigen_geometry import Quaternion

    x, y, z, w = xyzw
    return Quaternion(w, x, y, z).rotation()


def test_animation_frames_are_forward_kinematics(meshcat, panda):
    t, Q = _motion(panda)
    view = View(panda, meshcat=meshcat)
    n = view.animate(t + 5.0, Q, fps=10)  # times need not start at 0
    assert n == 21
    anim = viz_html.animation(view.html())
    assert anim is not None and anim["options"]["play"] is True
    assert {a["path"] for a in anim["animations"]} == set(view.link_paths().values())
    frames, p = viz_html.track(anim, view.link_paths()["panda_link7"], ".position")
    _, quat = viz_html.track(anim, view.link_paths()["panda_link7"], ".quaternion")
    np.testing.assert_array_equal(frames, np.arange(21))
    for k in (0, 7, 20):  # samples at 10 fps are exactly the given ones
        X_WB = panda.link_poses(Q[k])["panda_link7"]
        np.testing.assert_allclose(p[k], X_WB[:3, 3], atol=1e-12)
        np.testing.assert_allclose(_quaternion_to_matrix(quat[k]), X_WB[:3, :3], atol=1e-9)
    # between samples: the configuration is interpolated joint-wise, then FK (not link-wise)
    view.animate(t, Q, fps=20)
    frames, p = viz_html.track(viz_html.animation(view.html()), view.link_paths()["panda_link7"], ".position")
    assert frames.size == 41
    np.testing.assert_allclose(p[1], panda.link_poses(0.5 * (Q[0] + Q[1]))["panda_link7"][:3, 3], atol=1e-12)
    # the static scene shows the first configuration
    X = viz_html.transforms(view.html())
    np.testing.assert_allclose(X[view.link_paths()["panda_link7"]], panda.link_poses(Q[0])["panda_link7"], atol=1e-12)


def test_moving_obstacles_are_animated(meshcat, panda, scene):
    t, Q = _motion(panda, duration=1.0, K=11)
    view = View(panda, meshcat=meshcat)
    view.add_obstacles(scene)
    track_box = np.column_stack([np.linspace(0.5, 0.6, 11), np.full(11, -0.3), np.full(11, 0.3)])
    view.animate(t, Q, fps=10, obstacle_positions={"box": track_box}, move_obstacles=True)
    anim = viz_html.animation(view.html())
    _, p_box = viz_html.track(anim, view.obstacle_path("box"), ".position")
    _, p_ball = viz_html.track(anim, view.obstacle_path("ball"), ".position")
    np.testing.assert_allclose(p_box, track_box, atol=1e-12)
    expected_ball = np.array([0.45, 0.25, 0.55]) + np.outer(t, [0.0, -0.1, 0.0])
    np.testing.assert_allclose(p_ball, expected_ball, atol=1e-12)
    with pytest.raises(UnknownObstacle, match="box"):
        view.animate(t, Q, obstacle_positions={"boxx": track_box})
    with pytest.raises(InvalidTrajectory, match=r"\(11, 3\)"):
        view.animate(t, Q, obstacle_positions={"box": track_box[:5]})


def test_static_html_is_self_contained(meshcat, panda, scene):
    html = animation_html(panda, _motion(panda), scene=scene, meshcat=meshcat)
    assert html.lstrip().lower().startswith("<!doctype html>")
    # no external scripts, stylesheets, images or imports: everything is inline
    assert not re.search(r"<script[^>]*\ssrc\s*=", html, re.I)
    assert not re.search(r"<link\b", html, re.I)
    markup = re.sub(r"<script\b.*?</script>", "", html, flags=re.S | re.I)
    assert not re.search(r"\b(src|href)\s*=", markup, re.I)
    assert "@import" not in html
    assert not re.search(r"""\.src\s*=\s*["'`]https?:""", html)
    assert not re.search(r"""(importScripts|import)\(\s*["'`]https?:""", html)
    # the scene and the viewer's wasm are replayed from data: URLs only
    fetched = re.findall(r"""fetch\(\s*["'`]([a-z]+):""", html)
    assert fetched and set(fetched) == {"data"}
    # the page does not connect to a server (the viewer's connect() is never called)
    assert "viewer.connect(" not in html
    # the only absolute URLs are inside the bundled viewer code (docs links, an optional WebXR
    # controller-model CDN used only in VR mode), never loaded by the page itself
    urls = set(re.findall(r"https?://[^\s\"'`<>)]+", html))
    assert all(not u.endswith((".js", ".css")) for u in urls), urls
    assert 2.0e6 < len(html.encode()) < 3.5e6


def test_save_animation_writes_the_page(meshcat, panda, tmp_path):
    path = save_animation(tmp_path / "out" / "motion.html", panda, _motion(panda), meshcat=meshcat)
    text = path.read_text(encoding="utf-8")
    assert path.parent.name == "out" and viz_html.animation(text) is not None
    # a configuration (no trajectory) exports a page without animation
    assert viz_html.animation(animation_html(panda, panda.home, meshcat=meshcat)) is None


def test_show_accepts_trajectory_objects(meshcat, panda):
    from pydrake.trajectories import PiecewisePolynomial

    t, Q = _motion(panda, duration=1.0, K=6)
    traj_like = type("Traj", (), {"t": t, "Q": Q})()
    for value in (traj_like, (t, Q), {"traj_t": t, "traj_q": Q}, {"t": t, "Q": Q},
                  PiecewisePolynomial.FirstOrderHold(t, Q.T)):
        view = show(panda, value, meshcat=meshcat, fps=10)
        frames, _ = viz_html.track(viz_html.animation(view.html()), view.link_paths()["panda_link1"], ".position")
        assert frames.size == 11
        assert meshcat.HasPath(f"{view.prefix}/paths/ee_path")


def test_trajectory_errors(meshcat, panda):
    t, Q = _motion(panda)
    view = View(panda, meshcat=meshcat)
    with pytest.raises(InvalidTrajectory, match="21 samples but Q has 20 rows") as info:
        view.animate(t, Q[:-1])
    assert info.value.name == "Q"
    with pytest.raises(InvalidConfiguration, match=r"\(N, 7\)"):
        view.animate(t, Q[:, :6])
    with pytest.raises(InvalidTrajectory, match="strictly increasing"):
        view.animate(t[::-1], Q)
    with pytest.raises(InvalidTrajectory, match="strictly increasing"):
        view.animate(np.zeros(21), Q)
    with pytest.raises(InvalidTrajectory, match=r"shape \(K,\)"):
        view.animate(t[:, None], Q)
    with pytest.raises(InvalidTrajectory, match="NaN"):
        view.animate(np.where(t > 1, np.nan, t), Q)
    with pytest.raises(InvalidArgument, match="fps"):
        view.animate(t, Q, fps=0)
    with pytest.raises(InvalidTrajectory, match=r"without times; pass \(t, Q\)"):
        show(panda, Q, meshcat=meshcat)
    with pytest.raises(InvalidConfiguration, match=r"shape \(7,\)"):
        show(panda, np.zeros(3), meshcat=meshcat)
    with pytest.raises(InvalidArgument, match="cannot show"):
        show(panda, "home", meshcat=meshcat)
    with pytest.raises(InvalidArgument, match="keys"):
        show(panda, {"times": t}, meshcat=meshcat)


# --- report pages: framed camera, no announced server -----------------------------------------


def _camera(html: str) -> tuple[np.ndarray, np.ndarray]:
    """World position of the page's camera and of its target (the last ones the page sets).

    Meshcat works in three.js coordinates (y up): a world point (x, y, z) is (x, z, -y).
    """
    position = target = None
    for c in viz_html.commands(html):
        if c["type"] == "set_property" and c["path"] == "/Cameras/default/rotated/<object>" \
                and c["property"] == "position":
            position = c["value"]
        elif c["type"] == "set_target":
            target = c["value"]
    assert position is not None and target is not None, "the page does not set the camera"
    world = [np.array([v[0], -v[2], v[1]], dtype=float) for v in (position, target)]
    return world[0], world[1]


def _angles_from_axis(camera, target, points) -> np.ndarray:
    axis = (target - camera) / np.linalg.norm(target - camera)
    rays = points - camera
    return np.degrees(np.arccos(np.clip(rays @ axis / np.linalg.norm(rays, axis=1), -1, 1)))


def _link_points(robot, Q) -> np.ndarray:
    return np.array([X[:3, 3] for q in Q for X in robot.link_poses(q).values()])


def test_planar_arm_pages_look_down_the_joint_axis_and_fill_the_view(planar5):
    t, Q = _motion(planar5)
    camera, target = _camera(animation_html(planar5, (t, Q)))
    view_dir = (camera - target) / np.linalg.norm(camera - target)
    assert view_dir[2] > 0.97  # from above, along the joints' common z axis (about 10 degrees off)
    angles = _angles_from_axis(camera, target, _link_points(planar5, Q))
    assert angles.max() < 37.5  # every link inside the 75-degree field of view
    assert angles.max() > 15.0  # and the arm fills a good part of it (not a speck 3 m away)


def test_spatial_robot_pages_are_framed_obliquely(panda):
    t, Q = _motion(panda)
    camera, target = _camera(animation_html(panda, (t, Q)))
    view_dir = (camera - target) / np.linalg.norm(camera - target)
    assert 0.2 < view_dir[2] < 0.8  # from above at an angle, not edge-on and not top-down
    angles = _angles_from_axis(camera, target, _link_points(panda, Q))
    assert 12.0 < angles.max() < 37.5


def test_joint_axis_normal(planar5, planar2r, panda):
    from drake_mh.viz.camera import joint_axis_normal

    np.testing.assert_allclose(joint_axis_normal(planar5), [0, 0, 1], atol=1e-12)
    n = joint_axis_normal(planar2r)
    assert n is not None and abs(abs(n[1]) - 1) < 1e-12
    assert joint_axis_normal(panda) is None


def test_recording_a_page_announces_no_server_and_closes_it(planar5, capsys, caplog, monkeypatch):
    import importlib
    import logging
    import socket

    show_module = importlib.import_module("drake_mh.viz.show")  # the attribute drake_mh.viz.show is the function
    view_module = importlib.import_module("drake_mh.viz.view")

    def no_shared_server(*args, **kwargs):
        raise AssertionError("a report page must not start or use the shared Meshcat server")

    monkeypatch.setattr(view_module, "get_meshcat", no_shared_server)
    ports = []
    original = show_module.private_meshcat

    def spy():
        manager = original()
        meshcat = manager.__enter__()
        ports.append(meshcat.port())
        return _Wrap(manager, meshcat)

    class _Wrap:
        def __init__(self, manager, meshcat):
            self.manager, self.meshcat = manager, meshcat

        def __enter__(self):
            meshcat, self.meshcat = self.meshcat, None
            return meshcat

        def __exit__(self, *exc):
            return self.manager.__exit__(*exc)

    monkeypatch.setattr(show_module, "private_meshcat", spy)
    caplog.set_level(logging.DEBUG)
    page = animation_html(planar5, _motion(planar5))
    assert viz_html.animation(page) is not None
    out = capsys.readouterr()
    assert "Meshcat" not in out.out and "Meshcat" not in out.err
    assert not [r for r in caplog.records if "listening" in r.getMessage()]
    assert len(ports) == 1 and not 7000 <= ports[0] <= 7999
    with socket.socket() as sock:  # closed at once: nothing listens on its port any more
        assert sock.connect_ex(("127.0.0.1", ports[0])) != 0
