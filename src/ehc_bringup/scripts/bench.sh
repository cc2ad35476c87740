#!/usr/bin/env bash
# Runs every benchmark executable (devel/lib/<pkg>/bench_*; ROS-node benches through their
# launcher script); each prints JSON lines. The lines are also kept in $OUT/bench.jsonl
# (OUT [results/bench]) with $OUT/meta.json (command, code version, machine, dates) for
# make_results.py (docs/RESULTS.md).
set -eo pipefail
cd "$(dirname "$0")/../../.."
export PATH="/usr/bin:/bin:$PATH"
# shellcheck disable=SC1091
source devel/setup.bash
shopt -s nullglob
benches=(devel/lib/*/bench_*)
if [ ${#benches[@]} -eq 0 ]; then
  echo "[bench] no benchmark executables found (build first)" >&2
  exit 1
fi
echo "[bench] machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)" >&2
OUT="${OUT:-results/bench}"
RESULTS=(/usr/bin/python3 src/ehc_bringup/scripts/make_results.py)
"${RESULTS[@]}" meta "$OUT" --command "OUT=$OUT src/ehc_bringup/scripts/bench.sh"
# The JSON lines also go to $OUT/bench.jsonl (pipefail: a failing bench still fails the run).
for b in "${benches[@]}"; do
  # A bench that is a ROS node comes with a launcher, src/<pkg>/bench/<name without bench_>.sh,
  # that starts a private master and the nodes it measures (run without them it would wait for
  # a master forever).
  pkg=$(basename "$(dirname "$b")")
  name=$(basename "$b")
  launcher="src/$pkg/bench/${name#bench_}.sh"
  if [ -x "$launcher" ]; then
    echo "[bench] $launcher" >&2
    "$launcher"
  else
    echo "[bench] $b" >&2
    "$b"
  fi
done | tee "$OUT/bench.jsonl"
"${RESULTS[@]}" meta "$OUT" --finish
