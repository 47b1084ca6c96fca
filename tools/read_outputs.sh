#!/usr/bin/env bash
# Read every output of two scenes, of two model-problem scenes (and the 3D outputs of tools/hex_outputs.rs,
# tools/check_hex_outputs.py) back with independent readers (Python mcap + protobuf,
# meshio, and `rerun rrd verify` when a run.rrd is written, plus the `omega` timeline of a steady
# continuation, tools/check_rrd_timeline.py; zlib-compressed VTU against the
# uncompressed files, tools/check_vtu_zlib.py) and check steps, times and the
# static friction traction. Installs the readers into a venv ($TREAD_READER_VENV, default
# target/reader-venv). Without network access the check is SKIPPED (exit 0, message says so).
# Usage: tools/read_outputs.sh [path/to/tread]
set -euo pipefail
cd "$(dirname "$0")/.."
TREAD=${1:-target/release/tread}
VENV=${TREAD_READER_VENV:-target/reader-venv}
OUT=target/read_outputs
RERUN_VERSION=0.36.3
if [ ! -x "$VENV/bin/python" ] || ! "$VENV/bin/python" -c "import mcap, meshio, google.protobuf" 2>/dev/null; then
    python3 -m venv "$VENV"
    if ! "$VENV/bin/pip" install -q --disable-pip-version-check mcap meshio numpy protobuf; then
        echo "read_outputs: SKIPPED: cannot install the Python readers (no network?); the outputs were NOT checked"
        exit 0
    fi
fi
rm -rf "$OUT"
SINKS='output.sinks=["summary","csv","vtu","mcap","png","rerun"]'
RAYON_NUM_THREADS=1 "$TREAD" -q run scenarios/indentation_friction.toml --out "$OUT/indentation_friction" \
    --set mesh.n_r=3 --set mesh.n_theta=48 --set "$SINKS"
RAYON_NUM_THREADS=1 "$TREAD" -q run scenarios/free_rolling.toml --out "$OUT/free_rolling" --set "$SINKS"
"$VENV/bin/python" tools/read_outputs.py "$OUT/indentation_friction" "$OUT/free_rolling"
# Model problems (scenes with [problem]): steps.csv, solution.vtu by meshio, the PNGs, run.rrd.
for k in cavity lshape; do
    RAYON_NUM_THREADS=1 "$TREAD" -q run "scenarios/model_problems/$k.toml" --out "$OUT/model_$k" \
        --set 'output.sinks=["summary","csv","vtu","png","rerun"]'
done
"$VENV/bin/python" tools/read_outputs.py "$OUT/model_cavity" "$OUT/model_lshape"
# zlib-compressed VTU: the same scene with `output.vtu_compression = "zlib"` must give the same
# arrays (decoded independently, then by meshio, and by VTK when the `vtk` package is there).
RAYON_NUM_THREADS=1 "$TREAD" -q run scenarios/indentation_friction.toml --out "$OUT/indentation_friction_zlib" \
    --set mesh.n_r=3 --set mesh.n_theta=48 --set "$SINKS" --set output.vtu_compression=zlib
"$VENV/bin/python" tools/check_vtu_zlib.py "$OUT/indentation_friction_zlib" "$OUT/indentation_friction"
# A steady continuation in omega (its branch points on the recording's `omega` timeline).
RAYON_NUM_THREADS=1 "$TREAD" -q run scenarios/oden_figs_9_13.toml --out "$OUT/oden_figs_9_13" \
    --set continuation.max_steps=6 --set 'output.sinks=["summary","csv","rerun"]'
# 3D outputs of hexahedral meshes (Hex8, Hex27): VTU by meshio, MCAP by the Python reader,
# against the closed-form fields of tools/hex_outputs.rs (its .rrd is verified below).
HEX_OUTPUTS=${TREAD_HEX_OUTPUTS:-${CARGO_TARGET_DIR:-target}/release/examples/hex_outputs}
if [ ! -x "$HEX_OUTPUTS" ]; then
    cargo build -q --release --example hex_outputs
fi
"$HEX_OUTPUTS" "$OUT/hex"
"$VENV/bin/python" tools/check_hex_outputs.py "$OUT/hex"
# The .rrd files (only in builds with the `rerun` feature).
rrds=$(find "$OUT" -name run.rrd -o -name hex.rrd)
if [ -z "$rrds" ]; then
    echo "read_outputs: no run.rrd (build without the rerun feature): rrd verify SKIPPED"
    exit 0
fi
if ! "$VENV/bin/python" -c "import rerun" 2>/dev/null; then
    if ! "$VENV/bin/pip" install -q --disable-pip-version-check "rerun-sdk==$RERUN_VERSION"; then
        echo "read_outputs: SKIPPED: cannot install rerun-sdk==$RERUN_VERSION; the .rrd files were NOT verified"
        exit 0
    fi
fi
for f in $rrds; do
    "$VENV/bin/rerun" rrd verify "$f"
    echo "read_outputs: rrd verify $f: ok"
done
python3 tools/check_rrd_timeline.py "$VENV/bin/rerun" "$OUT/oden_figs_9_13"
