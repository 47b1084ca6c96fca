#!/usr/bin/env python3
"""Make the Gmsh meshes used by tread's scenes and tests (needs `pip install gmsh`).

    python3 tools/make_meshes.py            # writes every mesh below

Meshes (all .msh 4.1, physical groups: 1D "hub" and "contact", 2D regions):
* tests/gmsh_data/annulus_q1.msh, annulus_q2.msh (ASCII) and annulus_q2_binary.msh: the
  structured annulus ri = 1, ro = 2, 2 x 16 cells, nodes at the same positions as tread's
  built-in generator (radii uniform, angles -pi/2 + 2 pi k / 16). The annulus is cut into
  4 sectors x 2 layers, each a transfinite surface, so that every cell edge lies on a geometric
  line or circle arc and Gmsh puts the mid-side nodes of order 2 at the mid-radius / mid-angle
  (as the generator does). Before writing, every node is snapped onto the generator's polar
  grid (Gmsh's arcs are within ~1e-9 of it; the cell centres are blends of the edge nodes).
  2D group "annulus".
* scenarios/two_layer.msh: a soft tread (ri_t = 1.6 .. ro = 2) over a stiffer core
  (ri = 0.5 .. 1.6), unstructured 9-node quadrilaterals, 2D groups "core" and "tread".
* scenarios/footprint_refined.msh: the annulus ri = 1, ro = 2 with unstructured 9-node
  quadrilaterals of size `h_fine` near the road (the bottom of the cylinder) growing to
  `h_coarse` away from it; 2D group "rubber".
"""
import math
import os
import sys

import gmsh

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def init(name):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.add(name)


def structured_annulus(path, order, binary=False, ri=1.0, ro=2.0, n_r=2, n_theta=16):
    init("annulus")
    geo = gmsh.model.geo
    c = geo.addPoint(0, 0, 0)
    radii = [ri + (ro - ri) * j / n_r for j in range(n_r + 1)]
    angles = [-math.pi / 2 + k * math.pi / 2 for k in range(4)]
    pts = [[geo.addPoint(r * math.cos(t), r * math.sin(t), 0) for t in angles] for r in radii]
    arcs = [[geo.addCircleArc(pts[j][k], c, pts[j][(k + 1) % 4]) for k in range(4)]
            for j in range(n_r + 1)]
    rad = [[geo.addLine(pts[j][k], pts[j + 1][k]) for k in range(4)] for j in range(n_r)]
    surfs = []
    for j in range(n_r):
        for k in range(4):
            loop = geo.addCurveLoop([rad[j][k], arcs[j + 1][k], -rad[j][(k + 1) % 4], -arcs[j][k]])
            surfs.append(geo.addPlaneSurface([loop]))
    geo.synchronize()
    per_quadrant = n_theta // 4
    for row in arcs:
        for a in row:
            gmsh.model.mesh.setTransfiniteCurve(a, per_quadrant + 1)
    for row in rad:
        for l in row:
            gmsh.model.mesh.setTransfiniteCurve(l, 2)
    for s in surfs:
        gmsh.model.mesh.setTransfiniteSurface(s)
        gmsh.model.mesh.setRecombine(2, s)
    gmsh.model.addPhysicalGroup(1, arcs[0], name="hub")
    gmsh.model.addPhysicalGroup(1, arcs[-1], name="contact")
    gmsh.model.addPhysicalGroup(2, surfs, name="annulus")
    gmsh.model.mesh.generate(2)
    if order == 2:
        gmsh.model.mesh.setOrder(2)
    # Snap every node onto the generator's polar grid (radii ri + (ro - ri) i / (order n_r),
    # angles -pi/2 + 2 pi k / (order n_theta)): Gmsh's transfinite arcs put nodes within ~1e-9 of
    # it, and it places the cell centres by blending the edge nodes.
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    dr = (ro - ri) / (order * n_r)
    dt = 2 * math.pi / (order * n_theta)
    for k, tag in enumerate(tags):
        x, y = xyz[3 * k], xyz[3 * k + 1]
        i = round((math.hypot(x, y) - ri) / dr)
        l = round((math.atan2(y, x) + math.pi / 2) / dt)
        r, t = ri + dr * i, -math.pi / 2 + dt * l
        gmsh.model.mesh.setNode(int(tag), [r * math.cos(t), r * math.sin(t), 0.0], [])
    gmsh.option.setNumber("Mesh.Binary", 1 if binary else 0)
    gmsh.write(path)
    gmsh.finalize()


def two_layer(path, ri=0.5, rm=1.6, ro=2.0, h_core=0.6, h_tread=0.3):
    init("two_layer")
    occ = gmsh.model.occ
    d_out = occ.addDisk(0, 0, 0, ro, ro)
    d_mid = occ.addDisk(0, 0, 0, rm, rm)
    d_in = occ.addDisk(0, 0, 0, ri, ri)
    tread, _ = occ.cut([(2, d_out)], [(2, d_mid)], removeTool=False)
    core, _ = occ.cut([(2, d_mid)], [(2, d_in)])
    occ.synchronize()
    tread_s = [s for _, s in tread]
    core_s = [s for _, s in core]
    curves = gmsh.model.getBoundary([(2, s) for s in tread_s + core_s], oriented=False,
                                    combined=False)

    def radius(tag):
        x0, y0, _, x1, y1, _ = gmsh.model.getBoundingBox(1, tag)
        return 0.5 * (x1 - x0)

    ids = sorted({abs(t) for _, t in curves})
    hub = [t for t in ids if abs(radius(t) - ri) < 1e-6]
    outer = [t for t in ids if abs(radius(t) - ro) < 1e-6]
    gmsh.model.addPhysicalGroup(1, hub, name="hub")
    gmsh.model.addPhysicalGroup(1, outer, name="contact")
    gmsh.model.addPhysicalGroup(2, core_s, name="core")
    gmsh.model.addPhysicalGroup(2, tread_s, name="tread")
    gmsh.model.mesh.setSize(gmsh.model.getBoundary([(2, s) for s in core_s], recursive=True),
                            h_core)
    gmsh.model.mesh.setSize(gmsh.model.getBoundary([(2, s) for s in tread_s], recursive=True),
                            h_tread)
    for t in hub:
        gmsh.model.mesh.setSize([(0, p) for _, p in gmsh.model.getBoundary([(1, t)])], h_core)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 8)  # frontal-Delaunay for quads
    gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)  # blossom
    gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)  # all quadrilaterals
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    for c in ids:
        n = max(8, int(round(2 * math.pi * radius(c) / (h_core if radius(c) < rm - 1e-9 else h_tread))))
        gmsh.model.mesh.setTransfiniteCurve(c, n // 2 * 2 + 1)
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.setOrder(2)
    gmsh.write(path)
    gmsh.finalize()


def footprint_refined(path, ri=1.0, ro=2.0, h_fine=0.08, h_coarse=0.5, order=2):
    """Annulus refined toward the contact patch at the bottom (theta = -pi/2)."""
    init("footprint")
    occ = gmsh.model.occ
    outer = occ.addDisk(0, 0, 0, ro, ro)
    inner = occ.addDisk(0, 0, 0, ri, ri)
    ring, _ = occ.cut([(2, outer)], [(2, inner)])
    occ.synchronize()
    surf = [s for _, s in ring]
    curves = gmsh.model.getBoundary([(2, s) for s in surf], oriented=False)

    def radius(tag):
        x0, _, _, x1, _, _ = gmsh.model.getBoundingBox(1, tag)
        return 0.5 * (x1 - x0)

    ids = sorted({abs(t) for _, t in curves})
    gmsh.model.addPhysicalGroup(1, [t for t in ids if abs(radius(t) - ri) < 1e-6], name="hub")
    gmsh.model.addPhysicalGroup(1, [t for t in ids if abs(radius(t) - ro) < 1e-6], name="contact")
    gmsh.model.addPhysicalGroup(2, surf, name="rubber")
    # Size field: h_fine within the footprint region (a ball around the bottom point), growing
    # linearly to h_coarse.
    f = gmsh.model.mesh.field
    pt = occ.addPoint(0, -ro, 0)
    occ.synchronize()
    f.add("Distance", 1)
    f.setNumbers(1, "PointsList", [pt])
    f.add("Threshold", 2)
    f.setNumber(2, "InField", 1)
    f.setNumber(2, "SizeMin", h_fine)
    f.setNumber(2, "SizeMax", h_coarse)
    f.setNumber(2, "DistMin", 0.3)
    f.setNumber(2, "DistMax", 1.5)
    f.setAsBackgroundMesh(2)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 8)
    gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)
    gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.setOrder(order)
    gmsh.write(path)
    gmsh.finalize()


def triangles(path):
    """A small triangle mesh of the annulus (for the importer's error test: not quadrilaterals)."""
    init("triangles")
    occ = gmsh.model.occ
    ring, _ = occ.cut([(2, occ.addDisk(0, 0, 0, 2, 2))], [(2, occ.addDisk(0, 0, 0, 1, 1))])
    occ.synchronize()
    surf = [s for _, s in ring]
    curves = sorted({abs(t) for _, t in gmsh.model.getBoundary([(2, s) for s in surf], oriented=False)})
    gmsh.model.addPhysicalGroup(1, curves[:1], name="hub")
    gmsh.model.addPhysicalGroup(1, curves[1:], name="contact")
    gmsh.model.addPhysicalGroup(2, surf, name="rubber")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.8)
    gmsh.model.mesh.generate(2)
    gmsh.write(path)
    gmsh.finalize()


def main():
    tests = os.path.join(ROOT, "tests", "gmsh_data")
    scen = os.path.join(ROOT, "scenarios")
    os.makedirs(tests, exist_ok=True)
    structured_annulus(os.path.join(tests, "annulus_q1.msh"), 1)
    structured_annulus(os.path.join(tests, "annulus_q2.msh"), 2)
    structured_annulus(os.path.join(tests, "annulus_q2_binary.msh"), 2, binary=True)
    triangles(os.path.join(tests, "triangles.msh"))
    two_layer(os.path.join(scen, "two_layer.msh"))
    footprint_refined(os.path.join(scen, "footprint_refined.msh"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
