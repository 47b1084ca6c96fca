#!/usr/bin/env python3
"""Standing-wave pattern on the outer surface of a referential field.

    python3 tools/wave_pattern.py FIELD.csv [FIELD.csv ...] [--plot OUT.png]

FIELD.csv is a `steady_field.csv` written by `tread run` (steady mode) or by the transient mode
at its last cell passage, e.g. both halves of `tread compare`:

    tread compare scenarios/oden_figs_9_13.toml --set motion.omega=52 ...
    python3 tools/wave_pattern.py OUT/steady/steady_field.csv OUT/transient/steady_field.csv

For the outer ring of nodes it takes the radial displacement u_r(θ) (θ the reference angle;
−90° is the bottom, where the road is; with a counter-clockwise spin material enters the patch
from θ < −90° and leaves it toward θ > −90°) and prints, per file:
- the wave amplitude: half the peak-to-peak u_r more than 60° from the bottom (the definition
  of `wave_amplitude` in branch.csv);
- the local extrema of u_r along the ring (angle, value): the bulge in front of the patch, the
  patch itself and the undulations behind it, from which wavelength and decay are read;
- the grid-scale ripple: the largest |u_r − mean of its 5-point neighbourhood| behind and in
  front of the patch (waves one or two nodes long, the shortest the mesh carries).
With --plot (needs matplotlib) it draws u_r(θ) of all files on one axis.
Standard library only, apart from the optional plot.
"""
import csv
import math
import sys


def outer_ur(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no rows")
    ring = max(int(r["ring"]) for r in rows)
    pts = []
    for r in rows:
        if int(r["ring"]) != ring:
            continue
        x1, x2, u1, u2 = (float(r[k]) for k in ("X1", "X2", "u1", "u2"))
        rad = math.hypot(x1, x2)
        pts.append((math.degrees(math.atan2(x2, x1)), (x1 * u1 + x2 * u2) / rad))
    pts.sort()
    return pts


def from_bottom(theta_deg):
    return math.remainder(theta_deg + 90.0, 360.0)


def analyse(pts):
    n = len(pts)
    far = [u for th, u in pts if abs(from_bottom(th)) > 60.0]
    amplitude = 0.5 * (max(far) - min(far))
    extrema = []
    for i in range(n):
        a, b, c = pts[i - 1][1], pts[i][1], pts[(i + 1) % n][1]
        if (b > a and b > c) or (b < a and b < c):
            extrema.append((pts[i][0], b))

    def ripple(sign):
        dev = 0.0
        for i, (th, u) in enumerate(pts):
            d = from_bottom(th)
            if abs(d) > 60.0 and sign * d > 0:
                mean5 = sum(pts[(i + j) % n][1] for j in range(-2, 3)) / 5.0
                dev = max(dev, abs(u - mean5))
        return dev

    return amplitude, extrema, ripple(1.0), ripple(-1.0)


def main(argv):
    files, plot = [], None
    it = iter(argv)
    for a in it:
        if a == "--plot":
            plot = next(it, None)
            if plot is None:
                print("wave_pattern.py: --plot needs a file name", file=sys.stderr)
                return 2
        else:
            files.append(a)
    if not files:
        print(__doc__)
        return 2
    series = []
    for p in files:
        try:
            pts = outer_ur(p)
        except (OSError, KeyError, ValueError) as e:
            print(f"wave_pattern.py: cannot read {p}: {e}", file=sys.stderr)
            return 1
        amp, ext, behind, front = analyse(pts)
        series.append((p, pts))
        print(f"{p}: {len(pts)} outer nodes; wave amplitude {amp:.4e}; "
              f"grid-scale ripple behind {behind:.2e}, in front {front:.2e}")
        print("  extrema (theta deg, u_r): " + ", ".join(f"({t:.1f}, {u:+.4e})" for t, u in ext))
    if plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(10, 4))
        for p, pts in series:
            ax.plot([t for t, _ in pts], [u for _, u in pts], label=p)
        ax.axvline(-90.0, color="k", lw=0.5)
        ax.set_xlabel("reference angle theta (deg); -90 = bottom, at the road")
        ax.set_ylabel("u_r of the outer surface (length unit of the scene)")
        ax.grid(True)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(plot, dpi=80)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
