"""Link pairs that are always close: left out of a scene's self-collision checks by default.

The sphere model covers each link with spheres a little larger than its geometry
(:mod:`drake_mh.geometry.spheres`), so links that sit next to each other by construction — a joint's two
sides, a wrist whose housings nest — can be touching, or a millimetre apart, under the model in
*every* configuration. The capsule Panda's ``panda_link1``–``panda_link3`` spheres are at most
0.9 mm apart over the whole joint range; the UR5's ``base_link``–``upper_arm_link`` at most
4.1 mm. Checking such a pair only rejects every configuration for the model's own sake (with
any ``self_clearance`` above that distance, every motion), so it is left out.

The rule (structural, not a tuning of "how often"): a pair is **always close** when the joints
between its links cannot take its sphere models more than :data:`SEPARATION` (1 cm) apart: its
largest sphere-model clearance over :data:`SAMPLES` (1,000) configurations drawn uniformly
within the joint limits (seed 0, so deterministic) is below 1 cm. On the bundled and
example-robot-data arms the pairs fall in two well-separated groups: at most 7.5 mm apart
(always close) or at least 5 cm apart somewhere (checked). This is MoveIt Setup Assistant's
"adjacent" / "always in collision" classification of its self-collision matrix (sampled the
same way), stated as a distance.

:class:`drake_mh.scene.Scene` applies it with ``self_collision=True`` unless asked to keep them
(``keep_always_close=True``), lists the pairs it left out (``Scene.always_close_pairs``) and logs
them.
"""

from __future__ import annotations

import logging

import numpy as np

__all__ = ["SEPARATION", "SAMPLES", "always_close_pairs"]

log = logging.getLogger(__name__)

SEPARATION = 0.01
"""[m] a pair whose sphere models never get further apart than this is always close."""
SAMPLES = 1000
"""configurations drawn uniformly within the joint limits (seed 0) to measure the separation."""

_CACHE: dict = {}  # (id(robot), id(sphere model), pairs) -> (robot, model, always-close pairs)


def always_close_pairs(robot, sphere_model, pairs) -> tuple:
    """The pairs of ``pairs`` whose sphere models are never more than :data:`SEPARATION` apart.

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        sphere_model: its :class:`drake_mh.geometry.spheres.SphereModel`.
        pairs: candidate ``[(link_a, link_b)]`` (the self pairs Drake's filter keeps).

    Returns:
        ``((link_a, link_b), ...)`` sorted, names as in ``pairs``; computed once per robot,
        sphere model and pair set in a process.
    """
    pairs = tuple(sorted(tuple(sorted(p)) for p in pairs))
    key = (id(robot), id(sphere_model), pairs)
    if key not in _CACHE:
        _CACHE[key] = (robot, sphere_model, _measure(robot, sphere_model, pairs))
    return _CACHE[key][2]


def largest_separation(robot, sphere_model, pairs) -> dict:
    """``{(link_a, link_b): largest sphere-model clearance [m]}`` over the :data:`SAMPLES`
    configurations (what :func:`always_close_pairs` compares with :data:`SEPARATION`)."""
    from drake_mh.scene.batch import CollisionModel, obstacle_arrays

    if not pairs:
        return {}
    model = CollisionModel(robot, sphere_model, pairs, pair_tables=False)  # measures, then never again
    Q = robot.random_configurations(SAMPLES, np.random.default_rng(0))
    C = model.clearances(robot.batch._transposed(Q), obstacle_arrays(()), per_obstacle=False)
    largest = C[:, model.num_links:].max(axis=0)
    return {pair: float(d) for pair, d in zip(model.self_pairs, largest)}


def _measure(robot, sphere_model, pairs) -> tuple:
    separation = largest_separation(robot, sphere_model, pairs)
    close = tuple(sorted(p for p, d in separation.items() if d < SEPARATION))
    if close:
        log.info("%s: %d self-collision link pair(s) left out, never more than %.0f mm apart under the "
                 "sphere model (%s); keep them with Scene(..., keep_always_close=True)", robot.name, len(close),
                 SEPARATION * 1e3, ", ".join(f"{a}-{b} <= {separation[(a, b)] * 1e3:.1f} mm" for a, b in close))
    return close
