"""Reading (and writing) STL and OBJ triangle meshes into plain arrays, without extra dependencies.

Meta-World ships binary STL; users may bring OBJ or ASCII STL. Readers return raw ``(vertices, faces)``;
cleaning and normalisation happen in :func:`lerobot_factorworld.assets.mesh.normalize_mesh`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .mesh import Mesh

Array = np.ndarray

MESH_EXTENSIONS: tuple[str, ...] = (".stl", ".obj")

_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def read_stl(path: str | Path) -> tuple[Array, Array]:
    """Binary or ASCII STL -> (vertices (3M, 3) float64, faces (M, 3) int64); vertices are not welded."""
    data = Path(path).read_bytes()
    if len(data) >= 84:
        n = int.from_bytes(data[80:84], "little")
        if 84 + n * _STL_RECORD.itemsize == len(data):
            rec = np.frombuffer(data, dtype=_STL_RECORD, count=n, offset=84)
            verts = rec["v"].reshape(-1, 3).astype(np.float64)
            return verts, np.arange(len(verts), dtype=np.int64).reshape(-1, 3)
    text = data.decode("ascii", errors="replace")
    if not text.lstrip().lower().startswith("solid"):
        raise ValueError(f"{path}: not a binary STL (size does not match its triangle count) nor an ASCII STL")
    coords = [line.split()[1:4] for line in text.splitlines() if line.strip().lower().startswith("vertex")]
    if not coords or len(coords) % 3:
        raise ValueError(f"{path}: ASCII STL without complete triangles")
    verts = np.array(coords, dtype=np.float64)
    return verts, np.arange(len(verts), dtype=np.int64).reshape(-1, 3)


def read_obj(path: str | Path) -> tuple[Array, Array]:
    """Wavefront OBJ (``v`` and ``f`` records; polygons are fan-triangulated, negative indices allowed)."""
    verts: list[list[float]] = []
    faces: list[tuple[int, int, int]] = []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for lineno, line in enumerate(fh, 1):
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                try:
                    idx = [int(p.split("/")[0]) for p in parts[1:]]
                except ValueError as exc:
                    raise ValueError(f"{path}:{lineno}: bad face record {line.strip()!r}") from exc
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                faces.extend((idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1))
    if not verts or not faces:
        raise ValueError(f"{path}: OBJ file has no vertices or no faces")
    return np.array(verts, dtype=np.float64), np.array(faces, dtype=np.int64)


def read_mesh_file(path: str | Path) -> tuple[Array, Array]:
    """Dispatch on the extension (one of :data:`MESH_EXTENSIONS`)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".stl":
        return read_stl(path)
    if suffix == ".obj":
        return read_obj(path)
    raise ValueError(f"{path}: unsupported mesh extension {suffix!r}; supported: {', '.join(MESH_EXTENSIONS)}")


def write_stl(path: str | Path, mesh: Mesh) -> None:
    """Write a binary STL (e.g. to reference a generated shape from an MJCF ``<mesh file=...>``)."""
    v = np.asarray(mesh.vertices, dtype=np.float64)[mesh.faces]
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
    rec = np.zeros(len(v), dtype=_STL_RECORD)
    rec["normal"], rec["v"] = normals, v
    header = b"lerobot_factorworld".ljust(80, b" ")
    Path(path).write_bytes(header + len(v).to_bytes(4, "little") + rec.tobytes())


def write_obj(path: str | Path, mesh: Mesh) -> None:
    """Write a Wavefront OBJ with shared vertices."""
    lines = [f"v {x:.7g} {y:.7g} {z:.7g}" for x, y, z in mesh.vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces.tolist()]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
