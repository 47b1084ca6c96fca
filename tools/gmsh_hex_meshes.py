"""Write the small hexahedral .msh 4.1 test meshes of tests/gmsh_data/ with the gmsh module.

ring_hex8.msh: the whole annulus 1 <= r <= 2 (4 x (3 x 4) x 2 hexahedra); annular_hex{8,27}.msh: the quarter annulus 1 <= r <= 2, 0 <= theta <= pi/2, swept along
x3 in [-0.25, 0.25] (3 x 4 x 2 hexahedra, transfinite); box_hex27_bin.msh: the box
[0, 2] x [0, 1] x [0, 0.5] (2 x 2 x 2 hexahedra, binary); tet_box.msh: tetrahedra (refused by the hexahedral reader). Physical groups: 2D "hub" (r = 1 or
x = 0), "outer" (r = 2 or x = 2), 3D "body".

Usage: python3 tools/gmsh_hex_meshes.py tests/gmsh_data
"""
import math
import sys

import gmsh


def annular(order, path):
    gmsh.clear()
    geo = gmsh.model.geo
    c = geo.addPoint(0, 0, -0.25)
    p = [geo.addPoint(1, 0, -0.25), geo.addPoint(2, 0, -0.25),
         geo.addPoint(0, 2, -0.25), geo.addPoint(0, 1, -0.25)]
    l0 = geo.addLine(p[0], p[1])
    a1 = geo.addCircleArc(p[1], c, p[2])
    l2 = geo.addLine(p[2], p[3])
    a3 = geo.addCircleArc(p[3], c, p[0])
    loop = geo.addCurveLoop([l0, a1, l2, a3])
    s = geo.addPlaneSurface([loop])
    geo.mesh.setTransfiniteCurve(l0, 4)
    geo.mesh.setTransfiniteCurve(l2, 4)
    geo.mesh.setTransfiniteCurve(a1, 5)
    geo.mesh.setTransfiniteCurve(a3, 5)
    geo.mesh.setTransfiniteSurface(s)
    geo.mesh.setRecombine(2, s)
    out = geo.extrude([(2, s)], 0, 0, 0.5, numElements=[2], recombine=True)
    geo.synchronize()
    vol = [t for d, t in out if d == 3][0]
    # extrude returns [top, volume, lateral surfaces in the order of the loop's curves]
    lateral = [t for d, t in out if d == 2][1:]
    gmsh.model.addPhysicalGroup(2, [lateral[3]], name="hub")
    gmsh.model.addPhysicalGroup(2, [lateral[1]], name="outer")
    gmsh.model.addPhysicalGroup(3, [vol], name="body")
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(order)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(path)


def ring(order, path):
    """The whole annulus 1 <= r <= 2 swept along x3 in [-0.25, 0.25]: four transfinite quarter
    patches (3 x 4 cells each), 2 cells across the width."""
    gmsh.clear()
    geo = gmsh.model.geo
    c = geo.addPoint(0, 0, -0.25)
    inner = [geo.addPoint(math.cos(k * math.pi / 2), math.sin(k * math.pi / 2), -0.25)
             for k in range(4)]
    outer = [geo.addPoint(2 * math.cos(k * math.pi / 2), 2 * math.sin(k * math.pi / 2), -0.25)
             for k in range(4)]
    radial = [geo.addLine(inner[k], outer[k]) for k in range(4)]
    arc_o = [geo.addCircleArc(outer[k], c, outer[(k + 1) % 4]) for k in range(4)]
    arc_i = [geo.addCircleArc(inner[(k + 1) % 4], c, inner[k]) for k in range(4)]
    surfaces = []
    for k in range(4):
        loop = geo.addCurveLoop([radial[k], arc_o[k], -radial[(k + 1) % 4], arc_i[k]])
        s = geo.addPlaneSurface([loop])
        geo.mesh.setTransfiniteCurve(radial[k], 4)
        geo.mesh.setTransfiniteCurve(arc_o[k], 5)
        geo.mesh.setTransfiniteCurve(arc_i[k], 5)
        geo.mesh.setTransfiniteSurface(s)
        geo.mesh.setRecombine(2, s)
        surfaces.append(s)
    out = geo.extrude([(2, s) for s in surfaces], 0, 0, 0.5, numElements=[2], recombine=True)
    geo.synchronize()
    # extrude returns, per surface: top, volume, then the lateral surfaces in the order of
    # the loop's curves (radial, outer arc, radial, inner arc)
    vols, hub, rim = [], [], []
    for k in range(4):
        chunk = out[6 * k:6 * k + 6]
        vols.append(chunk[1][1])
        rim.append(chunk[3][1])
        hub.append(chunk[5][1])
    gmsh.model.addPhysicalGroup(2, hub, name="hub")
    gmsh.model.addPhysicalGroup(2, rim, name="outer")
    gmsh.model.addPhysicalGroup(3, vols, name="body")
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(order)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(path)


def box(path):
    gmsh.clear()
    occ = gmsh.model.occ
    v = occ.addBox(0, 0, 0, 2, 1, 0.5)
    occ.synchronize()
    for d, t in gmsh.model.getEntities(1):
        gmsh.model.mesh.setTransfiniteCurve(t, 3)
    for _, t in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(t)
        gmsh.model.mesh.setRecombine(2, t)
    gmsh.model.mesh.setTransfiniteVolume(v)
    faces = {}
    for _, t in gmsh.model.getEntities(2):
        x = gmsh.model.occ.getCenterOfMass(2, t)
        faces[tuple(round(q, 6) for q in x)] = t
    hub = [t for x, t in faces.items() if abs(x[0]) < 1e-9]
    outer = [t for x, t in faces.items() if abs(x[0] - 2) < 1e-9]
    gmsh.model.addPhysicalGroup(2, hub, name="hub")
    gmsh.model.addPhysicalGroup(2, outer, name="outer")
    gmsh.model.addPhysicalGroup(3, [v], name="body")
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 1)
    gmsh.write(path)




def tet_box(path):
    """A tetrahedral box: an element type the hexahedral reader refuses."""
    gmsh.clear()
    v = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [v], name="body")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.8)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(path)


if __name__ == "__main__":
    d = sys.argv[1] if len(sys.argv) > 1 else "tests/gmsh_data"
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    annular(1, f"{d}/annular_hex8.msh")
    annular(2, f"{d}/annular_hex27.msh")
    ring(1, f"{d}/ring_hex8.msh")
    box(f"{d}/box_hex27_bin.msh")
    tet_box(f"{d}/tet_box.msh")
    gmsh.finalize()
