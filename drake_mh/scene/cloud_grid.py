"""The structure of a point-cloud obstacle for the batched checks: a grid of distance bounds
and an implicit k-d tree of its points, laid out as the kernels read them
(:mod:`drake_mh.scene.kernels.pieces`; docs/scenes.md, "Point clouds")."""

from __future__ import annotations

import numpy as np

GRID_CELLS = 65_536
"""Most cells of a point cloud's grid (:mod:`.kernels.pieces`); the cell is at least 2 cm."""


def tree_builder():
    """``kd_build(P (N, 3)) -> (order, axes, tree, boxes)``: the compiled core's k-d tree build
    where it is built (:func:`drake_mh.scene.compiled_check.compiled_core`), else the numba
    kernel :func:`drake_mh.scene.kernels.pieces.kd_build`; both build the same tree of the same
    points (the same selection step for step)."""
    from drake_mh.scene.compiled_check import compiled_core

    core = compiled_core()
    if core is not None:
        return core.kd_build
    from drake_mh.scene.kernels.pieces import kd_build

    return kd_build


def cloud_entry(cloud, R: np.ndarray, p: np.ndarray, kind: int) -> tuple:
    """A point cloud's kernel entry ``(kind, R_WO, p_WO, (N, radius), table)`` for
    :func:`drake_mh.scene.batch.obstacle_arrays`: the cloud's points ``(N, 3)`` posed by
    ``R (3, 3)``, ``p (3,)`` into W; the table holds its grid of distance bounds, then its points
    in W in k-d tree order, the split axes and the ranges' bounding boxes
    (:mod:`drake_mh.scene.kernels.pieces`); ``p_WO`` is the centre of
    their bounding box, ``radius`` [m] its half diagonal + the points' radius (a ball about it
    that holds every point's ball)."""
    from drake_mh.scene.kernels.pieces import distance_transform

    identity = np.array_equal(R, np.eye(3)) and not np.any(p)
    # writable either way: one compiled kd_build
    p_W = np.array(cloud.points) if identity else np.ascontiguousarray(cloud.points @ R.T + p)
    # one column at a time: numpy reduces an (N, 3) array along axis 0 about 20 times slower
    low = np.array([p_W[:, a].min() for a in range(3)])
    high = np.array([p_W[:, a].max() for a in range(3)])
    h = max(0.02, float(np.prod(high - low + 0.02)) ** (1.0 / 3.0) / GRID_CELLS ** (1.0 / 3.0))
    shape = np.floor((high - low) / h).astype(np.int64) + 1
    cells = np.minimum(((p_W - low) / h).astype(np.int64), shape - 1)  # >= 0: truncation is floor
    near = np.zeros(shape, bool)
    near[cells[:, 0], cells[:, 1], cells[:, 2]] = True
    for axis in range(3):  # dilated by one cell (the 3 x 3 x 3 box, one axis at a time)
        lo, hi = [slice(None)] * 3, [slice(None)] * 3
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        grown = near.copy()
        grown[tuple(lo)] |= near[tuple(hi)]
        grown[tuple(hi)] |= near[tuple(lo)]
        near = grown
    floor = h * distance_transform(near)  # cells of the dilated set: 0
    n_cells, N = floor.size, len(p_W)
    head = 3 + (n_cells + 2) // 3
    axis_rows = (N + 2) // 3
    table = np.empty((head + N + axis_rows + 2 * N, 3))
    table[0] = cloud.radius, h, head
    table[1], table[2] = low, shape
    values = table[3:head].reshape(-1)
    np.maximum(floor.reshape(-1) - 1e-9, 0.0, out=values[:n_cells])  # round-off of the cells
    values[n_cells:] = 0.0
    order, axes, tree, boxes = tree_builder()(p_W)
    table[head:head + N] = tree
    axis_values = table[head + N:head + N + axis_rows].reshape(-1)
    axis_values[:N] = axes
    axis_values[N:] = 0.0
    table[head + N + axis_rows:] = boxes.reshape(2 * N, 3)  # each range's box: lower, upper corner
    centre = 0.5 * (low + high)
    radius = 0.5 * float(np.linalg.norm(high - low)) + cloud.radius  # the box's half diagonal
    return kind, np.eye(3), centre, (N, radius), table
