#!/usr/bin/env bash
# Bring-up of EHC-MM on the RealMan compound robot (RM65-B arm + Water2 base + D435), with
# rosrun only (no roslaunch). See src/ehc_realman/REALMAN.md for the machine set-up.
#
#   run_realman.sh [--dry-run] [COMPONENT...]
#
# COMPONENT: arm | base | perception | controller | sequencer | robot (= arm base)
#            | all (= arm base perception controller, the default)
#   arm         rm_arm_adapter       /arm/joint_velocity_cmd -> /rm_driver/JointPos
#               robot_state_publisher /joint_states + URDF -> tf base_link -> ... -> camera
#                                    (Debian ros-robot-state-publisher; the tag, grasp and
#                                    obstacle nodes need the camera's tf)
#   base        water2_base_bridge   /cmd_vel -> Water2 joy_control, robot_status -> /odom + tf
#   perception  ehc_tag_node, ehc_grasp_node, ehc_obstacle_node (camera-facing nodes)
#   controller  ehc_controller_node  /cmd_vel + /arm/joint_velocity_cmd
#   sequencer   ehc_grasp_sequencer_node (the grasping task: targets, gripper through
#               /arm/gripper/set); never in `all`. It exits when every object is handled: the
#               script then stops every node and exits 0 (1 if the sequencer failed).
# The vendor rm_driver and the D435 driver are not started here (see REALMAN.md).
#
# Environment (defaults in brackets):
#   EHC_WS             workspace root                         [three levels above this script]
#   ROBOT_YAML         robot description      [config/robots/realman_rm65_water2/robot.yaml]
#   ARM_CONFIG         rm_arm_adapter YAML            [config/realman/rm_arm_adapter.yaml]
#   BASE_CONFIG        water2_base_bridge YAML        [config/realman/water2_base_bridge.yaml]
#   WATER2_HOST/PORT   Water2 API address (override BASE_CONFIG)           [from BASE_CONFIG]
#   REQUIRE_OBSTACLES  0: controller runs without /ehc/obstacles (no obstacle sensing)  [1]
#   CONTROLLER_CONFIG  controller YAML (run with _trigger:=timer) [config/realman/controller.yaml]
#   CONTROLLER_MODE    ehc | neo_e | neo_c | tsmm          [the YAML's controller.mode]
#   TAG_CONFIG, GRASP_CONFIG, OBSTACLE_CONFIG  perception YAMLs       [config/perception/*.yaml]
#                      TAG_CONFIG may list several files (space-separated): one tag node each,
#                      named ehc_tag_<file name without .yaml> (e.g. one per object)
#   SEQUENCER_CONFIG   grasp sequencer YAML        [config/realman/rehearsal_grasp_sequencer.yaml]
#   SEQUENCER_SUMMARY  the sequencer's JSON summary          [$LOG_DIR/grasp_summary.json]
#   LOG_DIR            one log file per node                        [$HOME/.ros/ehc_realman]
#   MASTER_TIMEOUT     s to wait for the master to answer `rosnode list` (a busy computer
#                      takes seconds to start it: 5 s failed under load 35)          [20]
#   ROS_MASTER_URI, ROS_IP  as usual (the master runs on the robot computer)
#
# Parameters never leak from an earlier run: before a node starts, its private namespace on the
# parameter server (/<node name>, e.g. /ehc_controller_node) is deleted, so that it gets exactly
# this run's overrides (an earlier CONTROLLER_MODE=tsmm does not stay in force).
# Every node is started in the background; Ctrl-C (or any node exiting) stops all the nodes
# this script started, by their process ids (src/ehc_common/scripts/supervise.sh). Exit code:
# 0 on Ctrl-C or when the sequencer completed, 1 if a node died (or the sequencer failed), 2 on
# a usage or set-up error.
set -o pipefail

usage() { awk 'NR == 1 { next } /^#/ { sub(/^# ?/, ""); print; next } { exit }' "$0"; }

DRY_RUN=0
COMPONENTS=()
for arg in "$@"; do
  case "$arg" in
    --dry-run) DRY_RUN=1 ;;
    -h|--help) usage; exit 0 ;;
    arm|base|perception|controller|sequencer) COMPONENTS+=("$arg") ;;
    robot) COMPONENTS+=(arm base) ;;
    all) COMPONENTS+=(arm base perception controller) ;;
    *) echo "run_realman.sh: unknown argument '$arg'" >&2; usage >&2; exit 2 ;;
  esac
done
[ ${#COMPONENTS[@]} -eq 0 ] && COMPONENTS=(arm base perception controller)

export PATH="/usr/bin:/bin:$PATH"  # the catkin-aware python3 first
# The process supervisor beside this script's package (ehc_common, a dependency of ehc_realman).
# shellcheck source=../../ehc_common/scripts/supervise.sh
source "$(dirname "$0")/../../ehc_common/scripts/supervise.sh" || exit 2
SUP_TAG=run_realman.sh
EHC_WS="${EHC_WS:-$(cd "$(dirname "$0")/../../.." && pwd)}"
cd "$EHC_WS" || exit 2
if [ -z "${EHC_SKIP_SETUP:-}" ]; then
  if [ -f devel/setup.bash ]; then
    # shellcheck disable=SC1091
    source devel/setup.bash
  elif [ -f install/setup.bash ]; then
    # shellcheck disable=SC1091
    source install/setup.bash
  else
    echo "run_realman.sh: no devel/setup.bash in $EHC_WS: build first (make build)" >&2
    exit 2
  fi
fi

ROBOT_YAML="${ROBOT_YAML:-config/robots/realman_rm65_water2/robot.yaml}"
ARM_CONFIG="${ARM_CONFIG:-config/realman/rm_arm_adapter.yaml}"
BASE_CONFIG="${BASE_CONFIG:-config/realman/water2_base_bridge.yaml}"
CONTROLLER_CONFIG="${CONTROLLER_CONFIG:-config/realman/controller.yaml}"
TAG_CONFIG="${TAG_CONFIG:-config/perception/tag_node.yaml}"
GRASP_CONFIG="${GRASP_CONFIG:-config/perception/grasp_node.yaml}"
OBSTACLE_CONFIG="${OBSTACLE_CONFIG:-config/perception/obstacle_node.yaml}"
LOG_DIR="${LOG_DIR:-${HOME:-/tmp}/.ros/ehc_realman}"
SEQUENCER_CONFIG="${SEQUENCER_CONFIG:-config/realman/rehearsal_grasp_sequencer.yaml}"
SEQUENCER_SUMMARY="${SEQUENCER_SUMMARY:-$LOG_DIR/grasp_summary.json}"

# ---------------------------------------------------------------- the node list
# Each entry: "package executable arg..." (arguments in rosrun form).
# Fixed start order whatever the argument order: drivers' adapters first, controller last.
NODES=()
for c in arm base perception controller sequencer; do
  [[ " ${COMPONENTS[*]} " == *" $c "* ]] || continue
  case "$c" in
    arm)
      NODES+=("ehc_realman rm_arm_adapter _config:=$ARM_CONFIG")
      # tf of the arm, gripper and camera from the driver's /joint_states. robot_description is
      # ROBOT_YAML's URDF with its calibration applied (ehc_kinematics --urdf), set just before
      # it starts: the tf is the robot the controller computes with.
      NODES+=("robot_state_publisher robot_state_publisher") ;;
    base)
      n="ehc_realman water2_base_bridge _config:=$BASE_CONFIG"
      [ -n "${WATER2_HOST:-}" ] && n+=" _host:=$WATER2_HOST"
      [ -n "${WATER2_PORT:-}" ] && n+=" _port:=$WATER2_PORT"
      NODES+=("$n") ;;
    perception)
      read -r -a tag_configs <<<"$TAG_CONFIG"
      if [ ${#tag_configs[@]} -eq 1 ]; then
        NODES+=("ehc_perception ehc_tag_node _config:=$TAG_CONFIG")
      else
        for t in "${tag_configs[@]}"; do
          t_name="$(basename "$t" .yaml)"
          NODES+=("ehc_perception ehc_tag_node _config:=$t __name:=ehc_${t_name#ehc_}")
        done
      fi
      NODES+=("ehc_perception ehc_grasp_node _config:=$GRASP_CONFIG")
      NODES+=("ehc_perception ehc_obstacle_node _config:=$OBSTACLE_CONFIG") ;;
    controller)
      # The real robot has no lock-step simulator: the controller cycles on its timer whatever
      # CONTROLLER_CONFIG's node.trigger says (_trigger:=timer; the rate is the file's node.rate).
      n="ehc_control ehc_controller_node _config:=$CONTROLLER_CONFIG _robot:=$ROBOT_YAML _trigger:=timer"
      [ -n "${CONTROLLER_MODE:-}" ] && n+=" _mode:=$CONTROLLER_MODE"
      # REQUIRE_OBSTACLES=0: run without obstacle sensing (the controller otherwise stops with
      # OBSTACLES_STALE until /ehc/obstacles arrives; never do this next to people).
      [ "${REQUIRE_OBSTACLES:-1}" = 0 ] && n+=" _require_obstacles:=false"
      NODES+=("$n") ;;
    sequencer)
      NODES+=("ehc_bringup ehc_grasp_sequencer_node _config:=$SEQUENCER_CONFIG _summary:=$SEQUENCER_SUMMARY") ;;
  esac
done

# ---------------------------------------------------------------- pre-flight checks
problems=0
for n in "${NODES[@]}"; do
  read -r pkg exe args <<<"$n"
  if ! catkin_find --libexec --first-only "$pkg" "$exe" >/dev/null 2>&1; then
    echo "run_realman.sh: $pkg/$exe is not built (or not in this workspace)" >&2
    problems=1
  fi
  for a in $args; do
    case "$a" in
      _config:=*)
        f="${a#*:=}"
        [ -f "$f" ] || { echo "run_realman.sh: $pkg/$exe: file not found: $f" >&2; problems=1; } ;;
    esac
  done
done
[ -f "$ROBOT_YAML" ] || { echo "run_realman.sh: robot description not found: $ROBOT_YAML" >&2; problems=1; }

if [ "$DRY_RUN" = 1 ]; then
  echo "ROS_MASTER_URI=${ROS_MASTER_URI:-<unset>} ROS_IP=${ROS_IP:-<unset>}"
  for n in "${NODES[@]}"; do echo "rosrun $n"; done
  exit $(( problems ? 2 : 0 ))
fi
[ "$problems" = 0 ] || exit 2

if [ -z "${ROS_MASTER_URI:-}" ]; then
  echo "run_realman.sh: ROS_MASTER_URI is not set (the master runs on the robot computer)" >&2
  exit 2
fi
if ! timeout "${MASTER_TIMEOUT:-20}" rosnode list >/dev/null 2>&1; then
  echo "run_realman.sh: no ROS master at $ROS_MASTER_URI (start roscore on the robot computer)" >&2
  exit 2
fi

# ---------------------------------------------------------------- start, watch, stop
mkdir -p "$LOG_DIR"
SUP_LOG_DIR="$LOG_DIR"
sup_install_traps "stopping" 0

# Node names: the __name:= remap if any, else the executable's ros::init name, under ROS_NAMESPACE.
node_ns() { local ns="${ROS_NAMESPACE:-}"; ns="${ns#/}"; ns="${ns%/}"; echo "${ns:+/$ns}/$1"; }
node_name() {  # node_name EXE ARGS...
  local name="$1" a
  shift
  for a in "$@"; do case "$a" in __name:=*) name="${a#__name:=}" ;; esac; done
  echo "$name"
}
for n in "${NODES[@]}"; do
  read -r pkg exe args <<<"$n"
  # shellcheck disable=SC2086
  name="$(node_name "$exe" $args)"
  ns="$(node_ns "$name")"
  sup_clear_params "$ns" || exit 2
  if [ "$exe" = robot_state_publisher ]; then
    # robot_state_publisher reads robot_description in its own namespace (searchParam), the
    # usual global /robot_description; set on every run, so it is never an earlier run's.
    urdf="$LOG_DIR/robot_description.urdf"
    rosrun ehc_control ehc_kinematics --robot "$ROBOT_YAML" --urdf >"$urdf" &&
      rosparam set -t "$urdf" "${ns%/*}/robot_description" ||
      { echo "run_realman.sh: cannot set robot_description from $ROBOT_YAML" >&2; exit 2; }
  fi
  log="$LOG_DIR/$name.log"
  # shellcheck disable=SC2086
  sup_start "$name" rosrun "$pkg" "$exe" $args
  echo "started $name (pid $SUP_LAST_PID, log $log): rosrun $n"
done

# Any node exiting is an error: stop everything (the robot must not run half-controlled).
sup_watch
if [ "$SUP_DEAD" = ehc_grasp_sequencer_node ]; then
  # The task's end, not a fault: every object handled (summary in SEQUENCER_SUMMARY).
  echo "run_realman.sh: the grasp sequencer finished (code $SUP_DEAD_RC, summary $SEQUENCER_SUMMARY); stopping the others."
  sup_stop_all
  exit $(( SUP_DEAD_RC == 0 ? 0 : 1 ))
fi
echo "run_realman.sh: $SUP_DEAD exited (code $SUP_DEAD_RC); stopping the others." >&2
echo "  last lines of $LOG_DIR/$SUP_DEAD.log:" >&2
sup_log_tail "$SUP_DEAD"
sup_stop_all
exit 1
