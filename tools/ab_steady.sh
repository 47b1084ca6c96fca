#!/bin/bash
# A/B timing of two tread binaries on the default scene's steady solve (a benchmark, not a
# test): for each MESH:TANGENT, REPS alternating runs of each binary (one thread), then the
# median wall times (summary.json's wall_time_s), their ratio and the peak RSS (GNU time).
#
#   REPS=5 tools/ab_steady.sh OLD_TREAD NEW_TREAD 8x128:matrix_free 16x512:banded ...
#
# TANGENT is a `[solver] damping_tangent` keyword (auto, matrix_free, banded, assembled).
# AB_SET=KEY=VALUE adds one more scene override to every run (e.g. AB_SET=time.strain_rate_damping=0).
set -euo pipefail
[ $# -ge 3 ] || { sed -n '2,8p' "$0" >&2; exit 2; }
OLD=$1; NEW=$2; shift 2
SCENE=$(dirname "$0")/../scenarios/oden_hollow_cylinder.toml
[ -x /usr/bin/time ] || { echo "needs GNU time (/usr/bin/time)" >&2; exit 2; }
for b in "$OLD" "$NEW"; do [ -x "$b" ] || { echo "no tread binary at $b" >&2; exit 2; }; done
run() { # binary mesh tangent -> "wall_s rss_kB"
  local nr=${2%x*} nt=${2#*x} d
  d=$(mktemp -d)
  RAYON_NUM_THREADS=1 /usr/bin/time -f "%M" -o "$d/t" "$1" run "$SCENE" --mode steady -q --threads 1 \
    --set "mesh.n_r=$nr" --set "mesh.n_theta=$nt" --set 'output.sinks=["summary"]' \
    --set "solver.damping_tangent=\"$3\"" ${AB_SET:+--set "$AB_SET"} --out "$d/o" >/dev/null 2>&1 \
    || { echo "run failed: $1 $2 $3" >&2; rm -rf "$d"; exit 1; }
  python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['wall_time_s'], open(sys.argv[2]).read().strip())" "$d/o/summary.json" "$d/t"
  rm -rf "$d"
}
for spec in "$@"; do
  mesh=${spec%:*}; tan=${spec#*:}
  o=(); n=()
  for _ in $(seq "${REPS:-5}"); do
    o+=("$(run "$OLD" "$mesh" "$tan")"); n+=("$(run "$NEW" "$mesh" "$tan")")
  done
  python3 - "$mesh" "$tan" "${o[@]}" -- "${n[@]}" <<'PY'
import statistics as st, sys
a = sys.argv[3:]; k = a.index('--')
o = [list(map(float, x.split())) for x in a[:k]]; n = [list(map(float, x.split())) for x in a[k + 1:]]
mo, mn = st.median(x[0] for x in o), st.median(x[0] for x in n)
print(f"{sys.argv[1]} {sys.argv[2]}: old median {mo:.3f} s {[round(x[0], 3) for x in o]}, "
      f"new median {mn:.3f} s {[round(x[0], 3) for x in n]}, new/old {mn / mo:.3f}; "
      f"peak RSS old {max(x[1] for x in o) / 1024:.0f} MB, new {max(x[1] for x in n) / 1024:.0f} MB")
PY
done
