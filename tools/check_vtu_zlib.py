#!/usr/bin/env python3
"""Check zlib-compressed VTU files against the uncompressed ones of the same run.

Usage: check_vtu_zlib.py DIR_ZLIB DIR_RAW

DIR_ZLIB and DIR_RAW are the output folders of the same scene run with
`--set output.vtu_compression=zlib` and without. For every `fields/*.vtu` and `contact/*.vtu`:

* both files are decoded here with the standard library only (struct + zlib: the VTK header of
  UInt64 numbers, blocks of 32 KiB), and every array must be byte-identical;
* meshio reads the compressed file, and each of its arrays must equal the decoded one (NaN kept);
* when the `vtk` package is installed, VTK's own XML reader reads the compressed file too.

(meshio 5.3.5 itself is not used on the uncompressed raw-appended files: it rewrites their
offsets one array at a time and can swap two arrays when a raw offset equals an earlier
array's rewritten offset.)
"""
import glob
import os
import re
import struct
import sys
import zlib

import meshio
import numpy as np

TYPES = {"Float64": "<f8", "Int64": "<i8", "Int32": "<i4", "UInt8": "u1"}


def arrays(path):
    b = open(path, "rb").read()
    marker = b'<AppendedData encoding="raw">\n_'
    i = b.index(marker) + len(marker)
    head, blob = b[:i].decode(), b[i:]
    zlibbed = 'compressor="vtkZLibDataCompressor"' in head
    out = {}
    for tag in re.findall(r"<DataArray ([^>]*)>", head):
        m = re.search(r'offset="(\d+)"', tag)
        if not m:
            continue
        off = int(m.group(1))
        name = re.search(r'Name="([^"]+)"', tag)
        name = name.group(1) if name else "Points"
        dtype = TYPES[re.search(r'type="(\w+)"', tag).group(1)]
        if zlibbed:
            nb, bs, last = struct.unpack_from("<3Q", blob, off)
            sizes = struct.unpack_from("<%dQ" % nb, blob, off + 24)
            p, data = off + 24 + 8 * nb, b""
            for k, c in enumerate(sizes):
                d = zlib.decompress(blob[p : p + c])
                want = last if (k + 1 == nb and last) else bs
                assert len(d) == want, f"{path}: {name}: block {k}: {len(d)} bytes, header says {want}"
                data += d
                p += c
        else:
            (n,) = struct.unpack_from("<Q", blob, off)
            data = blob[off + 8 : off + 8 + n]
        out[name] = np.frombuffer(data, dtype=dtype)
    return zlibbed, out


def same(a, b):
    a, b = np.asarray(a).ravel(), np.asarray(b).ravel()
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


def main(dz, dr):
    try:
        import vtk  # noqa: F401
        from vtk.util.numpy_support import vtk_to_numpy
    except ImportError:
        vtk = None
    files = sorted(glob.glob(os.path.join(dz, "fields", "*.vtu")) + glob.glob(os.path.join(dz, "contact", "*.vtu")))
    if not files:
        sys.exit(f"check_vtu_zlib: no .vtu files under {dz}")
    for fz in files:
        fr = os.path.join(dr, os.path.relpath(fz, dz))
        zz, az = arrays(fz)
        zr, ar = arrays(fr)
        assert zz and not zr, f"{fz}: expected a compressed and an uncompressed file"
        assert az.keys() == ar.keys(), (fz, az.keys(), ar.keys())
        for k in ar:
            assert az[k].tobytes() == ar[k].tobytes(), f"{fz}: {k} differs from the uncompressed file"
        m = meshio.read(fz)
        assert same(m.points, az["Points"]), f"{fz}: meshio points"
        for k, v in m.point_data.items():
            assert same(v, az[k]), f"{fz}: meshio {k}"
        for k, v in m.cell_data.items():
            assert same(np.concatenate([np.asarray(x).ravel() for x in v]), az[k]), f"{fz}: meshio {k}"
        if vtk is not None:
            r = vtk.vtkXMLUnstructuredGridReader()
            r.SetFileName(fz)
            r.Update()
            g = r.GetOutput()
            assert same(vtk_to_numpy(g.GetPoints().GetData()), az["Points"]), f"{fz}: vtk points"
            pd = g.GetPointData()
            for j in range(pd.GetNumberOfArrays()):
                a = pd.GetArray(j)
                assert same(vtk_to_numpy(a), az[a.GetName()]), f"{fz}: vtk {a.GetName()}"
    print(
        f"check_vtu_zlib: {len(files)} compressed files equal the uncompressed ones "
        f"(own decoder, meshio{', vtk' if vtk is not None else ''}); "
        f"size {sum(os.path.getsize(f) for f in files)} vs "
        f"{sum(os.path.getsize(os.path.join(dr, os.path.relpath(f, dz))) for f in files)} bytes"
    )


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
