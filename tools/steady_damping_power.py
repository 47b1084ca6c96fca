#!/usr/bin/env python3
"""Closed-form reference of the steady damping test (`tests/steady_damping.rs`,
`damping_residual_converges_to_the_closed_form_power`): the power

    P = ∫ S_v : δE[w] dA,   S_v = η Ė,   Ė = sym(Fᵀ ∇v),   δE[w] = sym(Fᵀ ∇w),
    v = ω ∂θχ = ω (t + ∂θu),  t = (−X2, X1),  F = I + ∇u,

over the annulus 1 < r < 2 (plane strain, unit thickness) for the displacement and test fields
below, with η = 1 and ω = 10. Symbolic derivatives (sympy), Gauss–Legendre in r and the
trapezoidal rule in θ (spectrally accurate for periodic integrands): about 15 digits.

    python3 tools/steady_damping_power.py        # needs sympy and numpy
"""
import numpy as np
import sympy as sp

r, th = sp.symbols("r theta", positive=True)
omega, eta = 10.0, 1.0
u = sp.Matrix([0.05 * (r - 1) * sp.cos(2 * th + 0.3), 0.04 * (r - 1) ** 2 * sp.sin(3 * th)])
w = sp.Matrix([(r - 1) * sp.sin(th), (r - 1) * sp.cos(2 * th)])
e_r = sp.Matrix([sp.cos(th), sp.sin(th)])
e_t = sp.Matrix([-sp.sin(th), sp.cos(th)])


def grad(f):
    """Cartesian gradient G[i, j] = ∂f_i/∂X_j of a field given in (r, θ)."""
    return f.diff(r) * e_r.T + f.diff(th) * e_t.T / r


F = sp.eye(2) + grad(u)
v = omega * (r * e_t + u.diff(th))
L = grad(v)
e_dot = (F.T * L + L.T * F) / 2
de = (F.T * grad(w) + grad(w).T * F) / 2
integrand = eta * sum(e_dot[i, j] * de[i, j] for i in range(2) for j in range(2)) * r
f = sp.lambdify((r, th), integrand, "numpy")
xg, wg = np.polynomial.legendre.leggauss(60)
n_t = 2000
R, T = np.meshgrid(1.5 + 0.5 * xg, 2 * np.pi * np.arange(n_t) / n_t, indexing="ij")
p = float(np.sum(f(R, T) * (0.5 * wg)[:, None]) * 2 * np.pi / n_t)
print(f"P = {p!r}")
