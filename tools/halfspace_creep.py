#!/usr/bin/env python3
"""Half-space reference for steady rolling of a Hertz ellipse (numpy/scipy only, independent of tread).

Kalker's linear theory (full adhesion, vanishing creepage) for an ellipse with semi-axes a (rolling
direction x) and b (lateral y):

    F_x = -G a b C11 xi_x,      F_y = -G a b C22 xi_y - G (ab)^(3/2) C23 phi,

with xi_x, xi_y the longitudinal and lateral creepages (rigid slip velocity over the rolling
speed V) and phi the spin creepage (spin about the contact normal over V, per length).

Method (boundary elements, as in Kalker's CONTACT): a uniform grid of dx x dy cells over the
rectangle [-a, a] x [-b, b]; the cells whose centre lies inside the ellipse carry piecewise-constant
tractions q = (q_x, q_y) (on body 1). The relative surface displacement u = u1 - u2 of the cell
centres is u = A q with the Cerruti influence of a uniformly loaded rectangle (closed form below).
Material flows through the contact in +x here (it enters at the leading edge x = -a), so the
steady slip per unit rolling speed is

    s = xi + (-phi y, phi x) + du/dx,

discretised upwind as in CONTACT's steady rolling: du/dx at cell I is (u_I - u_I')/dx with I' the
cell at x - dx (the displacement there is computed whether or not I' is in contact). The linear
theory solves s = 0 in every contact cell (the traction then vanishes at the leading edge and is
square-root singular at the trailing edge). The forces are sums of q over the cells.

The grid converges at first order in the cell size (upwind difference, staircase boundary):
the coefficients are computed on several grids, with ab replaced by the discrete area / pi, and
extrapolated by a least-squares fit C(h) = C0 + c1 h + c2 h^2 in h = 1/N.

Combined modulus. For one elastic half-space, a tangential point force Q on its surface moves
the surface by (Johnson, Contact Mechanics, eq. 3.86a)

    u_x = Q / (2 pi G1) [ (1 - nu1) / r + nu1 x^2 / r^3 ],

and by the analogous expressions for u_y and the cross term nu1 x y / r^3. Kalker writes the
relative displacement of two bodies carrying opposite tractions as

    u = u1 - u2 = Q / (pi G) [ (1 - nu) / r + nu x^2 / r^3 ],   1/G = (1/G1 + 1/G2) / 2,
    nu / G = (nu1 / G1 + nu2 / G2) / 2,

so two identical bodies give G = G1, nu = nu1 (each deforms by half). A rigid counter-body
(1/G2 = 0) gives u = u1 = Q/(2 pi G1)[...] = Q/(pi (2 G1))[...], that is G = 2 G1 and nu = nu1: the
creep forces of an elastic wheel on a rigid road are F = -(2 G_wheel) a b C xi, twice those
of the same wheel on an identical elastic road. The normal-tangential coupling constant
beta = [(1 - 2 nu1)/G1 - (1 - 2 nu2)/G2] / (2 [(1 - nu1)/G1 + (1 - nu2)/G2]) vanishes for an
incompressible body on a rigid road (nu1 = 1/2, 1/G2 = 0), so the normal problem is Hertz's and
the tangential problem is the one solved here, uncoupled, with nu = 1/2 in the influence.

Saturation (``--curve``): the same grid with Coulomb's law |q| <= mu p (Hertz pressure p of the
ellipse, N = 2/3 pi a b p0): in stick s = 0, in slip q = -mu p s/|s|
(written q = proj(q - r s) on the disc of radius mu p, solved by the semismooth Newton method from
the previous creepage's solution).

Orientation: Kalker's tables take the material flowing toward -x. The mirror x -> -x keeps every
y component and reverses the sense of a spin about the normal, so C11 and C22 are the same in
both orientations and C23 changes sign; C23 is reported in Kalker's orientation (positive). The lateral force against
the lateral creepage xi_y = tan(alpha) is printed with the brush-model bound
F = mu N [1 - (1 - psi)^3], psi = min(1, k |xi| / (3 mu N)), of the same initial stiffness
k = G a b C22 (Johnson, Contact Mechanics, §8.4, the simplest saturation law with the linear
theory's slope).

Usage:
    python3 tools/halfspace_creep.py                 # the circle, nu = 1/2, against Kalker's table
    python3 tools/halfspace_creep.py --check-table   # more a/b and nu against the table
    python3 tools/halfspace_creep.py --curve --mu 1  # lateral force against xi_y up to full sliding
"""

import argparse
import sys
import time

import numpy as np
from scipy.sparse.linalg import LinearOperator, gmres

# Kalker (1990), "Three-dimensional elastic bodies in rolling contact", Table E.3: creepage
# coefficients of the linear theory for Hertz ellipses, as functions of g = min(a/b, b/a) and of
# nu in (0, 1/4, 1/2). Rows g = 0.1 ... 1.0. Columns: C11 (nu = 0, 1/4, 1/2), C22 (...),
# C23 (...). First block a/b = g <= 1, second block b/a = g (a >= b).
KALKER_G = [0.1 * k for k in range(1, 11)]
KALKER_A_LE_B = [
    [2.51, 3.31, 4.85, 2.51, 2.52, 2.53, 0.334, 0.473, 0.731],
    [2.59, 3.37, 4.81, 2.59, 2.63, 2.66, 0.483, 0.603, 0.809],
    [2.68, 3.44, 4.80, 2.68, 2.75, 2.81, 0.607, 0.715, 0.889],
    [2.78, 3.53, 4.82, 2.78, 2.88, 2.98, 0.720, 0.823, 0.977],
    [2.88, 3.62, 4.83, 2.88, 3.01, 3.14, 0.827, 0.929, 1.07],
    [2.98, 3.72, 4.91, 2.98, 3.14, 3.31, 0.930, 1.03, 1.18],
    [3.09, 3.81, 4.97, 3.09, 3.28, 3.48, 1.03, 1.14, 1.29],
    [3.19, 3.91, 5.05, 3.19, 3.41, 3.65, 1.13, 1.25, 1.40],
    [3.29, 4.01, 5.12, 3.29, 3.54, 3.82, 1.23, 1.36, 1.51],
    [3.40, 4.12, 5.20, 3.40, 3.67, 3.98, 1.33, 1.47, 1.63],
]
KALKER_A_GE_B = [
    [10.7, 11.7, 12.9, 10.7, 12.8, 16.0, 12.2, 14.6, 18.0],
    [6.96, 7.78, 8.82, 6.96, 8.14, 9.79, 5.72, 6.63, 7.89],
    [5.57, 6.34, 7.34, 5.57, 6.40, 7.51, 3.79, 4.32, 5.01],
    [4.84, 5.57, 6.57, 4.84, 5.48, 6.31, 2.88, 3.24, 3.70],
    [4.37, 5.10, 6.11, 4.37, 4.90, 5.56, 2.35, 2.62, 2.96],
    [4.06, 4.78, 5.80, 4.06, 4.50, 5.04, 2.01, 2.23, 2.50],
    [3.82, 4.54, 5.58, 3.82, 4.21, 4.67, 1.76, 1.95, 2.18],
    [3.65, 4.36, 5.42, 3.65, 3.99, 4.39, 1.58, 1.75, 1.94],
    [3.51, 4.22, 5.30, 3.51, 3.81, 4.16, 1.44, 1.59, 1.77],
    [3.40, 4.12, 5.20, 3.40, 3.67, 3.98, 1.33, 1.47, 1.63],
]
KALKER_NU = [0.0, 0.25, 0.5]


def kalker_table(a_over_b, nu):
    """(C11, C22, C23) of Table E.3 at a tabulated a/b and nu, or None."""
    if nu not in KALKER_NU:
        return None
    k = KALKER_NU.index(nu)
    g = a_over_b if a_over_b <= 1.0 else 1.0 / a_over_b
    rows = KALKER_A_LE_B if a_over_b <= 1.0 else KALKER_A_GE_B
    for gi, row in zip(KALKER_G, rows):
        if abs(gi - g) < 1e-9:
            return row[k], row[3 + k], row[6 + k]
    return None


def _asinh_ratio(num, den):
    """num * asinh(den_other) building block: asinh(num / |den|), 0 where num = 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.arcsinh(num / np.abs(den))
    return np.where(num == 0.0, 0.0, r)


def _primitives(x, y):
    """Primitives P with d2P/dxdy = 1/r (P1), x^2/r^3 (Pxx), y^2/r^3 (Pyy), xy/r^3 (Pxy).

    x ln(y + r) and y ln(x + r) are written with asinh (the dropped x ln|x|, y ln|y| cancel in
    the corner differences)."""
    r = np.hypot(x, y)
    pxx = y * _asinh_ratio(x, y)  # d/dx: y / r ... d/dy: x^2 / r^3
    pyy = x * _asinh_ratio(y, x)
    return pxx, pyy, -r


def influence(nx, ny, dx, dy, nu):
    """Influence kernels K_xx, K_yy, K_xy (times pi G) of a uniform unit traction on the
    dx x dy cell centred at the origin, at the cell centres (i dx, j dy), |i| < nx, |j| < ny."""
    i = np.arange(-(nx - 1), nx)[:, None] * dx
    j = np.arange(-(ny - 1), ny)[None, :] * dy
    out = [np.zeros((2 * nx - 1, 2 * ny - 1)) for _ in range(3)]
    # Integral over x' in [-dx/2, dx/2], y' in [-dy/2, dy/2] of f(x - x', y - y'):
    # corner sum of the primitive at (x - x', y - y').
    for sx, ox in ((1.0, -0.5 * dx), (-1.0, 0.5 * dx)):
        for sy, oy in ((1.0, -0.5 * dy), (-1.0, 0.5 * dy)):
            pxx, pyy, pxy = _primitives(i + ox, j + oy)
            s = sx * sy
            out[0] += s * pxx
            out[1] += s * pyy
            out[2] += s * pxy
    ixx, iyy, ixy = out
    i1 = ixx + iyy  # 1/r = x^2/r^3 + y^2/r^3
    kxx = (1.0 - nu) * i1 + nu * ixx
    kyy = (1.0 - nu) * i1 + nu * iyy
    kxy = nu * ixy
    return kxx, kyy, kxy


class Grid:
    """The discretised ellipse: n cells along 2a, m along 2b, one extra column upstream."""

    def __init__(self, a, b, n, m, nu, G=1.0):
        self.a, self.b, self.n, self.m, self.nu, self.G = a, b, n, m, nu, G
        self.dx, self.dy = 2.0 * a / n, 2.0 * b / m
        # Cell columns: index 0 is the extra column at x = -a - dx/2 (upstream of the leading
        # edge), 1..n the grid.
        self.x = -a - 0.5 * self.dx + self.dx * np.arange(n + 1)
        self.y = -b + self.dy * (np.arange(m) + 0.5)
        X, Y = np.meshgrid(self.x, self.y, indexing="ij")
        self.X, self.Y = X, Y
        self.inside = (X / a) ** 2 + (Y / b) ** 2 < 1.0
        self.nc = int(self.inside.sum())
        self.area = self.nc * self.dx * self.dy
        nx, ny = n + 1, m
        kxx, kyy, kxy = influence(nx, ny, self.dx, self.dy, nu)
        # FFT convolution on a (2nx) x (2ny) periodic grid: kernel index (i - i', j - j').
        px, py = 2 * nx, 2 * ny
        self.shape = (px, py)

        def fft_kernel(k):
            full = np.zeros((px, py))
            # k[i + nx - 1, j + ny - 1] is the offset (i, j); wrap negative offsets.
            ii = np.arange(-(nx - 1), nx) % px
            jj = np.arange(-(ny - 1), ny) % py
            full[np.ix_(ii, jj)] = k
            return np.fft.rfft2(full)

        self.fk = [fft_kernel(k) for k in (kxx, kyy, kxy)]
        self.scale = 1.0 / (np.pi * G)

    def displacement(self, qx, qy):
        """u = A q on the (n+1) x m grid (q zero outside the contact)."""
        px, py = self.shape
        fx = np.fft.rfft2(qx, s=(px, py))
        fy = np.fft.rfft2(qy, s=(px, py))
        kxx, kyy, kxy = self.fk
        nx, ny = qx.shape
        ux = np.fft.irfft2(kxx * fx + kxy * fy, s=(px, py))[:nx, :ny]
        uy = np.fft.irfft2(kxy * fx + kyy * fy, s=(px, py))[:nx, :ny]
        return self.scale * ux, self.scale * uy

    def scatter(self, v):
        nc = self.nc
        qx = np.zeros(self.X.shape)
        qy = np.zeros(self.X.shape)
        qx[self.inside] = v[:nc]
        qy[self.inside] = v[nc:]
        return qx, qy

    def elastic_slip(self, v):
        """du/dx (upwind) at the contact cells for the tractions v = (q_x, q_y) there."""
        qx, qy = self.scatter(v)
        ux, uy = self.displacement(qx, qy)
        dux = np.zeros_like(ux)
        duy = np.zeros_like(uy)
        dux[1:] = (ux[1:] - ux[:-1]) / self.dx
        duy[1:] = (uy[1:] - uy[:-1]) / self.dx
        return np.concatenate([dux[self.inside], duy[self.inside]])

    def rigid_slip(self, xi_x, xi_y, phi):
        x, y = self.X[self.inside], self.Y[self.inside]
        return np.concatenate([xi_x - phi * y, xi_y + phi * x])

    def solve_adhesion(self, xi_x, xi_y, phi, tol=1e-10):
        """Tractions with s = 0 in every contact cell (GMRES on the FFT operator)."""
        nc2 = 2 * self.nc
        op = LinearOperator((nc2, nc2), matvec=self.elastic_slip, dtype=float)
        rhs = -self.rigid_slip(xi_x, xi_y, phi)
        # Diagonal (Jacobi) preconditioner: the slip of a cell under its own unit traction.
        e = np.zeros(nc2)
        diag = np.zeros(nc2)
        # The self term is the same for every cell whose upstream cell is a grid cell.
        e[0] = 1.0
        d0 = self.elastic_slip(e)[0]
        e[0] = 0.0
        e[self.nc] = 1.0
        d1 = self.elastic_slip(e)[self.nc]
        diag[: self.nc] = d0
        diag[self.nc :] = d1
        pre = LinearOperator((nc2, nc2), matvec=lambda r: r / diag, dtype=float)
        v, info = gmres(op, rhs, M=pre, rtol=tol, atol=0.0, restart=200, maxiter=50)
        if info != 0:
            raise RuntimeError(f"GMRES did not converge (info {info})")
        return v

    def forces(self, v):
        nc, da = self.nc, self.dx * self.dy
        return v[:nc].sum() * da, v[nc:].sum() * da


def coefficients(a_over_b, nu, n):
    """C11, C22, C23 on the grid with n cells along 2a (and n / (a/b) ... along 2b, square cells
    where possible), normalised by the discrete area (ab -> area / pi)."""
    a, b = a_over_b, 1.0
    m = max(4, int(round(n / a_over_b)))
    g = Grid(a, b, n, m, nu)
    ab = g.area / np.pi
    fx, _ = g.forces(g.solve_adhesion(1.0, 0.0, 0.0))
    _, fy = g.forces(g.solve_adhesion(0.0, 1.0, 0.0))
    _, fs = g.forces(g.solve_adhesion(0.0, 0.0, 1.0))
    # C23 in Kalker's orientation (material flowing toward -x): the mirror x -> -x keeps the
    # y components and reverses the sense of the spin, so his C23 is minus the one of this
    # grid's orientation.
    return -fx / ab, -fy / ab, fs / ab**1.5, g


def extrapolate(ns, values):
    """Least-squares C0 + c1 h + c2 h^2, h = 1/n; returns C0."""
    h = 1.0 / np.asarray(ns, dtype=float)
    basis = np.vstack([np.ones_like(h), h, h * h]).T
    c, *_ = np.linalg.lstsq(basis, np.asarray(values), rcond=None)
    return c[0]


def converged(a_over_b, nu, ns, verbose=True):
    rows = []
    for n in ns:
        t0 = time.time()
        c11, c22, c23, g = coefficients(a_over_b, nu, n)
        rows.append((c11, c22, c23))
        if verbose:
            print(
                f"  a/b = {a_over_b:4.2f}  nu = {nu:4.2f}  grid {g.n:3d} x {g.m:3d} "
                f"({g.nc:5d} cells): C11 = {c11:.4f}  C22 = {c22:.4f}  C23 = {c23:.4f}"
                f"  ({time.time() - t0:.1f} s)"
            )
    rows = np.array(rows)
    return tuple(extrapolate(ns, rows[:, k]) for k in range(3))


def compare(a_over_b, nu, ns):
    c = converged(a_over_b, nu, ns)
    ref = kalker_table(a_over_b, nu)
    names = ("C11", "C22", "C23")
    print(f"  extrapolated (h -> 0), a/b = {a_over_b}, nu = {nu}:")
    for k, name in enumerate(names):
        line = f"    {name} = {c[k]:.4f}"
        if ref is not None:
            line += f"   Kalker Table E.3: {ref[k]:.3g}   difference {100 * (c[k] / ref[k] - 1):+.2f} %"
        print(line)
    return c, ref


def slip_matrix(g):
    """Dense matrix of the elastic slip: column k is the slip under unit traction component k."""
    nc = g.nc
    M = np.zeros((2 * nc, 2 * nc))
    e = np.zeros(2 * nc)
    for k in range(2 * nc):
        e[k] = 1.0
        M[:, k] = g.elastic_slip(e)
        e[k] = 0.0
    return M


def solve_coulomb(g, M, xi_x, xi_y, phi, mu_p, v0=None, iters=100, tol=1e-11):
    """Tractions with Coulomb's law |q| <= mu p in every cell: stick (s = 0, |q| <= mu p) or
    slip (q = -mu p s/|s|), written cell by cell as q = proj(q - r s) (projection on the disc
    of radius mu p, r > 0; Alart and Curnier's form) and solved by the semismooth Newton method
    with a backtracking line search. Returns the tractions, the number of slipping cells and
    the Newton iterations."""
    nc = g.nc
    c = g.rigid_slip(xi_x, xi_y, phi)
    v = np.zeros(2 * nc) if v0 is None else v0.copy()
    r = 1.0 / np.mean(np.diag(M))
    eye = np.eye(2 * nc)

    def residual(v):
        s = c + M @ v
        z = v - r * s
        zx, zy = z[:nc], z[nc:]
        zn = np.hypot(zx, zy)
        f = np.where(zn > mu_p, mu_p / np.maximum(zn, 1e-300), 1.0)
        return v - np.concatenate([f * zx, f * zy]), z, zn

    res, z, zn = residual(v)
    for it in range(iters):
        norm = np.linalg.norm(res)
        if norm <= tol * max(np.abs(mu_p).max(), 1e-300) * np.sqrt(2 * nc):
            break
        # Jacobian of the projection at z times dz / dv = I - r M.
        P = np.zeros((2 * nc, 2 * nc))
        slip = zn > mu_p
        idx = np.arange(nc)
        st = ~slip
        P[idx[st], idx[st]] = 1.0
        P[idx[st] + nc, idx[st] + nc] = 1.0
        sl = idx[slip]
        if sl.size:
            ex, ey = z[sl] / zn[sl], z[sl + nc] / zn[sl]
            k = mu_p[sl] / zn[sl]
            P[sl, sl] = k * (1.0 - ex * ex)
            P[sl, sl + nc] = -k * ex * ey
            P[sl + nc, sl] = -k * ex * ey
            P[sl + nc, sl + nc] = k * (1.0 - ey * ey)
        J = eye - P @ (eye - r * M)
        dv = np.linalg.solve(J, -res)
        step = 1.0
        for _ in range(30):
            trial, zt, znt = residual(v + step * dv)
            if np.linalg.norm(trial) < (1.0 - 1e-4 * step) * norm:
                break
            step *= 0.5
        v = v + step * dv
        res, z, zn = trial, zt, znt
    nslip = int((zn > mu_p * (1.0 + 1e-12)).sum())
    return v, nslip, it


def solve_regularised(g, M, xi_x, xi_y, phi, mu_p, eps, v0=None, iters=100, tol=1e-11):
    """Tractions with tread's regularised Coulomb law q = -mu p tanh(|s|/eps) s/|s| (s the slip
    per unit rolling speed, eps = epsilon / v0 the regularisation slip speed over the rolling
    speed), by Newton's method with a backtracking line search."""
    nc = g.nc
    c = g.rigid_slip(xi_x, xi_y, phi)
    v = np.zeros(2 * nc) if v0 is None else v0.copy()

    def traction(sv):
        sx, sy = sv[:nc], sv[nc:]
        sn = np.hypot(sx, sy)
        t = np.tanh(sn / eps)
        # tanh(|s|/eps)/|s| -> 1/eps at s = 0.
        k = np.where(sn > 1e-300, t / np.maximum(sn, 1e-300), 1.0 / eps)
        return -mu_p * k * sx, -mu_p * k * sy, sn, t, k

    def residual(v):
        sv = c + M @ v
        qx, qy, sn, t, k = traction(sv)
        return v - np.concatenate([qx, qy]), sv, sn, t, k

    res, sv, sn, t, k = residual(v)
    idx = np.arange(nc)
    for it in range(iters):
        norm = np.linalg.norm(res)
        if norm <= tol * max(np.abs(mu_p).max(), 1e-300) * np.sqrt(2 * nc):
            break
        ex = np.where(sn > 0, sv[:nc] / np.maximum(sn, 1e-300), 1.0)
        ey = np.where(sn > 0, sv[nc:] / np.maximum(sn, 1e-300), 0.0)
        dn = (1.0 - t * t) / eps  # d tanh(|s|/eps) / d|s|
        # d q / d s = -mu p [dn e e^T + k (I - e e^T)].
        D = np.zeros((2 * nc, 2 * nc))
        D[idx, idx] = -mu_p * (dn * ex * ex + k * (1 - ex * ex))
        D[idx + nc, idx + nc] = -mu_p * (dn * ey * ey + k * (1 - ey * ey))
        off = -mu_p * (dn - k) * ex * ey
        D[idx, idx + nc] = off
        D[idx + nc, idx] = off
        J = np.eye(2 * nc) - D @ M
        dv = np.linalg.solve(J, -res)
        step = 1.0
        for _ in range(30):
            trial = residual(v + step * dv)
            if np.linalg.norm(trial[0]) < (1.0 - 1e-4 * step) * norm:
                break
            step *= 0.5
        v = v + step * dv
        res, sv, sn, t, k = trial
    return v, it


def saturation_curve(a_over_b, nu, n, mu, creeps, eps=None):
    """Lateral force F_y / (mu N) against xi_y by the Coulomb half-space solver, with the
    brush-model bound of the same initial slope."""
    a, b = a_over_b, 1.0
    m = max(4, int(round(n / a_over_b)))
    g = Grid(a, b, n, m, nu)
    # Hertz pressure with p0 = 1 (G = 1): N = 2/3 pi a b p0; the creepage scale is mu p0 / G.
    p0 = 1.0
    rho2 = (g.X[g.inside] / a) ** 2 + (g.Y[g.inside] / b) ** 2
    p = p0 * np.sqrt(np.clip(1.0 - rho2, 0.0, None))
    N = p.sum() * g.dx * g.dy
    c22_h = -g.forces(g.solve_adhesion(0.0, 1.0, 0.0))[1] / (g.area / np.pi)
    M = slip_matrix(g)
    k = g.G * (g.area / np.pi) * c22_h
    print(
        f"  grid {g.n} x {g.m} ({g.nc} cells), a/b = {a_over_b}, nu = {nu}, mu = {mu}; "
        f"C22 on this grid {c22_h:.4f}"
    )
    head = "   xi_y G/(mu p0)   F_y/(mu N) half-space   brush bound   linear   slip cells"
    if eps is not None:
        head += f"   regularised (eps/V = {eps:g} mu p0/G)"
    print(head)
    v = None
    vr = None
    out = []
    for xi in creeps:
        xi_y = xi * mu * p0 / g.G
        v, nslip, iters = solve_coulomb(g, M, 0.0, xi_y, 0.0, mu * p, v0=v)
        fy = -g.forces(v)[1]
        psi = min(1.0, k * xi_y / (3.0 * mu * N))
        brush = 1.0 - (1.0 - psi) ** 3
        lin = k * xi_y / (mu * N)
        line = (
            f"   {xi:12.4f}   {fy / (mu * N):20.4f}   {brush:11.4f}   {lin:6.3f}   "
            f"{nslip:5d}/{g.nc}"
        )
        row = [xi, fy / (mu * N), brush, lin, nslip]
        if eps is not None:
            vr, _ = solve_regularised(g, M, 0.0, xi_y, 0.0, mu * p, eps * mu * p0 / g.G, v0=vr)
            fr = -g.forces(vr)[1] / (mu * N)
            row.append(fr)
            line += f"   {fr:10.4f}"
        out.append(tuple(row))
        print(line)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ab", type=float, default=1.0, help="a/b of the ellipse (default 1)")
    ap.add_argument("--nu", type=float, default=0.5, help="Poisson ratio (default 0.5)")
    ap.add_argument(
        "--grids",
        type=str,
        default="16,24,32,48,64,80",
        help="cells along 2a of the grids to extrapolate from",
    )
    ap.add_argument("--check-table", action="store_true", help="more a/b and nu against Table E.3")
    ap.add_argument("--curve", action="store_true", help="lateral force up to full sliding")
    ap.add_argument("--mu", type=float, default=1.0)
    ap.add_argument("--curve-grid", type=int, default=24)
    ap.add_argument(
        "--curve-eps",
        type=float,
        default=None,
        help="also the regularised law of tread, eps/V in units of mu p0/G",
    )
    ap.add_argument(
        "--creeps",
        type=str,
        default="0.05,0.1,0.2,0.3,0.4,0.5,0.6,0.8,1.0,1.2,1.5",
        help="lateral creepages xi_y in units of mu p0 / G",
    )
    args = ap.parse_args(argv)
    ns = [int(s) for s in args.grids.split(",")]

    if args.curve:
        creeps = [float(c) for c in args.creeps.split(",")]
        saturation_curve(args.ab, args.nu, args.curve_grid, args.mu, creeps, args.curve_eps)
        return 0

    print(f"Kalker's linear theory, discretised half-space (grids {ns} cells along 2a):")
    cases = [(args.ab, args.nu)]
    if args.check_table:
        cases += [(1.0, 0.0), (1.0, 0.25), (0.5, 0.5), (2.0, 0.5), (0.5, 0.25)]
    worst = 0.0
    for ab, nu in cases:
        c, ref = compare(ab, nu, ns)
        if ref is not None:
            worst = max(worst, max(abs(c[k] / ref[k] - 1) for k in range(3)))
    print(f"  largest difference from Table E.3: {100 * worst:.2f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
