#!/usr/bin/env bash
# The main job. Until the full grasping pipeline lands this prints the robot's kinematic
# summary and one whole-body kinematics query at the ready pose.
set -eo pipefail
cd "$(dirname "$0")/../../.."
export PATH="/usr/bin:/bin:$PATH"
# shellcheck disable=SC1091
source devel/setup.bash
ROBOT="${ROBOT:-config/robots/realman_rm65_water2/robot.yaml}"
echo "== EHC-MM: robot kinematic summary ($ROBOT)"
rosrun ehc_control ehc_kinematics --robot "$ROBOT" --summary
echo "== whole-body kinematics of the TCP at the ready pose, base at (1, 0.5, 0.3)"
rosrun ehc_control ehc_kinematics --robot "$ROBOT" --q ready --base 1,0.5,0.3
