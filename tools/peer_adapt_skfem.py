"""Peer run for tread-bench-adapt: the L-shape problem with scikit-fem.

-Δu = 0 on (-1, 1)² minus [0, 1) × (-1, 0], u = r^{2/3} sin(2θ/3) (θ from the +x axis in
[0, 3π/2]) on the boundary; adaptive P1 and P2 triangles (scikit-fem's conforming refinement of
the marked triangles), explicit residual estimator (flux jumps ½ h_E ‖[∂n u_h]‖²),
Dörfler marking (θ = 0.5 unless --fraction) on the squared indicators. Records per adaptive step: free DOFs,
relative energy error ‖∇(u - u_h)‖ / |u|₁ and the wall time of the step (assemble, solve,
estimate, mark, refine; the exact error is not timed).

Usage: python peer_adapt_skfem.py --out FILE.json [--smoke] [--fraction THETA]
"""
import argparse
import json
import time

import numpy as np
from skfem import (Basis, ElementTriP1, ElementTriP2, Functional, InteriorFacetBasis,
                   MeshTri, asm, condense, solve)
from skfem.helpers import dot, grad
from skfem.models.poisson import laplace

U_NORM_SQ = 1.8362266618751582  # |u|²₁, boundary integral (tests/adapt_lshape.rs)


def exact(x, y):
    r = np.sqrt(x * x + y * y)
    th = np.arctan2(y, x)
    th = np.where(th < 0, th + 2 * np.pi, th)
    return r ** (2 / 3) * np.sin(2 * th / 3)


def exact_grad(x, y):
    r = np.maximum(np.sqrt(x * x + y * y), 1e-300)
    th = np.arctan2(y, x)
    th = np.where(th < 0, th + 2 * np.pi, th)
    a = 2 / 3 * r ** (-1 / 3)
    ur, ut = a * np.sin(2 * th / 3), a * np.cos(2 * th / 3)
    c, s = np.cos(th), np.sin(th)
    return ur * c - ut * s, ur * s + ut * c


def lshape_mesh():
    p = np.array([[-1, -1], [0, -1], [-1, 0], [0, 0], [1, 0], [-1, 1], [0, 1], [1, 1]], float).T
    t = np.array([[0, 1, 3], [0, 3, 2], [2, 3, 6], [2, 6, 5], [3, 4, 7], [3, 7, 6]]).T
    return MeshTri(p, t)


@Functional
def err_form(w):
    gx, gy = exact_grad(w.x[0], w.x[1])
    return (gx - w['uh'].grad[0]) ** 2 + (gy - w['uh'].grad[1]) ** 2


def estimate(basis, uh, order):
    m = basis.mesh
    # Jump terms only: f = 0 and Δu_h ≡ 0 for P1; for P2 the element residual h²‖Δu_h‖² is
    # omitted (jumps dominate for this harmonic problem).
    fb = [InteriorFacetBasis(m, basis.elem, side=i, intorder=2 * order) for i in (0, 1)]
    w = {'u' + str(i + 1): fb[i].interpolate(uh) for i in (0, 1)}

    @Functional
    def jump(w):
        h = w.h
        n = w.n
        d1 = dot(grad(w['u1']), n)
        d2 = dot(grad(w['u2']), n)
        return h * (d1 - d2) ** 2

    eta_e = jump.elemental(fb[0], **w)
    tmp = np.zeros(m.facets.shape[1])
    np.add.at(tmp, fb[0].find, eta_e)
    eta_e = np.sum(0.5 * tmp[m.t2f], axis=0)
    return eta_e


def dorfler(eta2, theta=0.5):
    idx = np.argsort(-eta2)
    c = np.cumsum(eta2[idx])
    k = int(np.searchsorted(c, theta * c[-1])) + 1
    return idx[:k]


def run(order, target, max_dofs, theta):
    elem = ElementTriP1() if order == 1 else ElementTriP2()
    m = lshape_mesh().refined(1)
    steps = []
    while True:
        t0 = time.perf_counter()
        basis = Basis(m, elem, intorder=2 * order)
        A = asm(laplace, basis)
        b = np.zeros(basis.N)
        D = basis.get_dofs().all()
        x = np.zeros(basis.N)
        x[D] = exact(*basis.doflocs[:, D])
        uh = solve(*condense(A, b, x=x, D=D))
        t_solve = time.perf_counter() - t0
        # Exact error (not timed), higher-order quadrature.
        eb = Basis(m, elem, intorder=8)
        err = np.sqrt(err_form.assemble(eb, uh=eb.interpolate(uh)) / U_NORM_SQ)
        n_free = basis.N - len(D)
        t1 = time.perf_counter()
        done = err < target or n_free > max_dofs
        if not done:
            eta2 = estimate(basis, uh, order)
            m = m.refined(dorfler(eta2, theta))
        dt = t_solve + time.perf_counter() - t1
        steps.append({'n': int(n_free), 'rel_error': float(err), 'time': dt})
        if done:
            break
    return steps


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--out', required=True)
    ap.add_argument('--smoke', action='store_true')
    ap.add_argument('--fraction', type=float, default=0.5)
    a = ap.parse_args()
    if not 0.0 < a.fraction <= 1.0:
        ap.error(f'--fraction must be in (0, 1], got {a.fraction}')
    t1, t2 = (3e-2, 3e-3) if a.smoke else (1e-3, 1e-5)
    cap = 20000 if a.smoke else 400000
    out = [
        {'name': f'scikit-fem P1 (residual, Dörfler {a.fraction})',
         'steps': run(1, t1, cap, a.fraction)},
        {'name': f'scikit-fem P2 (residual, Dörfler {a.fraction})',
         'steps': run(2, t2, cap, a.fraction)},
    ]
    with open(a.out, 'w') as f:
        json.dump(out, f)


if __name__ == '__main__':
    main()
