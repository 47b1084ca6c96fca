"""Peer run of the lid-driven cavity at Re = 1000 with scikit-fem, for comparison with tread's
`cavity_refinement` example (docs/adaptivity.md, "Against a peer code").

Steady incompressible Navier–Stokes on [0, 1]², lid moving in +x on y = 1, ν = 1/Re, the same
weak form as `tread::adapt::navier_stokes`: ν (∇u, ∇v) + ((u·∇)u, v) − (p, div v) − (q, div u)
= 0, Taylor–Hood Q2/Q1 on a uniform n × n grid of squares (`--element quad`, the pair tread
uses) or P2/P1 on the same squares cut into two triangles each (`--element tri`). Newton with
the exact Jacobian and sparse LU (SciPy's SuperLU), continuation 100 → 400 → 1000, each from
the previous solution, converged when ‖R‖∞ ≤ 1e-10 over the free equations; a step that does not
reduce the residual is halved, as in tread. One pressure dof (the vertex at the origin) is
pinned to 0.

Lid data, as tread's `CavityLid::Discontinuous` builds them: u = 1 at every lid node strictly
between the top corners, u = 0 at the corners (they belong to the walls). On the two lid edges
that end at a corner, the velocity space's boundary projection (vertex values, then the edge
mode from −∫ (g − vertex part) b″ ds, which for a quadratic bubble keeps the edge integral of
g) makes the quadratic trace through 0 at the corner and 1 at the other end with the same mean
as g = 1 on the open edge: its midside value is 5/4 (`--corner-midside 1.25`, the default).
`--corner-midside 0.5` gives the linear ramp and `1` the nodal interpolant instead.

Reported per mesh: free equations (velocity and pressure, pinned dof excluded: the count tread
prints as n_eq), Newton iterations, wall time (mesh, spaces, the three Newton solves, stream
function and its minimum; the centreline evaluation is not timed), ψ_min and its relative error
against Botella & Peyret (1998), the largest deviations of u(0.5, y) and v(x, 0.5) from their
tables. The stream function solves −Δψ = ∂v/∂x − ∂u/∂y with ψ = 0 on ∂Ω in the scalar degree-2
space; ψ_min is the smallest value on a 9 × 9 grid per cell, polished by Nelder–Mead in the
four cells with the smallest samples.

Usage: python tools/cavity_peer.py [--element quad|tri] [--corner-midside V] [--json FILE] [n ...]
(n: cells per side, default 16 32 64). Without scikit-fem it prints a skip message and exits 0.
"""
import argparse
import json
import sys
import time

try:
    import numpy as np
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    from scipy.optimize import minimize
    from skfem import (Basis, BilinearForm, ElementQuad1, ElementQuad2, ElementTriP1,
                       ElementTriP2, LinearForm, MeshQuad, MeshTri, asm)
    from skfem.helpers import dot, grad
except ImportError as e:  # pragma: no cover - depends on the environment
    print(f"cavity_peer: skipped, scikit-fem/SciPy not importable ({e}); "
          "install with `pip install scikit-fem scipy` in a virtual environment")
    sys.exit(0)

# Botella & Peyret, Comput. Fluids 27 (1998), Re = 1000, lid moving in +x
# (src/adapt/cavity_reference.rs).
BP_Y = [0.0547, 0.0625, 0.0703, 0.1016, 0.1719, 0.2813, 0.4531, 0.5, 0.6172, 0.7344, 0.8516,
        0.9531, 0.9609, 0.9688, 0.9766]
BP_U = [-0.1812881, -0.2023300, -0.2228955, -0.3004561, -0.3885690, -0.2803696, -0.1081999,
        -0.0620561, 0.0570178, 0.1886747, 0.3372212, 0.4723329, 0.5169277, 0.5808359, 0.6644227]
BP_X = [0.0625, 0.0703, 0.0781, 0.0938, 0.1563, 0.2266, 0.2344, 0.5, 0.8047, 0.8594, 0.9063,
        0.9453, 0.9531, 0.9609, 0.9688]
BP_V = [0.2807056, 0.2962703, 0.3099097, 0.3330442, 0.3769189, 0.3339924, 0.3253592, 0.0257995,
        -0.3202137, -0.4264545, -0.5264392, -0.4103754, -0.3553213, -0.2936869, -0.2279225]
BP_PSI_MIN = -0.1189366
TOL = 1e-10


@BilinearForm
def laplace(u, v, w):
    return dot(grad(u), grad(v))


@BilinearForm
def advect(u, v, w):
    # (U·∇)δu · v for one component.
    return (w['u1'] * grad(u)[0] + w['u2'] * grad(u)[1]) * v


@BilinearForm
def mass_weighted(u, v, w):
    return w['c'] * u * v


@BilinearForm
def div_x(u, q, w):
    return -q * grad(u)[0]


@BilinearForm
def div_y(u, q, w):
    return -q * grad(u)[1]


def mesh_of(n, element):
    t = np.linspace(0.0, 1.0, n + 1)
    if element == 'quad':
        return MeshQuad.init_tensor(t, t), ElementQuad2(), ElementQuad1()
    return MeshTri.init_tensor(t, t), ElementTriP2(), ElementTriP1()


def lid_values(vb, n, corner_midside):
    """Dirichlet values of u on the boundary dofs of the scalar velocity basis."""
    bd = vb.get_dofs().flatten()
    x, y = vb.doflocs[0, bd], vb.doflocs[1, bd]
    g = np.zeros(len(bd))
    on_lid = (y > 1.0 - 1e-12) & (x > 1e-12) & (x < 1.0 - 1e-12)
    g[on_lid] = 1.0
    h = 1.0 / n
    corner_mid = on_lid & ((np.abs(x - 0.5 * h) < 1e-9) | (np.abs(x - (1.0 - 0.5 * h)) < 1e-9))
    g[corner_mid] = corner_midside
    return bd, g


def solve_cavity(n, element, corner_midside, reynolds=(100.0, 400.0, 1000.0)):
    t0 = time.perf_counter()
    mesh, ev, ep = mesh_of(n, element)
    # Quadrature exact for the convection term: degree 7 per direction on squares (4 × 4
    # Gauss points, as tread), degree 5 on triangles.
    vb = Basis(mesh, ev, intorder=7 if element == 'quad' else 5)
    pb = vb.with_element(ep)
    nv, npr = vb.N, pb.N
    bd, g = lid_values(vb, n, corner_midside)
    # Unknowns [u1, u2, p]; fixed: boundary velocity dofs and one pressure dof.
    pin = int(np.argmin(pb.doflocs[0] ** 2 + pb.doflocs[1] ** 2))
    fixed = np.concatenate([bd, nv + bd, [2 * nv + pin]])
    free = np.setdiff1d(np.arange(2 * nv + npr), fixed)
    x = np.zeros(2 * nv + npr)
    x[bd] = g
    L = asm(laplace, vb)
    Bx = asm(div_x, vb, pb)
    By = asm(div_y, vb, pb)
    B = sp.hstack([Bx, By]).tocsr()  # (q, −div u)

    def system(x, nu, with_jacobian):
        u1, u2 = x[:nv], x[nv:2 * nv]
        w1, w2 = vb.interpolate(u1), vb.interpolate(u2)
        C = asm(advect, vb, u1=w1, u2=w2)
        A1 = nu * L + C
        r1 = A1 @ u1 + Bx.T @ x[2 * nv:]
        r2 = A1 @ u2 + By.T @ x[2 * nv:]
        rp = B @ x[:2 * nv]
        r = np.concatenate([r1, r2, rp])
        if not with_jacobian:
            return r, None
        g1, g2 = w1.grad, w2.grad
        K11 = asm(mass_weighted, vb, c=g1[0])
        K12 = asm(mass_weighted, vb, c=g1[1])
        K21 = asm(mass_weighted, vb, c=g2[0])
        K22 = asm(mass_weighted, vb, c=g2[1])
        J = sp.bmat([[A1 + K11, K12, Bx.T], [K21, A1 + K22, By.T], [Bx, By, None]]).tocsr()
        return r, J

    iterations = []
    for re in reynolds:
        nu = 1.0 / re
        r, J = system(x, nu, True)
        rn = np.abs(r[free]).max()
        its = 0
        while rn > TOL:
            if its >= 30:
                raise RuntimeError(f"Newton did not converge at Re = {re}: residual {rn:.3e}")
            Jf = J[free][:, free].tocsc()
            d = spla.spsolve(Jf, -r[free])
            x0 = x.copy()
            lam = 1.0
            for _ in range(9):
                x = x0.copy()
                x[free] += lam * d
                rt, _ = system(x, nu, False)
                rtn = np.abs(rt[free]).max()
                if np.isfinite(rtn) and (rtn < rn or lam < 0.01):
                    break
                lam *= 0.5
            r, J = system(x, nu, True)
            rn = np.abs(r[free]).max()
            its += 1
        iterations.append(its)
    u1, u2 = x[:nv], x[nv:2 * nv]
    psi, sb = stream_function(mesh, ev, u1, u2)
    at, pm = psi_min(mesh, sb, psi)
    wall = time.perf_counter() - t0
    return {
        'n': n,
        'element': element,
        'n_eq': int(len(free)),
        'newton': int(sum(iterations)),
        'wall_s': wall,
        'psi_min': float(pm),
        'psi_at': [float(at[0]), float(at[1])],
        'psi_rel_err': float(abs(pm - BP_PSI_MIN) / abs(BP_PSI_MIN)),
        'max_du': centreline(vb, u1, [[0.5] * len(BP_Y), BP_Y], BP_U),
        'max_dv': centreline(vb, u2, [BP_X, [0.5] * len(BP_X)], BP_V),
    }


def stream_function(mesh, ev, u1, u2):
    sb = Basis(mesh, ev, intorder=7 if isinstance(mesh, MeshQuad) else 5)
    w1, w2 = sb.interpolate(u1), sb.interpolate(u2)

    @LinearForm
    def vorticity(v, w):
        return (w['u2'].grad[0] - w['u1'].grad[1]) * v

    K = asm(laplace, sb)
    f = asm(vorticity, sb, u1=w1, u2=w2)
    bd = sb.get_dofs().flatten()
    free = np.setdiff1d(np.arange(sb.N), bd)
    psi = np.zeros(sb.N)
    psi[free] = spla.spsolve(K[free][:, free].tocsc(), f[free])
    return psi, sb


def psi_min(mesh, sb, psi):
    """Smallest ψ: 9 × 9 samples per cell of the reference square (the triangle's half on
    triangles), then Nelder–Mead inside each of the four best cells."""
    elem = sb.elem
    s = np.linspace(0.0, 1.0, 9)
    X, Y = np.meshgrid(s, s)
    ref = np.array([X.ravel(), Y.ravel()])
    tri = isinstance(mesh, MeshTri)
    if tri:
        ref = ref[:, ref[0] + ref[1] <= 1.0 + 1e-12]

    def shape(r):
        return np.array([elem.lbasis(r, i)[0] for i in range(sb.Nbfun)])

    coef = psi[sb.element_dofs]  # (Nbfun, n_cells)
    vals = coef.T @ shape(ref)   # (n_cells, n_samples)
    best = np.argsort(vals.min(axis=1))[:4]
    found = (None, np.inf)
    for k in best:
        j = int(np.argmin(vals[k]))

        def obj(r, k=k):
            if np.any(r < 0.0) or np.any(r > 1.0) or (tri and r[0] + r[1] > 1.0):
                return np.inf
            return float(coef[:, k] @ shape(r.reshape(2, 1))[:, 0])

        res = minimize(obj, ref[:, j], method='Nelder-Mead',
                       options={'xatol': 1e-10, 'fatol': 1e-15, 'maxiter': 4000})
        r, v = (res.x, res.fun) if res.fun < vals[k, j] else (ref[:, j], vals[k, j])
        if v < found[1]:
            at = sb.mapping.F(r.reshape(2, 1), tind=np.array([k]))[:, 0, 0]
            found = (at, v)
    return found


def centreline(vb, u, pts, ref):
    vals = vb.interpolator(u)(np.array(pts, dtype=float))
    return float(np.max(np.abs(vals - np.array(ref))))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--element', choices=['quad', 'tri'], default='quad')
    ap.add_argument('--corner-midside', type=float, default=1.25)
    ap.add_argument('--json')
    ap.add_argument('n', nargs='*', type=int, default=[16, 32, 64])
    a = ap.parse_args()
    rows = []
    print(f"scikit-fem, {'Q2/Q1' if a.element == 'quad' else 'P2/P1'}, "
          f"corner midside {a.corner_midside}")
    print("   n   n_eq  newton  time_s   psi_min     x       y       rel_err   max|du|   max|dv|")
    for n in a.n:
        if n < 2:
            print(f"cells per side must be at least 2, got {n}", file=sys.stderr)
            return 2
        r = solve_cavity(n, a.element, a.corner_midside)
        rows.append(r)
        print(f"{n:4d} {r['n_eq']:6d} {r['newton']:6d} {r['wall_s']:7.2f}  {r['psi_min']:.7f} "
              f"{r['psi_at'][0]:.4f}  {r['psi_at'][1]:.4f}  {r['psi_rel_err']:.3e} "
              f"{r['max_du']:.3e} {r['max_dv']:.3e}", flush=True)
    if a.json:
        with open(a.json, 'w') as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
