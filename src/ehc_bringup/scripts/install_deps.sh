#!/usr/bin/env bash
# Installs the Debian packages EHC-MM needs (idempotent; quick when all are installed).
# Everything comes from Debian 12 packages: nothing is vendored or downloaded elsewhere.
set -euo pipefail

PACKAGES=(
  # build + ROS 1 (Debian packaging)
  build-essential cmake catkin ros-core-dev rosbash python3-roslaunch python3-rostest
  librostest-dev ros-message-generation ros-message-runtime python3-genmsg python3-gencpp
  libros-rosgraph-msgs-dev python3-rosgraph-msgs
  libstd-msgs-dev libstd-srvs-dev libsensor-msgs-dev libgeometry-msgs-dev libnav-msgs-dev
  libvisualization-msgs-dev libdiagnostic-msgs-dev
  libtf2-dev libtf2-ros-dev libtf2-eigen-dev libtf2-geometry-msgs-dev
  ros-robot-state-publisher  # run_realman.sh: arm / camera tf on the real robot
  # kinematics
  libeigen3-dev liborocos-kdl-dev libkdl-parser-dev liburdf-dev liburdfdom-dev liburdfdom-tools
  libyaml-cpp-dev nlohmann-json3-dev
  # servoing, QP, vision
  libvisp-dev libopencv-dev libapriltag-dev
  # perception, collision, physics
  libpcl-dev libfcl-dev liboctomap-dev libbullet-dev
  libassimp-dev  # mesh objects of the simulator (OBJ, STL, PLY)
  # tests and result plots
  googletest libgtest-dev python3-yaml python3-numpy python3-matplotlib python3-pytest
  # rostopic pub / echo of the messages the nodes use (README "Running a node")
  python3-geometry-msgs python3-sensor-msgs python3-nav-msgs
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "[deps] all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi

echo "[deps] installing ${#missing[@]} Debian packages: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "[deps] error: run as root (or install the packages above with sudo apt-get install)" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update
apt-get install -y --no-install-recommends "${missing[@]}"
