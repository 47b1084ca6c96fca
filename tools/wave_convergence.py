#!/usr/bin/env python3
"""Mesh convergence of the standing-wave pattern along a steady ω-continuation branch.

    python3 tools/wave_convergence.py --tread target/release/tread \
        [--scene scenarios/oden_figs_9_13.toml] [--meshes 3x64,6x128,12x256] \
        [--omega 55] [--direct] [--out out/wave_convergence] [--set KEY=VALUE ...]

Runs the scene (steady mode with [continuation] in ω) on each mesh `n_r x n_theta` with the
summary and CSV sinks, reads its branch.csv and reports, per mesh:
- the first branch point with a negative eigenvalue of the tangent (where the discrete
  critical speed has been passed) and its ω;
- at the requested supercritical ω (linear interpolation between the two branch points that
  bracket it on the way up; the nearest point for the wave number): the hub forces and torque,
  the wave amplitude and the dominant wave number n of the outer surface (`wave_amplitude`,
  `wave_number` of branch.csv), and the wavelength 2π Ro / n;
- the relative change of each from the previous mesh.
With --direct the branch is not followed from the scene's ω: each mesh is solved directly at the
requested ω (road speed scaled with ω as the continuation does, v0 = (v0/ω)_scene · ω) and one
continuation step is taken, so the values are those of the solution the press-in at that speed
reaches. (An arc-length path through a limit point can turn back or jump to another sheet,
depending on its step sizes; the direct solve does not depend on them.)
Writes OUT/wave_convergence.csv and prints a Markdown table. Standard library only.
"""
import argparse
import csv
import math
import os
import subprocess
import sys
import time


def run_mesh(args, n_r, n_theta):
    out = os.path.join(args.out, f"{n_r}x{n_theta}")
    cmd = [args.tread, "-q", "run", args.scene, "--out", out,
           "--set", f"mesh.n_r={n_r}", "--set", f"mesh.n_theta={n_theta}",
           "--set", 'output.sinks=["summary","csv"]']
    if args.direct:
        cmd += ["--set", f"motion.omega={args.omega}",
                "--set", f"road.v0={args.v0_ratio * args.omega}",
                "--set", f"continuation.target={args.omega + 1.0}",
                "--set", "continuation.max_steps=1"]
    for s in args.set:
        cmd += ["--set", s]
    t0 = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.time() - t0
    path = os.path.join(out, "branch.csv")
    if not os.path.exists(path):
        sys.exit(f"wave_convergence: {n_r}x{n_theta}: no branch.csv (exit {r.returncode}): {r.stderr.strip()}")
    with open(path, newline="") as f:
        rows = [{k: (float(v) if v not in ("", None) else math.nan) for k, v in row.items()}
                for row in csv.DictReader(f)]
    return rows, wall, r.returncode


def at_omega(rows, omega):
    """Interpolated values where the branch first passes `omega` going up, and the nearest row."""
    for a, b in zip(rows, rows[1:]):
        if a["omega"] <= omega <= b["omega"]:
            s = (omega - a["omega"]) / (b["omega"] - a["omega"]) if b["omega"] != a["omega"] else 0.0
            lerp = {k: a[k] + s * (b[k] - a[k]) for k in a}
            near = a if s < 0.5 else b
            return lerp, near
    return None, None


def scene_value(path, section, key):
    """A number `key = value` of `[section]` in a scene file (comments stripped)."""
    current = None
    with open(path) as f:
        for line in f:
            t = line.split("#")[0].strip()
            if t.startswith("[") and t.endswith("]"):
                current = t.strip("[]").strip()
            elif current == section and "=" in t and t.split("=")[0].strip() == key:
                return float(t.split("=", 1)[1])
    sys.exit(f"wave_convergence: {path} has no [{section}] {key}")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--tread", required=True)
    p.add_argument("--scene", default="scenarios/oden_figs_9_13.toml")
    p.add_argument("--meshes", default="3x64,6x128,12x256")
    p.add_argument("--omega", type=float, default=55.0)
    p.add_argument("--out", default="out/wave_convergence")
    p.add_argument("--direct", action="store_true")
    p.add_argument("--set", action="append", default=[])
    args = p.parse_args()
    args.v0_ratio = scene_value(args.scene, "road", "v0") / scene_value(args.scene, "motion", "omega")
    os.makedirs(args.out, exist_ok=True)
    ro = scene_value(args.scene, "geometry", "ro")
    table = []
    for m in args.meshes.split(","):
        n_r, n_theta = (int(x) for x in m.lower().split("x"))
        rows, wall, rc = run_mesh(args, n_r, n_theta)
        crit = next((r for r in rows if r["negative_eigenvalues"] > 0), None)
        lerp, near = at_omega(rows, args.omega)
        entry = {
            "mesh": m, "dofs_approx": 2 * (2 * n_r + 1) * 2 * n_theta, "exit": rc, "wall_s": wall,
            "points": len(rows), "omega_end": rows[-1]["omega"],
            "omega_first_negative": crit["omega"] if crit else math.nan,
        }
        if lerp is not None:
            n = near["wave_number"]
            entry.update({
                "hub_force_x": lerp["hub_force_x"], "hub_force_y": lerp["hub_force_y"],
                "hub_torque": lerp["hub_torque"], "wave_amplitude": lerp["wave_amplitude"],
                "wave_number": n,
                "wavelength": 2 * math.pi * ro / n if ro and n > 0 else math.nan,
            })
        table.append(entry)
        print(f"{m}: {len(rows)} branch points to ω = {rows[-1]['omega']:.2f}, exit {rc}, {wall:.1f} s",
              file=sys.stderr)
    keys = ["mesh", "dofs_approx", "exit", "wall_s", "points", "omega_end", "omega_first_negative",
            "hub_force_x", "hub_force_y", "hub_torque", "wave_amplitude", "wave_number", "wavelength"]
    with open(os.path.join(args.out, "wave_convergence.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(keys)
        for e in table:
            w.writerow(["" if (isinstance(e.get(k), float) and math.isnan(e[k])) else e.get(k, "")
                        for k in keys])
    how = "direct solve" if args.direct else "on the branch followed from the scene's ω"
    print(f"\nAt ω = {args.omega} rad/s ({args.scene}, {how}):\n")
    print("| mesh | ~DOFs | ω of the first negative eigenvalue | F_x | F_y | T | wave amplitude | n | wavelength | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    prev = None
    for e in table:
        def f(k, fmt="{:.5g}"):
            v = e.get(k)
            if v is None or (isinstance(v, float) and math.isnan(v)):
                return "–"
            s = fmt.format(v)
            if prev is not None and k in ("hub_force_x", "hub_force_y", "hub_torque", "wave_amplitude") \
                    and prev.get(k) not in (None, 0.0):
                s += f" ({(v - prev[k]) / abs(prev[k]):+.1%})"
            return s
        print(f"| {e['mesh']} | {e['dofs_approx']} | {f('omega_first_negative', '{:.2f}')} | {f('hub_force_x')} | "
              f"{f('hub_force_y')} | {f('hub_torque')} | {f('wave_amplitude', '{:.3e}')} | {f('wave_number', '{:.0f}')} | "
              f"{f('wavelength', '{:.3f}')} | {e['wall_s']:.1f} |")
        prev = e


if __name__ == "__main__":
    main()
