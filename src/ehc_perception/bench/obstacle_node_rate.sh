#!/bin/bash
# Rate of /ehc/obstacles under a full 640x480 D435 stream at cloud_hz, then under 2 M-point
# clouds (1920x1080) at 5 Hz: starts a private ROS master (free port), ehc_obstacle_node with
# CONFIG and bench_obstacle_node_rate (the camera + robot).
#   source devel/setup.bash
#   src/ehc_perception/bench/obstacle_node_rate.sh [CONFIG=config/perception/obstacle_node.yaml] \
#       [cloud_hz=30] [seconds=20]
# Wall-clock figures: noisy on a shared machine.
set -eu
CONFIG="$(realpath "${1:-config/perception/obstacle_node.yaml}")"
HZ="${2:-30}"
SECONDS_="${3:-20}"
PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://127.0.0.1:$PORT"
PIDS=()
trap 'for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true' EXIT
rosmaster --core -p "$PORT" >/dev/null 2>&1 & PIDS+=($!)
for _ in $(seq 100); do rosparam set /use_sim_time false >/dev/null 2>&1 && break; sleep 0.1; done
rosrun ehc_perception ehc_obstacle_node _config:="$CONFIG" >/dev/null 2>&1 & PIDS+=($!)
rosrun ehc_perception bench_obstacle_node_rate _cloud_hz:="$HZ" _seconds:="$SECONDS_"
rosrun ehc_perception bench_obstacle_node_rate _cloud_hz:=5 _seconds:="$SECONDS_" _width:=1920 _height:=1080
