#!/usr/bin/env python3
"""Check that a steady continuation in omega logged its branch points on the `omega` timeline
of a Rerun recording, read back by the Rerun CLI (`rerun rrd print -vv`, no tread code).

For every entity path the rows of the chunks indexed by the timeline are counted. The branch
series (`/branch/omega`) must have one row per point of `branch.csv` in the same output folder,
and the body mesh (`/body/mesh`) one per point after the first (the first point is the last load
step, whose body was logged before the continuation began).

Usage: check_rrd_timeline.py RERUN_CLI OUT_DIR [--timeline omega]
"""

import argparse
import csv
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

HEADER = re.compile(r"^Chunk\((\S+)\) with (\d+) rows .* - (\S+) - ")


def rows_on_timeline(rerun: str, rrd: Path, timeline: str) -> dict:
    """Rows per entity path of the chunks that carry the index `timeline`."""
    out = subprocess.run(
        [rerun, "rrd", "print", "-vv", str(rrd)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    counts = defaultdict(int)
    entity, rows, indexed = None, 0, False

    def flush():
        if entity is not None and indexed:
            counts[entity] += rows

    for line in out.splitlines():
        m = HEADER.match(line)
        if m:
            flush()
            entity, rows, indexed = m.group(3), int(m.group(2)), False
        elif f"index_name: {timeline} " in line or line.rstrip().endswith(f"index_name: {timeline}"):
            indexed = True
    flush()
    return counts


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rerun")
    ap.add_argument("out", type=Path)
    ap.add_argument("--timeline", default="omega")
    a = ap.parse_args()
    with open(a.out / "branch.csv", newline="") as f:
        branch = list(csv.DictReader(f))
    counts = rows_on_timeline(a.rerun, a.out / "run.rrd", a.timeline)
    ok = True
    for entity, want in (("/body/mesh", len(branch) - 1), ("/branch/omega", len(branch))):
        n = counts.get(entity, 0)
        good = n == want and want > 0
        ok &= good
        print(f"check_rrd_timeline: {entity}: {n} rows on the '{a.timeline}' timeline, "
              f"{want} expected ({len(branch)} branch points): {'ok' if good else 'MISMATCH'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
