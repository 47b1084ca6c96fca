#!/usr/bin/env bash
# Manual cross-check of a run's logs with the official Rerun CLI (not part of CI: it needs
# `pip install rerun-sdk==0.36.*`, i.e. network). Usage: tools/check_logs_with_rerun.sh OUT_DIR
# Checks: the .rrd decodes (`rerun rrd verify`), the MCAP is structurally sound for Rerun's
# importer (`rerun mcap check --full`) and converts, with the point clouds mapped to Points3D.
set -euo pipefail
dir="${1:?usage: $0 OUT_DIR}"
rerun="${RERUN:-rerun}"
command -v "$rerun" >/dev/null || { echo "install the Rerun CLI: pip install rerun-sdk==0.36.*" >&2; exit 1; }
"$rerun" rrd verify "$dir/run.rrd"
"$rerun" mcap check --full "$dir/run.mcap"
tmp="$(mktemp -d)"
"$rerun" mcap convert "$dir/run.mcap" -o "$tmp/from_mcap.rrd" --timeline-type duration
"$rerun" rrd verify "$tmp/from_mcap.rrd"
"$rerun" rrd stats "$tmp/from_mcap.rrd" | grep -q "Points3D:positions" \
  && echo "Rerun's MCAP importer maps the point clouds to Points3D"
rm -rf "$tmp"
