"""Certified floors of self-collision pairs that one or two joints move: tables over those joints.

Neighbouring links of meshed arms are close in every configuration, so their bounding spheres
always overlap and every query compares their sphere pairs: on the Panda with its hand
(778 spheres at 1 cm) link 6 against the hand, link 5 against the hand and link 5 against link 7
cost 1,000-2,100 sphere-pair products per configuration after pruning, most of a planning
query's time on the MotionBenchMaker problems, while only a few dozen of those pairs are within
2 cm. Their relative pose depends on one joint (``q7`` for link 6 and the hand) or two
(``q6, q7``), so their clearance is a function of one or two variables that can be tabulated
once per robot.

A table covers the joints' limits with a grid of cells. Each cell holds a **lower bound of the
pair's sphere-model clearance over the whole cell**: the clearance at the cell's centre, with
every sphere's radius grown by how far the sphere can move within the cell,
``Σ_j h_j ρ_sj`` (``h_j`` the half width of the cell in joint ``j``, ``ρ_sj`` the bound on the
sphere's distance from joint ``j``'s axis of :attr:`drake_mh.scene.batch.CollisionModel.reach`;
1 for a prismatic joint). Only the joints that move one link relative to the other change the
pair's distance (a joint carrying both links moves them rigidly), and each of them moves a
sphere, in the frame of the links' common ancestor, about an axis fixed there while the other
joints stay put: so no configuration of the cell brings two spheres closer than the grown
spheres at the centre are. The kernels read the floor of a configuration's cell
(:func:`drake_mh.scene.kernels.pairs.pair_floor`) and skip the sphere pairs where it already
shows the pair clear; answers are unchanged (where the floor is not enough, the sphere pairs are
compared as before).

Tables are built for the pairs whose sphere product is large (:data:`MIN_PRODUCT`) and whose one
or two joints have finite limits; the others get none. A table is computed once per robot,
sphere model and pair in a process, and cached on disk (:func:`drake_mh._support.cache.cache_dir`
``("pair_tables")``) by a content hash of everything it depends on.
"""

from __future__ import annotations

import io
import logging
import zipfile

import numba
import numpy as np

__all__ = ["CELLS_1D", "CELLS_2D", "MIN_PRODUCT", "pair_tables", "empty_tables"]

log = logging.getLogger(__name__)

CELLS_1D = 1024
"""Cells of a one-joint table (the Panda's ``q7``: 5.8 mrad wide, at most 0.9 mm of growth for
the hand's spheres)."""
CELLS_2D = 128
"""Cells per joint of a two-joint table (128 x 128, 128 KiB: small enough to stay in cache)."""
MIN_PRODUCT = 256
"""Pairs with fewer sphere pairs than this get no table (comparing them costs less than the
table's memory traffic)."""
GRID_COLUMNS = 5
"""Columns of ``t_grid``: ``[lower1, 1/width1, lower2, 1/width2, lowest floor]`` (:func:`pair_tables`)."""
LOWEST = 4
"""The column of ``t_grid`` holding a table's smallest floor (``-inf`` for a pair without a table)."""
VERSION = "pair-table-1"
"""Bump when the construction changes (part of the disk cache key)."""

_CACHE: dict = {}  # (id(model), pair) -> (model, (joints, lower, inverse width, cells, floors))


def empty_tables(num_pairs: int = 0) -> tuple:
    """``(t_meta (P, 6), t_grid (P, 5), t_vals (0,))`` of ``P`` pairs without tables (see
    :func:`pair_tables`)."""
    grid = np.zeros((num_pairs, GRID_COLUMNS))
    grid[:, LOWEST] = -np.inf
    return np.zeros((num_pairs, 6), np.int64), grid, np.zeros(0)


def pair_tables(model) -> tuple:
    """The floor tables of a :class:`drake_mh.scene.batch.CollisionModel`'s checked pairs.

    Returns:
        ``(t_meta (P, 6) int64, t_grid (P, 5), t_vals (T,))``: per pair ``[dims, j1, j2, n1, n2,
        offset]`` (``dims`` 0: no table; joints ``j1, j2`` of ``q``, cells per joint, start of the
        pair's row-major floors in ``t_vals``) and ``[lower1, 1/width1, lower2, 1/width2,
        lowest]`` (``lowest``: the smallest floor of the table, a lower bound of the pair's
        clearance in every configuration within its joints' limits; ``-inf`` without a table).
    """
    pair_a, pair_b = model.pair_index
    P = len(pair_a)
    meta, grid, values = np.zeros((P, 6), np.int64), np.zeros((P, GRID_COLUMNS)), []
    grid[:, LOWEST] = -np.inf
    offset = 0
    for i, (ga, gb) in enumerate(zip(pair_a, pair_b)):
        table = _table(model, int(ga), int(gb))
        if table is None:
            continue
        joints, lower, inverse_width, cells, floors = table
        meta[i] = (len(joints), joints[0], joints[-1], cells[0], cells[-1], offset)
        grid[i] = (lower[0], inverse_width[0], lower[-1], inverse_width[-1], floors.min())
        values.append(floors.ravel())
        offset += floors.size
    t_vals = np.ascontiguousarray(np.concatenate(values)) if values else np.zeros(0)
    return meta, grid, t_vals


def _relative_joints(model, ga: int, gb: int) -> list:
    """The joints (indices of ``q``) that move link ``gb`` relative to link ``ga``."""
    chain = model.robot.batch.chain
    g_anchor = model.model_arrays[0]
    F = len(chain.parent)

    def path(anchor):
        return chain.ancestors[anchor] if anchor >= 0 else np.zeros(F, bool)

    moving = path(g_anchor[ga]) ^ path(g_anchor[gb])
    return sorted({int(j) for j in chain.qidx[np.flatnonzero(moving)]})


def _table(model, ga: int, gb: int):
    """``(joints, lower, 1/width, cells, floors)`` of pair ``(ga, gb)``, or None (no table)."""
    start = model.model_arrays[3]
    sa, sb = np.arange(start[ga], start[ga + 1]), np.arange(start[gb], start[gb + 1])
    if len(sa) * len(sb) < MIN_PRODUCT:
        return None
    joints = _relative_joints(model, ga, gb)
    robot = model.robot
    if len(joints) not in (1, 2):
        return None
    lower, upper = robot.lower[joints].astype(float), robot.upper[joints].astype(float)
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper)) and np.all(upper > lower)):
        return None
    key = (id(model.sphere_model), id(robot), model.link_names[ga], model.link_names[gb])
    if key not in _CACHE:
        cells = [CELLS_1D] if len(joints) == 1 else [CELLS_2D, CELLS_2D]
        _CACHE[key] = (model.sphere_model, robot, _cached(model, sa, sb, joints, lower, upper, cells))
    return _CACHE[key][2]


def _cached(model, sa, sb, joints, lower, upper, cells):
    """:func:`_build`, cached on disk by a content hash of its inputs."""
    from drake_mh._support.cache import atomic_write_bytes, cache_dir, content_hash

    chain = model.robot.batch.chain
    _, _, _, _, s_offset, s_radius = model.model_arrays
    parts = [VERSION, repr((joints, cells)), lower.tobytes(), upper.tobytes(), chain.parent.tobytes(),
             np.ascontiguousarray(chain.K).tobytes(), chain.kind.tobytes(), chain.qidx.tobytes(),
             model.robot.lower.astype(float).tobytes(), model.robot.upper.astype(float).tobytes()]
    for s in (sa, sb):
        parts += [model.sphere_anchor[s].tobytes(), np.ascontiguousarray(s_offset[s]).tobytes(),
                  np.ascontiguousarray(s_radius[s]).tobytes()]
    path = cache_dir("pair_tables") / f"{content_hash(*parts)}.npy"
    try:
        floors = np.load(path)
        if floors.shape == tuple(cells):
            return _entry(joints, lower, upper, cells, floors)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile):
        pass  # missing or unreadable: recompute (and overwrite)
    floors = _build(model, sa, sb, joints, lower, upper, cells)
    buffer = io.BytesIO()
    np.save(buffer, floors)
    try:
        atomic_write_bytes(path, buffer.getvalue())
    except OSError as exc:  # a read-only cache only costs time
        log.warning("cannot write the pair-table cache %s: %s", path, exc)
    return _entry(joints, lower, upper, cells, floors)


def _entry(joints, lower, upper, cells, floors):
    width = (upper - lower) / np.asarray(cells)
    return (np.asarray(joints, np.int64), lower, 1.0 / width, np.asarray(cells, np.int64), floors)


def _build(model, sa, sb, joints, lower, upper, cells) -> np.ndarray:
    """The floors ``cells``-shaped: per cell, the pair's clearance at its centre with every
    sphere grown by its motion within the cell (module docstring), minus 1e-9 m for round-off."""
    robot = model.robot
    _, _, _, _, s_offset, s_radius = model.model_arrays
    cells = np.asarray(cells)
    width = (upper - lower) / cells
    half = 0.5 * width * (1.0 + 1e-9)  # a configuration on a cell's edge may be read into either cell
    rows = model.sphere_reach[:, joints]  # (S, len(joints)) [m per rad] or 1 (prismatic)
    grown = s_radius + rows @ half
    axes = [lower[j] + (np.arange(cells[j]) + 0.5) * width[j] for j in range(len(joints))]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(joints))
    q0 = np.clip(np.zeros(robot.nq), robot.lower, robot.upper)
    floors = np.empty(len(centres))
    anchors = model.sphere_anchor
    for c0 in range(0, len(centres), 4096):
        Q = np.tile(q0, (min(4096, len(centres) - c0), 1))
        Q[:, joints] = centres[c0:c0 + 4096]
        A = robot.batch.points(Q, anchors[sa], s_offset[sa])
        B = robot.batch.points(Q, anchors[sb], s_offset[sb])
        _grown_minimum(A, B, grown[sa], grown[sb], floors[c0:c0 + len(Q)])
    return (floors - 1e-9).reshape(tuple(cells))


@numba.njit(cache=True)
def _grown_minimum(A, B, ra, rb, out):
    """``out[m]`` = min over ``i, j`` of ``|A[m, i] - B[m, j]| - ra[i] - rb[j]``."""
    for m in range(A.shape[0]):
        best = np.inf
        for i in range(A.shape[1]):
            x, y, z = A[m, i, 0], A[m, i, 1], A[m, i, 2]
            for j in range(B.shape[1]):
                dx, dy, dz = x - B[m, j, 0], y - B[m, j, 1], z - B[m, j, 2]
                d2 = dx * dx + dy * dy + dz * dz
                lim = best + ra[i] + rb[j]
                if lim > 0.0 and d2 >= lim * lim:
                    continue
                best = min(best, np.sqrt(d2) - ra[i] - rb[j])
        out[m] = best
