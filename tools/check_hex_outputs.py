"""Read the 3D outputs written by `cargo run --release --example hex_outputs -- OUT` back with
independent readers and check them against the closed-form fields of tools/hex_outputs.rs.

Usage: check_hex_outputs.py OUT

meshio (every .vtu of OUT/hex8/hex.pvd and OUT/hex27/hex.pvd): the cell type (hexahedron /
hexahedron27) and counts, every cell's node order against VTK's (corners with a positive
volume, each mid-edge, mid-face and centre node the nearest of the cell's nodes to the mean of
the corners it lies between), `displacement`, `radius`, `cauchy_stress` (9 components,
symmetric) and `cell_index2` against their formulas at the points, TimeValue of each step.
Python mcap + protobuf (hex.mcap): two `/tread/hex/nodes` point clouds and two
`/tread/hex/mesh` scene updates per mesh, the triangle list closed and oriented outward
(every edge used once in each direction, enclosed volume > 0), its vertices on the deformed
surface of the .vtu, colours in [0, 1]. Exits 1 on the first failed check.
"""
import sys
import xml.etree.ElementTree as ET
from collections import Counter

import meshio
import numpy as np
from mcap.reader import make_reader
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory


def fail(msg):
    print(f"check_hex_outputs: FAIL: {msg}")
    sys.exit(1)


def check(cond, msg):
    if not cond:
        fail(msg)


# VTK parametric coordinates (r, s, t) of the 27 nodes of VTK_TRIQUADRATIC_HEXAHEDRON.
PC = np.array([
    [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1],
    [.5, 0, 0], [1, .5, 0], [.5, 1, 0], [0, .5, 0], [.5, 0, 1], [1, .5, 1], [.5, 1, 1], [0, .5, 1],
    [0, 0, .5], [1, 0, .5], [1, 1, .5], [0, 1, .5],
    [0, .5, .5], [1, .5, .5], [.5, 0, .5], [.5, 1, .5], [.5, .5, 0], [.5, .5, 1], [.5, .5, .5],
])


def check_cell_order(pts, cells, kind):
    for c in cells:
        x = pts[c]
        vol = np.dot(np.cross(x[1] - x[0], x[3] - x[0]), x[4] - x[0])
        check(vol > 0, f"{kind}: cell with corner volume {vol} <= 0")
        if len(c) == 27:
            for k in range(8, 27):
                # Corners whose parametric coordinates agree with node k where k is not 0.5.
                fixed = PC[k] != 0.5
                corners = [a for a in range(8) if np.all(PC[a][fixed] == PC[k][fixed])]
                mean = x[corners].mean(axis=0)
                near = int(np.argmin(np.linalg.norm(x - mean, axis=1)))
                check(near == k, f"{kind}: VTK node {k} is not nearest to its corners' mean")


def decoder(schema):
    fds = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        try:
            pool.Add(fd)
        except Exception:
            pass
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name)).FromString


def check_dir(d, kind, npc):
    root = ET.parse(f"{d}/hex.pvd").getroot()
    steps = [(float(e.get("timestep")), e.get("file")) for e in root.iter("DataSet")]
    check([t for t, _ in steps] == [0.0, 1.0], f"{d}: pvd times {steps}")
    last = None
    for index, (t, f) in enumerate(steps):
        m = meshio.read(f"{d}/{f}")
        check(len(m.cells) == 1 and m.cells[0].type == kind, f"{f}: cells {m.cells}")
        cells = m.cells[0].data
        check(cells.shape[1] == npc, f"{f}: {cells.shape[1]} nodes per cell")
        p = m.points
        check(np.all(np.isfinite(p)), f"{f}: non-finite points")
        check_cell_order(p, cells, f)
        s = 0.5 * (index + 1)
        u = np.stack([s * 0.01 * p[:, 1], s * 0.005 * p[:, 0], s * 0.001 * p[:, 2]], axis=1)
        check(np.allclose(m.point_data["displacement"], u, rtol=0, atol=1e-14), f"{f}: displacement")
        check(np.allclose(np.ravel(m.point_data["radius"]), np.hypot(p[:, 0], p[:, 1]), atol=1e-14), f"{f}: radius")
        sig = m.point_data["cauchy_stress"].reshape(-1, 3, 3)
        want = np.zeros_like(sig)
        want[:, 0, 0], want[:, 1, 1], want[:, 2, 2] = p[:, 0], p[:, 1], p[:, 2]
        want[:, 1, 2] = want[:, 2, 1] = 1.0
        want[:, 0, 2] = want[:, 2, 0] = 2.0
        want[:, 0, 1] = want[:, 1, 0] = 3.0
        check(np.array_equal(sig, want), f"{f}: cauchy_stress")
        ci = np.ravel(m.cell_data["cell_index2"][0])
        check(np.array_equal(ci, 2.0 * np.arange(len(cells))), f"{f}: cell_index2")
        tv = m.field_data.get("TimeValue")
        check(tv is not None and float(np.ravel(tv)[0]) == t, f"{f}: TimeValue {tv}")
        last = (p + u, len(p))
        print(f"check_hex_outputs: {f}: {kind}, {len(p)} points, {len(cells)} cells: ok")
    deformed, npts = last
    topics = Counter()
    meshes = []
    with open(f"{d}/hex.mcap", "rb") as fh:
        dec = {}
        for schema, ch, msg in make_reader(fh).iter_messages(log_time_order=True):
            if schema.id not in dec:
                dec[schema.id] = decoder(schema)
            topics[ch.topic] += 1
            if ch.topic == "/tread/hex/mesh":
                meshes.append(dec[schema.id](msg.data))
    check(topics["/tread/hex/nodes"] == 2 and topics["/tread/hex/mesh"] == 2, f"{d}: topics {dict(topics)}")
    ent = meshes[-1].entities[0]
    tri = ent.triangles[0]
    v = np.array([[q.x, q.y, q.z] for q in tri.points])
    idx = np.array(tri.indices).reshape(-1, 3)
    check(idx.max() < len(v), f"{d}: triangle index out of range")
    edges = Counter()
    for a, b, c in idx:
        for x, y in ((a, b), (b, c), (c, a)):
            edges[(min(x, y), max(x, y))] += 1 if x < y else -1
    check(all(n == 0 for n in edges.values()), f"{d}: surface not closed / not consistently oriented")
    vol = np.sum(np.einsum("ij,ij->i", v[idx[:, 0]], np.cross(v[idx[:, 1]], v[idx[:, 2]]))) / 6
    check(vol > 0, f"{d}: enclosed volume {vol} <= 0 (inward triangles)")
    # Every vertex is a deformed node of the last .vtu (f32 precision of nothing: f64 points).
    dmin = max(np.min(np.linalg.norm(deformed - q, axis=1)) for q in v)
    check(dmin < 1e-12, f"{d}: a mesh vertex is {dmin} from every deformed node")
    cols = np.array([[c.r, c.g, c.b, c.a] for c in tri.colors])
    check(len(cols) == len(v) and cols.min() >= 0 and cols.max() <= 1, f"{d}: colours")
    print(f"check_hex_outputs: {d}/hex.mcap: {len(idx)} triangles, {len(v)} vertices, volume {vol:.6f}: ok")


def main():
    out = sys.argv[1]
    check_dir(f"{out}/hex8", "hexahedron", 8)
    check_dir(f"{out}/hex27", "hexahedron27", 27)
    print("check_hex_outputs: all ok")


main()
