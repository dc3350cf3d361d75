"""The structure of a point-cloud obstacle for the batched checks: a grid of distance bounds
and a bounding-box tree of its points, laid out as the kernels read them
(:mod:`drake_mh.scene.kernels.cloud`; docs/scenes.md, "Point clouds")."""

from __future__ import annotations

import numpy as np

GRID_CELLS = 131_072
"""About the most cells of a point cloud's grid (:mod:`.kernels.cloud`)."""

CELL_MIN = 0.02
"""[m] the smallest cell of a point cloud's grid."""


def table_builder():
    """``cloud_table(P (N, 3), radius, h_min, max_cells) -> (table, low, high)``: the compiled
    core's build where it is built (:func:`drake_mh.scene.compiled_check.compiled_core`), else
    the numba kernel :func:`drake_mh.scene.kernels.cloud_table.cloud_table`; both write the same
    table."""
    from drake_mh.scene.compiled_check import compiled_core

    core = compiled_core()
    if core is not None:
        return core.cloud_table
    from drake_mh.scene.kernels.cloud_table import cloud_table

    return cloud_table


def cloud_entry(cloud, R: np.ndarray, p: np.ndarray, kind: int) -> tuple:
    """A point cloud's kernel entry ``(kind, R_WO, p_WO, (N, radius), table)`` for
    :func:`drake_mh.scene.batch.obstacle_arrays`: the cloud's points ``(N, 3)`` posed by
    ``R (3, 3)``, ``p (3,)`` into W; the table holds its grid of distance bounds, its points in
    W and their tree (:mod:`drake_mh.scene.kernels.cloud`); ``p_WO`` is the centre of their
    bounding box, ``radius`` [m] its half diagonal + the points' radius (a ball about it that
    holds every point's ball)."""
    identity = np.array_equal(R, np.eye(3)) and not np.any(p)
    p_W = cloud.points if identity else np.ascontiguousarray(cloud.points @ R.T + p)
    table, low, high = table_builder()(p_W, float(cloud.radius), CELL_MIN, float(GRID_CELLS))
    centre = 0.5 * (low + high)
    radius = 0.5 * float(np.linalg.norm(high - low)) + cloud.radius  # the box's half diagonal
    return kind, np.eye(3), centre, (len(p_W), radius), table
