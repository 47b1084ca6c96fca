#!/bin/bash
# Steady mode: the strain-rate damping's cost against the undamped solve (a benchmark, not a
# test). For each mesh of the default scene it runs the steady solve with the scene's damping
# (the default `auto` tangent: matrix-free below 60,000 equations, banded from there; pass
# `--set solver.damping_tangent=X` with X = matrix_free, banded or assembled to pick one) and
# with `time.strain_rate_damping = 0`, on one thread, and prints Newton
# iterations, wall time, time per iteration and peak RSS (GNU time), then the ratios. With the
# nested iteration (solver.coarse_start, on by default) the iterations are those on the scene's
# mesh and the time per iteration leaves out the coarser meshes' time.
#
#   tools/bench_steady_damping.sh [TREAD_BINARY] [MESHES] [extra --set arguments...]
#   tools/bench_steady_damping.sh target/release/tread "8x256 16x512 32x1024"
#
# 32x1024 (262k DOFs) takes under a minute and 2.2 GB.
set -euo pipefail
BIN=${1:-target/release/tread}
MESHES=${2:-"8x256 16x512"}
shift $(( $# > 2 ? 2 : $# ))
EXTRA=("$@")
SCENE=$(dirname "$0")/../scenarios/oden_hollow_cylinder.toml
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
[ -x "$BIN" ] || { echo "no tread binary at $BIN (cargo build --release first)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs GNU time (/usr/bin/time)" >&2; exit 2; }
echo "| mesh | DOFs | damped: iterations, wall (s), s/iteration, peak RSS (MB) | undamped: iterations, wall (s), s/iteration, peak RSS (MB) | per-iteration ratio | total ratio | memory ratio |"
echo "|---|---|---|---|---|---|---|"
for m in $MESHES; do
  nr=${m%x*}; nt=${m#*x}
  declare -A it wall rss coarse
  for d in damped undamped; do
    args=(run "$SCENE" --mode steady --threads 1 -q --set "mesh.n_r=$nr" --set "mesh.n_theta=$nt"
          --set 'output.sinks=["summary"]' --out "$OUT/$m-$d" "${EXTRA[@]}")
    [ "$d" = undamped ] && args+=(--set time.strain_rate_damping=0)
    RAYON_NUM_THREADS=1 /usr/bin/time -f "%e %M" -o "$OUT/time" "$BIN" "${args[@]}" >/dev/null 2>"$OUT/err" \
      || { echo "$m $d failed: $(tail -2 "$OUT/err")" >&2; continue 2; }
    read -r w r < "$OUT/time"
    wall[$d]=$w; rss[$d]=$r
    it[$d]=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['newton_iterations'])" "$OUT/$m-$d/summary.json")
    # Nested iteration (solver.coarse_start): the coarser meshes' time is left out of the
    # time per iteration (their iterations are not counted in newton_iterations).
    coarse[$d]=$(python3 -c "import json,sys; c=json.load(open(sys.argv[1]))['solver'].get('coarse_start'); print(c['coarse_wall_time_s'] if c else 0)" "$OUT/$m-$d/summary.json")
    dofs=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['dofs'])" "$OUT/$m-$d/summary.json")
  done
  python3 - "$m" "$dofs" "${it[damped]}" "${wall[damped]}" "${rss[damped]}" "${it[undamped]}" "${wall[undamped]}" "${rss[undamped]}" "${coarse[damped]}" "${coarse[undamped]}" <<'PY'
import sys
m, dofs, i1, w1, r1, i0, w0, r0, c1, c0 = sys.argv[1:]
i1, w1, r1, i0, w0, r0 = int(i1), float(w1), float(r1) / 1024, int(i0), float(w0), float(r0) / 1024
p1, p0 = (w1 - float(c1)) / i1, (w0 - float(c0)) / i0
print(f"| {m} | {dofs} | {i1}, {w1:.2f}, {p1:.3f}, {r1:.0f} | {i0}, {w0:.2f}, {p0:.3f}, {r0:.0f} | {p1/p0:.2f} | {w1/w0:.2f} | {r1/r0:.2f} |")
PY
done
