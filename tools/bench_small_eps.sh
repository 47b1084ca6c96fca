#!/bin/bash
# Steady frictional rolling with a small slip regularisation ε (a benchmark, not a test).
# For each ε/v0 it solves scenarios/creep_force.toml (mesh 6 x 256 Q2: 12,288 DOFs, road speed
# v0 = 4.2 in/s near free rolling, tanh Coulomb law, mu = 0.3) in steady mode on one thread, with
# the built-in ε continuation (`[solver] eps_continuation = true`, the default) and without it
# (pressing in at the scene's ε), and prints the Newton iterations, wall time, peak RSS and the
# hub force Fx of each, then the time ratio.
#
#   tools/bench_small_eps.sh [TREAD_BINARY] ["1e-2 1e-3 1e-4 1e-5"] [extra --set arguments...]
#
# Without the continuation ε = 1e-4 v0 takes a few minutes (hundreds of line-searched Newton
# iterations and cut-backs); pass a shorter list to skip the slow cases.
set -euo pipefail
BIN=${1:-target/release/tread}
RATIOS=${2:-"1e-2 1e-3 1e-4 1e-5"}
shift $(( $# > 2 ? 2 : $# ))
EXTRA=("$@")
SCENE=$(dirname "$0")/../scenarios/creep_force.toml
V0=4.2
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
[ -x "$BIN" ] || { echo "no tread binary at $BIN (cargo build --release first)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "needs GNU time (/usr/bin/time)" >&2; exit 2; }
echo "| eps / v0 | eps (in/s) | continuation: iterations, wall (s), peak RSS (MB), Fx (lbf/in) | direct: iterations, wall (s), peak RSS (MB), Fx (lbf/in) | time ratio direct / continuation |"
echo "|---|---|---|---|---|"
for r in $RATIOS; do
  eps=$(python3 -c "print(f'{$r * $V0:.6g}')")
  declare -A it wall rss fx
  for c in true false; do
    d="$OUT/$r-$c"
    if RAYON_NUM_THREADS=1 /usr/bin/time -f "%e %M" -o "$OUT/time" "$BIN" run "$SCENE" --threads 1 -q \
        --set mesh.n_r=6 --set mesh.n_theta=256 --set "road.v0=$V0" --set "friction.eps=$eps" \
        --set "solver.eps_continuation=$c" --set 'output.sinks=["summary"]' --out "$d" "${EXTRA[@]}" \
        >/dev/null 2>"$OUT/err"; then
      read -r w m < "$OUT/time"
      wall[$c]=$w; rss[$c]=$((m / 1024))
      read -r i f < <(python3 -c "import json,sys; s=json.load(open(sys.argv[1])); print(s['newton_iterations'], '%.9g' % s['results']['hub_force_x'])" "$d/summary.json")
      it[$c]=$i; fx[$c]=$f
    else
      it[$c]="failed"; wall[$c]=nan; rss[$c]=0; fx[$c]=nan
    fi
  done
  ratio=$(python3 -c "import math; a, b = float('${wall[false]}'), float('${wall[true]}'); print('%.1f' % (a / b) if math.isfinite(a) and b > 0 else 'n/a')")
  echo "| $r | $eps | ${it[true]}, ${wall[true]}, ${rss[true]}, ${fx[true]} | ${it[false]}, ${wall[false]}, ${rss[false]}, ${fx[false]} | $ratio |"
done
