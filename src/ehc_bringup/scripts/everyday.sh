#!/usr/bin/env bash
# `make everyday`: Exp-2 on the simulator's object library (three untagged library objects per
# set, in-process), the tuning half and the validation half, each over its own seeds:
#   ehc_experiment grasp --library <half> --method $METHOD --sets $SETS --seed N -> $OUT/<half>/seed_N/
#   (table.md, trials.csv, summary.json, trace.csv and the PNG plots of experiment_plots.py)
# then $OUT/meta.json (command lines, seeds, robot, code version, machine, dates) and
# docs/RESULTS.md (make_results.py; a run into another OUT writes $OUT/RESULTS.md instead).
# Environment (defaults in brackets): EHC_DEVEL [devel], OUT [results/everyday], SETS [5],
#   METHOD [ehc] (or all), JOBS [2], ROBOT [realman_rm65_water2], TUNING_SEEDS [one fresh seed],
#   VALIDATION_SEEDS [three fresh seeds] (comma-separated; fresh seeds are drawn and printed first,
#   so a run reproduces with the seeds it printed). Progress and ETA on stderr.
# shellcheck source=devel_env.sh
source "$(dirname "$0")/devel_env.sh" everyday.sh
OUT="${OUT:-results/everyday}"
SETS="${SETS:-5}"
METHOD="${METHOD:-ehc}"
JOBS="${JOBS:-2}"
ROBOT="${ROBOT:-realman_rm65_water2}"
fresh() { shuf -i 100000-999999 -n "$1" | paste -sd, -; }
TUNING_SEEDS="${TUNING_SEEDS:-$(fresh 1)}"
VALIDATION_SEEDS="${VALIDATION_SEEDS:-$(fresh 3)}"
echo "everyday.sh: tuning seeds $TUNING_SEEDS, validation seeds $VALIDATION_SEEDS (rerun: TUNING_SEEDS=$TUNING_SEEDS VALIDATION_SEEDS=$VALIDATION_SEEDS make everyday)" >&2
for s in ${TUNING_SEEDS//,/ } ${VALIDATION_SEEDS//,/ }; do
  [[ "$s" =~ ^[0-9]+$ ]] || { echo "everyday.sh: seed '$s' is not a number" >&2; exit 2; }
done
rm -rf "$OUT/tuning" "$OUT/validation"
mkdir -p "$OUT"
RESULTS=(/usr/bin/python3 src/ehc_bringup/scripts/make_results.py)
"${RESULTS[@]}" meta "$OUT" --command "ROBOT=$ROBOT METHOD=$METHOD SETS=$SETS JOBS=$JOBS TUNING_SEEDS=$TUNING_SEEDS \
VALIDATION_SEEDS=$VALIDATION_SEEDS OUT=$OUT src/ehc_bringup/scripts/everyday.sh" \
  --run everyday "rosrun ehc_bringup ehc_experiment grasp --robot $ROBOT --library <half> --method $METHOD --sets $SETS --seed <seed> --jobs $JOBS --out $OUT/<half>/seed_<seed>" \
  --seed "tuning $TUNING_SEEDS; validation $VALIDATION_SEEDS" --robot "$ROBOT"
runs=()
for s in ${TUNING_SEEDS//,/ }; do runs+=("tuning $s"); done
for s in ${VALIDATION_SEEDS//,/ }; do runs+=("validation $s"); done
t0=$(date +%s)
for i in "${!runs[@]}"; do
  read -r half seed <<<"${runs[$i]}"
  rosrun ehc_bringup ehc_experiment grasp --robot "$ROBOT" --library "$half" --method "$METHOD" --sets "$SETS" \
    --seed "$seed" --jobs "$JOBS" --out "$OUT/$half/seed_$seed" >/dev/null 2>"$OUT/$half.seed_$seed.log" || {
    echo "everyday.sh: the $half run of seed $seed failed (log: $OUT/$half.seed_$seed.log)" >&2; exit 2; }
  /usr/bin/python3 src/ehc_bringup/scripts/experiment_plots.py "$OUT/$half/seed_$seed" 2>/dev/null
  done_n=$((i + 1)); elapsed=$(( $(date +%s) - t0 ))
  echo "everyday.sh: $done_n/${#runs[@]} ($half, seed $seed) done, elapsed ${elapsed} s, ETA $(( elapsed * (${#runs[@]} - done_n) / done_n )) s" >&2
done
"${RESULTS[@]}" meta "$OUT" --finish
if [ "$OUT" = results/everyday ]; then RESULTS_MD=docs/RESULTS.md; else RESULTS_MD="$OUT/RESULTS.md"; fi
"${RESULTS[@]}" --everyday "$OUT" --out "$RESULTS_MD"
