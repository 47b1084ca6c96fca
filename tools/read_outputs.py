"""Read every output of a tread run back with independent readers and check it.

Usage: read_outputs.py OUT_DIR [OUT_DIR ...]; a folder of a model-problem scene (summary
`mode` = `model_problem`) is checked by `check_model_dir`.

Readers: Python `mcap` (with the protobuf schemas embedded in run.mcap, decoded by the
`protobuf` runtime), meshio (every .vtu of fields.pvd and steady.vtu), the csv module, json.
Checks: steps unique and increasing 0, 1, 2, … in history.csv and the MCAP step channel; times
increasing and equal across history.csv, fields.pvd, the .vtu TimeValue and the MCAP log times;
when the run has friction (summary terms.friction) and contact, a non-zero tangential traction
in contact.csv and the last MCAP contact patch. Exits 1 on the first failed check.
"""
import csv
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

import meshio
from mcap.reader import make_reader
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory


def fail(msg):
    print(f"read_outputs: FAIL: {msg}")
    sys.exit(1)


def check(cond, msg):
    if not cond:
        fail(msg)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return rows


def decoder(schema):
    fds = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        try:
            pool.Add(fd)
        except Exception:
            pass
    desc = pool.FindMessageTypeByName(schema.name)
    cls = message_factory.GetMessageClass(desc)
    return cls.FromString


def read_mcap(path):
    msgs = []
    decoders = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema.id not in decoders:
                decoders[schema.id] = decoder(schema)
            msgs.append((channel.topic, message.log_time, decoders[schema.id](message.data)))
    return msgs


def check_dir(d):
    s = json.load(open(os.path.join(d, "summary.json")))
    print(f"read_outputs: {d}: scene {s['scene']} ({s['mode']}), converged {s['converged']}")
    hist = read_csv(os.path.join(d, "history.csv"))
    steps = [int(r["step"]) for r in hist]
    check(steps == list(range(len(steps))), f"{d}/history.csv steps {steps[:10]}…")
    times = [float(r["time"]) for r in hist]
    check(all(b > a for a, b in zip(times, times[1:])), f"{d}/history.csv times not increasing")
    for r in hist:
        check(r["newton_iterations"].isdigit(), f"newton_iterations {r['newton_iterations']!r}")

    # fields.pvd and every .vtu with meshio.
    pvd = ET.parse(os.path.join(d, "fields.pvd")).getroot()
    entries = [(float(e.get("timestep")), e.get("file")) for e in pvd.iter("DataSet")]
    pt = [t for t, _ in entries]
    check(all(b > a for a, b in zip(pt, pt[1:])), f"{d}/fields.pvd times {pt}")
    for t, f in entries:
        step = int(os.path.basename(f)[5:-4])
        check(t == times[step], f"{f}: pvd time {t} != history time {times[step]}")
        m = meshio.read(os.path.join(d, f))
        check(m.points.shape[0] > 0 and "displacement" in m.point_data, f"{f}: no displacement")
        tv = m.field_data.get("TimeValue")
        if tv is not None:
            check(float(tv.ravel()[0]) == t, f"{f}: TimeValue {tv} != {t}")
    if os.path.exists(os.path.join(d, "steady.vtu")):
        m = meshio.read(os.path.join(d, "steady.vtu"))
        u = m.point_data["displacement"]
        umax = max(math.hypot(a, b) for a, b, _ in u)
        sf = os.path.join(d, "steady_field.csv")
        if os.path.exists(sf):
            rows = read_csv(sf)
            fmax = max(math.hypot(float(r["u1"]), float(r["u2"])) for r in rows)
            check(abs(umax - fmax) <= 1e-9 * fmax, f"steady.vtu max|u| {umax} != steady_field {fmax}")
    print(f"read_outputs:   history.csv {len(hist)} steps, fields.pvd {len(entries)} .vtu read by meshio")

    # MCAP with its embedded schemas.
    msgs = read_mcap(os.path.join(d, "run.mcap"))
    st = [m for m in msgs if m[0] == "/tread/step"]
    idx = [m[2].index for m in st]
    check(idx == list(range(len(idx))), f"MCAP /tread/step indices {idx[:10]}…")
    check(idx == steps, "MCAP steps differ from history.csv")
    for (_, lt, m), t in zip(st, times):
        check(m.time == t, f"MCAP step time {m.time} != {t}")
        check(abs(lt - t * 1e9) <= 1, f"MCAP log_time {lt} != {t} s")
    for topic in ("/tread/hub", "/tread/energy"):
        s_ = [m[2].step for m in msgs if m[0] == topic]
        check(all(b > a for a, b in zip(s_, s_[1:])), f"{topic} steps {s_}")
    logs = [m for m in msgs if m[0] == "/tread/log"]
    if len(times) > 0:
        check(logs[-1][1] >= int(times[-1] * 1e9) - 1, "end-of-run log not at the last step")
    print(f"read_outputs:   run.mcap {len(msgs)} messages, {len(st)} steps")

    # Static friction: the tangential traction is reported.
    contact = os.path.join(d, "contact.csv")
    if s.get("terms", {}).get("friction") and os.path.exists(contact):
        rows = read_csv(contact)
        tn = max(float(r["t_n"]) for r in rows)
        tt = max(abs(float(r["t_t"])) for r in rows)
        check(tn > 0 and tt > 0.01 * tn, f"contact.csv: max |t_t| {tt} vs max t_n {tn}")
        patch = [m for m in msgs if m[0] == "/tread/contact_patch"]
        check(patch and max(abs(v) for v in patch[-1][2].t_t) > 0.01 * tn, "MCAP t_t all 0")
        print(f"read_outputs:   friction: max |t_t| = {tt:.4g}, max t_n = {tn:.4g}")


def check_model_dir(d):
    """A model problem: steps.csv against summary.json, solution.vtu by meshio (quads only,
    the cell fields per cell, their root sum of squares against the summary's error and
    estimate where the VTU has one sub-quad per cell)."""
    s = json.load(open(os.path.join(d, "summary.json")))
    r = s["results"]
    print(f"read_outputs: {d}: model problem {s['kind']} ({s['scene']}), converged {s['converged']}")
    check(s["converged"], f"{d}: not converged")
    rows = read_csv(os.path.join(d, "steps.csv"))
    check(len(rows) == s["steps"], f"{d}/steps.csv: {len(rows)} rows, summary steps {s['steps']}")
    m = meshio.read(os.path.join(d, "solution.vtu"))
    check([c.type for c in m.cells] == ["quad"], f"{d}/solution.vtu cells {[c.type for c in m.cells]}")
    n = len(m.cells[0].data)
    for f in ("error_indicator", "degree", "level"):
        check(f in m.cell_data and len(m.cell_data[f][0]) == n, f"{d}/solution.vtu: cell field {f}")
    check(len(m.point_data) >= 1, f"{d}/solution.vtu: no point field")
    for name, v in m.point_data.items():
        check(len(v) == len(m.points), f"{d}/solution.vtu: point field {name}")
    if s["kind"] == "lshape" and r["max_degree"] == 1:
        ind = m.cell_data["error_indicator"][0]
        err = m.cell_data["error"][0]
        est = math.sqrt(sum(float(x) ** 2 for x in ind))
        e = math.sqrt(sum(float(x) ** 2 for x in err))
        check(abs(est - r["estimate"]) <= 1e-9 * r["estimate"], f"VTU estimate {est} vs {r['estimate']}")
        check(abs(e - r["energy_error"]) <= 1e-9 * r["energy_error"], f"VTU error {e} vs {r['energy_error']}")
    if s["kind"] == "cavity":
        check(n == 4 * r["cells"], f"{d}/solution.vtu: {n} quads for {r['cells']} cells")
        check(r["centreline_error"] < r["uniform_centreline_error"], "moved mesh not better")
    for png in ("error_mesh.png", "solution.png"):
        with open(os.path.join(d, png), "rb") as f:
            check(f.read(8) == b"\x89PNG\r\n\x1a\n", f"{d}/{png}: not a PNG")
    print(f"read_outputs:   steps.csv {len(rows)} rows, solution.vtu {n} quads, {len(m.points)} points")


if __name__ == "__main__":
    for d in sys.argv[1:]:
        with open(os.path.join(d, "summary.json")) as f:
            mode = json.load(f).get("mode")
        if mode == "model_problem":
            check_model_dir(d)
        else:
            check_dir(d)
    print("read_outputs: all checks passed")
