#!/usr/bin/env python3
"""How well an assembled Newton matrix preconditions the exact steady tangent.

Reads the exact tangent J and a preconditioning matrix P (MatrixMarket, as written by
`tread run SCENE --mode steady --dump-matrix FILE`) and prints, for right-preconditioned GMRES
on J with the LU of P, the number of iterations to a relative residual of 1e-6 (random
right-hand side), and, for n <= 12,000, the spectrum of P^-1 J: how many eigenvalues lie
farther than 0.2 and 0.5 from 1 and the range of |lambda|.

    tread run scenarios/oden_hollow_cylinder.toml --mode steady --set mesh.n_r=4 \
        --set mesh.n_theta=64 --set 'solver.damping_tangent="assembled"' --dump-matrix J.mtx
    tread run ... --set 'solver.damping_tangent="matrix_free"' --dump-matrix P.mtx
    python3 tools/precond_spectrum.py J.mtx P.mtx

The two runs converge to the same steady state (to the solver's tolerance), so the matrices
are taken at the same state up to that tolerance. Needs numpy and scipy.
"""
import sys

import numpy as np
import scipy.io as sio
import scipy.linalg as la
import scipy.sparse.linalg as sla


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    J = sio.mmread(argv[1]).tocsc()
    P = sio.mmread(argv[2]).tocsc()
    if J.shape != P.shape:
        print(f"shapes differ: {J.shape} and {P.shape}", file=sys.stderr)
        return 2
    n = J.shape[0]
    print(f"n = {n}, nnz(J) = {J.nnz}, nnz(P) = {P.nnz}")
    lu = sla.splu(P, permc_spec="COLAMD")
    b = np.random.default_rng(0).standard_normal(n)
    count = [0]

    def tick(_):
        count[0] += 1

    x, _ = sla.gmres(J, b, M=sla.LinearOperator((n, n), matvec=lu.solve), rtol=1e-6,
                     restart=400, maxiter=1, callback=tick, callback_type="pr_norm")
    res = np.linalg.norm(J @ x - b) / np.linalg.norm(b)
    print(f"GMRES with the LU of P: {count[0]} iterations, |b - J x| / |b| = {res:.2e}")
    if n > 12000:
        print("spectrum skipped (n > 12,000)")
        return 0
    ev = la.eigvals(la.solve(P.toarray(), J.toarray()))
    d = np.abs(ev - 1.0)
    print(f"eigenvalues of P^-1 J: {np.sum(d > 0.5)} of {n} farther than 0.5 from 1 "
          f"({100 * np.mean(d > 0.5):.1f} %), {np.sum(d > 0.2)} farther than 0.2; "
          f"|lambda| in [{np.abs(ev).min():.3f}, {np.abs(ev).max():.3f}]")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
