"""Minimal reader for the VTK XML files cdemblast writes (numpy + zlib + xml.etree only).

Reads UnstructuredGrid .vtu files and .pvd collections. It understands what
src/cdem/io/vtu.cpp writes -- appended raw binary data after the '_' marker, each
DataArray's `offset` counted from the byte after '_', header_type UInt64 (UInt32 also
accepted), optional vtkZLibDataCompressor -- plus the inline "ascii" and base64 "binary"
formats other tools write, so a file saved by ParaView can be read as well.

Layout of one appended array (vtu.cpp, write_vtu):
  uncompressed: [UInt64 byte count][raw bytes]
  compressed:   [UInt64 nblocks, blocksize, lastblocksize, csize_1 .. csize_n][zlib blocks]
                (lastblocksize 0 means the last block is full)

Arrays are decoded lazily (on first access) and cached, so reading only `damage` from a
large 3D file does not decompress the stress tensor.

The grid's field data (<UnstructuredGrid><FieldData>) is read too: `grid.time` is the
TimeValue the writer puts in every file (None without it). A grid written with the writer's
empty-grid placeholder (no point, one polygon of no nodes: see src/cdem/io/vtu.hpp) reads as
0 cells.

    from cdemblast.vtu import read_vtu, read_pvd
    grid = read_vtu("run/fields/fields_0003.vtu")
    grid.points            # (npoints, 3) float64
    grid.cell_array("damage")          # (ncells,) or None when absent
    grid.cell_nodes(5)     # (n, 3) node ids of the triangles; grid.cells_of_type(5) their ids
"""

from __future__ import annotations

import base64
import os
import struct
import xml.etree.ElementTree as ET
import zlib

import numpy as np

VTK_LINE, VTK_TRIANGLE, VTK_POLYGON, VTK_QUAD, VTK_TETRA = 3, 5, 7, 9, 10

_DTYPES = {
    "Int8": "i1", "UInt8": "u1", "Int16": "i2", "UInt16": "u2",
    "Int32": "i4", "UInt32": "u4", "Int64": "i8", "UInt64": "u8",
    "Float32": "f4", "Float64": "f8",
}


class VtuError(RuntimeError):
    """A file that is not a VTU file this reader understands (the message names the file)."""


class VtuGrid:
    """One UnstructuredGrid piece. Data arrays are decoded on first access."""

    def __init__(self, path, npoints, ncells, arrays, decode):
        self.path = path
        self.npoints = npoints
        self.ncells = ncells
        self._arrays = arrays  # (section, name) -> DataArray element
        self._decode = decode
        self._cache = {}
        self.placeholder = False
        if npoints == 0 and ncells == 1:
            # The writer's empty-grid placeholder: one polygon without nodes, no point.
            types, offsets = self._get("cells", "types"), self._get("cells", "offsets")
            if (types is not None and offsets is not None and types.size == 1
                    and int(types[0]) == VTK_POLYGON and int(offsets[0]) == 0):
                self.placeholder = True
                self.ncells = 0
            self._cache.clear()

    # ---- array access ----
    def _get(self, section, name):
        key = (section, name)
        if key not in self._arrays:
            return None
        if key not in self._cache:
            n = self.npoints if section in ("point", "points") else self.ncells
            if section == "cells":
                n = None
            elif section == "field":
                n = int(self._arrays[key].get("NumberOfTuples", "1"))
            elif section == "cell" and getattr(self, "placeholder", False):
                n = 1
            v = self._decode(self._arrays[key], n)
            if getattr(self, "placeholder", False) and section in ("cell", "cells"):
                v = v[:0]
            self._cache[key] = v
        return self._cache[key]

    @property
    def field_array_names(self):
        return [n for (s, n) in self._arrays if s == "field"]

    def field_array(self, name):
        """A field-data array of the grid (e.g. TimeValue), or None when absent."""
        return self._get("field", name)

    @property
    def time(self):
        """The TimeValue field data (s), or None when the file has none."""
        t = self.field_array("TimeValue")
        return float(np.ravel(t)[0]) if t is not None and np.size(t) else None

    def component_names(self, section, name):
        """ComponentName0.. of a 'point' or 'cell' array ([] when not named or absent)."""
        da = self._arrays.get((section, name))
        if da is None:
            return []
        n = int(da.get("NumberOfComponents", "1"))
        names = [da.get(f"ComponentName{i}") for i in range(n)]
        return names if all(names) else []

    def array_type(self, section, name):
        """The VTK type name ('Float64', 'Int32', ...) of an array, or None when absent."""
        da = self._arrays.get((section, name))
        return None if da is None else da.get("type")

    @property
    def point_array_names(self):
        return [n for (s, n) in self._arrays if s == "point"]

    @property
    def cell_array_names(self):
        return [n for (s, n) in self._arrays if s == "cell"]

    def point_array(self, name):
        """(npoints,) or (npoints, ncomp) array, or None when the file has no such array."""
        return self._get("point", name)

    def cell_array(self, name):
        """(ncells,) or (ncells, ncomp) array, or None when the file has no such array."""
        return self._get("cell", name)

    @property
    def points(self):
        p = self._get("points", "Points")
        if p is None:
            return np.zeros((0, 3))
        return p.reshape(-1, 3) if p.ndim == 1 else p

    @property
    def connectivity(self):
        c = self._get("cells", "connectivity")
        return np.zeros(0, np.int64) if c is None else c.astype(np.int64, copy=False)

    @property
    def offsets(self):
        c = self._get("cells", "offsets")
        return np.zeros(0, np.int64) if c is None else c.astype(np.int64, copy=False)

    @property
    def types(self):
        c = self._get("cells", "types")
        return np.zeros(0, np.uint8) if c is None else c.astype(np.uint8, copy=False)

    # ---- cells by type ----
    def cells_of_type(self, vtk_type):
        """Indices of the cells of one VTK type."""
        return np.nonzero(self.types == vtk_type)[0]

    def cell_nodes(self, vtk_type):
        """(n, k) node ids of the cells of one fixed-size VTK type (k nodes each)."""
        ids = self.cells_of_type(vtk_type)
        if ids.size == 0:
            return np.zeros((0, 0), np.int64)
        off = self.offsets
        start = np.where(ids > 0, off[ids - 1], 0) if ids.size else ids
        k = int(off[ids[0]] - (off[ids[0] - 1] if ids[0] > 0 else 0))
        return self.connectivity[start[:, None] + np.arange(k)[None, :]]


def _parse_header(path, raw):
    """Splits a VTU file into its XML tree and the appended binary data (or None)."""
    marker = raw.find(b"<AppendedData")
    appended = None
    if marker >= 0:
        underscore = raw.find(b"_", raw.find(b">", marker) + 1)
        if underscore < 0:
            raise VtuError(f"{path}: <AppendedData> without the '_' marker")
        appended = memoryview(raw)[underscore + 1:]
        # The XML before <AppendedData> closes every element except <VTKFile>.
        xml = raw[:marker] + b"</VTKFile>"
    else:
        xml = raw
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as e:
        raise VtuError(f"{path}: not valid XML ({e})") from None
    return root, appended


def read_vtu(path):
    """Reads a .vtu file; raises VtuError when it cannot."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise VtuError(f"{path}: cannot read ({e.strerror})") from None
    root, appended = _parse_header(path, raw)
    if root.tag != "VTKFile" or root.get("type") != "UnstructuredGrid":
        raise VtuError(f"{path}: not a VTK UnstructuredGrid file")
    endian = "<" if root.get("byte_order", "LittleEndian") == "LittleEndian" else ">"
    header_type = root.get("header_type", "UInt32")
    if header_type not in ("UInt32", "UInt64"):
        raise VtuError(f"{path}: unsupported header_type {header_type}")
    hdt = np.dtype(endian + _DTYPES[header_type])
    compressor = root.get("compressor", "")
    if compressor not in ("", "vtkZLibDataCompressor"):
        raise VtuError(f"{path}: unsupported compressor {compressor}")
    compressed = compressor == "vtkZLibDataCompressor"

    piece = root.find("UnstructuredGrid/Piece")
    if piece is None:
        raise VtuError(f"{path}: no <UnstructuredGrid><Piece>")
    npoints = int(piece.get("NumberOfPoints", "0"))
    ncells = int(piece.get("NumberOfCells", "0"))

    arrays = {}
    fd = root.find("UnstructuredGrid/FieldData")
    for da in ([] if fd is None else fd.findall("DataArray")):
        arrays[("field", da.get("Name", ""))] = da
    for section, tag in (("point", "PointData"), ("cell", "CellData"),
                         ("points", "Points"), ("cells", "Cells")):
        el = piece.find(tag)
        if el is None:
            continue
        for da in el.findall("DataArray"):
            name = da.get("Name", "")
            if section == "points":
                name = "Points"
            arrays[(section, name)] = da

    def binary_block(data, pos):
        """Decodes one binary (appended or base64-decoded) array starting at data[pos:]."""
        hsize = hdt.itemsize

        def need(end):
            if pos < 0 or end > len(data):
                raise VtuError(f"{path}: the file is truncated (data end at byte {end} of "
                               f"{len(data)} in the binary section)")

        need(pos + hsize)
        first = int(np.frombuffer(data, hdt, 1, pos)[0])
        if not compressed:
            need(pos + hsize + first)
            return bytes(data[pos + hsize: pos + hsize + first])
        need(pos + hsize * (3 + first))
        head = np.frombuffer(data, hdt, 3 + first, pos).astype(np.int64)
        q = pos + hsize * (3 + first)
        need(q + int(head[3:].sum()))
        out = []
        for s in head[3:]:
            out.append(zlib.decompress(data[q:q + int(s)]))
            q += int(s)
        return b"".join(out)

    def decode(da, n):
        tname = da.get("type")
        if tname not in _DTYPES:
            raise VtuError(f"{path}: array '{da.get('Name')}' has unsupported type {tname}")
        dt = np.dtype(endian + _DTYPES[tname])
        ncomp = int(da.get("NumberOfComponents", "1"))
        fmt = da.get("format", "ascii")
        try:
            if fmt == "appended":
                if appended is None:
                    raise VtuError(f"{path}: appended array without <AppendedData>")
                buf = binary_block(appended, int(da.get("offset", "0")))
                values = np.frombuffer(buf, dt)
            elif fmt == "binary":
                text = "".join((da.text or "").split()).encode()
                if compressed:
                    # base64 header and the base64 data are encoded separately.
                    hsize = hdt.itemsize
                    first = base64.b64decode(text[:((hsize + 2) // 3) * 4])
                    nblocks = int(np.frombuffer(first, hdt, 1, 0)[0])
                    hlen = ((hsize * (3 + nblocks) + 2) // 3) * 4
                    header = base64.b64decode(text[:hlen])
                    body = base64.b64decode(text[hlen:])
                    buf = binary_block(header + body, 0)
                else:
                    buf = binary_block(base64.b64decode(text), 0)
                values = np.frombuffer(buf, dt)
            else:
                values = np.array((da.text or "").split(), dtype=dt)
        except (zlib.error, ValueError, struct.error) as e:
            raise VtuError(f"{path}: array '{da.get('Name')}' is damaged ({e})") from None
        if n is not None and values.size != n * ncomp:
            raise VtuError(f"{path}: array '{da.get('Name')}' has {values.size} values, "
                           f"expected {n * ncomp}")
        values = values.astype(values.dtype.newbyteorder("="), copy=False)
        return values.reshape(-1, ncomp) if ncomp > 1 else values

    return VtuGrid(path, npoints, ncells, arrays, decode)


def read_pvd(path):
    """[(time, absolute path of the dataset file), ...] sorted by time; [] when missing."""
    if not os.path.isfile(path):
        return []
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise VtuError(f"{path}: not valid XML ({e})") from None
    base = os.path.dirname(os.path.abspath(path))
    steps = []
    for ds in root.iter("DataSet"):
        f = ds.get("file")
        if not f:
            continue
        try:
            t = float(ds.get("timestep", "nan"))
        except ValueError:
            t = float("nan")
        steps.append((t, os.path.join(base, f)))
    steps.sort(key=lambda s: (np.nan_to_num(s[0], nan=np.inf)))
    return steps
