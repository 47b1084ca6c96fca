"""Fuzz the tread command line in three phases, each case with bounded time and memory:

* scene: the shipped scenes mutated (lines deleted, duplicated, cut, values replaced) and random
  `--set` values, run or checked;
* mesh: mutants of the shipped Gmsh files (scenarios/footprint_refined.msh,
  scenarios/two_layer.msh) through `tread check SCENE --set mesh.file="PATH"`. The node order
  of a $Nodes block permuted (each tag keeps its coordinates), the node tags renumbered with
  gaps, and the file written as binary .msh 4.1 are the same mesh: `check` must accept them and
  `tread run` on them must give the original file's summary.json hub loads to 1e-9 of the
  largest (else wrong-refuse, wrong-result). Two node tags swapped (a tangled mesh) must be
  refused with exit 2 and a message saying "inverted" or "degenerate". Every header count
  ($PhysicalNames, the four of $Entities and of $Nodes and $Elements, a block's count) set to
  1e11, 2^62, 2^64, -1 or 0, `/dev/zero` and a 2 GiB sparse file must be refused with exit 2,
  the last two within 5 s. Truncations (also of the binary file), line deletions and
  duplications and byte flips may be accepted or refused. A refusal must name the file. Every
  other mutant `check` accepts is also run (one load step, summary and CSV): a crash, hang or
  NaN there is a finding, and a refusal by `run` of what had to be refused makes the
  finding "wrong-accept by check" (`check` does not read what `run` reads);
* fault: runs into a full disk (tmpfs of 64k, 256k, 1M; skipped with the reason when not root
  or when mount fails): exit 0 or 3, no `*.tmp` file left, no empty *.png/*.json/*.csv/*.vtu,
  and with summary.json saying `converged: true` its outputs (those it lists, else every file
  present) whole, except those its `incomplete_outputs` names; `tread replay` of a run's .mcap
  (and .rrd) into a 64k tmpfs must exit non-zero (skipped when the build has no .rrd
  support); SIGINT, SIGTERM 2-5 s into a long transient run: exit 130 (SIGTERM: 130 or 143)
  within 30 s, summary.json and a finished run.sta left; SIGKILL: the files left readable (JSON
  parses, CSV rows whole but the last, no NaN); a second run into the folder of a running one
  refused with exit 3 and a message naming the folder.

A finding is a panic ("panicked", exit status 101), an abort or any other death by a signal, a
run past the time limit (a hang), a non-finite number (NaN, inf) in a text output file (CSV,
JSON, the XML of a VTU, PVD, run.sta), and a broken expectation of the mesh and fault phases:
wrong-accept, wrong-refuse, wrong-exit, wrong-message, unnamed-file, wrong-result,
slow-refusal, leftover-tmp, zero-byte, missing-output, incomplete-output, unfinished-sta,
killed by SIGTERM. Each finding is printed with its command line; a summary per phase gives
the cases, their outcomes (exit statuses) and the findings by kind, then one line of totals;
the run exits 1 on any finding and keeps the inputs of the findings (the folder is named).
The cases depend only on --seed (one random generator per phase); --budget S shares S seconds
between the phases (each an equal share of what is left when it starts), stops starting cases
once a phase's share is spent and says where it stopped.

Usage: fuzz.py [--tread PATH] [--phases scene,mesh,fault] [--budget S] [--seconds N]
               [--cases N] [--timeout S] [--memory MB] [--seed N]
       fuzz.py --shipped [--tread PATH] [--timeout S]   (every shipped scene once, as it is;
                                                          a sweep file through `tread sweep plan`)
--cases and --seconds bound the random cases of the scene and mesh phases (each); the mesh
phase's fixed cases and the fault phase always run, within --budget.
The run in CI: fuzz.py --phases scene,mesh,fault --cases 25 --timeout 60 --budget 240 --seed 1.
"""
import argparse
import copy
import glob
import json
import os
import random
import re
import resource
import shutil
import signal
import struct
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
    """Run one tread command with one rayon thread: (kind, output), kind being "panic", "hang",
    "signal N" or "exit N", output its stderr then its stdout."""
    try:
        p = subprocess.run(cmd, capture_output=True, timeout=timeout, preexec_fn=preexec_fn,
                           env=dict(os.environ, RAYON_NUM_THREADS="1"))
    except subprocess.TimeoutExpired:
        return "hang", ""
    err = p.stderr.decode(errors="replace") + p.stdout.decode(errors="replace")
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


SCENARIOS = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                          "scenarios"))
PHASES = ("scene", "mesh", "fault")


def finding_kind(kind):
    """The finding a run's kind is ("abort" for SIGABRT), or None."""
    if kind == "signal 6":
        return "abort"
    return kind if is_finding(kind) else None


def exit_code(kind):
    return int(kind.split()[1]) if kind.startswith("exit ") else None


BACKTRACE = re.compile(r"^\s+(\d+: |at )|^stack backtrace:|^note: Some details are omitted")


def gist(text, n=3):
    """The lines of a command's output that say what happened: a panic's message, an
    allocation failure, else the last `n` lines, without backtraces."""
    lines = [l for l in text.strip().splitlines() if l.strip() and not BACKTRACE.search(l)]
    for i, l in enumerate(lines):
        if "panicked at" in l:
            return lines[i:i + 2]
        if l.startswith("memory allocation of"):
            return [l]
    return lines[-n:]


class Phase:
    """Cases run, outcome counts and findings of one phase."""

    def __init__(self, name):
        self.name, self.cases, self.counts, self.findings, self.notes = name, 0, {}, [], []

    def outcome(self, kind):
        self.cases += 1
        self.counts[kind] = self.counts.get(kind, 0) + 1

    def finding(self, kind, cmd, detail=""):
        self.findings.append((kind, cmd, detail))
        first = detail.strip().splitlines()[0] if detail.strip() else ""
        print(f"fuzz: {self.name}: FINDING {kind}: {first}", flush=True)

    def note(self, text):
        self.notes.append(text)
        print(f"fuzz: {self.name}: {text}", flush=True)


class Budget:
    """The total time of the run (0: no limit), shared by the phases: each gets an equal share
    of what is left when it starts. No new case starts once the phase's share is spent."""

    def __init__(self, seconds):
        self.t0, self.seconds, self.stops, self.phase_end = time.time(), seconds, [], None

    def begin(self, phases_left):
        if self.seconds:
            left = self.seconds - (time.time() - self.t0)
            self.phase_end = time.time() + max(left, 0) / phases_left

    def spent(self, where):
        if self.seconds and time.time() >= self.phase_end:
            if not self.stops or self.stops[-1][0] != self.phase_end:
                self.stops.append((self.phase_end, where))
            return True
        return False


def run_env():
    return dict(os.environ, RAYON_NUM_THREADS="1")


# ---------------------------------------------------------------------------------------------
# Scene phase: mutated shipped scenes and `--set` values.

def scene_phase(a, rng, work, ph, budget):
    scenes = sorted(glob.glob(SCENES_GLOB))
    n, t0 = 0, time.time()
    while time.time() - t0 < a.seconds and (a.cases == 0 or n < a.cases):
        if budget.spent(f"scene phase, case {n + 1}"):
            break
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
        ph.outcome(kind)
        f = finding_kind(kind)
        if f:
            keep = os.path.join(work, f"finding_{n}.toml")
            shutil.copy(path, keep)
            ph.finding(f, cmd[:3] + [keep] + cmd[4:], f"{os.path.basename(sc)}\n{err}")
        shutil.rmtree(out, ignore_errors=True)


# ---------------------------------------------------------------------------------------------
# Mesh phase: mutants of the shipped Gmsh files.

MESHES = [("footprint_refined.msh", "steady_footprint_refined.toml"),
          ("two_layer.msh", "two_layer_cylinder.toml")]
HUGE = ["100000000000", str(2 ** 62), str(2 ** 64), "-1", "0"]


def read_msh(path):
    """An ASCII .msh 4.1 file as its sections [name, body]; $Nodes and $Elements parsed into
    {"head": [str], "blocks": [{"head": [str], "tags": [int], "xyz": [str]}]} and
    {"head": [str], "blocks": [{"head": [str], "els": [[int]]}]}."""
    lines = open(path).read().splitlines()
    secs, i = [], 0
    while i < len(lines):
        name = lines[i][1:]
        j = lines.index("$End" + name, i)
        body = lines[i + 1:j]
        if name == "Nodes":
            blocks, k = [], 1
            for _ in range(int(body[0].split()[0])):
                h = body[k].split()
                c = int(h[3])
                blocks.append({"head": h, "tags": [int(t) for t in body[k + 1:k + 1 + c]],
                               "xyz": [l.strip() for l in body[k + 1 + c:k + 1 + 2 * c]]})
                k += 1 + 2 * c
            body = {"head": body[0].split(), "blocks": blocks}
        elif name == "Elements":
            blocks, k = [], 1
            for _ in range(int(body[0].split()[0])):
                h = body[k].split()
                c = int(h[3])
                blocks.append({"head": h, "els": [[int(t) for t in l.split()]
                                                  for l in body[k + 1:k + 1 + c]]})
                k += 1 + c
            body = {"head": body[0].split(), "blocks": blocks}
        secs.append([name, body])
        i = j + 1
    return secs


def section(secs, name):
    return next(b for n, b in secs if n == name)


def msh_text(secs):
    out = []
    for name, body in secs:
        out.append("$" + name)
        if name == "Nodes":
            out.append(" ".join(body["head"]))
            for b in body["blocks"]:
                out.append(" ".join(b["head"]))
                out += [str(t) for t in b["tags"]] + b["xyz"]
        elif name == "Elements":
            out.append(" ".join(body["head"]))
            for b in body["blocks"]:
                out.append(" ".join(b["head"]))
                out += [" ".join(map(str, e)) for e in b["els"]]
        else:
            out += body
        out.append("$End" + name)
    return ("\n".join(out) + "\n").encode()


def msh_binary(secs):
    """The same mesh as a binary .msh 4.1 file (little-endian, size_t of 8 bytes)."""
    sz = lambda *v: struct.pack(f"<{len(v)}Q", *v)
    i32 = lambda *v: struct.pack(f"<{len(v)}i", *v)
    f64 = lambda *v: struct.pack(f"<{len(v)}d", *v)
    out = [b"$MeshFormat\n4.1 1 8\n", i32(1), b"\n$EndMeshFormat\n"]
    for name, body in secs:
        if name == "MeshFormat":
            continue
        if name == "Entities":
            counts = [int(x) for x in body[0].split()]
            data, k = [sz(*counts)], 1
            for dim, c in enumerate(counts):
                for _ in range(c):
                    t = body[k].split()
                    k += 1
                    if dim == 0:
                        np_ = int(t[4])
                        data += [i32(int(t[0])), f64(*map(float, t[1:4])), sz(np_),
                                 i32(*map(int, t[5:5 + np_]))]
                    else:
                        np_ = int(t[7])
                        nb = int(t[8 + np_])
                        data += [i32(int(t[0])), f64(*map(float, t[1:7])), sz(np_),
                                 i32(*map(int, t[8:8 + np_])), sz(nb),
                                 i32(*map(int, t[9 + np_:9 + np_ + nb]))]
            body_b = b"".join(data)
        elif name == "Nodes":
            data = [sz(*map(int, body["head"]))]
            for b in body["blocks"]:
                h = b["head"]
                data += [i32(*map(int, h[:3])), sz(int(h[3])), sz(*b["tags"])]
                for l in b["xyz"]:
                    data.append(f64(*map(float, l.split()[:3])))
            body_b = b"".join(data)
        elif name == "Elements":
            data = [sz(*map(int, body["head"]))]
            for b in body["blocks"]:
                h = b["head"]
                data += [i32(*map(int, h[:3])), sz(int(h[3]))]
                data += [sz(*e) for e in b["els"]]
            body_b = b"".join(data)
        else:
            out.append(("$" + name + "\n" + "\n".join(body) + "\n$End" + name + "\n").encode())
            continue
        out += [f"${name}\n".encode(), body_b, f"\n$End{name}\n".encode()]
    return b"".join(out)


def xy(line):
    v = line.split()
    return float(v[0]), float(v[1])


def largest_block(secs):
    return max(section(secs, "Nodes")["blocks"], key=lambda b: len(b["tags"]))


def permuted(secs, rng):
    """The nodes of the largest $Nodes block listed in a random order, each tag with its own
    coordinates: the same mesh."""
    m = copy.deepcopy(secs)
    b = largest_block(m)
    pairs = list(zip(b["tags"], b["xyz"]))
    rng.shuffle(pairs)
    b["tags"], b["xyz"] = [p[0] for p in pairs], [p[1] for p in pairs]
    return m


def swapped(secs, rng):
    """Two nodes of the largest block exchange their tags: a random node and the one farthest
    from it, so that the cells of both are tangled."""
    m = copy.deepcopy(secs)
    b = largest_block(m)
    i = rng.randrange(len(b["tags"]))
    xi, yi = xy(b["xyz"][i])
    j = max(range(len(b["tags"])),
            key=lambda k: (xy(b["xyz"][k])[0] - xi) ** 2 + (xy(b["xyz"][k])[1] - yi) ** 2)
    b["tags"][i], b["tags"][j] = b["tags"][j], b["tags"][i]
    return m


def non_contiguous(secs, rng):
    """Node tags renumbered with random gaps (in increasing order), in $Nodes, the header's
    min/max tags and the elements' node lists: the same mesh."""
    m = copy.deepcopy(secs)
    nodes = section(m, "Nodes")
    old = sorted(t for b in nodes["blocks"] for t in b["tags"])
    new, t = {}, rng.randint(1, 1000)
    for o in old:
        new[o] = t
        t += rng.randint(1, 7)
    for b in nodes["blocks"]:
        b["tags"] = [new[t] for t in b["tags"]]
    nodes["head"][2], nodes["head"][3] = str(min(new.values())), str(max(new.values()))
    for b in section(m, "Elements")["blocks"]:
        b["els"] = [[e[0]] + [new[t] for t in e[1:]] for e in b["els"]]
    return m


def huge_counts(secs, rng):
    """(label, mutant) for every header count set to each value of HUGE (a value equal to the
    file's own is skipped)."""
    out = []

    def put(label, get, setv):
        for v in HUGE:
            m = copy.deepcopy(secs)
            if get(m) == v:
                continue
            setv(m, v)
            out.append((f"{label}={v}", m))

    def line_token(name, idx):
        def get(m):
            return section(m, name)[0].split()[idx]

        def setv(m, v):
            body = section(m, name)
            t = body[0].split()
            t[idx] = v
            body[0] = " ".join(t)
        return get, setv

    put("PhysicalNames count", *line_token("PhysicalNames", 0))
    for i, what in enumerate(["numPoints", "numCurves", "numSurfaces", "numVolumes"]):
        put(f"Entities {what}", *line_token("Entities", i))
    for sec, what in (("Nodes", ["numEntityBlocks", "numNodes", "minNodeTag", "maxNodeTag"]),
                      ("Elements", ["numEntityBlocks", "numElements", "minElementTag",
                                    "maxElementTag"])):
        for i, w in enumerate(what):
            def get(m, sec=sec, i=i):
                return section(m, sec)["head"][i]

            def setv(m, v, sec=sec, i=i):
                section(m, sec)["head"][i] = v
            put(f"{sec} {w}", get, setv)
        k = rng.randrange(len(section(secs, sec)["blocks"]))

        def getb(m, sec=sec, k=k):
            return section(m, sec)["blocks"][k]["head"][3]

        def setb(m, v, sec=sec, k=k):
            section(m, sec)["blocks"][k]["head"][3] = v
        put(f"{sec} block {k + 1} num{sec}InBlock", getb, setb)
    return out


def random_mutant(data, rng):
    """(label, bytes): a truncation, line deletions or duplications, or byte flips."""
    op = rng.randrange(4)
    if op == 0:
        k = rng.randrange(len(data))
        return f"truncated at byte {k}", data[:k]
    if op in (1, 2):
        lines = data.split(b"\n")
        done = []
        for _ in range(rng.randint(1, 3)):
            i = rng.randrange(len(lines))
            if op == 1:
                del lines[i]
            else:
                lines.insert(i, lines[rng.randrange(len(lines))])
            done.append(i + 1)
        return f"lines {done} {'deleted' if op == 1 else 'duplicated'}", b"\n".join(lines)
    b = bytearray(data)
    done = []
    for _ in range(rng.randint(1, 8)):
        i = rng.randrange(len(b))
        b[i] = rng.randrange(256)
        done.append(i)
    return f"bytes {done} flipped", bytes(b)


def check_cmd(a, scene, path):
    return [a.tread, "-q", "check", os.path.join(SCENARIOS, scene), "--set", f'mesh.file="{path}"']


def judge(kind, out, path, expect):
    """The finding of a `tread check` of a mesh mutant, or None. expect: "accept" (exit 0),
    "tangled" (exit 2 saying inverted or degenerate), "refuse" (exit 2) or "any" (0 or 2); an
    exit 2 must name the file."""
    f = finding_kind(kind)
    if f:
        return f
    code = exit_code(kind)
    if code == 0:
        return "wrong-accept" if expect in ("tangled", "refuse") else None
    if code != 2:
        return "wrong-exit"
    if expect == "accept":
        return "wrong-refuse"
    if path not in out and os.path.basename(path) not in out:
        return "unnamed-file"
    if expect == "tangled" and "inverted" not in out and "degenerate" not in out:
        return "wrong-message"
    return None


def hub_loads(summary):
    """Every number of summary.json whose key names the hub, by its path."""
    found = {}

    def walk(v, path):
        if isinstance(v, dict):
            for k, x in v.items():
                walk(x, path + [k])
        elif isinstance(v, list):
            for i, x in enumerate(v):
                walk(x, path + [str(i)])
        elif isinstance(v, (int, float)) and not isinstance(v, bool) and any(
                "hub" in p for p in path):
            found[".".join(path)] = float(v)
    walk(summary.get("results", summary), [])
    return found


def mesh_phase(a, rng, work, ph, budget):
    mdir = os.path.join(work, "mesh")
    os.makedirs(mdir, exist_ok=True)
    cases = []  # (label, scene, path, expect)
    n = 0

    def write(data):
        nonlocal n
        n += 1
        p = os.path.join(mdir, f"mutant_{n}.msh")
        open(p, "wb").write(data)
        return p

    parsed = {}
    for msh, scene in MESHES:
        secs = read_msh(os.path.join(SCENARIOS, msh))
        parsed[msh] = secs
        cases.append((f"{msh}: permuted node order", scene, write(msh_text(permuted(secs, rng))),
                      "accept"))
        for _ in range(2):
            cases.append((f"{msh}: two node tags swapped", scene,
                          write(msh_text(swapped(secs, rng))), "tangled"))
        cases.append((f"{msh}: non-contiguous tags", scene,
                      write(msh_text(non_contiguous(secs, rng))), "accept"))
        cases.append((f"{msh}: binary 4.1", scene, write(msh_binary(secs)), "accept"))
        binary = msh_binary(secs)
        for _ in range(3):
            k = rng.randrange(len(binary))
            cases.append((f"{msh}: binary 4.1 truncated at byte {k}", scene, write(binary[:k]),
                          "any"))
    for msh, scene in MESHES:
        for label, m in huge_counts(parsed[msh], rng):
            cases.append((f"{msh}: {label}", scene, write(msh_text(m)), "refuse"))
    cases.append(("/dev/zero", MESHES[1][1], "/dev/zero", "refuse"))
    big = os.path.join(mdir, "sparse_2G.msh")
    with open(big, "wb") as f:
        f.truncate(2 << 30)
    cases.append(("a 2 GiB sparse file", MESHES[1][1], big, "refuse"))
    k = 0
    t0 = time.time()
    while time.time() - t0 < a.seconds and k < (a.cases or 10 ** 9):
        k += 1
        msh, scene = rng.choice(MESHES)
        data = open(os.path.join(SCENARIOS, msh), "rb").read()
        if rng.random() < 0.2:
            data = msh_binary(parsed[msh])
            msh += " (binary)"
        label, mut = random_mutant(data, rng)
        cases.append((f"{msh}: {label}", scene, write(mut), "any"))
        if len(cases) > 10000:
            break
    # Generating random mutants is cheap; running them is bounded by --cases and --seconds.
    ref = {}
    for label, scene, path, expect in cases:
        if budget.spent(f"mesh phase, {label}"):
            break
        cmd = check_cmd(a, scene, path)
        # The bounded inputs (/dev/zero, a file past the bound) must be refused quickly.
        bounded = path in ("/dev/zero", big)
        t = min(a.timeout, 30) if bounded else a.timeout
        t1 = time.time()
        kind, out = run_case(cmd, t, limit(a.memory))
        ph.outcome(kind)
        f = judge(kind, out, path, expect)
        slow(ph, bounded, kind, time.time() - t1, cmd, label)
        if f and f != "wrong-accept":
            ph.finding(f, cmd, f"{label}\n{out}")
            continue
        if exit_code(kind) != 0:
            continue
        # The same mesh must give the same results: each accepted file that is the original
        # mesh (permuted, renumbered, binary) is run against the original file.
        if expect == "accept":
            res = same_results(a, scene, path, ref, work, ph, label)
            if res:
                ph.finding(res[0], res[1], f"{label}\n{res[2]}")
            continue
        # Every other accepted mutant is run (coarse: one load step, summary and CSV only): a
        # file `check` lets through must not crash, hang or give NaN in `run`, and `run`'s
        # verdict says what the accepted file is.
        o = os.path.join(work, "mesh_run")
        rcmd = [a.tread, "-q", "run", os.path.join(SCENARIOS, scene), "--set",
                f'mesh.file="{path}"', "--set", "solver.load_steps=1", "--set",
                'output.sinks=["summary","csv"]', "--out", o, "--max-memory",
                f"{a.memory // 2}M"]
        t1 = time.time()
        rkind, rout = run_case(rcmd, t, limit(a.memory))
        ph.outcome(rkind)
        slow(ph, bounded, rkind, time.time() - t1, rcmd, label)
        rf = finding_kind(rkind)
        bad = non_finite_outputs(o) if not rf else []
        shutil.rmtree(o, ignore_errors=True)
        if f:
            # `run` refusing what `check` accepted: the check does not read what the run reads.
            if f == "wrong-accept" and judge(rkind, rout, path, expect) is None:
                f = "wrong-accept by check"
            ph.finding(f, cmd, f"{label}; `tread run` of it: {rkind}\n{rout}")
        if rf or bad:
            ph.finding(rf or "non-finite output", rcmd, f"{label}\n" + (rout if rf else bad[0]))
    os.remove(big)


BOUNDED_SECONDS = 5


def slow(ph, bounded, kind, seconds, cmd, label):
    """A refusal of an input past the reader's bound (/dev/zero, a 2 GiB file) taking longer
    than BOUNDED_SECONDS: the file was read (into memory) rather than refused by its size."""
    if bounded and exit_code(kind) == 2 and seconds > BOUNDED_SECONDS:
        ph.finding("slow-refusal", cmd, f"{label}: refused after {seconds:.1f} s (more than "
                   f"{BOUNDED_SECONDS} s; the address space is limited to --memory)")


def summary_run(a, scene, path, out):
    cmd = [a.tread, "-q", "run", os.path.join(SCENARIOS, scene), "--out", out,
           "--set", 'output.sinks=["summary"]', "--max-memory", f"{a.memory // 2}M"]
    if path:
        cmd += ["--set", f'mesh.file="{path}"']
    kind, err = run_case(cmd, a.timeout, limit(a.memory))
    try:
        s = json.load(open(os.path.join(out, "summary.json")))
    except (OSError, ValueError):
        s = None
    shutil.rmtree(out, ignore_errors=True)
    return cmd, kind, err, s


def same_results(a, scene, path, ref, work, ph, label):
    """Run `scene` on the mesh `path` and on its own mesh: (finding, cmd, what differs), or
    None when the hub loads agree to 1e-9 of the largest of them."""
    if scene not in ref:
        cmd, kind, err, s = summary_run(a, scene, None, os.path.join(work, "ref_run"))
        ph.outcome(kind)
        ref[scene] = s
        if s is None or exit_code(kind) != 0:
            ph.note(f"{scene} on its own mesh: {kind}, no summary to compare with")
    if ref[scene] is None:
        return None
    cmd, kind, err, s = summary_run(a, scene, path, os.path.join(work, "cmp_run"))
    ph.outcome(kind)
    f = finding_kind(kind)
    if f or exit_code(kind) == 2:
        # The same mesh refused by `run` (or crashing it) although `check` accepted it.
        return f or "wrong-refuse", cmd, f"`tread run`: {kind}\n{err}"
    if s is None or exit_code(kind) != 0:
        return "wrong-result", cmd, f"{kind}, no summary.json\n{err}"
    h0, h1 = hub_loads(ref[scene]), hub_loads(s)
    if not h0:
        ph.note(f"{scene}: summary.json has no hub loads to compare")
        return None
    scale = max(abs(v) for v in h0.values()) or 1.0
    bad = [f"{k}: {h0[k]} vs {h1.get(k)}" for k in h0
           if k not in h1 or not abs(h1[k] - h0[k]) <= 1e-9 * max(abs(h0[k]), scale)]
    return ("wrong-result", cmd, "hub loads differ from the original file's: "
            + "; ".join(bad[:3])) if bad else None


# ---------------------------------------------------------------------------------------------
# Fault phase: full disks, signals, a second run into the same folder.

FINAL = (".png", ".json", ".csv", ".vtu")


def complete(path):
    """Whether an output file is whole: JSON parses, every CSV row has the header's fields and
    the file ends with a newline, a VTU/PVD ends with its closing tag, a PNG with IEND."""
    try:
        data = open(path, "rb").read()
    except OSError:
        return False
    if path.endswith(".json"):
        try:
            json.loads(data)
            return True
        except ValueError:
            return False
    if path.endswith(".csv"):
        rows = data.split(b"\n")
        if not data.endswith(b"\n"):
            return False
        n = rows[0].count(b",")
        return all(r.count(b",") == n for r in rows[1:-1] if not r.startswith(b"#"))
    if path.endswith((".vtu", ".pvd")):
        return data.rstrip().endswith(b"</VTKFile>")
    if path.endswith(".png"):
        return data.endswith(b"IEND\xaeB`\x82")
    return len(data) > 0


def incomplete_outputs(summary, out):
    """The files summary.json `incomplete_outputs` names (entries as paths or as objects with
    a `path`), relative to the output folder."""
    names = set()
    for e in (summary or {}).get("incomplete_outputs") or []:
        p = e.get("path") or e.get("file") if isinstance(e, dict) else e
        if isinstance(p, str):
            names.add(os.path.relpath(p, out) if os.path.isabs(p) else p)
    return names


def inspect_outputs(out):
    """(kind, detail) of every problem of an output folder after a run into a full disk."""
    problems = []
    try:
        summary = json.load(open(os.path.join(out, "summary.json")))
    except FileNotFoundError:
        summary = None
    except (OSError, ValueError) as e:
        problems.append(("incomplete-output", f"summary.json: {e}"))
        summary = None
    allowed = incomplete_outputs(summary, out)
    present = []
    for root, _, files in os.walk(out):
        for f in files:
            p = os.path.join(root, f)
            rel = os.path.relpath(p, out)
            if f.endswith(".tmp"):
                problems.append(("leftover-tmp", rel))
            elif f.endswith(FINAL) and os.path.getsize(p) == 0 and rel not in allowed:
                problems.append(("zero-byte", rel))
            elif not f.startswith("."):
                present.append(rel)
    if summary and summary.get("converged") is True:
        listed = summary.get("outputs") or summary.get("files")
        if isinstance(listed, dict):
            listed = list(listed.values())
        names = [x for x in listed if isinstance(x, str)] if isinstance(listed, list) else None
        # Without a list of outputs in the summary, every file present must be whole.
        for rel in (names if names is not None else present):
            if rel in allowed:
                continue
            p = os.path.join(out, rel)
            if not os.path.exists(p):
                problems.append(("missing-output", rel))
            elif not complete(p):
                problems.append(("incomplete-output", rel))
    for line in non_finite_outputs(out):
        problems.append(("non-finite output", line))
    return grouped(problems)


def grouped(problems):
    """(kind, "a, b, c"): the problems of one case, one per kind."""
    by = {}
    for k, d in problems:
        by.setdefault(k, []).append(d)
    return [(k, ", ".join(v)) for k, v in by.items()]


def mount_tmpfs(d, size):
    """None when a tmpfs of `size` is mounted on `d`, else why not."""
    if os.geteuid() != 0:
        return "not running as root"
    os.makedirs(d, exist_ok=True)
    p = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", d],
                       capture_output=True)
    if p.returncode != 0:
        return f"mount -t tmpfs failed: {p.stderr.decode(errors='replace').strip()}"
    return None


def umount(d):
    subprocess.run(["umount", d], capture_output=True)


FULL_DISK_RUNS = [
    ("spinning_neo_hookean.toml", []),
    ("rolling_frictionless.toml", ["--mode", "steady", "--set", "mesh.n_r=2", "--set",
                                   "mesh.n_theta=16"]),
]
SIZES = ["64k", "256k", "1M"]
LONG_RUN = "oden_hollow_cylinder.toml"
# Rolling on past steady state, for about a minute on one core: still running when signalled.
LONG_SETS = ["--set", "time.stop_at_steady=false", "--set", "time.t_end=10"]


def full_disk(a, work, ph, budget):
    mnt = os.path.join(work, "tmpfs")
    why = mount_tmpfs(mnt, "64k")
    if why:
        ph.note(f"SKIPPED the full-disk runs and replays: {why}")
        return False
    umount(mnt)
    for scene, extra in FULL_DISK_RUNS:
        for size in SIZES:
            if budget.spent(f"fault phase, {scene} into a {size} tmpfs"):
                return True
            why = mount_tmpfs(mnt, size)
            if why:
                ph.note(f"SKIPPED {scene} into a {size} tmpfs: {why}")
                continue
            try:
                out = os.path.join(mnt, "out")
                cmd = [a.tread, "-q", "run", os.path.join(SCENARIOS, scene), "--out", out] + extra
                kind, err = run_case(cmd, a.timeout, limit(a.memory))
                ph.outcome(kind)
                label = f"a {size} tmpfs at {mnt}"
                f = finding_kind(kind)
                if f:
                    ph.finding(f, cmd, f"{label}\n{err}")
                elif exit_code(kind) not in (0, 3):
                    ph.finding("wrong-exit", cmd, f"{label}: {kind} (expected 0 or 3)\n{err}")
                for k, detail in inspect_outputs(out):
                    ph.finding(k, cmd, f"{label}: {detail}")
            finally:
                umount(mnt)
    return True


def replay_full(a, work, ph, budget):
    """`tread replay` of a run's .mcap (and .rrd when this build writes one) into a 64k tmpfs."""
    src = os.path.join(work, "replay_src")
    cmd = [a.tread, "-q", "run", os.path.join(SCENARIOS, "spinning_neo_hookean.toml"), "--out",
           src, "--set", 'output.sinks=["summary","mcap","rerun"]']
    kind, err = run_case(cmd, a.timeout, limit(a.memory))
    ph.outcome(kind)
    if finding_kind(kind):
        ph.finding(finding_kind(kind), cmd, err)
    mnt = os.path.join(work, "tmpfs")
    for log in ("run.mcap", "run.rrd"):
        p = os.path.join(src, log)
        if not os.path.exists(p):
            ph.note(f"SKIPPED replay of {log} into a full disk: the run wrote no {log}")
            continue
        if budget.spent(f"fault phase, replay of {log}"):
            return
        why = mount_tmpfs(mnt, "64k")
        if why:
            ph.note(f"SKIPPED replay of {log} into a full disk: {why}")
            return
        try:
            cmd = [a.tread, "replay", p, "--to", os.path.join(mnt, "y.rrd")]
            kind, err = run_case(cmd, a.timeout, limit(a.memory))
            if "needs the `rerun` cargo feature" in err or "rerun` feature" in err:
                ph.note(f"SKIPPED replay of {log} into a full disk: this build has no .rrd "
                        f"support ({err.strip().splitlines()[-1]})")
                continue
            ph.outcome(kind)
            f = finding_kind(kind)
            if f:
                ph.finding(f, cmd, err)
            elif exit_code(kind) == 0:
                ph.finding("wrong-accept", cmd, f"exit 0 into a 64k tmpfs ({os.path.getsize(p)}"
                           f" bytes of {log})\n{err}")
            for k, detail in inspect_outputs(mnt):
                if k in ("leftover-tmp", "zero-byte"):
                    ph.finding(k, cmd, detail)
        finally:
            umount(mnt)


def sta_finished(out):
    try:
        lines = open(os.path.join(out, "run.sta")).read().splitlines()
    except OSError:
        return False
    last = lines[-1] if lines else ""
    return last.startswith("#") and any(w in last for w in ("completed", "interrupted", "failed"))


def readable(out):
    """Problems of the files a killed run left: JSON that does not parse, a CSV row cut short
    before the last line, a non-finite number."""
    problems = []
    for root, _, files in os.walk(out):
        for f in files:
            p = os.path.join(root, f)
            rel = os.path.relpath(p, out)
            if f.startswith(".") or f.endswith(".tmp"):
                continue
            if f.endswith(".json") and not complete(p):
                problems.append(("incomplete-output", rel))
            if f.endswith(".csv"):
                rows = open(p, "rb").read().split(b"\n")
                n = rows[0].count(b",")
                if any(r.count(b",") != n for r in rows[1:-2] if not r.startswith(b"#")):
                    problems.append(("incomplete-output", rel))
    return grouped(problems + [("non-finite output", l) for l in non_finite_outputs(out)])


def start(cmd, a, log):
    return subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=open(log, "wb"),
                            preexec_fn=limit(a.memory), env=run_env())


def signals(a, rng, work, ph, budget):
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
        if budget.spent(f"fault phase, {sig.name}"):
            return
        out = os.path.join(work, f"sig_{sig.name}")
        log = out + ".log"
        cmd = [a.tread, "-q", "run", os.path.join(SCENARIOS, LONG_RUN), "--out", out] + LONG_SETS
        delay = round(rng.uniform(2, 5), 1)
        p = start(cmd, a, log)
        time.sleep(delay)
        label = f"kill -{sig.name[3:]} after {delay} s"
        shown = cmd + [f"# {label}"]
        if p.poll() is not None:
            ph.outcome(f"exit {p.returncode}")
            ph.note(f"{LONG_RUN} ended before {sig.name} ({p.returncode}): case not run")
            continue
        p.send_signal(sig)
        try:
            rc = p.wait(30)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
            ph.outcome("hang")
            ph.finding("hang", shown, f"no exit within 30 s of {sig.name}")
            continue
        err = open(log, "rb").read().decode(errors="replace")
        kind = f"signal {-rc}" if rc < 0 else f"exit {rc}"
        if "panicked" in err or rc == 101:
            kind = "panic"
        ph.outcome(kind)
        if sig == signal.SIGKILL:
            for k, detail in readable(out):
                ph.finding(k, shown, detail)
            continue
        ok = (130,) if sig == signal.SIGINT else (130, 143)
        if kind == "panic":
            ph.finding("panic", shown, err)
        elif rc < 0:
            ph.finding(f"killed by {signal.Signals(-rc).name}", shown,
                       f"died of the signal, without cleanup\n{err}")
        elif rc not in ok:
            ph.finding("wrong-exit", shown,
                       f"exit {rc}, expected {' or '.join(map(str, ok))}\n{err}")
        if not os.path.exists(os.path.join(out, "summary.json")):
            ph.finding("missing-output", shown, "no summary.json")
        if not sta_finished(out):
            ph.finding("unfinished-sta", shown, "run.sta has no final line")
        for k, detail in readable(out):
            ph.finding(k, shown, detail)


def concurrent(a, work, ph, budget):
    if budget.spent("fault phase, concurrent runs"):
        return
    out = os.path.join(work, "shared_out")
    cmd = [a.tread, "-q", "run", os.path.join(SCENARIOS, LONG_RUN), "--out", out] + LONG_SETS
    first = start(cmd, a, out + ".first.log")
    try:
        t0 = time.time()
        while not os.path.exists(os.path.join(out, ".tread.lock")) and time.time() - t0 < 20:
            if first.poll() is not None:
                break
            time.sleep(0.1)
        if first.poll() is not None:
            ph.note(f"the first run ended ({first.returncode}) before a second could start")
            return
        second = [a.tread, "-q", "run", os.path.join(SCENARIOS, "spinning_neo_hookean.toml"),
                  "--out", out]
        kind, err = run_case(second, a.timeout, limit(a.memory))
        ph.outcome(kind)
        f = finding_kind(kind)
        if f:
            ph.finding(f, second, err)
        elif exit_code(kind) != 3:
            ph.finding("wrong-accept" if exit_code(kind) == 0 else "wrong-exit", second,
                       f"{kind} while another run writes into {out} (expected 3)\n{err}")
        elif out not in err and os.path.basename(out) not in err:
            ph.finding("unnamed-file", second, f"the refusal does not name {out}\n{err}")
    finally:
        if first.poll() is None:
            first.send_signal(signal.SIGINT)
            try:
                first.wait(30)
            except subprocess.TimeoutExpired:
                first.kill()
                first.wait()


def fault_phase(a, rng, work, ph, budget):
    if full_disk(a, work, ph, budget):
        replay_full(a, work, ph, budget)
    signals(a, rng, work, ph, budget)
    concurrent(a, work, ph, budget)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tread", default="target/release/tread")
    ap.add_argument("--seconds", type=float, default=600,
                    help="time of the random cases of the scene and mesh phases, each")
    ap.add_argument("--cases", type=int, default=0,
                    help="random cases of the scene and mesh phases, each (0: time only)")
    ap.add_argument("--timeout", type=float, default=60)
    ap.add_argument("--memory", type=int, default=4096, help="address-space limit, MB")
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--phases", default=",".join(PHASES),
                    help=f"comma-separated, of {', '.join(PHASES)} (default: all)")
    ap.add_argument("--budget", type=float, default=0,
                    help="total seconds: no new case starts once spent (0: no limit)")
    ap.add_argument("--shipped", action="store_true",
                    help="run every shipped scene once, unmutated, and check it the same way")
    a = ap.parse_args()
    if a.shipped:
        sys.exit(shipped(a))
    phases = [p.strip() for p in a.phases.split(",") if p.strip()]
    unknown = [p for p in phases if p not in PHASES]
    if unknown:
        ap.error(f"unknown phase {', '.join(unknown)} (expected {', '.join(PHASES)})")
    a.tread = os.path.abspath(a.tread) if os.sep in a.tread else a.tread
    seed = a.seed if a.seed is not None else int(time.time())
    budget = Budget(a.budget)
    work = tempfile.mkdtemp(prefix="tread-fuzz-")
    print(f"fuzz: seed {seed}, phases {','.join(phases)}, timeout {a.timeout} s, memory "
          f"{a.memory} MB{f', budget {a.budget:.0f} s' if a.budget else ''}", flush=True)
    report = []
    for i, name in enumerate(phases):
        budget.begin(len(phases) - i)
        ph = Phase(name)
        report.append(ph)
        # One generator per phase: a phase's cases do not depend on which others run.
        rng = random.Random(f"{seed}:{name}")
        t0 = time.time()
        {"scene": scene_phase, "mesh": mesh_phase, "fault": fault_phase}[name](
            a, rng, work, ph, budget)
        ph.seconds = time.time() - t0
    total_f = 0
    for ph in report:
        kinds = {}
        for k, _, _ in ph.findings:
            kinds[k] = kinds.get(k, 0) + 1
        total_f += len(ph.findings)
        print(f"fuzz: {ph.name}: {ph.cases} cases in {ph.seconds:.0f} s: outcomes "
              f"{dict(sorted(ph.counts.items()))}; "
              f"findings {dict(sorted(kinds.items())) or 'none'}")
        for t in ph.notes:
            print(f"fuzz: {ph.name}:   {t}")
    for ph in report:
        for kind, cmd, detail in ph.findings:
            print(f"fuzz: FINDING [{ph.name}] {kind}: {' '.join(cmd)}")
            first, _, rest = detail.strip().partition("\n")
            for l in ([first] if first else []) + gist(rest):
                print(f"    {l}")
    for _, where in budget.stops:
        print(f"fuzz: budget: the share of the {a.budget:.0f} s was spent before {where}")
    print(f"fuzz: total: {sum(p.cases for p in report)} cases, {total_f} findings in "
          f"{time.time() - budget.t0:.0f} s (seed {seed})")
    if total_f:
        print(f"fuzz: the inputs of the findings are kept in {work}")
    else:
        shutil.rmtree(work, ignore_errors=True)
    sys.exit(1 if total_f else 0)


if __name__ == "__main__":
    main()
