"""Hertz elliptic contact of a body with principal radii R1 (along x1) and R2 (along x3) on a
rigid plane (Johnson, Contact Mechanics, section 4.2), with scipy's complete elliptic integrals.

Prints semi-axes a (larger), b, peak pressure p0, approach delta for the cases used by
tests/common/hertz.rs. Run: python tools/hertz_reference.py
"""
from math import pi, sqrt
from scipy.special import ellipk, ellipe
from scipy.optimize import brentq


def hertz(r1, r2, e_star, load):
    a_c, b_c = sorted([0.5 / r1, 0.5 / r2])  # A <= B: a along the smaller curvature
    ratio = b_c / a_c

    def f(m):
        k, e = ellipk(m), ellipe(m)
        return (e / (1.0 - m) - k) / (k - e) - ratio

    m = brentq(f, 1e-12, 1.0 - 1e-15, xtol=1e-16, rtol=1e-15) if ratio > 1.0 else 0.0
    k, e = ellipk(m), ellipe(m)
    km = (k - e) / m
    a = (3.0 * load * km / (2.0 * pi * a_c * e_star)) ** (1.0 / 3.0)
    b = a * sqrt(1.0 - m)
    p0 = 3.0 * load / (2.0 * pi * a * b)
    delta = p0 * b * k / e_star
    return m, a, b, p0, delta


for (r1, r2, es, p) in [(0.3, 0.05, 2.0e6, 500.0), (1.0, 0.2, 1.0e7, 1.0e3), (0.4, 0.39, 3.0e6, 50.0)]:
    m, a, b, p0, d = hertz(r1, r2, es, p)
    print(f"R1={r1} R2={r2} E*={es} P={p}: e2={m!r} a={a!r} b={b!r} p0={p0!r} delta={d!r}")
for m in [0.1, 0.5, 0.9, 0.999]:
    print(f"m={m}: K={ellipk(m)!r} E={ellipe(m)!r}")
