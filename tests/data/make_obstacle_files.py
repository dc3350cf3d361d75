"""Writes the small obstacle files of tests/data/ (meshes and point clouds); run once and commit them.

    python tests/data/make_obstacle_files.py

Meshes (metres): ``bin.obj`` (an open-top bin: 0.30 x 0.20 x 0.15 with 0.02 walls, not convex),
``bracket.obj`` (an L-shaped bracket, extruded: not convex), ``bracket_mm.stl`` (the bracket in
millimetres), ``cube.stl`` (a 0.1 cube: convex), ``wedge.ply`` (a triangular prism: convex),
``flat.obj`` (one square, no volume: refused), ``empty.obj`` (no face: refused).
Clouds: 600 points on the faces of a 0.2 x 0.1 x 0.1 box, as ``cloud.ply``, ``cloud.xyz``,
``cloud.npy``, ``cloud_ascii.pcd`` (with an rgb field and one NaN row) and ``cloud_binary.pcd``
(float32 x y z then an intensity field).
"""

from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent


def _write(mesh: trimesh.Trimesh, name: str) -> None:
    trimesh.repair.fix_normals(mesh)
    assert mesh.is_watertight, name
    mesh.export(HERE / name)


def bin_mesh(size=(0.30, 0.20, 0.15), wall=0.02) -> trimesh.Trimesh:
    x, y, z = (0.5 * s for s in size)
    xi, yi, zf = x - wall, y - wall, -z + wall
    v = np.array([[-x, -y, -z], [x, -y, -z], [x, y, -z], [-x, y, -z],       # 0-3 outer bottom
                  [-x, -y, z], [x, -y, z], [x, y, z], [-x, y, z],           # 4-7 outer top
                  [-xi, -yi, z], [xi, -yi, z], [xi, yi, z], [-xi, yi, z],   # 8-11 inner top
                  [-xi, -yi, zf], [xi, -yi, zf], [xi, yi, zf], [-xi, yi, zf]])  # 12-15 inner floor
    quads = [(0, 3, 2, 1), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7),  # outer
             (4, 5, 9, 8), (5, 6, 10, 9), (6, 7, 11, 10), (7, 4, 8, 11),           # rim
             (8, 9, 13, 12), (9, 10, 14, 13), (10, 11, 15, 14), (11, 8, 12, 15),   # inner walls
             (12, 13, 14, 15)]                                                     # inner floor
    faces = [(a, b, c) for a, b, c, d in quads] + [(a, c, d) for a, b, c, d in quads]
    return trimesh.Trimesh(v, faces, process=True)


def bracket_mesh(a=0.20, b=0.15, t=0.03, depth=0.08) -> trimesh.Trimesh:
    poly = np.array([[0, 0], [a, 0], [a, t], [t, t], [t, b], [0, b]], dtype=float)
    n = len(poly)
    v = np.vstack([np.c_[poly, np.zeros(n)], np.c_[poly, np.full(n, depth)]])
    fan = [(3, 4, 5), (3, 5, 0), (3, 0, 1), (3, 1, 2)]  # from the reflex corner (t, t)
    faces = [(i, k, j) for i, j, k in fan] + [(i + n, j + n, k + n) for i, j, k in fan]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    return trimesh.Trimesh(v - [0.5 * a, 0.5 * b, 0.5 * depth], faces, process=True)


def box_surface_points(n=600, size=(0.2, 0.1, 0.1), seed=0) -> np.ndarray:
    box = trimesh.creation.box(extents=size)
    points, _ = trimesh.sample.sample_surface_even(box, n, seed=seed)
    return np.asarray(points[:n])


def write_pcd_ascii(path: Path, points: np.ndarray) -> None:
    lines = ["# .PCD v0.7 - Point Cloud Data file format (drake_mh test data)", "VERSION 0.7",
             "FIELDS x y z rgb", "SIZE 4 4 4 4", "TYPE F F F F", "COUNT 1 1 1 1", f"WIDTH {len(points)}",
             "HEIGHT 1", "VIEWPOINT 0 0 0 1 0 0 0", f"POINTS {len(points)}", "DATA ascii"]
    lines += [f"{x:.6f} {y:.6f} {z:.6f} 4.2108e+06" if np.isfinite(x) else "nan nan nan 0"
              for x, y, z in points]
    path.write_text("\n".join(lines) + "\n")


def write_pcd_binary(path: Path, points: np.ndarray) -> None:
    header = ("VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
              f"WIDTH {len(points)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(points)}\nDATA binary\n")
    body = np.c_[points, np.arange(len(points))].astype("<f4").tobytes()
    path.write_bytes(header.encode() + body)


def main() -> None:
    _write(bin_mesh(), "bin.obj")
    bracket = bracket_mesh()
    _write(bracket, "bracket.obj")
    _write(bracket_mesh(200, 150, 30, 80), "bracket_mm.stl")
    _write(trimesh.creation.box(extents=(0.1, 0.1, 0.1)), "cube.stl")
    wedge = trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.05], [0.1, 0, 0.05], [0, 0.1, 0.05]],
                            [[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [2, 0, 3], [2, 3, 5]])
    _write(wedge, "wedge.ply")
    (HERE / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    (HERE / "empty.obj").write_text("# no geometry\n")
    points = box_surface_points()
    trimesh.PointCloud(points).export(HERE / "cloud.ply")
    np.savetxt(HERE / "cloud.xyz", np.c_[points, np.ones(len(points))], fmt="%.6f", header="x y z intensity")
    np.save(HERE / "cloud.npy", points)
    with_nan = points.copy()
    with_nan[7] = np.nan
    write_pcd_ascii(HERE / "cloud_ascii.pcd", with_nan)
    write_pcd_binary(HERE / "cloud_binary.pcd", points)


if __name__ == "__main__":
    main()
