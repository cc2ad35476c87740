#!/usr/bin/env bash
# `make experiments`: the paper's three experiments in-process (no ROS master), one report.
#   Exp-1 ehc_experiment reach  (Table II)   -> $OUT/exp1/
#   Exp-2 ehc_experiment grasp  (Table III)  -> $OUT/exp2/
#   Exp-3 ehc_experiment poses  (Table IV)   -> $OUT/exp3/
# then PNG plots (experiment_plots.py), $OUT/REPORT.md with every table and plot, $OUT/meta.json
# (command lines, seed, robot, code version, machine, dates) and docs/RESULTS.md (make_results.py;
# a run into another OUT writes $OUT/RESULTS.md instead).
# Environment (defaults in brackets): EHC_DEVEL [devel], OUT [results/experiments], SEED [1],
#   JOBS [2] (parallel runs of Exp-2/3), EXP1_SETS [10], EXP1_POINTS [50], SETS [15] (Exp-2/3),
#   PER_SET [5] (Exp-3 grasps per approach per set), ROBOT [realman_rm65_water2] (every protocol;
#   make experiments ROBOT=kuka_iiwa14_kmr). Progress and ETA on stderr.
# shellcheck source=devel_env.sh
source "$(dirname "$0")/devel_env.sh" experiments.sh
OUT="${OUT:-results/experiments}"
SEED="${SEED:-1}"
JOBS="${JOBS:-2}"
SETS="${SETS:-15}"
PER_SET="${PER_SET:-5}"
ROBOT="${ROBOT:-realman_rm65_water2}"   # robot name (config/robots/<name>/) or robot.yaml: every protocol
mkdir -p "$OUT"
t0=$(date +%s)
EXP1=(rosrun ehc_bringup ehc_experiment reach --robot "$ROBOT" --method all --sets "${EXP1_SETS:-10}"
  --points "${EXP1_POINTS:-50}" --seed "$SEED" --out "$OUT/exp1")
EXP2=(rosrun ehc_bringup ehc_experiment grasp --robot "$ROBOT" --method all --sets "$SETS" --seed "$SEED" --jobs "$JOBS" --out "$OUT/exp2")
EXP3=(rosrun ehc_bringup ehc_experiment poses --robot "$ROBOT" --method all --sets "$SETS" --per-set "$PER_SET" --seed "$SEED" --jobs "$JOBS"
  --out "$OUT/exp3")
RESULTS=(/usr/bin/python3 src/ehc_bringup/scripts/make_results.py)
"${RESULTS[@]}" meta "$OUT" --command "ROBOT=$ROBOT SEED=$SEED EXP1_SETS=${EXP1_SETS:-10} EXP1_POINTS=${EXP1_POINTS:-50} \
SETS=$SETS PER_SET=$PER_SET JOBS=$JOBS OUT=$OUT src/ehc_bringup/scripts/experiments.sh" \
  --run exp1 "${EXP1[*]}" --run exp2 "${EXP2[*]}" --run exp3 "${EXP3[*]}" --seed "$SEED" --robot "$ROBOT"
echo "== Exp-1 (random reaching)" >&2
"${EXP1[@]}" >/dev/null
echo "== Exp-2 (three objects in sequence)" >&2
"${EXP2[@]}" >/dev/null
echo "== Exp-3 (grasp orientations, TfM)" >&2
"${EXP3[@]}" >/dev/null
for e in exp2 exp3; do /usr/bin/python3 src/ehc_bringup/scripts/experiment_plots.py "$OUT/$e"; done
wall=$(( $(date +%s) - t0 ))
{
  echo "# EHC-MM experiments (in-process, simulated)"
  echo
  echo "Seed $SEED; Exp-1 ${EXP1_SETS:-10} x ${EXP1_POINTS:-50} targets; Exp-2 $SETS sets; Exp-3 $SETS sets x $PER_SET per approach;"
  echo "$JOBS job(s); $wall s wall on $(nproc) core(s), load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)."
  echo
  echo "## Exp-1: random reaching (paper Table II)"
  echo
  cat "$OUT/exp1/table.md"
  echo
  echo "## Exp-2: grasping three objects in sequence (paper Table III)"
  echo
  cat "$OUT/exp2/table.md"
  echo
  echo "![distance](exp2/distance.png) ![speeds](exp2/speeds.png) ![tfm](exp2/tfm.png)"
  echo
  echo "## Exp-3: grasp orientations, TfM (paper Table IV)"
  echo
  cat "$OUT/exp3/table.md"
  echo
  echo "![distance](exp3/distance.png) ![speeds](exp3/speeds.png) ![tfm](exp3/tfm.png)"
} >"$OUT/REPORT.md"
echo "experiments.sh: $OUT/REPORT.md ($wall s)" >&2
"${RESULTS[@]}" meta "$OUT" --finish
if [ "$OUT" = results/experiments ]; then RESULTS_MD=docs/RESULTS.md; else RESULTS_MD="$OUT/RESULTS.md"; fi
"${RESULTS[@]}" --experiments "$OUT" --out "$RESULTS_MD"
