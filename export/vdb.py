"""OpenVDB volumes through the ``openvdb`` module that Blender bundles.

The module ships inside the ``bpy`` wheel (and Blender itself).  Blender's own
way to reach it is ``bpy.utils.expose_bundled_modules()``; this package stays
free of ``bpy`` and finds the same file through the import system instead.

Volumes are written slab by slab, so a bake never holds a dense copy of the
grid: :class:`VolumeWriter` takes float32 slabs (nz, ny, nx) or (nz, ny, nx, 3)
indexed like the bake's arrays and stores them at VDB coordinates (x, y, z).
Voxels equal to zero stay inactive (sparse), so empty space costs nothing.
"""
from __future__ import annotations

import glob
import importlib.util
import os
import sys

import numpy as np

from .atomic import WriteError, atomic_path, no_space, require_finite

__all__ = ["openvdb_module", "VolumeWriter", "read_volume", "read_vdb_metadata"]

_F = np.float32


def openvdb_module():
    """The ``openvdb`` module: importable directly (Blender 4.4+), as ``pyopenvdb`` (Blender 4.2-4.3),
    or found inside the bpy wheel.  The 4.2 ``bpy`` wheel has none: RuntimeError says so in one line."""
    for name in ("openvdb", "pyopenvdb"):
        try:
            return importlib.import_module(name)
        except ImportError:
            pass
    spec = importlib.util.find_spec("bpy")
    roots = list(spec.submodule_search_locations or []) if spec is not None else []
    for root in roots:
        for so in sorted(glob.glob(os.path.join(root, "*", "python", "lib", "python3*", "site-packages", "openvdb*"))):
            folder = os.path.dirname(so)
            if folder not in sys.path:
                sys.path.append(folder)
            import openvdb

            return openvdb
    raise RuntimeError("writing .vdb needs the OpenVDB Python module (openvdb, or pyopenvdb in Blender 4.2), "
                       "which this Python lacks; write .npy or .exr instead, or install it: Blender 4.4+ and "
                       "the bpy package bundle it (pip install bpy), Debian ships python3-openvdb")


class VolumeWriter:
    """Collects named grids slab by slab, then writes one .vdb atomically.

    voxel  (3,) spacing along x, y, z;  first  (3,) world position of voxel (0, 0, 0)'s centre
    grids  {name: "float" | "vec3"}
    half   store voxel values as 16-bit half floats (about half the file size)
    """

    def __init__(self, voxel, first, grids: dict, metadata: dict | None = None, half: bool = False):
        self.vdb = openvdb_module()
        vx, vy, vz = (float(v) for v in voxel)
        tx, ty, tz = (float(v) for v in first)
        matrix = [[vx, 0.0, 0.0, 0.0], [0.0, vy, 0.0, 0.0], [0.0, 0.0, vz, 0.0], [tx, ty, tz, 1.0]]
        self.grids = {}
        for name, kind in grids.items():
            g = self.vdb.FloatGrid() if kind == "float" else self.vdb.Vec3SGrid()
            g.name = name
            g.transform = self.vdb.createLinearTransform(matrix)
            if name == "density":
                g.gridClass = self.vdb.GridClass.FOG_VOLUME
            g.saveFloatAsHalf = bool(half)
            self.grids[name] = (g, kind)
        self.half = bool(half)
        self.metadata = {str(k): str(v) for k, v in (metadata or {}).items()}

    def add(self, name: str, z0: int, slab: np.ndarray) -> None:
        """Store ``slab`` float32 (nz, ny, nx) or (nz, ny, nx, 3) at z = z0 ... z0 + nz - 1."""
        g, kind = self.grids[name]
        a = np.asarray(slab, _F)
        require_finite(a, f"grid {name!r}", self.half)
        if kind == "float":
            if a.ndim != 3:
                raise ValueError(f"grid {name!r} takes (nz, ny, nx) slabs, got {a.shape}")
            g.copyFromArray(np.ascontiguousarray(a.transpose(2, 1, 0)), ijk=(0, 0, int(z0)), tolerance=0.0)
        else:
            if a.ndim != 4 or a.shape[3] != 3:
                raise ValueError(f"grid {name!r} takes (nz, ny, nx, 3) slabs, got {a.shape}")
            g.copyFromArray(np.ascontiguousarray(a.transpose(2, 1, 0, 3)), ijk=(0, 0, int(z0)),
                            tolerance=(0.0, 0.0, 0.0))

    def active_voxels(self, name: str) -> int:
        return int(self.grids[name][0].activeVoxelCount())

    def write(self, path: str) -> None:
        """Prune and write all grids to ``path`` (temporary file, then rename).  OpenVDB does not say when it cannot
        write (a full disk leaves a cut file and no error), so the file is read back before the rename: each grid
        with its active voxels, else :class:`~.atomic.WriteError` and nothing written.  The writer is spent: its
        grids are let go before the file is read back, so that the two are not held at once."""
        grids = []
        for g, kind in self.grids.values():
            g.prune(0.0) if kind == "float" else g.prune((0.0, 0.0, 0.0))
            grids.append(g)
        voxels = {g.name: int(g.activeVoxelCount()) for g in grids}
        with atomic_path(path, suffix=".vdb") as tmp:
            self.vdb.write(tmp, grids=grids, metadata=self.metadata)
            grids.clear()
            self.grids.clear()      # the file holds them now: read back in their place, not beside them
            self._check_written(tmp, path, voxels)

    def _check_written(self, tmp: str, path: str, voxels: dict) -> None:
        """WriteError naming ``path`` unless the file ``tmp`` reads back as the grids ``voxels`` {name: active}."""
        try:
            back = self.vdb.readAll(tmp)[0]
            read = {g.name: int(g.activeVoxelCount()) for g in back}
        except Exception:  # noqa: BLE001  (a cut file fails in any of OpenVDB's readers: KeyError, RuntimeError...)
            read = None
        if read != voxels:
            raise WriteError(path, no_space(os.path.dirname(os.path.abspath(path))) or
                             "the file read back is not the volume written (a failing disk or a full quota?)")


#: bounds of read_vdb_metadata: the bytes it reads at most, entries, and one entry's name or value
METADATA_BYTES, METADATA_ENTRIES, METADATA_FIELD = 1 << 20, 1024, 1 << 16
_VDB_MAGIC = 0x56444220


def read_vdb_metadata(path: str) -> dict:
    """The string entries of a .vdb file's own metadata (the bake's key among them), read from the file's header
    with bounds on time and memory (at most METADATA_BYTES, no voxels, no OpenVDB module needed): {} for a file that
    is not a VDB of format 222 or later, or is damaged (a bake then treats it as out of date).

    The header (OpenVDB's io/File.cc, format 222+): int64 magic, uint32 format version, uint32 x 2 library
    version, uint8 has-grid-offsets, 36 ASCII bytes of UUID, then uint32 count of metadata entries, each a
    uint32-length-prefixed name, type name and value."""
    import struct

    try:
        with open(path, "rb") as fh:
            data = fh.read(METADATA_BYTES)
    except OSError:
        return {}
    try:
        magic, version = struct.unpack_from("<qI", data, 0)
        if magic != _VDB_MAGIC or version < 222:
            return {}
        pos = 8 + 4 + 8 + 1 + 36
        (count,) = struct.unpack_from("<I", data, pos)
        pos += 4
        if count > METADATA_ENTRIES:
            return {}
        out = {}
        for _ in range(count):
            fields = []
            for _ in range(3):
                (n,) = struct.unpack_from("<I", data, pos)
                if n > METADATA_FIELD or pos + 4 + n > len(data):
                    return {}
                fields.append(data[pos + 4:pos + 4 + n])
                pos += 4 + n
            name, kind, value = fields
            if kind == b"string":
                out[name.decode("utf-8", "replace")] = value.decode("utf-8", "replace")
        return out
    except struct.error:
        return {}


def read_volume(path: str, name: str, shape: tuple) -> np.ndarray:
    """Grid ``name`` as a dense array indexed like the bake: float32 (nz, ny, nx[, 3])."""
    vdb = openvdb_module()
    g = vdb.read(path, name)
    nz, ny, nx = shape
    if isinstance(g, vdb.FloatGrid):
        a = np.zeros((nx, ny, nz), _F)
    else:
        a = np.zeros((nx, ny, nz, 3), _F)
    g.copyToArray(a, ijk=(0, 0, 0))
    return np.ascontiguousarray(np.moveaxis(a, (0, 1, 2), (2, 1, 0)))
