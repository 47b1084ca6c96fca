#!/usr/bin/env python3
"""Peer sparse LU solvers on a tangent written by tread (a benchmark, not a test).

    python tools/lu_peer.py A.mtx [b.mtx]

A.mtx: MatrixMarket coordinate real general (``tread run --mode steady --dump-matrix A.mtx``
or ``tread-bench-lu --dump DIR``); b.mtx: the right-hand side (MatrixMarket array). Needs scipy;
scikit-umfpack (``pip install scikit-umfpack``) adds UMFPACK. Run it in a virtual environment.

For each solver and ordering: factorization CPU time (median of 3), solve time, stored factor
entries nnz(L)+nnz(U) and fill (that over nnz(A)), and the relative residual ||Ax-b||/||b||.
Prints a Markdown table. Single-threaded timings are what the Rust benchmark compares with:
set OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 (the tool sets them when unset).
"""
import os
import sys
import time

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402
import scipy.io  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402


def median_time(f, repeats=3):
    # CPU time of this thread (the solvers are single-threaded), like tread-bench-lu: immune to
    # other load on a shared machine.
    ts, out = [], None
    for _ in range(repeats):
        t = time.thread_time()
        out = f()
        ts.append(time.thread_time() - t)
    return float(np.median(ts)), out


def superlu(a, b, permc):
    t_fac, lu = median_time(lambda: spla.splu(a, permc_spec=permc))
    t = time.thread_time()
    x = lu.solve(b)
    t_sol = time.thread_time() - t
    return t_fac, t_sol, lu.L.nnz + lu.U.nnz, x


def umfpack(a, b):
    import scikits.umfpack as um

    a = a.tocsc()
    a.indices = a.indices.astype(np.int64)
    a.indptr = a.indptr.astype(np.int64)
    ctx = um.UmfpackContext("dl")

    def factor():
        ctx.symbolic(a)
        ctx.numeric(a)

    t_fac, _ = median_time(factor)
    t = time.thread_time()
    x = ctx.solve(um.UMFPACK_A, a, b, autoTranspose=True)
    t_sol = time.thread_time() - t
    # nnz of the factors: extracted from the last numeric factorization.
    try:
        L, U, _, _, _, _ = ctx.lu(a)
        nnz = L.nnz + U.nnz
    except Exception:  # noqa: BLE001 - report the timing even when extraction fails
        nnz = None
    return t_fac, t_sol, nnz, x


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        sys.exit(2)
    a = sp.csc_matrix(scipy.io.mmread(sys.argv[1]))
    n = a.shape[0]
    if len(sys.argv) > 2:
        b = np.asarray(scipy.io.mmread(sys.argv[2])).reshape(-1)
    else:
        b = np.ones(n)
    nnz_a = a.nnz
    bnorm = max(np.linalg.norm(b), np.finfo(float).tiny)
    print(f"n = {n}, nnz(A) = {nnz_a}, scipy {scipy.__version__}")
    print("| solver | ordering | factor (s) | solve (s) | nnz(L+U) | fill | ||Ax-b||/||b|| |")
    print("|---|---|---|---|---|---|---|")
    runs = [("SuperLU", p, lambda p=p: superlu(a, b, p)) for p in ("COLAMD", "MMD_AT_PLUS_A")]
    runs.append(("UMFPACK", "default (auto)", lambda: umfpack(a, b)))
    for name, order, f in runs:
        try:
            t_fac, t_sol, nnz, x = f()
        except ImportError:
            print(f"| {name} | {order} | not installed | | | | |")
            continue
        except Exception as e:  # noqa: BLE001 - a failed peer is reported, not fatal
            print(f"| {name} | {order} | failed: {e} | | | | |")
            continue
        res = np.linalg.norm(a @ x - b) / bnorm
        fill = f"{nnz / nnz_a:.2f}" if nnz else "-"
        print(f"| {name} | {order} | {t_fac:.3f} | {t_sol:.4f} | {nnz if nnz else '-'} | {fill} | {res:.1e} |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
