"""Certified motion between the follower's points: detours where the straight line is not certified,
an honest halt where no detour is found."""

import numpy as np
import pytest

from drake_mh.reactive.follower import DetourConfig, FollowerConfig, RegeneratingFollower, certify_chains, find_detour

SWING = 2.0   # [rad] on joint 1: a branch-switch-sized step


@pytest.fixture(scope="module")
def robot():
    import drake_mh

    return drake_mh.load_robot("seed000_6dof")


def swing_scene(robot):
    """The arm stretched out, swinging 2 rad about joint 1; a 0.1 m ball on the middle of the swing
    (on link4's origin at the half-way configuration): both ends clear by ~0.5 m, the straight
    line through the ball."""
    from drake_mh.scene import Scene, Sphere

    q_a = robot.home.copy()
    q_b = q_a.copy()
    q_b[0] += SWING
    scene = Scene(robot)
    scene.add("ball", Sphere(0.1), robot.link_poses(0.5 * (q_a + q_b))["link4"][:3, 3])
    return scene, q_a, q_b


def dense(chain, per_piece=50):
    """``per_piece`` configurations on every straight piece of ``chain`` (ends included)."""
    s = np.linspace(0.0, 1.0, per_piece)[:, None]
    return np.vstack([a + s * (b - a) for a, b in zip(chain[:-1], chain[1:])])


def test_detour_around_a_blocked_straight_line(robot):
    scene, q_a, q_b = swing_scene(robot)
    assert scene.exact_min_distance(np.vstack([q_a, q_b])).min() > 0.4
    assert not scene.segment_free(q_a, q_b)                          # the straight line hits the ball
    assert scene.exact_min_distance(dense(np.vstack([q_a, q_b]))).min() < 0
    d = find_detour(scene, q_a, q_b, seed=0)
    assert d.found and 1 <= len(d.vias) <= 2 and d.min_clearance >= 0
    assert d.extra_length > 0 and d.candidates >= d.free > 0 and d.evaluations > 0 and d.time > 0
    chain = np.vstack([q_a, d.vias, q_b])
    assert certify_chains(scene, [chain]).all_certified
    assert scene.exact_min_distance(dense(chain)).min() >= 0          # Drake agrees, 50 per piece
    again = find_detour(scene, q_a, q_b, seed=0)
    assert np.array_equal(again.vias, d.vias)                         # same seed, same detour


def test_no_detour_from_a_configuration_inside_the_obstacle(robot):
    scene, q_a, q_b = swing_scene(robot)
    scene.move("ball", robot.link_poses(q_a)["link4"][:3, 3])
    d = find_detour(scene, q_a, q_b, seed=0)
    assert not d.found and len(d.vias) == 0 and "start configuration" in d.reason and np.isnan(d.extra_length)


def follower_over_the_swing(robot, config=FollowerConfig()):
    """Five configurations with the swing between points 2 and 3; the points are their tool positions."""
    scene, q_a, q_b = swing_scene(robot)
    Q = np.vstack([q_a - [0.2, 0, 0, 0, 0, 0], q_a - [0.1, 0, 0, 0, 0, 0], q_a, q_b, q_b + [0.1, 0, 0, 0, 0, 0]])
    points = np.array([robot.fk(q)[:3, 3] for q in Q])
    times = np.arange(5) * 0.5
    return RegeneratingFollower(robot, scene, points, Q, config, seed=3, times=times), scene


def test_follower_detours_instead_of_executing_the_straight_line(robot):
    follower, scene = follower_over_the_swing(robot)
    event = follower.react()                                  # nothing collides at the points ...
    assert event.colliding.size == 0 and event.regenerated.size == 0
    assert [d.segment for d in event.detours] == [2] and event.detours[0].found    # ... but between 2 and 3
    assert event.motion_certified and event.motion_min_clearance >= 0 and event.blocked.size == 0
    assert "detour" in event.summary()
    record = follower.detours[0]
    assert record.when == 0 and record.vias >= 1 and record.extra_length > 0 and record.time > 0
    assert record.tool_deviation > 0 and record.straight_tool_deviation > 0 and "blocked" in record.reason
    follower.advance(4)
    assert follower.done and follower.halted is None
    chains = follower.executed_chains()
    assert len(chains[2]) >= 3                                 # the detour was executed, not the line
    assert np.all(follower.segment_lower >= 0)                 # each motion certified when executed
    assert certify_chains(scene, chains).all_certified
    assert scene.exact_min_distance(np.vstack([dense(c) for c in chains])).min() >= 0
    summary = follower.detour_summary()
    assert summary["detours_found"] == 1 and summary["detours_executed"] == 1 and summary["detour_vias"] >= 1


def test_follower_halts_where_no_certified_motion_is_found(robot):
    tiny = DetourConfig(candidates=4, spreads=(1e-4,), max_vias=1)  # a search that cannot get around
    follower, scene = follower_over_the_swing(robot, FollowerConfig(detour=tiny))
    event = follower.react()
    assert event.blocked.tolist() == [2] and not event.motion_certified and np.isnan(event.motion_min_clearance)
    assert not follower.detours[0].found and "no certified connection" in follower.detours[0].reason
    follower.advance(4)
    assert follower.index == 2 and not follower.done              # the arm stopped before the line
    assert np.all(np.isnan(follower.executed[3:]))                 # never executed
    assert follower.halted.startswith("halted at point 2") and follower.halts[-1][0] == 2
    assert "NO certified motion" in event.summary()
    follower.advance()                                             # still no motion: stays
    assert follower.index == 2 and len(follower.halts) == 2
    scene.move("ball", [2.0, 2.0, 2.0])                            # the obstacle leaves: it goes on
    follower.advance(2)
    assert follower.done and follower.halted is None


def test_without_detours_the_line_blocks_the_arm(robot):
    follower, _ = follower_over_the_swing(robot, FollowerConfig(detour=None))
    follower.react()
    assert 2 in follower.blocked and "detours are off" in follower.blocked[2] and not follower.detours
    follower.advance(4)
    assert follower.index == 2 and follower.halted


def test_moving_obstacle_is_certified_with_the_path_times(robot):
    # the ball starts far from the swing and moves onto it during the motion from point 2 to 3
    follower, scene = follower_over_the_swing(robot)
    middle = scene.obstacles["ball"].position
    start = middle + [0.0, 0.0, 1.25]
    scene.move("ball", start, velocity=[0.0, 0.0, -1.0])        # at the middle at t = 1.25 s: mid-swing
    assert follower.certify_remaining() is not None
    static = certify_chains(scene, [follower.chain(2)])           # where it stands now: clear
    assert static.all_certified
    follower.react()                                               # with the times: the line is hit
    assert [d.segment for d in follower.detours] == [2] and follower.detours[0].found
    for _ in range(4):                                             # the arm moves, time goes on
        follower.advance()
        scene.step(0.5)
    assert follower.done
    # Drake at 50 configurations per piece, the ball where it is at each one's time
    from drake_mh.reactive.follower.detour import chain_durations

    worst = np.inf
    for k, chain in enumerate(follower.executed_chains()):
        t0 = 0.5 * k
        for (a, b), dt in zip(zip(chain[:-1], chain[1:]), chain_durations(chain, 0.5)):
            for s_ in np.linspace(0.0, 1.0, 50):
                scene.move("ball", start + np.array([0.0, 0.0, -1.0]) * (t0 + s_ * dt))
                worst = min(worst, scene.min_distance(a + s_ * (b - a)))
            t0 += dt
    assert worst >= 0


def test_config_validation():
    from drake_mh.errors import InvalidArgument

    with pytest.raises(InvalidArgument, match="motion_clearance"):
        FollowerConfig(motion_clearance=-1.0)
    with pytest.raises(InvalidArgument, match="detour"):
        FollowerConfig(detour="yes")
    with pytest.raises(InvalidArgument, match="spreads"):
        DetourConfig(spreads=())
    with pytest.raises(InvalidArgument, match="max_vias"):
        DetourConfig(max_vias=3)
