"""Point-cloud files: ``.ply``, ``.pcd``, ``.xyz`` and ``.npy`` read into ``(N, 3)`` arrays.

* ``.ply``: read with trimesh (a point cloud, or the vertices of a mesh);
* ``.pcd`` (the Point Cloud Library's format): the header (``FIELDS``, ``SIZE``, ``TYPE``,
  ``COUNT``, ``WIDTH``, ``HEIGHT``, ``POINTS``, ``DATA``) and the ``x``, ``y``, ``z`` fields
  of ``DATA ascii`` and ``DATA binary`` bodies, read here (a few dozen lines; the registry's PCD
  readers pull in Open3D or a C++ build). ``DATA binary_compressed`` is refused with how to
  convert it;
* ``.xyz``: text, one point per line, the first three columns (more columns, e.g. colours or
  normals, are ignored; ``#`` starts a comment);
* ``.npy``: a NumPy array of shape ``(N, 3)`` (or ``(N, k >= 3)``: its first three columns).

Every reader returns the points as stored, NaN and infinities included:
:class:`drake_mh.geometry.cloud.PointCloud` decides what to do with them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_mh.errors import ObstacleFileError

__all__ = ["CLOUD_SUFFIXES", "read_points"]

CLOUD_SUFFIXES = (".ply", ".pcd", ".xyz", ".npy")
"""File suffixes :func:`read_points` reads (case-insensitive)."""

_PCD_TYPES = {("F", 4): "<f4", ("F", 8): "<f8", ("I", 1): "<i1", ("I", 2): "<i2", ("I", 4): "<i4", ("I", 8): "<i8",
              ("U", 1): "<u1", ("U", 2): "<u2", ("U", 4): "<u4", ("U", 8): "<u8"}


def read_points(path: Path) -> np.ndarray:
    """``(N, 3)`` float64 points [file units] of a point-cloud file (module docstring).

    Raises:
        ObstacleFileError: a format not in :data:`CLOUD_SUFFIXES`, or a file that its reader
            rejects (the message names what is missing or malformed).
    """
    suffix = path.suffix.lower()
    readers = {".ply": _read_ply, ".pcd": _read_pcd, ".xyz": _read_xyz, ".npy": _read_npy}
    if suffix not in readers:
        raise ObstacleFileError(path, f"unknown point-cloud format {suffix or '(no suffix)'!r}; "
                                      f"use one of {', '.join(CLOUD_SUFFIXES)}")
    points = readers[suffix](path)
    return np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))


def _read_ply(path: Path) -> np.ndarray:
    import trimesh

    try:
        loaded = trimesh.load(str(path), process=False)
    except Exception as exc:  # trimesh raises many kinds (ValueError, KeyError ...)
        raise ObstacleFileError(path, f"cannot read the PLY file ({type(exc).__name__}: {exc})") from exc
    vertices = getattr(loaded, "vertices", None)
    if vertices is None:
        raise ObstacleFileError(path, "the PLY file has no vertex element with x, y, z")
    return np.asarray(vertices, dtype=float)


def _read_xyz(path: Path) -> np.ndarray:
    try:
        data = np.loadtxt(path, comments="#", ndmin=2, usecols=(0, 1, 2))
    except (ValueError, IndexError) as exc:
        raise ObstacleFileError(path, f"an .xyz file needs three numbers (x y z) per line ({exc})") from exc
    return data


def _read_npy(path: Path) -> np.ndarray:
    try:
        data = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise ObstacleFileError(path, f"cannot read the .npy file ({exc}); save an (N, 3) float array "
                                      "with numpy.save") from exc
    if data.ndim != 2 or data.shape[1] < 3 or data.dtype.kind not in "fiu":
        raise ObstacleFileError(path, f"a .npy point cloud must be a numeric (N, 3) array, got shape "
                                      f"{data.shape} of {data.dtype}")
    return data[:, :3]


def _pcd_header(path: Path, raw: bytes) -> tuple[dict, int]:
    """The header fields of a PCD file (names upper-cased) and where its body starts."""
    header, offset = {}, 0
    while "DATA" not in header:
        end = raw.find(b"\n", offset)
        if end < 0:
            raise ObstacleFileError(path, "the PCD header has no DATA line (a PCD file starts with VERSION, "
                                          "FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS, DATA)")
        line = raw[offset:end].decode("ascii", "replace").strip()
        offset = end + 1
        if not line or line.startswith("#"):
            continue
        key, *values = line.split()
        header[key.upper()] = values
    return header, offset


def _read_pcd(path: Path) -> np.ndarray:
    raw = path.read_bytes()
    header, body = _pcd_header(path, raw)
    fields = header.get("FIELDS")
    if not fields or not {"x", "y", "z"} <= set(fields):
        raise ObstacleFileError(path, f"the PCD FIELDS line must name x, y and z, got {fields}")
    n_fields = len(fields)
    sizes = header.get("SIZE", ["4"] * n_fields)
    types = header.get("TYPE", ["F"] * n_fields)
    counts = header.get("COUNT", ["1"] * n_fields)
    try:
        sizes, counts = [int(s) for s in sizes], [int(c) for c in counts]
        n_points = int(header["POINTS"][0]) if "POINTS" in header else \
            int(header["WIDTH"][0]) * int(header.get("HEIGHT", ["1"])[0])
    except (ValueError, KeyError, IndexError) as exc:
        raise ObstacleFileError(path, f"malformed PCD header: SIZE, COUNT, POINTS (or WIDTH, HEIGHT) must be "
                                      f"integers ({exc})") from exc
    if not (len(sizes) == len(types) == len(counts) == n_fields) or n_points < 0:
        raise ObstacleFileError(path, "malformed PCD header: FIELDS, SIZE, TYPE and COUNT must have one entry "
                                      "per field")
    xyz = [sum(counts[:fields.index(axis)]) for axis in "xyz"]  # an ascii row's column of x, y, z
    kind = header["DATA"][0].lower() if header["DATA"] else ""
    if kind == "ascii":
        text = raw[body:].decode("ascii", "replace").split("\n")
        rows = [line.split() for line in text if line.strip()][:n_points]
        width = sum(counts)
        if len(rows) < n_points or any(len(r) < width for r in rows):
            raise ObstacleFileError(path, f"the ascii PCD body has fewer than {n_points} rows of {width} values")
        try:
            return np.array([[float(r[c]) for c in xyz] for r in rows]).reshape(-1, 3)
        except ValueError as exc:
            raise ObstacleFileError(path, f"the ascii PCD body holds a value that is not a number ({exc})") from exc
    if kind == "binary":
        try:
            dtype = np.dtype([(f"f{i}", _PCD_TYPES[(t.upper(), s)], (c,))
                              for i, (t, s, c) in enumerate(zip(types, sizes, counts))])
        except KeyError as exc:
            raise ObstacleFileError(path, f"unknown PCD field type/size {exc.args[0]}") from None
        if len(raw) - body < n_points * dtype.itemsize:
            raise ObstacleFileError(path, f"the binary PCD body is truncated: {len(raw) - body} bytes for "
                                          f"{n_points} points of {dtype.itemsize} bytes")
        data = np.frombuffer(raw, dtype=dtype, count=n_points, offset=body)
        return np.stack([data[f"f{fields.index(axis)}"][:, 0].astype(float) for axis in "xyz"], axis=1)
    if kind == "binary_compressed":
        raise ObstacleFileError(path, "DATA binary_compressed is not read; convert the file with PCL's "
                                      "'pcl_convert_pcd_ascii_binary in.pcd out.pcd 1' (binary) or save it as "
                                      "ascii or binary")
    raise ObstacleFileError(path, f"unknown PCD DATA kind {kind!r}; expected ascii or binary")
