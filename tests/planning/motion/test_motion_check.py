"""The compiled planners' motion check (drake_mh.planning.motion.check): its workspace holds the
longest motion within the joint limits, and a motion longer than the workspace gets the same
answer from arrays of its own."""

import numba
import numpy as np

import drake_mh
from drake_mh.planning.motion import (STAT_NAMES, certified_motion, clock_address, motion_capacity, scene_arguments,
                                      workspaces)
from drake_mh.planning.rrt_connect import planner
from drake_mh.scene import Box, Scene, Sphere
from drake_mh.scene.kernels import CheckContext, check_blocks, unpack

CLOCK = clock_address()

PANDA = drake_mh.load_robot("panda")


def shelf_scene() -> Scene:
    scene = Scene(PANDA, self_collision=True)
    scene.add("board", Box((0.4, 0.8, 0.02)), [0.55, 0.0, 0.45])
    scene.add("ball", Sphere(0.08), [0.4, 0.3, 0.7])
    return scene


def free_motions(scene, seed, samples, count, sigma, clearance=0.0):
    """``(QA, QB)``: ``count`` starts free at ``clearance`` among ``samples`` random
    configurations, each moved by a normal step of ``sigma`` rad within the limits."""
    rng = np.random.default_rng(seed)
    QA = PANDA.random_configurations(samples, rng=rng)
    QA = np.ascontiguousarray(QA[scene.collision_free(QA, clearance)][:count])
    return QA, np.ascontiguousarray(np.clip(QA + rng.normal(0.0, sigma, QA.shape), PANDA.lower, PANDA.upper))


def panda_reach():
    return np.ascontiguousarray(shelf_scene().collision_model.reach)


@numba.njit
def _answers(QA, QB, ints, floats, v_WO, reach, capacity, clock, probes=0, interior=0):
    arrays = unpack(ints, floats)
    # owned: no borrowing
    ws, mws = workspaces(arrays, QA.shape[1], reach.shape[0], 32, capacity, probes, interior, 0.0, 0.0)
    stats, buf = np.zeros(len(STAT_NAMES)), np.zeros(2, np.int64)
    out = np.empty(QA.shape[0], np.bool_)
    ctx = CheckContext(arrays, ws, mws)
    for i in range(QA.shape[0]):
        out[i] = certified_motion(QA[i], QB[i], ctx, (8, 32), v_WO, reach, 0.0, 0.0, 16.0, 0.02, 512, None, stats,
                                  clock, buf, False, interior > 0)
    return out, stats


def test_the_capacity_bounds_every_motion_within_the_limits():
    reach = panda_reach()
    span = PANDA.upper - PANDA.lower
    capacity = motion_capacity(span, reach, 16.0, 0.02)
    rng = np.random.default_rng(0)
    QA, QB = PANDA.random_configurations(500, rng=rng), PANDA.random_configurations(500, rng=rng)
    dq = np.abs(QB - QA)
    n = np.maximum(np.ceil(np.linalg.norm(dq, axis=1) * 16.0), np.ceil((dq @ reach.T).max(axis=1) / 0.04))
    assert np.all(n + 1 <= capacity) and capacity < 4096
    assert motion_capacity(np.full(7, np.inf), reach, 16.0, 0.02) == 4096


def test_a_motion_longer_than_the_workspace_gets_the_same_answer():
    scene = shelf_scene()
    QA, QB = free_motions(scene, 1, 300, 40, 0.5)
    ints, floats, v_WO, reach = scene_arguments(scene)[:4]
    big, stats_big = _answers(QA, QB, ints, floats, v_WO, reach, 4096, CLOCK)
    small, stats_small = _answers(QA, QB, ints, floats, v_WO, reach, 2, CLOCK)
    assert 0 < big.sum() < len(big)
    np.testing.assert_array_equal(big, small)
    np.testing.assert_array_equal(stats_big, stats_small)
    np.testing.assert_array_equal(big, planner.certify_motions(scene, QA, QB))


def test_probes_reject_colliding_motions_before_their_setup_and_change_no_answer():
    """The probe states only reject, and only motions that collide: with 0, 1, 4 or 8 probes
    the same motions are certified; the rejected ones that a probe stopped checked only the
    probes."""
    scene = shelf_scene()
    QA, QB = free_motions(scene, 5, 600, 150, 0.6)
    ints, floats, v_WO, reach = scene_arguments(scene)[:4]
    none, stats_none = _answers(QA, QB, ints, floats, v_WO, reach, 4096, CLOCK, 0)
    assert 10 <= none.sum() <= len(none) - 10
    assert stats_none[STAT_NAMES.index("rejected_by_probes")] == 0
    for probes in (1, 4, 8):
        ok, stats = _answers(QA, QB, ints, floats, v_WO, reach, 4096, CLOCK, probes)
        np.testing.assert_array_equal(ok, none)
        by_probes = stats[STAT_NAMES.index("rejected_by_probes")]
        assert 0 < by_probes <= stats[STAT_NAMES.index("rejected")] == stats_none[STAT_NAMES.index("rejected")]
    ends = scene.collision_free(QB)
    assert np.all(~ok[~ends])  # a motion whose end collides is never certified
    # the interior probes (for motions whose ends are free) neither: same answers, some rejected by them
    inside = ends & scene.collision_free(QA)
    ref, _ = _answers(QA[inside], QB[inside], ints, floats, v_WO, reach, 4096, CLOCK, 0)
    for interior in (1, 4, 8):
        ok, stats = _answers(QA[inside], QB[inside], ints, floats, v_WO, reach, 4096, CLOCK, 4, interior)
        np.testing.assert_array_equal(ok, ref)
        assert stats[STAT_NAMES.index("states")] > 0 and stats[STAT_NAMES.index("rejected_by_probes")] > 0


def test_the_refinement_of_the_rows_that_came_near_never_certifies_a_collision():
    """Motions that come within their margins are refined on the rows that did (the others kept
    theirs at every state): the certified ones keep the clearance under the scene's own
    certificate and dense exact sampling, and some are rejected only by the refinement."""
    scene = shelf_scene()
    QA, QB = free_motions(scene, 7, 600, 200, 0.3)
    ints, floats, v_WO, reach = scene_arguments(scene)[:4]
    refined, outcome = [], []
    for a, b in zip(QA, QB):
        ok, stats = _answers(a[None], b[None], ints, floats, v_WO, reach, 4096, CLOCK)
        refined.append(stats[STAT_NAMES.index("refined")] > 0)
        outcome.append(ok[0])
    refined, outcome = np.array(refined), np.array(outcome)
    assert np.sum(refined & outcome) >= 3 and np.sum(refined & ~outcome) >= 1
    sure = refined & outcome
    assert np.all(scene.certify_segments(QA[sure], QB[sure], 0.0).status != 0)  # never found blocked
    t = np.linspace(0.0, 1.0, 200)[:, None]
    for a, b in zip(QA[sure][:10], QB[sure][:10]):
        assert scene.exact_min_distance(a + t * (b - a)).min() >= -1e-9


@numba.njit
def _taus(QA, QB, t, lam, ints, floats, margin_scale, local):
    """``(kept, tau)`` of ``check_blocks`` for the states ``QA + t (QB - QA)``, rows at the
    clearance 0 plus ``margin_scale · Λ_c`` (the motion's ``Λ_c`` in ``lam (M, C)``); with
    ``local`` the links' bound from the state's joint axes and the motion's speeds."""
    arrays = unpack(ints, floats)
    G = arrays[6].shape[0]
    C = lam.shape[1]
    ws, _ = workspaces(arrays, QA.shape[1], C, 1, 4, 0, 0, 0.0, 0.0)
    ctx = CheckContext(arrays, ws, None)
    kept, tau = np.empty(QA.shape[0], np.bool_), np.empty(QA.shape[0])
    for i in range(QA.shape[0]):
        QT = np.empty((QA.shape[1], 1))
        QT[:, 0] = QA[i] + t[i] * (QB[i] - QA[i])
        margins = (margin_scale * lam[i, :G] + 1e-12, margin_scale * lam[i, G:] + 1e-12)
        plain = (np.full(G, 1e-12), np.full(C - G, 1e-12))
        inv = 1.0 / lam[i]
        k, tv = np.empty(1, np.bool_), np.empty(1)
        speeds = np.abs(QB[i] - QA[i]) if local else np.zeros(QA.shape[1])
        check_blocks(QT, 1, (1, 1), margins, plain, inv, speeds, ctx, k, tv)
        kept[i], tau[i] = k[0], tv[0]
    return kept, tau


def test_a_states_tau_certifies_the_motion_around_it():
    """``check_states``' ``tau``: a state within its margins certifies ``[t - τ, t + τ]`` of the
    motion (dense exact sampling finds no collision there), and one that keeps them reports none.
    Without the motion's speeds ``tau`` is the rows' static bound (a state asked for its margin
    keeps it); with them a link's local bound is at least that, and certifies as much."""
    scene = shelf_scene()
    QA, QB = free_motions(scene, 3, 800, 300, 0.4, clearance=0.01)
    ints, floats, v_WO, reach = scene_arguments(scene)[:4]
    lam = np.ascontiguousarray(np.abs(QB - QA) @ reach.T)
    t = np.zeros(len(QA))
    kept, tau = _taus(QA, QB, t, lam, ints, floats, 0.05, False)
    kept_local, tau_local = _taus(QA, QB, t, lam, ints, floats, 0.05, True)
    assert np.array_equal(kept, kept_local) and np.all(tau_local[~kept] >= tau[~kept])
    assert np.all(np.isinf(tau[kept])) and np.all(np.isfinite(tau[~kept]))
    near = np.flatnonzero(~kept & (tau > 0.0))
    assert len(near) >= 5
    tighter = near[tau_local[near] > 1.01 * tau[near]]  # where the local bound is the larger
    assert len(tighter) >= 3
    for i in list(near[:5]) + list(tighter[:5]):
        s = np.linspace(0.0, min(tau_local[i], 1.0), 60)[:, None]
        assert scene.exact_min_distance(QA[i] + s * (QB[i] - QA[i])).min() >= -1e-9
    for i in near[:5]:
        # and the static tau is the row values' bound: a state asked for tau's margin keeps it
        k2, _ = _taus(QA[i:i + 1], QB[i:i + 1], t[:1], lam[i:i + 1], ints, floats, 0.999 * tau[i], False)
        assert k2[0]
