"""Fuzz the tread command line: mutate the shipped scenes and `--set` values and run them with
bounded time and memory. A panic ("panicked", exit status 101), an abort or any other death by
a signal, a run past the time limit (a hang), or a non-finite number (NaN, inf) in a text
output file (CSV, JSON, the XML of a VTU, PVD, run.sta) is a finding; every finding is printed
with its command line and the run exits 1.

Usage: fuzz.py [--tread PATH] [--seconds N] [--cases N] [--timeout S] [--memory MB] [--seed N]
       fuzz.py --shipped [--tread PATH] [--timeout S]   (every shipped scene once, as it is;
                                                          a sweep file through `tread sweep plan`)
The smoke run in CI: fuzz.py --cases 25.
"""
import argparse
import glob
import os
import random
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time

KEYS = [
    "mesh.n_r", "mesh.n_theta", "mesh.order", "mesh.grading_r", "mesh.grading_theta",
    "geometry.ri", "geometry.ro", "material.mu", "material.lambda", "material.c1",
    "material.c2", "material.kappa", "material.rho", "motion.omega", "motion.ramp",
    "road.disp", "road.v0", "road.load", "contact.c_n", "contact.m_n", "contact.points",
    "friction.mu", "friction.eps", "solver.tolerance", "solver.max_iterations",
    "solver.load_steps", "solver.max_cutbacks", "time.dt", "time.t_end", "time.max_steps",
    "output.every", "analysis.mode", "continuation.max_steps", "continuation.ds",
    "stick_slip.t_end", "stick_slip.mass",
]
VALUES = [
    "0", "-1", "1", "2", "3", "7", "1e-300", "1e300", "-1e300", "nan", "inf", "-inf",
    "4611686018427387904", "1099511627776", "1000000", "1e7", "0.5", "-0.5", "\"text\"",
    "[]", "true", "\"spinning\"", "\"static\"", "\"transient\"", "\"steady\"", "\"stick_slip\"",
    "1e-12", "18446744073709551616", "2.5e-3", "",
]


def mutate_text(text, rng):
    lines = text.splitlines()
    for _ in range(rng.randint(0, 3)):
        if not lines:
            break
        i = rng.randrange(len(lines))
        op = rng.randrange(4)
        if op == 0:
            del lines[i]
        elif op == 1:
            lines.insert(i, lines[rng.randrange(len(lines))])
        elif op == 2 and "=" in lines[i]:
            k = lines[i].split("=")[0]
            lines[i] = f"{k}= {rng.choice(VALUES)}"
        else:
            lines[i] = lines[i][: rng.randrange(len(lines[i]) + 1)]
    return "\n".join(lines) + "\n"


# A non-finite number as a writer prints it (Rust's `NaN`, `inf`, `-inf`; `nan`, `Infinity`), as
# a whole token: not a part of a word such as "info" or "inflation", nor of base64 data (whose
# alphabet adds `+`, `/` and `=`).
NON_FINITE = re.compile(rb"(?<![A-Za-z0-9_.+/=])[-+]?(NaN|nan|inf|Infinity)(?![A-Za-z0-9_+/=])")
TEXT_OUTPUTS = (".csv", ".json", ".vtu", ".pvd", ".sta", ".txt")


def non_finite_outputs(out):
    """The text output files under `out` that contain a non-finite number, with the first
    offending line of each."""
    hits = []
    for root, _, files in os.walk(out):
        for f in files:
            if not f.endswith(TEXT_OUTPUTS):
                continue
            path = os.path.join(root, f)
            with open(path, "rb") as fh:
                data = fh.read()
            # A VTU file's raw appended data are binary: only its XML part is text.
            data = data.split(b"<AppendedData", 1)[0]
            for line in data.splitlines():
                if NON_FINITE.search(line):
                    hits.append(f"{os.path.relpath(path, out)}: {line.strip()[:160].decode(errors='replace')}")
                    break
    return hits


def limit(memory_mb):
    def f():
        b = memory_mb * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (b, b))
    return f


SCENES_GLOB = os.path.join(os.path.dirname(__file__), "..", "scenarios", "*.toml")


def run_case(cmd, timeout, preexec_fn=None):
    """Run one tread command with one rayon thread: (kind, stderr), kind being "panic", "hang",
    "signal N" or "exit N"."""
    try:
        p = subprocess.run(cmd, capture_output=True, timeout=timeout, preexec_fn=preexec_fn,
                           env=dict(os.environ, RAYON_NUM_THREADS="1"))
    except subprocess.TimeoutExpired:
        return "hang", ""
    err = p.stderr.decode(errors="replace")
    if "panicked" in err or p.returncode == 101:
        return "panic", err
    if p.returncode < 0:
        return f"signal {-p.returncode}", err
    return f"exit {p.returncode}", err


def is_finding(kind):
    return kind in ("panic", "hang", "non-finite output") or kind.startswith("signal")


def shipped(a):
    """Run each scene under scenarios/ once with its own settings; a panic, a death by a
    signal, a hang or a non-finite text output is a finding. Returns the exit status."""
    work = tempfile.mkdtemp(prefix="tread-shipped-")
    findings = 0
    for sc in sorted(glob.glob(SCENES_GLOB)):
        out = os.path.join(work, os.path.basename(sc)[:-5])
        with open(sc, encoding="utf-8") as f:
            sweep = re.search(r"^\[sweep\]", f.read(), re.M) is not None
        # A sweep file is planned (every run's scene built and checked), not run as a scene.
        cmd = ([a.tread, "-q", "sweep", "plan", sc] if sweep
               else [a.tread, "-q", "run", sc, "--out", out])
        kind, _ = run_case(cmd, a.timeout)
        bad = non_finite_outputs(out)
        finding = is_finding(kind) or bool(bad)
        findings += finding
        print(f"shipped: {os.path.basename(sc)}: {kind}{'; non-finite: ' + bad[0] if bad else ''}"
              f"{'  FINDING' if finding else ''}", flush=True)
    shutil.rmtree(work, ignore_errors=True)
    return 1 if findings else 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tread", default="target/release/tread")
    ap.add_argument("--seconds", type=float, default=600)
    ap.add_argument("--cases", type=int, default=0, help="stop after N cases (0: time only)")
    ap.add_argument("--timeout", type=float, default=60)
    ap.add_argument("--memory", type=int, default=4096, help="address-space limit, MB")
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--shipped", action="store_true",
                    help="run every shipped scene once, unmutated, and check it the same way")
    a = ap.parse_args()
    if a.shipped:
        sys.exit(shipped(a))
    seed = a.seed if a.seed is not None else int(time.time())
    rng = random.Random(seed)
    scenes = sorted(glob.glob(SCENES_GLOB))
    work = tempfile.mkdtemp(prefix="tread-fuzz-")
    findings, counts, n, t0 = [], {}, 0, time.time()
    print(f"fuzz: seed {seed}, {len(scenes)} scenes, timeout {a.timeout} s, memory {a.memory} MB")
    while time.time() - t0 < a.seconds and (a.cases == 0 or n < a.cases):
        n += 1
        sc = rng.choice(scenes)
        text = open(sc).read()
        path = os.path.join(work, "scene.toml")
        if rng.random() < 0.5:
            text = mutate_text(text, rng)
        open(path, "w").write(text)
        sets = []
        for _ in range(rng.randint(0, 3)):
            sets += ["--set", f"{rng.choice(KEYS)}={rng.choice(VALUES)}"]
        # Keep most cases short enough to finish: a coarse mesh unless the mutation says otherwise.
        base = ["--set", "mesh.n_r=2", "--set", "mesh.n_theta=16"] if rng.random() < 0.7 else []
        sub = rng.choice(["run", "run", "run", "check"])
        out = os.path.join(work, "out")
        cmd = [a.tread, "-q", sub, path] + base + sets
        if sub == "run":
            cmd += ["--out", out, "--max-memory", f"{a.memory // 2}M"]
        kind, err = run_case(cmd, a.timeout, limit(a.memory))
        if sub == "run" and not is_finding(kind):
            bad = non_finite_outputs(out)
            if bad:
                kind, err = "non-finite output", "\n".join(bad)
        counts[kind] = counts.get(kind, 0) + 1
        if is_finding(kind):
            keep = os.path.join(work, f"finding_{n}.toml")
            shutil.copy(path, keep)
            findings.append((kind, cmd[:3] + [keep] + cmd[4:], err.strip().splitlines()[-3:]))
        shutil.rmtree(out, ignore_errors=True)
    print(f"fuzz: {n} cases in {time.time() - t0:.0f} s: {dict(sorted(counts.items()))}")
    for kind, cmd, tail in findings:
        print(f"fuzz: FINDING {kind}: {' '.join(cmd)}")
        for l in tail:
            print(f"    {l}")
    sys.exit(1 if findings else 0)


if __name__ == "__main__":
    main()
