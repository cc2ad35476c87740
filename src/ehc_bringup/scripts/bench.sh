#!/usr/bin/env bash
# Runs every benchmark executable (devel/lib/<pkg>/bench_*); each prints JSON lines.
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
for b in "${benches[@]}"; do
  echo "[bench] $b" >&2
  "$b"
done
