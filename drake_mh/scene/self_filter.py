"""The robot's self-collision filter in a :class:`~drake_mh.scene.Scene`'s own context: which
robot geometry pairs Drake's distance query keeps.

Without ``self_collision`` every robot pair is filtered out. With it, Drake's own filter
(adjacent links) stays, the user's ``ignore_link_pairs`` are added, and so are the link pairs
that are always close (:mod:`drake_mh.scene.always_close`, unless kept) and the capsule-capsule
pairs, which the scene computes in closed form (Drake's value was up to 1.1e-5 m optimistic and
its capsule-capsule query can hang on collinear axes).
"""

from __future__ import annotations


def link_geometries(robot, robot_ids: list, link: str) -> list:
    """The proximity geometry ids of ``robot_ids`` on the link named ``link``.

    Raises:
        FrameNotFound: no such link (the message lists the robot's links).
    """
    from drake_mh.errors import FrameNotFound

    if not robot.plant.HasBodyNamed(link):
        raise FrameNotFound(link, robot.link_names(), what="link")
    body = robot.plant.GetBodyByName(link)
    frame_id = robot.plant.GetBodyFrameIdOrThrow(body.index())
    inspector = robot.scene_graph.model_inspector()
    return [g for g in robot_ids if inspector.GetFrameId(g) == frame_id]


def unfiltered_link_pairs(robot, robot_ids: list, inspector) -> list:
    """``[(link_a, link_b)]`` (sorted names) with a geometry pair that ``inspector``'s collision
    filter keeps."""
    plant = robot.plant
    link = {g: plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name() for g in robot_ids}
    pairs = set()
    for i, a in enumerate(robot_ids):
        for b in robot_ids[i + 1:]:
            if link[a] != link[b] and not inspector.CollisionFiltered(a, b):
                pairs.add(tuple(sorted((link[a], link[b]))))
    return sorted(pairs)


def filter_self_pairs(robot, sg_context, robot_ids: list, self_collision: bool, ignore_link_pairs,
                      keep_always_close: bool, sphere_model, capsule_links) -> tuple[list, tuple, list]:
    """Apply the scene's self-collision filter to ``sg_context`` (the scene's scene-graph context).

    Args:
        robot_ids: the robot's proximity geometry ids.
        ignore_link_pairs: ``[(link_a, link_b)]`` left out of self-collision.
        sphere_model, capsule_links: callables giving the scene's sphere model and its
            ``{geometry id: Capsule}`` (asked only with ``self_collision``).

    Returns:
        ``(self_link_pairs, always_close, self_capsule_pairs)``: the link pairs still checked,
        those left out as always close, and the capsule geometry pairs computed in closed form.

    Raises:
        FrameNotFound: a link of ``ignore_link_pairs`` that the robot lacks.
    """
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

    manager = robot.scene_graph.collision_filter_manager(sg_context)
    if not self_collision:
        manager.Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(robot_ids)))
        return [], (), []

    def exclude(a, b):
        ga, gb = (link_geometries(robot, robot_ids, link) for link in (a, b))
        manager.Apply(CollisionFilterDeclaration().ExcludeBetween(GeometrySet(ga), GeometrySet(gb)))

    for a, b in ignore_link_pairs:
        exclude(a, b)
    query_inspector = robot.scene_graph.get_query_output_port().Eval(sg_context).inspector()
    link_pairs = unfiltered_link_pairs(robot, robot_ids, query_inspector)
    always_close: tuple = ()
    if not keep_always_close and robot_ids:
        from drake_mh.scene.always_close import always_close_pairs

        always_close = always_close_pairs(robot, sphere_model(), link_pairs)
        for a, b in always_close:
            exclude(a, b)
        dropped = {frozenset(pair) for pair in always_close}
        link_pairs = [p for p in link_pairs if frozenset(p) not in dropped]
        query_inspector = robot.scene_graph.get_query_output_port().Eval(sg_context).inspector()
    capsules = sorted(capsule_links(), key=lambda g: g.get_value())
    capsule_pairs = [(a, b) for i, a in enumerate(capsules) for b in capsules[i + 1:]
                     if not query_inspector.CollisionFiltered(a, b)]
    for a, b in capsule_pairs:
        manager.Apply(CollisionFilterDeclaration().ExcludeBetween(GeometrySet([a]), GeometrySet([b])))
    return link_pairs, always_close, capsule_pairs
