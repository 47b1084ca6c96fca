#!/usr/bin/env python3
"""Thin-contact check of 3D steady rolling against Kalker's linear theory.

Runs tread on tools/kalker_wheel.toml (a crowned wheel, R_c = Ro, so that the Hertz contact
is a circle with a/Ro ≈ 0.03, on a thick nearly incompressible layer, rigid road, friction
μ = 50) at small creepages and prints the creep-force coefficients against the half-space
reference of tools/halfspace_creep.py (and Kalker's Table E.3):

* longitudinal: motion.control = "creep" at ξ = −xi (free rolling found first), then the
  arc-length continuation in the creep to +xi; the creepage of the linear theory at each point
  is ξ_x = (v0_free − v0)/v0 (the wheel's surface speed over the road's, minus one), and C11 is
  the slope −dF_long/dξ_x / (G_K a b) of the least-squares line through the points;
* lateral: free rolling at the slip angle α, then the continuation in α to −α at that road
  speed: ξ_y = tan α (the wheel slips along +x3 relative to the road), C22 = −dF_lat/dξ_y /
  (G_K a b);
* spin: free rolling at the camber γ, then the continuation to −γ: the spin creepage
  φ = ω sin γ / v0 (the component of the wheel's angular velocity along the road normal over
  the rolling speed), C23 = |dF_lat/dφ| / (G_K (ab)^{3/2}). In tread's frame the
  material enters the patch at x1 = −a and the spin of the wheel about −n is +ω sin γ, so the
  half-space (whose grid has the same orientation, y = x3) gives F_lat = +G_K (ab)^{3/2} C23 φ:
  toward +e3, the side pressed onto the road, for γ > 0; the script checks the sign.

G_K = 2 G: the combined shear modulus of Kalker's formulas for an elastic body on a rigid
counter-body (tools/halfspace_creep.py derives it). a and b are the semi-axes of the FE
footprint of the free-rolling longitudinal run from the second moments of the contact force
density, ∫p x² / ∫p = a²/5 (the method of tests/hertz3d.rs).

The FE coefficients differ from the half-space ones by the discretisation (cells per
semi-axis), the finite layer and width, the normal compliance and the regularised friction
(slip ε t/(μ p) in the stick zone, a relative softening of about 66 (ε/v0)/μ ≈ 1.3 %; with
--mu-extrapolate the runs are repeated at 2μ and the coefficients extrapolated linearly in
1/μ).

Usage:
    python3 tools/kalker_study.py [--tread target/release/tread] [--set mesh.n_theta=96 ...]
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import halfspace_creep  # noqa: E402

SCENE = os.path.join(HERE, "kalker_wheel.toml")


def run(tread, out, sets):
    cmd = [tread, "run", SCENE, "--out", out, "-q"]
    for s in sets:
        cmd += ["--set", s]
    t0 = time.time()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.time() - t0
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout + proc.stderr)
        raise SystemExit(f"tread failed: {' '.join(cmd)}")
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    return summary, wall


def semi_axes(out):
    """a (along x1) and b (along x3) from the second moments of t_n dA0 in contact.csv."""
    f = f1 = f3 = f11 = f33 = 0.0
    with open(os.path.join(out, "contact.csv")) as fh:
        for row in csv.DictReader(fh):
            w = float(row["t_n"]) * float(row["dA0"])
            if w <= 0.0:
                continue
            x1, x3 = float(row["x1"]), float(row["x3"])
            f += w
            f1 += w * x1
            f3 += w * x3
            f11 += w * x1 * x1
            f33 += w * x3 * x3
    c1, c3 = f1 / f, f3 / f
    return math.sqrt(5.0 * (f11 / f - c1 * c1)), math.sqrt(5.0 * (f33 / f - c3 * c3)), f


def hub(summary, key):
    return summary["results"]["hub_loads"][key]


def branch(out):
    """Rows of branch.csv as dicts of floats."""
    with open(os.path.join(out, "branch.csv")) as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def slope(xs, ys):
    """Least-squares slope of y against x."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx


def dofs(summary):
    return summary["dofs"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    default_tread = os.environ.get("TREAD", os.path.join(HERE, "..", "target", "release", "tread"))
    ap.add_argument("--tread", default=default_tread, help="the tread binary")
    ap.add_argument("--out", default=os.path.join("out", "kalker_study"), help="run directories")
    ap.add_argument("--set", action="append", default=[], help="scene override for every run")
    ap.add_argument("--xi", type=float, default=0.002, help="longitudinal creep range ±ξ")
    ap.add_argument("--alpha", type=float, default=0.1, help="slip angle range ±α, degrees")
    ap.add_argument("--gamma", type=float, default=0.5, help="camber range ±γ, degrees")
    ap.add_argument("--mu", type=float, default=50.0, help="friction coefficient of the runs")
    ap.add_argument("--mu-extrapolate", action="store_true", help="also run at 2 μ, extrapolate in 1/μ")
    ap.add_argument("--grids", default="16,24,32,48", help="half-space grids (cells along 2a)")
    ap.add_argument("--only", default="long,slip,camber", help="which runs (comma-separated)")
    ap.add_argument(
        "--curve",
        action="store_true",
        help="instead: the lateral force against the slip angle up to full sliding (μ = 1)",
    )
    ap.add_argument("--curve-target", type=float, default=4.0, help="largest slip angle, degrees")
    ap.add_argument("--curve-grid", type=int, default=16, help="half-space grid of the curve")
    ap.add_argument(
        "--no-run", action="store_true", help="--curve: read the run directory of an earlier run"
    )
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    if args.curve:
        return curve(args)
    only = args.only.split(",")

    # Scene constants the coefficients need (tools/kalker_wheel.toml).
    G = 200.0  # 2 (C1 + C2)
    GK = 2.0 * G  # Kalker's combined modulus with a rigid road
    omega = 1.0
    mu0 = args.mu
    cont = ["continuation.ds=0.5", "continuation.ds_max=0.5"]

    def case(name, sets):
        out = os.path.join(args.out, name)
        s, wall = run(args.tread, out, args.set + sets)
        print(f"  {name:14s} {wall:7.1f} s  DOFs {dofs(s)}  points {len(branch(out))}", flush=True)
        return s, out, wall

    def coefficients(mu):
        extra = [f"friction.mu={mu}"]
        tag = f"mu{mu:g}"
        res = {"walls": []}
        fr = ["motion.control=free_rolling"]
        if "long" in only:
            s, out, w = case(
                f"long_{tag}",
                extra
                + ["motion.control=creep", f"motion.creep={-args.xi}", "continuation.parameter=creep",
                   "road.slip_angle=0", f"continuation.target={args.xi}"]
                + cont,
            )
            v_free = s["results"]["control"]["v0_free"]
            rows = branch(out)
            xs = [(v_free - r["v0"]) / r["v0"] for r in rows]
            fs = [r["longitudinal_force"] for r in rows]
            a, b, _ = semi_axes(out)
            res.update(a=a, b=b, load=hub(s, "vertical_force"), dofs=dofs(s))
            res["C11"] = -slope(xs, fs) / (GK * a * b)
            res["walls"].append(w)
        ab = res["a"] * res["b"]
        if "slip" in only:
            s, out, w = case(
                f"slip_{tag}",
                extra
                + fr
                + [f"road.slip_angle={args.alpha}", "continuation.parameter=slip_angle",
                   f"continuation.target={-args.alpha}"]
                + cont,
            )
            rows = branch(out)
            xs = [math.tan(math.radians(r["slip_angle"])) for r in rows]
            fs = [r["lateral_force"] for r in rows]
            res["C22"] = -slope(xs, fs) / (GK * ab)
            res["walls"].append(w)
        if "camber" in only:
            s, out, w = case(
                f"camber_{tag}",
                extra
                + fr
                + ["road.slip_angle=0", f"road.camber={args.gamma}", "continuation.parameter=camber",
                   f"continuation.target={-args.gamma}"]
                + cont,
            )
            rows = branch(out)
            xs = [omega * math.sin(math.radians(r["camber"])) / r["v0"] for r in rows]
            fs = [r["lateral_force"] for r in rows]
            k = slope(xs, fs)
            res["C23"] = abs(k) / (GK * ab**1.5)
            res["spin_force_sign_as_half_space"] = k > 0.0
            res["walls"].append(w)
        return res

    print(f"FE runs ({args.tread}, {SCENE}, overrides {args.set}):")
    r = coefficients(mu0)
    names = [n for n, run_ in (("C11", "long"), ("C22", "slip"), ("C23", "camber")) if run_ in only]
    fe = {k: r[k] for k in names}
    if args.mu_extrapolate:
        r2 = coefficients(2.0 * mu0)
        # C(1/μ) linear: C(0) = 2 C(2μ) − C(μ).
        fe = {k: 2.0 * r2[k] - r[k] for k in names}
    a, b = r["a"], r["b"]
    print(
        f"footprint: a = {a:.5f} in, b = {b:.5f} in, a/b = {a / b:.4f}, a/Ro = {a / 2.0:.4f}, "
        f"load {r['load']:.5f} lbf, DOFs {r['dofs']}, run times "
        f"{', '.join(f'{w:.0f}' for w in r['walls'])} s"
    )
    ns = [int(s) for s in args.grids.split(",")]
    print(f"half-space reference at a/b = {a / b:.4f}, nu = 0.5 (grids {ns}):")
    ref = halfspace_creep.converged(a / b, 0.5, ns, verbose=False)
    table = halfspace_creep.kalker_table(1.0, 0.5)
    print()
    print(
        f"| coefficient | FE (μ = {mu0:g}) |"
        + (" FE (1/μ → 0) |" if args.mu_extrapolate else "")
        + " half-space (this a/b) | Kalker Table E.3 (a/b = 1) | FE vs half-space |"
    )
    print("|---|---|" + ("---|" if args.mu_extrapolate else "") + "---|---|---|")
    for k, name in enumerate(("C11", "C22", "C23")):
        if name not in fe:
            continue
        cells = f"| {name} | {r[name]:.3f} |"
        if args.mu_extrapolate:
            cells += f" {fe[name]:.3f} |"
        cells += f" {ref[k]:.3f} | {table[k]:.3g} | {100 * (fe[name] / ref[k] - 1):+.1f} % |"
        print(cells)
    if "camber" in only:
        print(
            "spin force along +e3 for γ > 0, as the half-space gives: "
            f"{r['spin_force_sign_as_half_space']}"
        )
    return 0


def curve(args):
    """The cornering curve at μ = 1 by the continuation in the slip angle from 0, against the
    half-space with Coulomb's law, with tread's regularised law (the same ε/v0) and the brush
    bound (tools/halfspace_creep.py), in the variables F_y/(μ F_z) and ξ_y G_K/(μ p0)."""
    GK, mu = 400.0, 1.0
    out = os.path.join(args.out, "curve")
    sets = args.set + [
        f"friction.mu={mu}",
        "road.slip_angle=0",
        "continuation.parameter=slip_angle",
        f"continuation.target={args.curve_target}",
        "continuation.ds=0.1",
        "continuation.ds_max=0.1",
    ]
    if args.no_run:
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
        wall = s["wall_time_s"]
    else:
        s, wall = run(args.tread, out, sets)
    rows = branch(out)
    a, b, n_load = semi_axes(out)
    p0 = 1.5 * n_load / (math.pi * a * b)
    eps = 0.02 / s["results"]["v0"]  # friction.eps of the scene over the rolling speed
    for o in args.set:
        if o.startswith("friction.eps="):
            eps = float(o.split("=")[1]) / s["results"]["v0"]
    scale = mu * p0 / GK
    print(
        f"FE: {len(rows)} points, {wall:.0f} s, DOFs {dofs(s)}; a = {a:.5f}, b = {b:.5f}, "
        f"p0 = {p0:.3f} psi, mu p0 / G_K = {scale:.5f}, eps/v0 = {eps:.4f} = {eps / scale:.3f} mu p0/G_K"
    )
    pts = [(math.tan(math.radians(r["slip_angle"])) / scale, -r["lateral_force"] / (mu * r["vertical_force"]),
            r["slip_angle"]) for r in rows[1:]]
    hs = halfspace_creep.saturation_curve(
        a / b, 0.5, args.curve_grid, mu, [x for x, _, _ in pts], eps / scale
    )
    print()
    print("| slip angle | ξ_y G_K/(μ p0) | FE F_y/(μ F_z) | half-space, tread's regularised law | "
          "half-space, Coulomb | brush bound |")
    print("|---|---|---|---|---|---|")
    for (x, f, al), h in zip(pts, hs):
        print(f"| {al:.3f}° | {x:.3f} | {f:.4f} | {h[5]:.4f} | {h[1]:.4f} | {h[2]:.4f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
