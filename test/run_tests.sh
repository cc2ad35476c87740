#!/usr/bin/env bash
# Builds the workspace, runs every gtest and rostest (catkin run_tests), prints the failed
# cases and a closing line `N passed, N failed`. Exit code != 0 on any failure.
set -o pipefail
cd "$(dirname "$0")/.."
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"
JOBS="${JOBS:-2}"
CATKIN=(catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=Release "-j${JOBS}")

if ! "${CATKIN[@]}"; then
  echo "[tests] build failed"
  echo "0 passed, 1 failed"
  exit 1
fi
rm -rf build/test_results
# shellcheck disable=SC1091
source devel/setup.bash
export ROS_HOME="${ROS_HOME:-$PWD/build/ros_home}"
build_failed=0
# --force-cmake: catkin caches the test environment at configure time; on a fresh clone the devel
# space had no Python packages then (PYTHONPATH=''), so rostests importing ehc_msgs failed.
if ! "${CATKIN[@]}" --force-cmake run_tests; then
  echo "[tests] catkin run_tests reported an error (test build failure?)"
  build_failed=1
fi
/usr/bin/python3 test/summarize_results.py build/test_results "$build_failed"
