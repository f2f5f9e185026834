"""The workspace's solid and the frame loads as files: ``boundary.csv`` (planar) or
``workspace.stl`` (spatial), and ``frame_loads.csv`` (:mod:`cdpr_design.workspaces.boundary`,
:mod:`cdpr_design.workspaces.frame_loads`)."""

from __future__ import annotations

from cdpr_design.jobs.tables import file_name, write_table
from cdpr_design.workspaces.frame_loads import csv_columns


def solid_names(design, format: str = "csv") -> list[str]:
    """The files :func:`write_solid` writes for ``design`` (tables in ``format``)."""
    shape = file_name("boundary", format) if design.motion.planar else "workspace.stl"
    return [shape, file_name("frame_loads", format)]


def write_solid(out, result, format: str = "csv") -> None:
    """Write the boundary and the frame loads of ``result`` (a sweep planned with ``solid``) into
    the output folder ``out``."""
    design = result.design
    b = result.boundary
    if design.motion.planar:
        write_table(out, "boundary", b.loop_table(), format, design, names=["x", "y", "loop"],
                    boundary_measure=b.measure, boundary_surface=b.surface)
    else:
        out.write_bytes("workspace.stl", stl_bytes(b.vertices, b.faces))
    names = csv_columns(design.motion.planar)
    write_table(out, "frame_loads", result.frame_loads.rows(design.cable_names), format, design, names=names)


#: One triangle of a binary STL: normal, three vertices (float32, little-endian), attribute count.
_STL_TRIANGLE = [("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attributes", "<u2")]


def stl_bytes(vertices, faces, name: str = "cdpr-design workspace") -> bytes:
    """A binary STL of a triangle mesh: ``vertices`` (V, 3) [m], ``faces`` (F, 3) wound
    counter-clockwise seen from outside (80-byte header, the triangle count, then per triangle
    its unit normal and its three vertices as float32, and a zero attribute count)."""
    import numpy as np

    v = np.asarray(vertices, float)
    tri = v[np.asarray(faces, dtype=np.int64)] if len(faces) else np.zeros((0, 3, 3))
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, norm, out=np.zeros_like(n), where=norm > 0)
    rec = np.zeros(len(tri), dtype=_STL_TRIANGLE)
    rec["normal"], rec["vertices"] = n, tri
    header = name.encode("ascii")[:80].ljust(80, b" ")
    return header + np.uint32(len(tri)).tobytes() + rec.tobytes()
